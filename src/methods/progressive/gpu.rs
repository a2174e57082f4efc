//! Progressive refinement on the GPU: the shots of [`super::shooter`] (selection, hemicube item
//! buffer, gather), an iteration being a fixed number of shots in one submission; and the raster
//! frame of the antiradiance GPU backend, drawing a display table made from the gathered
//! irradiance (read back, 16 bytes per element, and uploaded as I_total of a link-less
//! [`GpuSolver`], which holds the table image and the source scale the frame reads).

use super::shooter::Shooter;
use super::{
    direct_irradiance, environment_irradiance, shots_per_iteration, surface_offset, Elements,
    State, TableShape,
};
use crate::backend::{Backend, Draw, Prepared, Solve};
use crate::error::Result;
use crate::frame::lights::direct_in_table;
use crate::frame::Image;
use crate::gpu::frame::{FrameScene, GpuFrame};
use crate::gpu::memory::{MemoryReport, Purpose};
use crate::gpu::{Context, GpuOptions, GpuSolver};
use crate::methods::{MethodReport, MethodSettings, Shot};
use crate::plan::Features;
use crate::raycast::RayCaster;
use crate::scene::{Precision, Scheme};
use crate::settings::BackendKind;
use crate::solver::convergence::{Change, Figures};
use crate::solver::Table;
use glam::DVec3;
use std::sync::Arc;
use std::time::Instant;

/// Progressive refinement with a hemicube item buffer, and the raster frame.
pub struct GpuShooting {
    ctx: Arc<Context>,
    shooter: Shooter,
    display: GpuSolver,
    frame: GpuFrame,
    els: Elements,
    shape: TableShape,
    direct: Vec<DVec3>,
    environment: Vec<DVec3>,
    initial: f64,
    shots_per_iteration: usize,
    report: MethodReport,
    pending: Vec<(String, f64)>,
    notes: Vec<String>,
}

impl GpuShooting {
    /// The shooter's buffers and pipelines, the display table and the frame for `prep`.
    pub fn new(ctx: Arc<Context>, prep: &Prepared, settings: &MethodSettings) -> Result<Self> {
        let sys = &prep.system;
        let els = Elements::new(sys);
        let eps = surface_offset(sys);
        let t = Instant::now();
        let (environment, rays) = if prep.scene.environment == DVec3::ZERO {
            (vec![DVec3::ZERO; els.len()], 0)
        } else {
            let caster = RayCaster::new(sys);
            environment_irradiance(&els, &caster, prep.scene.environment, eps)
        };
        let mut report = MethodReport {
            setup_ms: t.elapsed().as_secs_f64() * 1e3,
            rays,
            ..Default::default()
        };
        let spi = shots_per_iteration(settings, els.len());
        for (k, v) in [
            ("hemicube", settings.hemicube as f64),
            ("subdivision", settings.subdivision as f64),
            ("gradient", settings.gradient),
            ("shots_per_iteration", spi as f64),
        ] {
            report.figures.insert(k.into(), v);
        }
        let shooter = Shooter::new(&ctx, &els, settings, eps, spi + 1)?;
        // The display table only: no sources, no antiradiance (its passes never run).
        let features = Features {
            antiradiance: false,
            direct: false,
            environment: false,
            emission: false,
            ..prep.plan.features
        };
        let display = GpuSolver::new(
            ctx.clone(),
            sys,
            GpuOptions {
                precision: prep.plan.precision,
                features: Some(features),
                ..Default::default()
            },
        )?;
        let mut frame = GpuFrame::new(
            ctx.clone(),
            &FrameScene {
                sys,
                ..crate::methods::antiradiance::gpu::frame_scene(prep)
            },
        )?;
        frame.bind_solver(&display);
        let direct = vec![DVec3::ZERO; els.len()];
        let state = State::initial(&els, &direct, &environment);
        Ok(Self {
            ctx,
            shooter,
            display,
            frame,
            initial: state.unshot_power(&els),
            shape: TableShape::of(sys),
            els,
            direct,
            environment,
            shots_per_iteration: spi,
            report,
            pending: Vec::new(),
            notes: Elements::glossy_note(sys).into_iter().collect(),
        })
    }

