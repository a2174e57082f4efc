//! The CPU backend: the f64 solver (the specification the GPU must equal) and a ray-cast frame.

use crate::backend::{Backend, Draw, Prepared, Solve};
use crate::error::Result;
use crate::frame::lights::direct_in_table;
use crate::frame::Image;
use crate::raycast::RayCaster;
use crate::scene::Scheme;
use crate::settings::BackendKind;
use crate::solver::convergence::Figures;
use crate::solver::{CpuSolver, CpuState, Table};
use std::time::Instant;

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// The f64 solver's state and the ray caster of the frame and shadow maps.
pub struct CpuBackend {
    state: Option<CpuState>,
    caster: RayCaster,
    timings: Vec<(String, f64)>,
    /// After a bounded move ([`Solve::follow`]): the previous shadow maps and spheres around
    /// the moved objects before and after, so that only rays near them are cast again.
    reuse: Option<(crate::frame::shadow::ShadowMaps, Vec<(glam::DVec3, f64)>)>,
}

impl CpuBackend {
    /// A backend for `prep` (builds the ray caster over its elements).
    pub fn new(prep: &Prepared) -> Self {
        let mut state = CpuState::new(&prep.system);
        state.antiradiance = prep.plan.features.antiradiance;
        state.emission = prep.plan.features.emission;
        Self {
            state: Some(state),
            caster: RayCaster::new(&prep.system),
            timings: Vec::new(),
            reuse: None,
        }
    }

    /// Runs `f` on a solver over `prep`'s system with this backend's state.
    fn with_solver<T>(&mut self, prep: &Prepared, f: impl FnOnce(&mut CpuSolver<'_>) -> T) -> T {
        let state = self
            .state
            .take()
            .expect("the state is put back after every use");
        let mut solver = CpuSolver::resume(&prep.system, state);
        let out = f(&mut solver);
        self.state = Some(solver.state);
        out
    }

    fn state(&self) -> &CpuState {
        self.state
            .as_ref()
            .expect("the state is put back after every use")
    }

    fn time(&mut self, name: &str, t: Instant) {
        self.timings.push((name.to_string(), ms(t)));
    }
}

impl Solve for CpuBackend {
    fn prepare_lights(&mut self, prep: &mut Prepared) -> Result<()> {
        let t = Instant::now();
        if !prep.maps.views.is_empty() {
            let reuse = self.reuse.take();
            prep.maps
                .render_cpu_reusing(&self.caster, reuse.as_ref().map(|(m, s)| (m, s.as_slice())));
        }
        self.time("shadow", t);
        let t = Instant::now();
        let direct = (!prep.lights.is_empty())
            .then(|| direct_in_table(&prep.system, &prep.lights, &prep.maps));
        let state = self.state.as_mut().expect("state present");
        state.set_direct_in(&prep.system, direct);
        self.time("direct", t);
        let t = Instant::now();
        let sky = prep.sky(Some(&self.caster));
        let state = self.state.as_mut().expect("state present");
        state.set_environment_in(&prep.system, sky);
        self.time("environment", t);
        Ok(())
    }
    fn initialize(&mut self, prep: &Prepared) -> Result<()> {
        let t = Instant::now();
        self.with_solver(prep, |s| s.initialize());
        self.time("solve", t);
        Ok(())
    }
    fn iterate_batch(
        &mut self,
        prep: &Prepared,
        scheme: Scheme,
        steps: usize,
        n: usize,
    ) -> Result<Vec<Figures>> {
        let t = Instant::now();
        let figures = self.with_solver(prep, |s| {
            (0..n)
                .map(|_| {
                    let before = s.i_ex.clone();
                    s.iterate(scheme, steps);
                    Figures::between(s.sys, &before, &s.i_ex)
                })
                .collect()
        });
        self.time("solve", t);
        Ok(figures)
    }
    fn resumable(&self) -> bool {
        true
    }
    fn damp(&mut self, weight: f64) -> bool {
        self.state.as_mut().expect("state present").damping = weight;
        true
    }
    fn warm_start(&mut self, _: &Prepared, i_ex: &Table) -> Result<()> {
        let state = self.state.as_mut().expect("state present");
        state.i_ex = i_ex.clone();
        state.residuals.clear();
        state.energies.clear();
        Ok(())
    }
    fn keep_solution(&mut self, _: &Prepared) -> Result<()> {
        let state = self.state.as_mut().expect("state present");
        state.residuals.clear();
        state.energies.clear();
        Ok(())
    }
    fn follow(&mut self, before: &Prepared, prep: &Prepared) -> Result<bool> {
        // The solver reads the system at every iteration: only the ray caster holds geometry.
        self.caster = RayCaster::new(&prep.system);
        // The same lights see a change only along rays near the moved objects (conservative:
        // their bounding spheres before and after).
        self.reuse = (before.lights == prep.lights).then(|| {
            let mut spheres = before.system.moving_spheres();
            spheres.extend(prep.system.moving_spheres());
            (before.maps.clone(), spheres)
        });
        Ok(true)
    }
    fn i_ex(&mut self) -> Result<Table> {
        Ok(self.state().i_ex.clone())
    }
    fn i_total(&mut self) -> Result<Table> {
        Ok(self.state().i_total.clone())
    }
}

impl Draw for CpuBackend {
    fn draw(&mut self, prep: &Prepared) -> Result<Image> {
        let t = Instant::now();
        let image = prep.render_cpu(&self.state().i_total, &self.caster);
        self.time("frame", t);
        Ok(image)
    }
}

impl Backend for CpuBackend {
    fn kind(&self) -> BackendKind {
        BackendKind::Cpu
    }
    fn take_timings(&mut self) -> Vec<(String, f64)> {
        std::mem::take(&mut self.timings)
    }
}
