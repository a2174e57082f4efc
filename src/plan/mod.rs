//! Scene analysis: which passes a render of this scene needs, and so which images, buffers and
//! pipelines exist. Every rule leaves something out only where the result cannot change (up to
//! float rounding); `--all-passes` ([`Plan::everything`]) turns everything on for comparison.
//! The pass names are listed in the README ("Passes a scene needs").

pub mod occlusion;
pub mod range;
pub mod target;

use crate::frame::surfaces::{Surfaces, MODE_SPLAT, MODE_VERTEX};
use crate::scene::{Light, Precision, Scene};
use crate::system::System;
use occlusion::Occlusion;
use range::Range;
use serde::Serialize;
use std::collections::BTreeMap;

/// What the solver and the frame compute; the GPU turns each flag into a specialization constant
/// or into an image, buffer or pipeline that exists or not.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Features {
    /// Antiradiance (eq. 19 in the local pass, the asymmetric scheme's antiradiance steps).
    pub antiradiance: bool,
    /// The diffuse fast path for Lambertian leaves (irradiance image, no BRDF sum).
    pub diffuse: bool,
    /// The general BRDF pass (Phong sum over incident bins) and its lobe tables.
    pub glossy: bool,
    /// Every leaf goes through the general BRDF pass (`--all-passes`), not only glossy ones.
    pub glossy_everywhere: bool,
    /// Direct light from shadow maps at the leaves (a direct-light table and irradiance image).
    pub direct: bool,
    /// The constant environment added to every leaf's incident light.
    pub environment: bool,
    /// Emission in the local pass.
    pub emission: bool,
    /// Splatting of flat-surface elements (splat pass and its accumulation image).
    pub splat: bool,
    /// Vertex interpolation for smooth shared-vertex meshes (per-vertex radiance in the G-buffer).
    pub vertex: bool,
    /// Shading normals from OBJ `vn` (an interpolated-normal target in the G-buffer).
    pub normals: bool,
}

impl Features {
    /// Everything on (what `--all-passes` runs, and what a solver built without a plan assumes).
    pub const ALL: Features = Features {
        antiradiance: true,
        diffuse: true,
        glossy: true,
        glossy_everywhere: true,
        direct: true,
        environment: true,
        emission: true,
        splat: true,
        vertex: true,
        normals: true,
    };

    /// What `sys` could use without knowing its lights: its materials decide the local passes;
    /// antiradiance, direct light, environment and emission stay on.
    pub fn for_system(sys: &System) -> Self {
        let glossy = sys
            .leaves
            .iter()
            .any(|l| sys.lobes[l.material as usize].is_some());
        let diffuse = sys
            .leaves
            .iter()
            .any(|l| sys.lobes[l.material as usize].is_none());
        Features {
            diffuse,
            glossy,
            glossy_everywhere: false,
            ..Self::ALL
        }
    }
}

/// How the frame draws one object's indirect light.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Shading {
    /// Flat surfaces only: splatted.
    Splat,
    /// A smooth shared-vertex mesh: vertex interpolation.
    Vertex,
    /// Both kinds of triangles in one object.
    Both,
}

/// The analysis of one scene: features, table precision, and the reason for every decision.
#[derive(Debug, Clone, Serialize)]
pub struct Plan {
    /// What runs.
    pub features: Features,
    /// Light types whose shadow-map passes run (`directional`, `spot`, `point`).
    pub shadow: Vec<String>,
    /// Table precision (float16 unless the dynamic range needs float32).
    pub precision: Precision,
    /// Why float16 was asked for but float32 is used (for the render's `fallbacks`).
    pub precision_fallback: Option<String>,
    /// Indirect-light shading per object (mesh name).
    pub shading: BTreeMap<String, Shading>,
    /// True when `--all-passes` forced everything on.
    pub all_passes: bool,
    /// One sentence per rule: what was decided and why.
    pub decisions: Vec<String>,
}

