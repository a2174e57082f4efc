//! The prepared scene: everything the CPU builds before a backend runs — the effective settings
//! and camera, the discrete system (elements, hierarchy, links), the screen surfaces, the plan
//! and the shadow-map views. `info` stops here; an [`super::Engine`] adds a backend.

use super::options::{Options, Resolved};
use crate::error::{Error, Result};
use crate::frame::shadow::ShadowMaps;
use crate::frame::surfaces::Surfaces;
use crate::gpu::resources::ResourcePlan;
use crate::plan::target::TargetChoice;
use crate::plan::Plan;
use crate::progress::Progress;
use crate::scene::{Camera, Scene, SolverSettings};
use crate::system::System;

/// Rows of the stacked shadow-map image (maxImageDimension2D of lavapipe and most GPUs).
pub const MAX_SHADOW_ROWS: u32 = 16384;

/// A scene prepared for solving.
#[derive(Clone)]
pub struct Prepared {
    /// The engine's copy of the scene (lights and objects may change between frames).
    pub scene: Scene,
    /// Effective solver settings (the scene's with the options applied).
    pub settings: SolverSettings,
    /// Effective camera.
    pub camera: Camera,
    /// The setting `--target-error` chose, if given.
    pub target: Option<TargetChoice>,
    /// Elements, hierarchy, bins, links.
    pub system: System,
    /// Screen-space data of the leaves (splat / vertex interpolation).
    pub surfaces: Surfaces,
    /// Which passes run, at which precision.
    pub plan: Plan,
    /// Shadow-map views of the lights (their texels are filled by a backend).
    pub maps: ShadowMaps,
    /// Departures from the requested configuration made while preparing.
    pub fallbacks: Vec<String>,
}

impl Prepared {
    /// Resolves `options` against `scene`, discretizes and links it (refusing before linking
    /// when the tables would not fit a device's `device_memory` bytes), and plans the passes.
    pub fn new(
        scene: &Scene,
        options: &Options,
        device_memory: Option<u64>,
        progress: &dyn Progress,
    ) -> Result<Self> {
        let Resolved {
            settings,
            camera,
            target,
        } = options.resolve(scene)?;
        progress.begin("linking", 1);
        let budget = |rows: u64, bins: usize| -> Result<()> {
            let Some(limit) = device_memory else {
                return Ok(());
            };
            let needed = ResourcePlan::worst_table_bytes(
                rows.min(u32::MAX as u64) as u32,
                bins as u32,
                settings.precision,
            )?;
            if needed > limit {
                return Err(Error::TooLarge {
                    what: format!(
                        "GPU tables for {rows} nodes × {bins} bins (solver.element_size, solver.bins)"
                    ),
                    needed_bytes: needed,
                    limit_bytes: limit,
                });
            }
            Ok(())
        };
        let system = System::build_linked(scene, &settings, &budget, options.method.uses_links());
        progress.end();
        let system = system?;
        let surfaces = Surfaces::new(scene, &system);
        let plan = Plan::new(
            scene,
            &system,
            &surfaces,
            settings.precision,
            options.all_passes,
        );
        let mut maps = ShadowMaps::new(scene, options.shadow_map_size);
        let mut fallbacks = Vec::new();
        // All views share one image of side × (side · views) texels; keep it within 16384 rows.
        let views = maps.views.len().max(1) as u32;
        if options.shadow_map_size * views > MAX_SHADOW_ROWS {
            let size = MAX_SHADOW_ROWS / views;
            fallbacks.push(format!(
                "{views} shadow-map views do not fit {} texels each; using {size}",
                options.shadow_map_size
            ));
            maps = ShadowMaps::new(scene, size);
        }
        Ok(Self {
            scene: scene.clone(),
            settings,
            camera,
            target,
            system,
            surfaces,
            plan,
            maps,
            fallbacks,
        })
    }

    /// The same prepared scene with every pass on at the plan's table precision (what
    /// `profile` times the plan against).
    pub fn with_every_pass(&self) -> Self {
        let mut p = self.clone();
        p.plan = Plan {
            precision: self.plan.precision,
            ..Plan::everything(&self.scene, &self.system, &self.surfaces)
        };
        p
    }
}