    fn display_table(&mut self) -> Result<Table> {
        let gathered = self.shooter.gathered()?;
        Ok(self.shape.display(&self.els, &gathered))
    }
}

impl Solve for GpuShooting {
    fn prepare_lights(&mut self, prep: &mut Prepared) -> Result<()> {
        self.direct = vec![DVec3::ZERO; self.els.len()];
        if !prep.maps.views.is_empty() {
            self.frame.render_shadow_maps()?;
            self.pending.extend(self.frame.timings().iter().cloned());
            prep.maps.data = self.frame.read_shadow_maps()?;
            let table = direct_in_table(&prep.system, &prep.scene.lights, &prep.maps);
            self.direct = direct_irradiance(&prep.system, &table);
        }
        Ok(())
    }
    fn initialize(&mut self, _: &Prepared) -> Result<()> {
        let state = State::initial(&self.els, &self.direct, &self.environment);
        self.initial = state.unshot_power(&self.els);
        self.shooter.upload(&state)?;
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
        let mut figures = Vec::with_capacity(n);
        for _ in 0..n {
            let (slots, timings) = self.shooter.shoot(self.shots_per_iteration)?;
            self.pending.extend(timings);
            let (last, shots) = slots.split_last().expect("one slot after the shots");
            self.report.shots.extend(shots.iter().filter_map(|s| {
                s.shooter.map(|i| Shot {
                    shooter: i,
                    unshot: s.unshot,
                    power: s.power,
                })
            }));
            figures.push(Figures {
                change: Change {
                    relative: if self.initial > 0.0 {
                        last.unshot / self.initial
                    } else {
                        0.0
                    },
                    absolute: last.unshot,
                },
                flux: last.flux,
                peak: 0.0,
            });
        }
        Ok(figures)
    }
    fn i_ex(&mut self) -> Result<Table> {
        let gathered = self.shooter.gathered()?;
        let state = State {
            gathered,
            unshot: vec![DVec3::ZERO; self.els.len()],
            base: State::initial(&self.els, &self.direct, &self.environment).base,
        };
        Ok(self.shape.exitant(&self.els, &state))
    }
    fn i_total(&mut self) -> Result<Table> {
        self.display_table()
    }
    fn precision(&self) -> Precision {
        Precision::F32
    }
    fn method_report(&self) -> Option<MethodReport> {
        let mut r = self.report.clone();
        r.figures
            .insert("shots".into(), self.report.shots.len() as f64);
        Some(r)
    }
}

impl Draw for GpuShooting {
    fn draw(&mut self, _: &Prepared) -> Result<Image> {
        let t = Instant::now();
        let table = self.display_table()?;
        self.display.upload_i_total(&table)?;
        self.pending
            .push(("display".into(), t.elapsed().as_secs_f64() * 1e3));
        let image = self.frame.render(&mut self.display)?;
        self.pending.extend(self.frame.timings().iter().cloned());
        Ok(image)
    }
    fn set_camera(&mut self, prep: &Prepared) -> Result<()> {
        crate::methods::antiradiance::gpu::take_camera(&mut self.frame, prep)
    }
}

impl Backend for GpuShooting {
    fn kind(&self) -> BackendKind {
        BackendKind::Gpu
    }
    fn device(&self) -> String {
        self.ctx.info.name.clone()
    }
    fn take_timings(&mut self) -> Vec<(String, f64)> {
        std::mem::take(&mut self.pending)
    }
    fn fallbacks(&self) -> Vec<String> {
        self.notes.clone()
    }
    fn memory(&self) -> MemoryReport {
        let mut m = self.display.memory();
        m.add(Purpose::Tables, self.shooter.bytes());
        m
    }
}