impl Plan {
    /// Analyses `scene` lit by `lights` (its analytic lights and any emitter samples, see
    /// [`crate::frame::emitters`]), discretized as `sys`, drawn with `surf`, when `requested`
    /// table precision is asked for.
    pub fn analyze(
        scene: &Scene,
        lights: &[Light],
        sys: &System,
        surf: &Surfaces,
        requested: Precision,
    ) -> Self {
        let mut d = Vec::new();
        let f0 = Features::for_system(sys);
        // A closed scene's system already analysed it (for its energy normalization).
        let occ = sys
            .occlusion
            .clone()
            .unwrap_or_else(|| occlusion::analyze(scene));
        let antiradiance = match occ {
            Occlusion::Impossible => {
                d.push("antiradiance off: no surface has light arriving at one side and a surface on the other, so nothing can occlude (U = G)".to_string());
                false
            }
            Occlusion::Possible(a, b) => {
                d.push(format!(
                    "antiradiance on: '{b}' can be occluded by '{a}' (opaque from both sides)"
                ));
                true
            }
            Occlusion::Undecided => {
                d.push(format!(
                    "antiradiance on: occlusion not decided within {} triangle pairs",
                    occlusion::PAIR_BUDGET
                ));
                true
            }
        };
        if let Some(l) = sys.energy_normalization {
            d.push(format!("closed surfaces: every form factor divided by the transport's spectral radius λ = {l:.6}, so that no light is gained or lost per bounce"));
        }
        d.push(match (f0.diffuse, f0.glossy) {
            (true, false) => "diffuse fast path only: no glossy material, no BRDF tables".into(),
            (false, true) => "general BRDF pass only: every element is glossy".into(),
            (true, true) => {
                "diffuse fast path for Lambertian elements, general BRDF pass for glossy ones"
                    .into()
            }
            (false, false) => "no elements: no local pass".into(),
        });
        let shadow: Vec<String> = ["directional", "spot", "point", "emitter"]
            .into_iter()
            .filter(|k| lights.iter().any(|l| l.kind() == *k))
            .map(String::from)
            .collect();
        d.push(if shadow.is_empty() {
            "no lights and no sampled emitters: no shadow maps, no direct-light table".into()
        } else {
            format!("shadow maps for {} lights", shadow.join(", "))
        });
        let emitters = sys
            .leaves
            .iter()
            .any(|l| sys.materials[l.material as usize].is_emitter());
        let sampled = lights
            .iter()
            .any(|l| matches!(l, Light::EmitterSample { .. }));
        // Sampled emitters light the leaves' first bounce through shadow maps; their emission
        // then stays out of the bins (§3.3: antiradiance carries indirect light only).
        let emission = emitters && !sampled;
        if !emitters {
            d.push("no emitters: no emission term".into());
        }
        let environment = scene.environment.max_element() > 0.0;
        if !environment {
            d.push("no environment: no environment term".into());
        }
        let mut shading = BTreeMap::new();
        for (li, leaf) in sys.leaves.iter().enumerate() {
            let e = sys
                .hierarchy
                .element(leaf.node)
                .expect("leaf rows hold elements");
            let name = &scene.meshes[sys.elements[e as usize].mesh as usize].name;
            let kind = if surf.mode[li] == MODE_VERTEX {
                Shading::Vertex
            } else {
                Shading::Splat
            };
            let s = shading.entry(name.clone()).or_insert(kind.clone());
            if *s != kind {
                *s = Shading::Both;
            }
        }
        let splat = surf.mode.contains(&MODE_SPLAT);
        let vertex = surf.mode.contains(&MODE_VERTEX);
        d.push(format!(
            "indirect light: {}",
            match (splat, vertex) {
                (true, true) =>
                    "splatting for flat surfaces, vertex interpolation for smooth meshes",
                (true, false) => "splatting only (no smooth shared-vertex mesh)",
                (false, true) => "vertex interpolation only (no flat surface)",
                (false, false) => "nothing to draw",
            }
        ));
        let normals = surf.shaded.contains(&true);
        if normals {
            d.push("shading normals: OBJ vn interpolated per pixel for direct light and the bin toward the eye (a G-buffer normal target)".into());
        }
        let (precision, why) = Range::of(sys, scene.environment, 0.0).precision(requested);
        d.push(match (precision, why.clone()) {
            (_, Some(why)) => why,
            (Precision::F16, None) => "float16 tables: the dynamic range fits".into(),
            (_, None) => "float32 tables (requested)".into(),
        });
        Plan {
            features: Features {
                antiradiance,
                direct: !lights.is_empty(),
                environment,
                emission,
                splat,
                vertex,
                normals,
                ..f0
            },
            shadow,
            precision,
            precision_fallback: why,
            shading,
            all_passes: false,
            decisions: d,
        }
    }

    /// Everything on, float32 tables (`--all-passes`); shadow maps for the lights present (a
    /// light type that is absent has nothing to draw).
    pub fn everything(scene: &Scene, lights: &[Light], sys: &System, surf: &Surfaces) -> Self {
        let mut p = Self::analyze(scene, lights, sys, surf, Precision::F32);
        // Sampled emitters are a way of lighting, not a pass to leave out: their emission stays
        // out of the bins with every pass on too.
        let sampled = lights
            .iter()
            .any(|l| matches!(l, Light::EmitterSample { .. }));
        p.features = Features {
            emission: !sampled,
            ..Features::ALL
        };
        p.precision = Precision::F32;
        p.precision_fallback = None;
        p.all_passes = true;
        p.decisions = vec!["--all-passes: every pass and table on, float32 tables".into()];
        p
    }

    /// The passes a render runs, in order (names documented in the README).
    pub fn passes(&self) -> Vec<String> {
        let f = &self.features;
        let mut p: Vec<String> = self.shadow.iter().map(|k| format!("shadow_{k}")).collect();
        let mut add = |on: bool, name: &str| {
            if on {
                p.push(name.to_string());
            }
        };
        add(f.direct, "direct_init");
        add(f.emission, "emission_init");
        add(f.environment, "environment_init");
        add(true, "global");
        add(true, "push");
        add(true, "local_irradiance");
        add(f.diffuse && !f.glossy_everywhere, "local_diffuse");
        add(f.glossy, "local_glossy");
        add(f.antiradiance, "antiradiance");
        add(true, "pull");
        add(true, "gbuffer");
        add(f.vertex, "interpolate");
        add(f.splat, "splat");
        add(true, "compose");
        p
    }

    /// The plan for a render: [`Plan::everything`] when `all_passes`, else [`Plan::analyze`]
    /// with `requested` precision.
    pub fn new(
        scene: &Scene,
        lights: &[Light],
        sys: &System,
        surf: &Surfaces,
        requested: Precision,
        all_passes: bool,
    ) -> Self {
        if all_passes {
            Self::everything(scene, lights, sys, surf)
        } else {
            Self::analyze(scene, lights, sys, surf, requested)
        }
    }
}
