//! The two backends as the iteration loop ([`super::drive`]) sees them: the f64 CPU solver with a
//! ray-cast frame, and the GPU solver with its raster frame.

use super::drive::Iterative;
use crate::error::Result;
use crate::frame::cpu;
use crate::frame::shadow::ShadowMaps;
use crate::frame::surfaces::Surfaces;
use crate::frame::Image;
use crate::gpu::frame::GpuFrame;
use crate::gpu::{GpuOptions, GpuSolver};
use crate::raycast::RayCaster;
use crate::scene::{Precision, Scene, Scheme};
use crate::solver::Table;
use crate::system::System;
use crate::CpuSolver;
use std::collections::BTreeMap;
use std::time::Instant;

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// The f64 solver and the ray-cast frame.
pub(crate) struct Cpu<'a> {
    pub solver: CpuSolver<'a>,
    pub scene: &'a Scene,
    pub maps: &'a ShadowMaps,
    pub surfaces: &'a Surfaces,
    pub caster: &'a RayCaster,
    pub solve_ms: f64,
    pub frame_ms: f64,
}

impl Iterative for Cpu<'_> {
    fn initialize(&mut self) -> Result<()> {
        let t = Instant::now();
        self.solver.initialize();
        self.solve_ms += ms(t);
        Ok(())
    }
    fn iterate(&mut self, scheme: Scheme, steps: usize) -> Result<()> {
        let t = Instant::now();
        self.solver.iterate(scheme, steps);
        self.solve_ms += ms(t);
        Ok(())
    }
    fn i_ex(&mut self) -> Result<Table> {
        Ok(self.solver.i_ex.clone())
    }
    fn overflow_limit(&self) -> f64 {
        f64::MAX
    }
    fn widen(&mut self) -> Result<Option<String>> {
        Ok(None)
    }
    fn draw(&mut self) -> Result<Image> {
        let t = Instant::now();
        let s = &self.solver;
        let image = cpu::render(
            self.scene,
            s.sys,
            &s.i_total,
            self.maps,
            self.surfaces,
            self.caster,
        );
        self.frame_ms += ms(t);
        Ok(image)
    }
    fn timings(&mut self, passes: &mut BTreeMap<String, f64>) {
        *passes.entry("solve".into()).or_insert(0.0) += std::mem::take(&mut self.solve_ms);
        *passes.entry("frame".into()).or_insert(0.0) += std::mem::take(&mut self.frame_ms);
    }
}

/// The GPU solver and frame; keeps what a restart in float32 needs.
pub(crate) struct Gpu<'a> {
    pub solver: GpuSolver,
    pub frame: GpuFrame,
    pub sys: &'a System,
    pub scene: &'a Scene,
    pub direct: Option<Table>,
    pub pending: Vec<(String, f64)>,
}

impl Gpu<'_> {
    fn collect(&mut self, timings: Vec<(String, f64)>) {
        self.pending.extend(timings);
    }
}

impl Iterative for Gpu<'_> {
    fn initialize(&mut self) -> Result<()> {
        self.solver.initialize()?;
        self.collect(self.solver.timings().to_vec());
        Ok(())
    }
    fn iterate(&mut self, scheme: Scheme, steps: usize) -> Result<()> {
        self.solver.iterate(scheme, steps)?;
        self.collect(self.solver.timings().to_vec());
        Ok(())
    }
    fn i_ex(&mut self) -> Result<Table> {
        self.solver.read_i_ex()
    }
    fn overflow_limit(&self) -> f64 {
        self.solver.overflow_limit()
    }
    fn widen(&mut self) -> Result<Option<String>> {
        if self.solver.precision() == Precision::F32 {
            return Ok(None);
        }
        let mut wide = GpuSolver::new(
            self.solver.context().clone(),
            self.sys,
            GpuOptions {
                precision: Precision::F32,
                features: Some(*self.solver.features()),
                ..Default::default()
            },
        )?;
        wide.set_environment(self.scene.environment)?;
        if let Some(d) = &self.direct {
            wide.set_direct(d)?;
        }
        self.solver = wide;
        Ok(Some("tables switched to float32".into()))
    }
    fn draw(&mut self) -> Result<Image> {
        let image = self.frame.render(&mut self.solver)?;
        self.collect(self.frame.timings().to_vec());
        Ok(image)
    }
    fn timings(&mut self, passes: &mut BTreeMap<String, f64>) {
        for (k, v) in self.pending.drain(..) {
            *passes.entry(k).or_insert(0.0) += v;
        }
    }
}
