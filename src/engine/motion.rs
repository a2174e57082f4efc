//! Moving objects and lights between frames (§3.3): [`Engine::set_time`],
//! [`Engine::set_light`] and [`Engine::set_object_transform`] say where things stand;
//! [`Engine::update`] makes the engine follow, and the next iterations continue from the
//! previous frame's solution (warm start).
//!
//! - **Only lights moved**: the elements and links are kept; the lights, plan and shadow-map
//!   views are made anew, the backend keeps its tables and solution unless the plan's passes or
//!   precision changed; the GPU frame draws again only the shadow views of the lights that
//!   moved.
//! - **Keyframed objects moved along their keyframes** (`set_time`): the **bounded link mesh**
//!   ([`crate::bound`]). The scene was linked once, at preparation, for the worst case over the
//!   whole motion (moving objects are their own subtrees); an update moves the elements and
//!   moving nodes and recomputes the sides, bins, cone class and form factor of only the links
//!   touching a moving node ([`crate::System::follow`]) — nothing is relinked, the nodes and
//!   rows stay, and both backends keep their tables and solution in place. The CPU backend
//!   casts again only the shadow-map rays that pass near a moved object (before or after);
//!   the GPU backend uploads the re-packed link records, the leaves' normals and lobe factors
//!   (recorded into a host's command buffer by [`Engine::record_update`]), writes the frame's
//!   buffers in place and draws again only the shadow views that may see a moved object. The
//!   direct light is recomputed in both.
//! - **Any other object motion** (a pose a host set with `set_object_transform`, which the
//!   bound may not cover; objects marked `moving` without keyframes; a scene without a bound):
//!   a **re-preparation**: the moved scene is discretized and linked again, the backend made
//!   anew, and the previous I_ex carried over leaf by leaf (elements keep their index: a rigid
//!   motion subdivides a mesh the same way) and pulled into the new hierarchy. Keyframed
//!   objects are linked for their motion again, so later `set_time` updates follow the new
//!   bound.

use super::prepared::Prepared;
use super::Engine;
use crate::error::{Error, Result};
use crate::progress::Silent;
use crate::scene::{Light, Scene};
use crate::solver::Table;
use crate::system::System;
use ash::vk;
use glam::DMat4;
use std::time::Instant;

impl Engine {
    /// The scene as the next [`Engine::update`] will prepare it (moves made so far).
    fn next_scene(&mut self) -> &mut Scene {
        if self.next.is_none() {
            self.next = Some(self.prep.scene.clone());
        }
        self.next.as_mut().expect("set above")
    }

    /// Moves every keyframed object and light to scene time `t` (seconds). Records nothing and
    /// computes nothing: [`Engine::update`] does.
    pub fn set_time(&mut self, t: f64) -> Result<()> {
        if !t.is_finite() {
            return Err(Error::Invalid(format!("time must be finite, got {t}")));
        }
        self.next_scene().move_to(t);
        self.time = t;
        Ok(())
    }

    /// The scene time last set ([`Engine::set_time`]; 0 at creation).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Replaces analytic light `index` (a light of the scene file, in its order) for the next
    /// [`Engine::update`]. Area emitters' samples are made by the engine and cannot be set.
    pub fn set_light(&mut self, index: usize, light: Light) -> Result<()> {
        let n = self.prep.scene.lights.len();
        if index >= n {
            return Err(Error::Invalid(format!(
                "light {index} does not exist ({n} analytic lights)"
            )));
        }
        let finite = match &light {
            Light::Directional {
                direction,
                irradiance,
            } => direction.is_normalized() && irradiance.is_finite() && irradiance.min_element() >= 0.0,
            Light::Point {
                position,
                intensity,
            } => position.is_finite() && intensity.is_finite() && intensity.min_element() >= 0.0,
            Light::Spot {
                position,
                axis,
                intensity,
                cutoff,
                beam_width,
            } => {
                position.is_finite()
                    && axis.is_normalized()
                    && intensity.is_finite()
                    && intensity.min_element() >= 0.0
                    && *cutoff > 0.0
                    && *cutoff <= std::f64::consts::PI
                    && (0.0..=*cutoff).contains(beam_width)
            }
            Light::EmitterSample { .. } => {
                return Err(Error::Invalid(
                    "emitter samples are made by the engine from the emitting faces; move the emitting object instead".into(),
                ))
            }
        };
        if !finite {
            return Err(Error::Invalid(format!(
                "light {index}: positions and intensities must be finite and non-negative, directions unit, angles 0 ≤ beam width ≤ cutoff ≤ π: {light:?}"
            )));
        }
        self.next_scene().lights[index] = light;
        Ok(())
    }

