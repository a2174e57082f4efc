//! Can anything in the scene occlude anything? Antiradiance (eq. 12) is the light a surface x
//! receives on its front that unoccluded transport U would carry on through it; it reaches a
//! surface y only when y lies (partly) behind x's plane and x lies (partly) in front of y's
//! plane (y receives only on its front, Fig. 7). When no pair of input triangles is placed that
//! way — one convex enclosure seen from inside, one convex solid seen from outside, a floor under
//! lights — U = G and antiradiance never reaches anything, so the solver can leave it out.
//!
//! The test is conservative: triangles, not elements, with a tolerance of [`TOLERANCE`] of the
//! scene's size (points that close to a plane count as neither side), and a scene too large to check in
//! [`PAIR_BUDGET`] pair tests is reported as undecided (antiradiance kept).

use crate::scene::Scene;
use glam::DVec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// Distances to a plane below this fraction of the scene's size count as on the plane: float32
/// OBJ coordinates (6e-8 relative) make flat quads and tessellated spheres that far from exact, and
/// a sliver that thin cannot occlude anything visible.
pub const TOLERANCE: f64 = 1e-6;

/// Triangle pairs examined at most before giving up (undecided keeps antiradiance).
pub const PAIR_BUDGET: u64 = 400_000_000;

/// Result of the analysis.
#[derive(Debug, Clone, PartialEq)]
pub enum Occlusion {
    /// No triangle can send antiradiance to another: U = G.
    Impossible,
    /// These two meshes (by name) hold a pair that can occlude: the second lies behind the
    /// first's plane while the first faces it.
    Possible(String, String),
    /// The scene was too large to check within [`PAIR_BUDGET`].
    Undecided,
}

struct Tri {
    v: [DVec3; 3],
    n: DVec3,
    d: f64,
    mesh: usize,
}

impl Tri {
    /// Largest signed distance of any corner of `o` to this triangle's plane, and the smallest.
    fn extent(&self, o: &Tri) -> (f64, f64) {
        let s = o.v.map(|p| self.n.dot(p) - self.d);
        (s[0].max(s[1]).max(s[2]), s[0].min(s[1]).min(s[2]))
    }
}

/// Decides whether antiradiance can reach any surface of `scene`.
pub fn analyze(scene: &Scene) -> Occlusion {
    let (lo, hi) = scene.bounds();
    let eps = (hi - lo).length().max(1e-300) * TOLERANCE;
    let tris: Vec<Tri> = scene
        .meshes
        .iter()
        .enumerate()
        .flat_map(|(mi, m)| {
            m.triangles.iter().filter_map(move |t| {
                let v = t.map(|i| m.positions[i as usize]);
                let n = (v[1] - v[0]).cross(v[2] - v[0]).try_normalize()?;
                Some(Tri {
                    v,
                    n,
                    d: n.dot(v[0]),
                    mesh: mi,
                })
            })
        })
        .collect();
    // Triangles with some corner of the scene strictly behind their plane: only they can
    // occlude. In a convex enclosure there are none and the check ends here.
    let all: Vec<DVec3> = tris.iter().flat_map(|t| t.v).collect();
    let occluders: Vec<usize> = (0..tris.len())
        .into_par_iter()
        .filter(|&i| {
            let t = &tris[i];
            all.iter().any(|&p| t.n.dot(p) - t.d < -eps)
        })
        .collect();
    if occluders.is_empty() {
        return Occlusion::Impossible;
    }
    let examined = AtomicU64::new(0);
    let n = tris.len() as u64;
    let hit = occluders.par_iter().find_map_any(|&i| {
        if examined.fetch_add(n, Ordering::Relaxed) > PAIR_BUDGET {
            return Some(None);
        }
        let x = &tris[i];
        tris.iter()
            .find(|y| {
                // y partly behind x, and x partly in front of y.
                x.extent(y).1 < -eps && y.extent(x).0 > eps
            })
            .map(|y| Some((x.mesh, y.mesh)))
    });
    match hit {
        Some(Some((a, b))) => {
            Occlusion::Possible(scene.meshes[a].name.clone(), scene.meshes[b].name.clone())
        }
        Some(None) => Occlusion::Undecided,
        None => Occlusion::Impossible,
    }
}
