//! The prepared scene: everything the CPU builds before a backend runs — the effective settings
//! and camera, the discrete system (elements, hierarchy, links), the screen surfaces, the plan
//! and the shadow-map views. `info` stops here; an [`crate::engine::Engine`] adds a backend.

use super::options::{Options, Resolved, DEFAULT_MAX_LINKS};
use crate::error::{Error, Result};
use crate::frame::emitters;
use crate::frame::shadow::{ShadowMaps, MAX_ATLAS};
use crate::frame::surfaces::Surfaces;
use crate::gpu::resources::ResourcePlan;
use crate::meshed::Meshed;
use crate::plan::target::TargetChoice;
use crate::plan::Plan;
use crate::progress::Progress;
use crate::raycast::RayCaster;
use crate::scene::{Camera, Light, Scene, SolverSettings};
use crate::settings::Method;
use crate::solver::Table;
use crate::system::System;
use std::sync::Arc;
use std::time::Instant;

/// A scene prepared for solving.
#[derive(Clone)]
pub struct Prepared {
    /// The engine's copy of the scene (lights and objects may change between frames).
    pub scene: Scene,
    /// The lights that shine: the scene's analytic lights and the samples of its area
    /// emitters ([`crate::frame::emitters`]).
    pub lights: Vec<Light>,
    /// The lights whose direct light the frame evaluates once per pixel where its 2×2 samples
    /// lie on one flat surface (`frame::cpu::shared_direct`): the area emitters' samples, not
    /// instant radiosity's VPLs appended after them; empty with `solver.direct_per_sample`.
    pub shared_lights: std::ops::Range<usize>,
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
    /// The environment's shadowed incident radiance and the radiance it was cast for
    /// ([`Self::sky`]): kept where only lights move ([`Self::relit`]), cast anew where the
    /// geometry does.
    sky: Option<(glam::DVec3, Arc<Table>)>,
}

impl Prepared {
    /// The CPU frame (`frame::cpu::render`) of this prepared scene from the display table
    /// `i_total`, ray cast with `caster`: what every CPU backend draws.
    pub fn render_cpu(
        &self,
        i_total: &crate::solver::Table,
        caster: &crate::raycast::RayCaster,
    ) -> crate::frame::Image {
        self.render_cpu_with(i_total, caster, None)
    }

    /// [`Self::render_cpu`] with the indirect light of `store` where one is given.
    pub fn render_cpu_with(
        &self,
        i_total: &crate::solver::Table,
        caster: &crate::raycast::RayCaster,
        store: Option<&dyn crate::frame::cpu::SampleIndirect>,
    ) -> crate::frame::Image {
        let lit = crate::frame::lights::LightSet {
            lights: &self.lights,
            maps: &self.maps,
            shared: self.shared_lights.clone(),
        };
        crate::frame::cpu::render(
            &self.scene,
            &lit,
            &self.camera,
            &self.system,
            i_total,
            &self.surfaces,
            caster,
            store,
        )
    }

    /// Resolves `options` against `scene`, discretizes and links it (refusing before linking
    /// when the tables would not fit a device's `device_memory` bytes), and plans the passes.
    pub fn new(
        scene: &Scene,
        options: &Options,
        device_memory: Option<u64>,
        progress: &dyn Progress,
    ) -> Result<Self> {
        let Resolved {
            mut settings,
            camera,
            target,
        } = options.resolve(scene)?;
        let memory = match (options.memory_budget, device_memory) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        let max_links = options.max_links.unwrap_or(DEFAULT_MAX_LINKS);
        progress.begin("linking", 1);
        let fit = fit_system(
            scene,
            &mut settings,
            memory,
            max_links,
            options.method.uses_links(),
        );
        progress.end();
        let (system, fitted) = fit?;
        let surfaces = Surfaces::new(scene, &system);
        let mut prep = Self::lit(scene, options, settings, camera, target, system, surfaces)?;
        prep.plan.decisions.extend(fitted);
        Ok(prep)
    }