    /// Places object `object` (an `[[object]]` of the scene file, in its order, or one a host
    /// registered with [`Scene::add_object`]) at `m` (object-to-world) for the next
    /// [`Engine::update`]. Only objects marked moving (keyframes, `moving = true`) may move.
    pub fn set_object_transform(&mut self, object: usize, m: DMat4) -> Result<()> {
        self.next_scene().set_object_transform(object, m)?;
        self.placed = true;
        Ok(())
    }

    /// Makes the engine follow what moved since the last update (no-op when nothing did):
    /// along the bounded link mesh where keyframed objects moved, else re-preparing the moved
    /// scene (module doc); the shadow maps and direct light are recomputed and the previous
    /// solution carries over as the start of the next iterations. GPU: where the backend is
    /// made anew (relinked, or new passes) its tables are uploaded here and its result image is
    /// a new one: hosts re-read [`super::gpu::GpuBackend::frame`] after an update.
    pub fn update(&mut self) -> Result<()> {
        if self.method != crate::settings::Method::Antiradiance {
            return Err(Error::Invalid(format!(
                "moving objects and lights need the antiradiance method, not {}",
                self.method
            )));
        }
        let Some(scene) = self.next.take() else {
            return Ok(());
        };
        let ms = |t: Instant| t.elapsed().as_secs_f64() * 1e3;
        let t = Instant::now();
        let ctx = super::gpu_of(&mut self.backend).map(|g| g.context().clone());
        let memory = ctx.as_ref().map(|c| c.info.device_local_bytes);
        // Only lights moved: the elements and links stay (no relinking), the solution carries
        // over row for row.
        let still = scene
            .meshes
            .iter()
            .zip(&self.prep.scene.meshes)
            .all(|(a, b)| a.positions == b.positions);
        // Objects moved along their keyframes: the bounded link mesh follows them (nothing
        // relinked, the nodes and rows stay, the solution carries over row for row). A pose a
        // host set may lie outside the bound: prepared anew, as is a scene without a bound.
        let followed = if still || self.placed {
            None
        } else {
            self.prep.moved(&scene, &self.options)?
        };
        let bounded = followed.is_some();
        let mut prep = if still {
            self.prep.relit(&scene, &self.options)?
        } else if let Some(prep) = followed {
            prep
        } else {
            Prepared::new(&scene, &self.options, memory, &Silent)?
        };
        self.relinked = !still && !bounded;
        self.placed = false;
        let prepare_ms = ms(t);
        let t1 = Instant::now();
        // A camera a host set (Engine::set_camera) stays: the re-prepared scene has its own.
        prep.camera = self.prep.camera.clone();
        // A backend that can follow the moved system in place keeps its tables and solution
        // (both backends, along the bound and where only lights moved); the others are made
        // anew for it, from the previous solution read back (and, relinked, mapped leaf by
        // leaf onto the new hierarchy).
        let kept = (bounded || still) && self.backend.follow(&self.prep, &prep)?;
        let warm = if kept {
            None
        } else {
            let old = self.backend.i_ex()?;
            let warm = if self.relinked {
                carry_over(&self.prep.system, &prep.system, &old)
            } else {
                Some(old)
            };
            self.backend = crate::methods::create(&self.options, &mut prep, ctx)?;
            warm
        };
        let backend_ms = ms(t1);
        let t2 = Instant::now();
        let backend = &mut self.backend;
        backend.prepare_lights(&mut prep)?;
        let lights_ms = ms(t2);
        let t3 = Instant::now();
        match &warm {
            _ if kept => backend.keep_solution(&prep)?,
            Some(table) => backend.warm_start(&prep, table)?,
            None => backend.initialize(&prep)?,
        }
        self.prep = prep;
        self.update_times = UpdateTimes {
            prepare_ms,
            backend_ms,
            lights_ms,
            carry_ms: ms(t3),
            total_ms: ms(t),
        };
        self.warm = kept || warm.is_some();
        Ok(())
    }

