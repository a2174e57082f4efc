//! Can anything in the scene occlude anything? Antiradiance (eq. 12) is the light a surface x
//! receives on either side that unoccluded transport U would carry on through it (surfaces are
//! opaque from both sides); it reaches a surface y on the other side of x's plane. Without an
//! environment, x can occlude only when some triangle lies (partly) in front of its plane and some
//! (partly) behind it; under an environment, which reaches both sides of everything, when any
//! triangle lies off its plane. When no triangle is placed that way — one convex enclosure seen
//! from inside or one convex solid seen from outside, without environment; a floor alone under
//! lights — U = G and antiradiance never reaches anything, so the solver can leave it out.
//!
//! The test is conservative: triangles, not elements, with a tolerance of [`TOLERANCE`] of the
//! scene's size (points that close to a plane count as neither side), and a scene too large to check in
//! [`PAIR_BUDGET`] pair tests is reported as undecided (antiradiance kept).

use crate::scene::Scene;
use glam::DVec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// Distances to a plane below this fraction of the scene's size count as on the plane
/// ([`crate::solids::TOLERANCE`], the stage below, judges solids with it too).
pub use crate::solids::TOLERANCE;

/// Triangle pairs examined at most before giving up (undecided keeps antiradiance).
pub const PAIR_BUDGET: u64 = 400_000_000;

/// Result of the analysis.
#[derive(Debug, Clone, PartialEq)]
pub enum Occlusion {
    /// No triangle can send antiradiance to another: U = G.
    Impossible,
    /// These two meshes (by name) hold a pair that can occlude: the second lies off the first's
    /// plane, on the side the first sends antiradiance to.
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
    // A triangle x blocks light arriving at either side and sends the antiradiance on out of
    // the other side, where any surface off its plane receives it. So x can occlude when light
    // can arrive at one side and something lies on the other: something on both sides, or,
    // under an environment (which arrives at both sides of everything), anything off its plane.
    // In a convex enclosure without environment nothing lies behind any wall, and around one
    // convex solid nothing lies in front of any face.
    let environment = scene.environment.max_element() > 0.0;
    let examined = AtomicU64::new(0);
    let n = tris.len() as u64;
    let hit = (0..tris.len()).into_par_iter().find_map_any(|i| {
        if examined.fetch_add(n, Ordering::Relaxed) > PAIR_BUDGET {
            return Some(None);
        }
        let x = &tris[i];
        let behind = tris.iter().find(|y| x.extent(y).1 < -eps);
        let front = tris.iter().find(|y| x.extent(y).0 > eps);
        let y = match (behind, front) {
            (Some(b), Some(_)) => Some(b),
            (b, f) if environment => b.or(f),
            _ => None,
        };
        y.map(|y| Some((x.mesh, y.mesh)))
    });
    match hit {
        Some(Some((a, b))) => {
            Occlusion::Possible(scene.meshes[a].name.clone(), scene.meshes[b].name.clone())
        }
        Some(None) => Occlusion::Undecided,
        None => Occlusion::Impossible,
    }
}