    /// This prepared scene with `scene`'s lights, where only lights changed (its geometry is
    /// this one's): the system, links and surfaces are kept, the lights, plan and shadow-map
    /// views made anew.
    pub fn relit(&self, scene: &Scene, options: &Options) -> Result<Self> {
        let mut p = Self::lit(
            scene,
            options,
            self.settings.clone(),
            self.camera.clone(),
            self.target.clone(),
            self.system.clone(),
            self.surfaces.clone(),
        )?;
        // The same geometry: the sky's rays would meet what they met.
        p.sky = self.sky.clone();
        Ok(p)
    }

    /// This prepared scene with its objects where `scene` has them, along its bounded link
    /// mesh ([`crate::System::follow`]: the elements, moving nodes and the links touching them
    /// recomputed, nothing relinked), the surfaces, lights, plan and shadow-map views made
    /// anew. `None` where the system has no bound or `scene` is not its scene moved rigidly.
    pub fn moved(&self, scene: &Scene, options: &Options) -> Result<Option<Self>> {
        let mut system = self.system.clone();
        if !system.follow(scene, &self.settings)? {
            return Ok(None);
        }
        let surfaces = Surfaces::new(scene, &system);
        Self::lit(
            scene,
            options,
            self.settings.clone(),
            self.camera.clone(),
            self.target.clone(),
            system,
            surfaces,
        )
        .map(Some)
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
        let vpl_method = matches!(
            options.method,
            Method::InstantRadiosity | Method::ImageBasedRadiosity
        );
        let emitter_choice = if vpl_method {
            // Instant radiosity has no bins to take emission: its emitters are always sampled.
            if settings.emitter_samples == Some(0) {
                return Err(Error::Invalid(format!(
                    "{} needs emitter samples (solver.emitter_samples = 0 sends \
                     emission through the bins, which this method does not have)",
                    options.method
                )));
            }
            emitters::choose(
                scene,
                Some(
                    settings
                        .emitter_samples
                        .unwrap_or(emitters::DEFAULT_SAMPLES),
                ),
            )
        } else if options.method.samples_emitters() {
            emitters::choose(scene, settings.emitter_samples)
        } else {
            emitters::Choice {
                samples: 0,
                reason: format!("{}: area emitters shoot (no samples)", options.method),
            }
        };
        let first_sample = lights.len();
        lights.extend(emitters::sample(scene, emitter_choice.samples));
        let shared_lights = if settings.direct_per_sample {
            0..0
        } else {
            first_sample..lights.len()
        };
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
        plan.decisions.extend(crate::system::receivers::decision(
            &system, scene, &settings,
        ));
        if let Some(t) = settings.tolerance {
            plan.decisions.push(format!(
                "iterations: until the estimated error (distance to the discrete fixed point) is below {t:.0e}, at most {}",
                settings.max_iterations
            ));
        }
        let (maps, fallbacks) = fit_shadow_maps(scene, &lights, map_sizes(options), usize::MAX)?;
        Ok(Self {
            scene: scene.clone(),
            lights,
            shared_lights,
            settings,
            camera,
            target,
            system,
            surfaces,
            plan,
            maps,
            fallbacks,
            sky: None,
        })
    }

    /// The sky [`Self::sky`] has cast for this geometry, if it has.
    pub fn sky_cast(&self) -> Option<&Arc<Table>> {
        self.sky.as_ref().map(|(_, t)| t)
    }

    /// The constant environment's incident radiance per leaf and bin, shadowed by rays
    /// ([`crate::frame::environment::environment_in_table`]), or `None` without one. Cast once
    /// for this geometry and environment (with `caster` where the caller has one, else a new
    /// one), then shared: a moved light or a copy of this prepared scene does not cast again
    /// (the breakfast room's sky is 5 s of rays).
    pub fn sky(&mut self, caster: Option<&RayCaster>) -> Option<Arc<Table>> {
        let env = self.scene.environment;
        if env == glam::DVec3::ZERO {
            return None;
        }
        if let Some((e, t)) = &self.sky {
            if *e == env {
                return Some(t.clone());
            }
        }
        let owned;
        let caster = match caster {
            Some(c) => c,
            None => {
                owned = RayCaster::new(&self.system);
                &owned
            }
        };
        let t =
            Arc::new(crate::frame::environment::environment_in_table(&self.system, env, caster).0);
        self.sky = Some((env, t.clone()));
        Some(t)
    }