    /// For hosts recording into their own command buffer: performs [`Engine::update`], and
    /// where the GPU backend follows a move along the bounded link mesh in place, records its
    /// uploads (the changed link records, the leaves' normals and lobe factors) into `cmd`
    /// instead of submitting them; the next [`Engine::record_iterations`] into `cmd` read
    /// them. What the host needs back at once is still submitted here and waited for: the
    /// moved frame geometry and the shadow maps (the leaves' direct light is computed from
    /// them on the host) and the direct-light table. Where the backend is made anew (a pose
    /// outside the bound, new passes), everything is uploaded here. The previous command
    /// buffer that holds engine work must have completed (the library writes its buffers and
    /// descriptor sets here), and `cmd` must not hold engine commands before this one (record
    /// the update first). A new source scale (a light made much brighter) reads the solution
    /// back and uploads it rescaled, here too.
    pub fn record_update(&mut self, cmd: vk::CommandBuffer) -> Result<()> {
        if let Some(g) = super::gpu_of(&mut self.backend) {
            g.record_follow_into(Some(cmd));
        }
        let out = self.update();
        if let Some(g) = super::gpu_of(&mut self.backend) {
            g.record_follow_into(None);
        }
        out
    }

    /// How long the last [`Engine::update`] took, by part (zero before any).
    pub fn update_times(&self) -> UpdateTimes {
        self.update_times
    }

    /// Whether the last [`Engine::update`] discretized and linked the scene again (objects
    /// moved outside a bounded link mesh); false where only lights moved or keyframed objects
    /// moved along their bound, and the links were kept.
    pub fn relinked(&self) -> bool {
        self.relinked
    }

    /// Whether the last [`Engine::update`] continued from the previous solution (false when the
    /// elements changed and it started from the initial state).
    pub fn warm_started(&self) -> bool {
        self.warm
    }
}

/// The parts of one [`Engine::update`], milliseconds.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct UpdateTimes {
    /// Following the bounded link mesh (moving the elements, recomputing the moving links) or
    /// discretizing and linking the moved scene, and planning it.
    pub prepare_ms: f64,
    /// The backend following in place (CPU: its ray caster; GPU: the link records, normals and
    /// lobe factors packed and uploaded or recorded, the frame's buffers written), or, where it
    /// cannot, reading the old solution back and creating the backend's tables, link buffers
    /// and frame anew (allocations, uploads, pipelines from the cache).
    pub backend_ms: f64,
    /// Shadow maps (after a bounded move only rays (CPU) or views (GPU) that may see a moved
    /// object; after a light move only its views on the GPU) and the leaves' direct light.
    pub lights_ms: f64,
    /// Handing the carried-over solution to a backend made anew (GPU: its upload); nearly
    /// nothing where the backend kept it.
    pub carry_ms: f64,
    /// The whole update.
    pub total_ms: f64,
}

/// The previous solution `old` (rows of `before`'s nodes) as rows of `after`'s: each leaf's row
/// moves to the node its element has now, clusters are pulled. `None` when the elements are
/// not the same ones (a different subdivision), where nothing carries over.
pub fn carry_over(before: &System, after: &System, old: &Table) -> Option<Table> {
    let same = before.elements.len() == after.elements.len()
        && before
            .elements
            .iter()
            .zip(&after.elements)
            .all(|(a, b)| a.same_faces(b));
    if !same || old.bins != after.bins.count {
        return None;
    }
    let mut t = Table::zeros(after.rows(), old.bins);
    for (&from, &to) in before
        .hierarchy
        .leaf_of_element
        .iter()
        .zip(&after.hierarchy.leaf_of_element)
    {
        t.row_mut(to as usize)
            .copy_from_slice(old.row(from as usize));
    }
    crate::solver::pull::pull(&after.hierarchy, &mut t);
    Some(t)
}
