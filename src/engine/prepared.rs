//! The prepared scene: everything the CPU builds before a backend runs — the effective settings
//! and camera, the discrete system (elements, hierarchy, links), the screen surfaces, the plan
//! and the shadow-map views. `info` stops here; an [`super::Engine`] adds a backend.

use super::options::{Options, Resolved};
use crate::error::{Error, Result};
use crate::frame::emitters;
use crate::frame::shadow::{ShadowMaps, MAX_ATLAS};
use crate::frame::surfaces::Surfaces;
use crate::gpu::resources::ResourcePlan;
use crate::plan::target::TargetChoice;
use crate::plan::Plan;
use crate::progress::Progress;
use crate::scene::{Camera, Light, Scene, SolverSettings};
use crate::system::System;

/// A scene prepared for solving.
#[derive(Clone)]
pub struct Prepared {
    /// The engine's copy of the scene (lights and objects may change between frames).
    pub scene: Scene,
    /// The lights that shine: the scene's analytic lights and the samples of its area
    /// emitters ([`crate::frame::emitters`]).
    pub lights: Vec<Light>,
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
        Self::lit(scene, options, settings, camera, target, system, surfaces)
    }

    /// This prepared scene with `scene`'s lights, where only lights changed (its geometry is
    /// this one's): the system, links and surfaces are kept, the lights, plan and shadow-map
    /// views made anew.
    pub fn relit(&self, scene: &Scene, options: &Options) -> Result<Self> {
        Self::lit(
            scene,
            options,
            self.settings.clone(),
            self.camera.clone(),
            self.target.clone(),
            self.system.clone(),
            self.surfaces.clone(),
        )
    }

    /// The lights (analytic and emitter samples), the plan and the shadow-map views of a
    /// discretized scene.
    fn lit(
        scene: &Scene,
        options: &Options,
        settings: SolverSettings,
        camera: Camera,
        target: Option<TargetChoice>,
        system: System,
        surfaces: Surfaces,
    ) -> Result<Self> {
        // The analytic lights, then the area emitters' samples (§3.3).
        let mut lights = scene.lights.clone();
        let emitter_choice = if options.method.samples_emitters() {
            emitters::choose(scene, settings.emitter_samples)
        } else {
            emitters::Choice {
                samples: 0,
                reason: format!("{}: area emitters shoot (no samples)", options.method),
            }
        };
        lights.extend(emitters::sample(scene, emitter_choice.samples));
        let mut plan = Plan::new(
            scene,
            &lights,
            &system,
            &surfaces,
            settings.precision,
            options.all_passes,
        );
        if emitter_choice.samples > 0
            || settings.emitter_samples.is_some()
            || !options.method.samples_emitters()
        {
            plan.decisions.push(emitter_choice.reason);
        }
        let mut fallbacks = Vec::new();
        // All views share one atlas of at most 16384² texels; halve the maps until they fit.
        let (mut size, mut sample_size) = (options.shadow_map_size, emitters::SAMPLE_MAP_SIZE);
        let maps = loop {
            if let Some(m) = ShadowMaps::new(scene, &lights, size, sample_size) {
                break m;
            }
            if size <= 16 && sample_size <= 16 {
                return Err(Error::Invalid(format!(
                    "{} lights' shadow maps do not fit a {MAX_ATLAS}² atlas even at 16² texels each",
                    lights.len()
                )));
            }
            (size, sample_size) = ((size / 2).max(16), (sample_size / 2).max(16));
            fallbacks.push(format!(
                "the shadow maps do not fit a {MAX_ATLAS}² atlas at {}² texels each; using {size}² ({sample_size}² for emitter samples)",
                size * 2
            ));
        };
        Ok(Self {
            scene: scene.clone(),
            lights,
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
            ..Plan::everything(&self.scene, &self.lights, &self.system, &self.surfaces)
        };
        p
    }
}