    /// Re-plans and re-fits the shadow maps after a method added lights (instant radiosity's
    /// VPLs, from `lights[first_vpl..]`); earlier decisions are kept after the new plan's.
    pub fn relight(&mut self, options: &Options, first_vpl: usize) -> Result<()> {
        let all_passes = options.all_passes;
        let old = std::mem::take(&mut self.plan.decisions);
        self.plan = Plan::new(
            &self.scene,
            &self.lights,
            &self.system,
            &self.surfaces,
            self.settings.precision,
            all_passes,
        );
        for d in old {
            if !self.plan.decisions.contains(&d) {
                self.plan.decisions.push(d);
            }
        }
        let (maps, fallbacks) =
            fit_shadow_maps(&self.scene, &self.lights, map_sizes(options), first_vpl)?;
        self.maps = maps;
        self.fallbacks.extend(fallbacks);
        Ok(())
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

/// How much coarser each refinement step makes the discretization: the oracle's τ doubles up to
/// [`MAX_ORACLE_STEPS`] times its given value, then the element size grows by this factor.
pub const COARSEN_SIZE: f64 = 1.5;
/// Doublings of τ before the element size grows.
pub const MAX_ORACLE_STEPS: u32 = 4;

/// Discretizes and links `scene` at `settings`, coarsened until the links fit `max_links` and
/// the tables fit `memory` bytes (`None`: no limit): τ doubles (at most [`MAX_ORACLE_STEPS`]
/// times; as many at once as the sampled count asks for), then the element size grows by [`COARSEN_SIZE`]; `settings` ends as used. Returns the
/// system and one decision per coarsening (empty when the given settings fit). Refused only
/// when even an element size of the scene's diagonal does not fit.
pub fn fit_system(
    scene: &Scene,
    settings: &mut SolverSettings,
    memory: Option<u64>,
    max_links: u64,
    link: bool,
) -> Result<(System, Vec<String>)> {
    let (oracle0, size0) = (settings.oracle, settings.element_size);
    let (lo, hi) = scene.bounds();
    let diagonal = (hi - lo).length();
    let mut doublings = 0;
    let mut reasons: Vec<&'static str> = Vec::new();
    let (mut tries, mut tries_ms) = (0u32, 0.0f64);
    // Meshed once per element size: the tries at larger τ link the same elements.
    let mut meshed: Option<Meshed> = None;
    loop {
        let precision = settings.precision;
        let budget = |rows: u64, bins: usize| -> Result<()> {
            let Some(limit) = memory else {
                return Ok(());
            };
            let needed = ResourcePlan::worst_table_bytes(
                rows.min(u32::MAX as u64) as u32,
                bins as u32,
                precision,
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
        let coarser_size = settings.element_size * COARSEN_SIZE;
        let m = match meshed.take() {
            Some(m) if m.element_size == settings.element_size => m,
            old => {
                // A meshing for a size that did not fit is part of the fitting's cost.
                tries_ms += old.map_or(0.0, |o| o.meshing_ms);
                Meshed::new(scene, settings, link)?
            }
        };
        let t = Instant::now();
        let result = System::link_meshed(scene, &m, settings, &budget, link, max_links);
        let failed = match result {
            Ok(linked) => {
                let mut sys = System::from_stages(scene, settings, m, linked);
                // The tries that did not fit are part of what linking this scene cost.
                sys.links.linking_ms += tries_ms;
                let mut said = Vec::new();
                if settings.oracle != oracle0 || settings.element_size != size0 {
                    said.push(format!(
                        "refinement coarsened to fit {}: τ {oracle0} → {}, element size {size0:.4} → {:.4} ({} elements, {} links; {tries} tries that did not fit took {:.1} s, counted in the linking time); coarser links blur indirect light: on the Cornell box τ 1 → 4 → 16 moves the error against the path tracer from 0.087 to 0.093 to 0.104 (docs/measurements.md)",
                        reasons.join(" and "),
                        settings.oracle,
                        settings.element_size,
                        sys.elements.len(),
                        sys.links.len(),
                        tries_ms / 1e3
                    ));
                }
                return Ok((sys, said));
            }
            Err(e @ Error::LinkBudget { .. }) => {
                if !reasons.contains(&"the link budget") {
                    reasons.push("the link budget");
                }
                meshed = Some(m);
                e
            }
            Err(e @ Error::TooLarge { .. }) => {
                if !reasons.contains(&"the memory budget") {
                    reasons.push("the memory budget");
                }
                meshed = Some(m);
                e
            }
            Err(e) => return Err(e),
        };
        tries += 1;
        tries_ms += t.elapsed().as_secs_f64() * 1e3;
        if let Error::LinkBudget { estimate, .. } = failed {
            if doublings < MAX_ORACLE_STEPS {
                // Links fall about as 1/τ (Cornell box τ 1 → 16: 699K → 39K links, exponent
                // 1.04): jump straight to the doubling the estimate asks for.
                let wanted = (estimate / max_links as f64).log2().ceil().max(1.0) as u32;
                let k = wanted.min(MAX_ORACLE_STEPS - doublings);
                settings.oracle *= f64::from(1u32 << k);
                doublings += k;
                continue;
            }
        }
        if coarser_size <= diagonal {
            settings.element_size = coarser_size;
        } else {
            return Err(Error::Setting {
                field: "element_size",
                message: format!(
                    "the scene does not fit even at its coarsest settings (τ {}, element size {:.4}, the scene's diagonal): {failed}",
                    settings.oracle, settings.element_size
                ),
            });
        }
    }
}

/// The sides `options` asks of the analytic lights' maps and of the emitter samples'.
fn map_sizes(options: &Options) -> (u32, u32) {
    (options.shadow_map_size, options.emitter_map_size)
}

/// Every light's shadow-map views in one atlas of at most [`MAX_ATLAS`]² texels: analytic
/// lights' maps at `sizes.0`², emitter samples' at `sizes.1`² (`--emitter-map-size`, default
/// [`emitters::SAMPLE_MAP_SIZE`]), VPLs (lights from `first_vpl` on) at
/// [`super::method::VPL_MAP_SIZE`]²; all halved together until they fit, each halving a
/// fallback sentence.
pub fn fit_shadow_maps(
    scene: &Scene,
    lights: &[Light],
    sizes: (u32, u32),
    first_vpl: usize,
) -> Result<(ShadowMaps, Vec<String>)> {
    let mut fallbacks = Vec::new();
    let (mut size, mut sample, mut vpl) = (sizes.0, sizes.1, super::method::VPL_MAP_SIZE);
    loop {
        let sides: Vec<u32> = lights
            .iter()
            .enumerate()
            .map(|(i, l)| match l {
                _ if i >= first_vpl => vpl,
                Light::EmitterSample { .. } => sample,
                _ => size,
            })
            .collect();
        if let Some(m) = ShadowMaps::with_sides(scene, lights, size, &sides) {
            return Ok((m, fallbacks));
        }
        if size <= 16 && sample <= 16 && vpl <= 16 {
            return Err(Error::Invalid(format!(
                "{} lights' shadow maps do not fit a {MAX_ATLAS}² atlas even at 16² texels each",
                lights.len()
            )));
        }
        (size, sample, vpl) = ((size / 2).max(16), (sample / 2).max(16), (vpl / 2).max(16));
        fallbacks.push(format!(
            "the shadow maps do not fit a {MAX_ATLAS}² atlas at {}² texels each; using {size}² ({sample}² for emitter samples, {vpl}² for VPLs)",
            size * 2
        ));
    }
}
