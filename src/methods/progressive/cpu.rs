//! Progressive refinement on the CPU: the same shots as the GPU backend, with the visibility of
//! every receiver sample from the shooter's center by a ray (so the method runs without Vulkan,
//! and the GPU's item buffer can be checked against exact point visibility), and the ray-cast
//! frame of the antiradiance CPU backend.

use super::{
    direct_irradiance, environment_irradiance, facing, kernel, receive, shots_per_iteration,
    surface_offset, Elements, State, TableShape,
};
use crate::backend::{Backend, Draw, Prepared, Solve};
use crate::error::Result;
use crate::frame::lights::direct_in_table;
use crate::frame::Image;
use crate::methods::{MethodReport, MethodSettings, Shot};
use crate::raycast::RayCaster;
use crate::scene::Scheme;
use crate::settings::BackendKind;
use crate::solver::convergence::{Change, Figures};
use crate::solver::Table;
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;
use std::time::Instant;

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Shooting with ray-cast visibility.
pub struct CpuShooting {
    els: Elements,
    shape: TableShape,
    settings: MethodSettings,
    caster: RayCaster,
    eps: f64,
    direct: Vec<DVec3>,
    environment: Vec<DVec3>,
    state: State,
    /// Unshot power before the first shot (the residual's scale).
    initial: f64,
    shots_per_iteration: usize,
    report: MethodReport,
    timings: Vec<(String, f64)>,
    notes: Vec<String>,
}

impl CpuShooting {
    /// Elements, ray caster and the environment's irradiance for `prep`.
    pub fn new(prep: &Prepared, settings: &MethodSettings) -> Result<Self> {
        let sys = &prep.system;
        let els = Elements::new(sys);
        let caster = RayCaster::new(sys);
        let eps = surface_offset(sys);
        let t = Instant::now();
        let (environment, rays) =
            environment_irradiance(&els, &caster, prep.scene.environment, eps);
        let n = els.len();
        let mut report = MethodReport {
            setup_ms: ms(t),
            rays,
            ..Default::default()
        };
        let spi = shots_per_iteration(settings, n);
        for (k, v) in [
            ("subdivision", settings.subdivision as f64),
            ("gradient", settings.gradient),
            ("shots_per_iteration", spi as f64),
        ] {
            report.figures.insert(k.into(), v);
        }
        let direct = vec![DVec3::ZERO; n];
        let state = State::initial(&els, &direct, &environment);
        Ok(Self {
            initial: state.unshot_power(&els),
            els,
            shape: TableShape::of(sys),
            settings: *settings,
            caster,
            eps,
            direct,
            environment,
            state,
            shots_per_iteration: spi,
            report,
            timings: Vec::new(),
            notes: Elements::glossy_note(sys).into_iter().collect(),
        })
    }

    /// One shot from the element with the most unshot power; `None` when nothing is left.
    fn shoot(&mut self) -> Option<Shot> {
        let (s, power) = self.state.shooter(&self.els)?;
        let shot = Shot {
            shooter: s as u32,
            unshot: self.state.unshot_power(&self.els),
            power,
        };
        let (els, caster, eps, settings) = (&self.els, &self.caster, self.eps, &self.settings);
        let eye = els.center[s] + els.normal[s] * eps;
        let radiance = self.state.unshot[s] / PI;
        let got: Vec<f64> = (0..els.len())
            .into_par_iter()
            .map(|i| {
                if i == s || !facing(els, s, i) {
                    return 0.0;
                }
                let (n, c) = (els.normal[i], &els.corners[i]);
                let point = |b: [f64; 3]| c[0] * b[0] + c[1] * b[1] + c[2] * b[2];
                // Seen from the shooter's eye, in front of its surface.
                let visible = |x: DVec3| {
                    let d = x + n * eps - eye;
                    let len = d.length();
                    d.dot(els.normal[s]) > 0.0 && !caster.occluded(eye, d / len, 0.0, len)
                };
                receive(
                    settings,
                    |b| {
                        let x = point(b);
                        let k = kernel(els, s, x, n);
                        (k, k > 0.0 && visible(x))
                    },
                    |b| visible(point(b)),
                )
                .0
            })
            .collect();
        for (i, g) in got.into_iter().enumerate() {
            let dh = radiance * g;
            self.state.gathered[i] += dh;
            self.state.unshot[i] += self.els.albedo[i] * dh;
        }
        self.state.unshot[s] = DVec3::ZERO;
        Some(shot)
    }
}

impl Solve for CpuShooting {
    fn prepare_lights(&mut self, prep: &mut Prepared) -> Result<()> {
        let t = Instant::now();
        if !prep.maps.views.is_empty() {
            prep.maps.render_cpu(&self.caster);
        }
        self.timings.push(("shadow".into(), ms(t)));
        let t = Instant::now();
        self.direct = if prep.scene.lights.is_empty() {
            vec![DVec3::ZERO; self.els.len()]
        } else {
            let table = direct_in_table(&prep.system, &prep.scene.lights, &prep.maps);
            direct_irradiance(&prep.system, &table)
        };
        self.timings.push(("direct".into(), ms(t)));
        Ok(())
    }
    fn initialize(&mut self, _: &Prepared) -> Result<()> {
        self.state = State::initial(&self.els, &self.direct, &self.environment);
        self.initial = self.state.unshot_power(&self.els);
        self.report.shots.clear();
        Ok(())
    }
    fn iterate_batch(
        &mut self,
        _: &Prepared,
        _: Scheme,
        _: usize,
        n: usize,
    ) -> Result<Vec<Figures>> {
        let t = Instant::now();
        let mut figures = Vec::with_capacity(n);
        for _ in 0..n {
            for _ in 0..self.shots_per_iteration {
                match self.shoot() {
                    Some(s) => self.report.shots.push(s),
                    None => break,
                }
            }
            let unshot = self.state.unshot_power(&self.els);
            let peak = (0..self.els.len())
                .map(|i| self.state.radiosity(&self.els, i).max_element())
                .fold(0.0, f64::max);
            figures.push(Figures {
                change: Change {
                    relative: if self.initial > 0.0 {
                        unshot / self.initial
                    } else {
                        0.0
                    },
                    absolute: unshot,
                },
                flux: self.state.flux(&self.els),
                peak,
            });
        }
        self.timings.push(("shoot".into(), ms(t)));
        Ok(figures)
    }
    fn i_ex(&mut self) -> Result<Table> {
        Ok(self.shape.exitant(&self.els, &self.state))
    }
    fn i_total(&mut self) -> Result<Table> {
        Ok(self.shape.display(&self.els, &self.state.gathered))
    }
    fn method_report(&self) -> Option<MethodReport> {
        let mut r = self.report.clone();
        r.figures
            .insert("shots".into(), self.report.shots.len() as f64);
        Some(r)
    }
}

impl Draw for CpuShooting {
    fn draw(&mut self, prep: &Prepared) -> Result<Image> {
        let t = Instant::now();
        let table = self.shape.display(&self.els, &self.state.gathered);
        let image = prep.render_cpu(&table, &self.caster);
        self.timings.push(("frame".into(), ms(t)));
        Ok(image)
    }
}

impl Backend for CpuShooting {
    fn kind(&self) -> BackendKind {
        BackendKind::Cpu
    }
    fn take_timings(&mut self) -> Vec<(String, f64)> {
        std::mem::take(&mut self.timings)
    }
    fn fallbacks(&self) -> Vec<String> {
        self.notes.clone()
    }
}
