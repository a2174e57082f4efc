//! The preparation's stages below the links: the scene's meshes → face clusters and elements
//! ([`crate::elements`]) → their hierarchy ([`crate::hierarchy`]), with the keyframed objects'
//! groups. A link budget's tries at other thresholds τ reuse one [`Meshed`]; only a new
//! element size makes it again.

use crate::elements::{build_elements, Element};
use crate::error::Result;
use crate::hierarchy::Hierarchy;
use crate::scene::{Scene, SolverSettings};
use std::time::Instant;

/// Group of a mesh (or node) that does not move.
pub const STATIC: u32 = 0;
/// Group of a cluster node over more than one group (a top cluster).
pub const MIXED: u32 = u32::MAX;

/// A scene meshed into leaf elements and their hierarchy.
#[derive(Debug, Clone)]
pub struct Meshed {
    /// Leaf elements (face clusters, triangles and their subdivisions).
    pub elements: Vec<Element>,
    /// The hierarchy over them.
    pub hierarchy: Hierarchy,
    /// The keyframed objects and every mesh's group ([`mesh_groups`]), when linked.
    pub groups: Option<(Vec<usize>, Vec<u32>)>,
    /// The element size it was made at.
    pub element_size: f64,
    /// Time to build elements and hierarchy, ms.
    pub meshing_ms: f64,
}

impl Meshed {
    /// Meshes `scene` at `settings`; `link`: for a method with links (without, triangles are
    /// not clustered and keyframed objects are not grouped).
    pub fn new(scene: &Scene, settings: &SolverSettings, link: bool) -> Result<Self> {
        let t0 = Instant::now();
        // Methods without links (progressive refinement, instant radiosity) work on triangles.
        let elements = if link {
            build_elements(scene, settings)?
        } else {
            build_elements(
                scene,
                &SolverSettings {
                    face_clusters: false,
                    ..settings.clone()
                },
            )?
        };
        // Keyframed objects are their own subtrees, linked for their whole motion (§3.3).
        let groups = if link { mesh_groups(scene) } else { None };
        let hierarchy = match &groups {
            Some((_, mesh_group)) => {
                let g: Vec<u32> = elements
                    .iter()
                    .map(|e| mesh_group[e.mesh as usize])
                    .collect();
                Hierarchy::build_grouped(&elements, &g)
            }
            None => Hierarchy::build(&elements),
        };
        Ok(Self {
            elements,
            hierarchy,
            groups,
            element_size: settings.element_size,
            meshing_ms: t0.elapsed().as_secs_f64() * 1e3,
        })
    }
}

/// The keyframed objects of `scene` and the group of every mesh ([`STATIC`], `g + 1` moving
/// with the `g`-th), or `None` when no object has keyframes (nothing to bound).
pub fn mesh_groups(scene: &Scene) -> Option<(Vec<usize>, Vec<u32>)> {
    let objects: Vec<usize> = (0..scene.objects.len())
        .filter(|&i| {
            scene.objects[i]
                .motion
                .as_ref()
                .is_some_and(|m| !m.keys.is_empty())
        })
        .collect();
    if objects.is_empty() {
        return None;
    }
    let mut group = vec![STATIC; scene.meshes.len()];
    for (g, &o) in objects.iter().enumerate() {
        for m in scene.objects[o].meshes.clone() {
            group[m] = g as u32 + 1;
        }
    }
    Some((objects, group))
}
