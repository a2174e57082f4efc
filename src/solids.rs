//! Which triangles are part of a surface that wraps around behind them. A surface is opaque
//! from both sides (light arriving at its back is blocked, `src/solver/local.rs`), but the back
//! of a solid's face (a closed box, or a block without a bottom standing on a floor) faces only
//! the solid's inside, where the light U carries in through one face is already cancelled by
//! that face's antiradiance: blocking it again at the far face only amplifies the
//! discretization's imperfect cancellation (a closed box with a floating block: elements +50%
//! off at τ = 1; the Cornell box's open-bottomed blocks: image mean +7.6% against the path
//! tracer). So a face with some corner of its own connected surface behind its plane keeps the
//! paper's rule (light from behind ignored); flat thin walls and rooms whose faces look inward
//! (their backs face the world outside) block it.
//!
//! A closed surface modelled inside out (faces looking inward, as MNRoom's table) with nothing
//! inside it is a solid too: every line through it enters at a back and leaves at a front, whose
//! antiradiance already blocks it, and its inside holds nothing to be lit. Blocking at its backs
//! as well cancels twice across a thin slab, through links between faces a few millimetres apart
//! (MNRoom: the floor under the table +100–225% in indirect light). A room (closed, looking
//! inward) keeps blocking: the camera, a light or other geometry lies inside it.
//!
//! A wall of zero thickness lit on both sides is two faces back to back (a two-sided material's
//! twin, or two quads): light crossing it arrives at one face's front and the other's back, and
//! the first face's antiradiance already blocks it. So a face lying on a face of opposite
//! orientation ignores light from behind too; blocking at both cancelled twice (the thin-walled
//! corridors of `tests/corridors.rs` 6–11% too dark, medians 17–33%; once: 1–3%, 5–8%).

use crate::scene::{Light, Scene};
use glam::DVec3;
use std::collections::HashMap;

/// Distances to a plane below this fraction of the scene's size count as on the plane: float32
/// OBJ coordinates (6e-8 relative) make flat quads and tessellated spheres that far from exact, and
/// a sliver that thin cannot occlude anything visible.
pub const TOLERANCE: f64 = 1e-6;

/// Per mesh, per triangle: true when a corner of the triangle's connected surface (triangles
/// sharing edges at exact coordinates, as [`crate::system::closed_surfaces`] compares them) lies
/// behind its plane, by more than [`TOLERANCE`] of the scene's size; or
/// when the surface is closed (every edge shared by exactly two of its triangles), a corner lies
/// in front of the triangle's plane, and nothing (a vertex, the camera, a point or spot light)
/// lies inside the surface's bounding box.
pub fn solid_triangles(scene: &Scene) -> Vec<Vec<bool>> {
    let key = |p: DVec3| [p.x + 0.0, p.y + 0.0, p.z + 0.0].map(f64::to_bits);
    let tris: Vec<[DVec3; 3]> = scene
        .meshes
        .iter()
        .flat_map(|m| {
            m.triangles
                .iter()
                .map(|t| t.map(|i| m.positions[i as usize]))
        })
        .collect();
    // Union-find over triangles sharing an (undirected) edge; uses per edge.
    let mut parent: Vec<usize> = (0..tris.len()).collect();
    fn find(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    let mut first: HashMap<([u64; 3], [u64; 3]), (usize, u32)> = HashMap::new();
    for (t, c) in tris.iter().enumerate() {
        for i in 0..3 {
            let (a, b) = (key(c[i]), key(c[(i + 1) % 3]));
            if a == b {
                continue;
            }
            let e = if a < b { (a, b) } else { (b, a) };
            match first.get_mut(&e) {
                Some((o, uses)) => {
                    *uses += 1;
                    let (x, y) = (find(&mut parent, *o), find(&mut parent, t));
                    parent[x.max(y)] = x.min(y);
                }
                None => {
                    first.insert(e, (t, 1));
                }
            }
        }
    }
    // Per component: its corners, and whether it is closed.
    let (lo, hi) = scene.bounds();
    let eps = (hi - lo).length().max(1e-300) * TOLERANCE;
    let mut corners: HashMap<usize, Vec<DVec3>> = HashMap::new();
    for (t, c) in tris.iter().enumerate() {
        let r = find(&mut parent, t);
        corners.entry(r).or_default().extend_from_slice(c);
    }
    let mut closed: HashMap<usize, bool> = corners.keys().map(|&r| (r, true)).collect();
    for &(t, uses) in first.values() {
        if uses != 2 {
            let r = find(&mut parent, t);
            closed.insert(r, false);
        }
    }
    let empty = empty_closed_surfaces(scene, &corners, &closed, eps);
    let backed = back_to_back(&tris, eps);
    let mut examined = 0u64;
    let mut out = Vec::with_capacity(scene.meshes.len());
    let mut t = 0;
    for m in &scene.meshes {
        let mut v = Vec::with_capacity(m.triangles.len());
        for _ in &m.triangles {
            let r = find(&mut parent, t);
            let c = &tris[t];
            let n = (c[1] - c[0]).cross(c[2] - c[0]).normalize_or_zero();
            let all = &corners[&r];
            examined += all.len() as u64;
            // Past the budget, keep the paper's rule (light from behind ignored).
            let behind = || all.iter().any(|&p| n.dot(p - c[0]) < -eps);
            let inside_out = || empty.contains(&r) && all.iter().any(|&p| n.dot(p - c[0]) > eps);
            v.push(examined > PAIR_BUDGET || behind() || inside_out() || backed[t]);
            t += 1;
        }
        out.push(v);
    }
    out
}

/// Faces of one plane searched for a back-to-back face that is not an exact twin.
const MAX_BUCKET: usize = 256;

/// Per triangle: whether its centroid lies on a triangle of the opposite orientation in the
/// same plane (within `eps`): the face of a zero-thickness wall whose other side is another face.
fn back_to_back(tris: &[[DVec3; 3]], eps: f64) -> Vec<bool> {
    // Planes bucketed by normal (to 1e-6) and offset (to eps); a plane near a bucket's edge
    // is also looked up in the neighbouring offset buckets.
    let plane = |c: &[DVec3; 3]| {
        let n = (c[1] - c[0]).cross(c[2] - c[0]).normalize_or_zero();
        (n, n.dot(c[0]))
    };
    let key = |n: DVec3, d: f64| {
        let q = |v: f64| (v * 1e6).round() as i64;
        ([q(n.x), q(n.y), q(n.z)], (d / eps).round() as i64)
    };
    let mut buckets: HashMap<([i64; 3], i64), Vec<usize>> = HashMap::new();
    for (t, c) in tris.iter().enumerate() {
        let (n, d) = plane(c);
        if n != DVec3::ZERO {
            buckets.entry(key(n, d)).or_default().push(t);
        }
    }
    // Exact twins (the same corners), found by their corner set whatever the bucket sizes.
    let corners = |c: &[DVec3; 3]| {
        let mut k = c.map(|p| [p.x + 0.0, p.y + 0.0, p.z + 0.0].map(f64::to_bits));
        k.sort();
        k
    };
    let mut by_corners: HashMap<[[u64; 3]; 3], Vec<usize>> = HashMap::new();
    for (t, c) in tris.iter().enumerate() {
        by_corners.entry(corners(c)).or_default().push(t);
    }
    tris.iter()
        .map(|c| {
            let (n, d) = plane(c);
            if n == DVec3::ZERO {
                return false;
            }
            let twin = by_corners[&corners(c)]
                .iter()
                .any(|&o| plane(&tris[o]).0.dot(n) < 0.0);
            if twin {
                return true;
            }
            let centroid = (c[0] + c[1] + c[2]) / 3.0;
            let (kn, kd) = key(-n, -d);
            (kd - 1..=kd + 1).any(|kd| {
                // A large flat tessellation backed face by face has exact twins; past
                // MAX_BUCKET faces in one plane the search stops (the face keeps blocking).
                buckets.get(&(kn, kd)).is_some_and(|list| {
                    list.len() <= MAX_BUCKET
                        && list.iter().any(|&o| {
                            let q = &tris[o];
                            // The centroid inside the other triangle (edge tests in its plane).
                            let m = (q[1] - q[0]).cross(q[2] - q[0]);
                            (0..3).all(|i| {
                                let (a, b) = (q[i], q[(i + 1) % 3]);
                                (b - a).cross(centroid - a).dot(m) >= 0.0
                            })
                        })
                })
            })
        })
        .collect()
}

/// The closed surfaces (by component root) whose bounding box, shrunk by `eps`, holds no vertex
/// (of another surface, or a concave corner of its own), no camera eye and no point or spot light. Past [`PAIR_BUDGET`] vertex
/// tests the rest count as occupied (they keep blocking at their backs).
fn empty_closed_surfaces(
    scene: &Scene,
    corners: &HashMap<usize, Vec<DVec3>>,
    closed: &HashMap<usize, bool>,
    eps: f64,
) -> std::collections::HashSet<usize> {
    let mut others: Vec<DVec3> = scene
        .meshes
        .iter()
        .flat_map(|m| m.positions.iter().copied())
        .collect();
    others.push(scene.camera.eye);
    others.extend(scene.lights.iter().filter_map(|l| match l {
        Light::Point { position, .. } | Light::Spot { position, .. } => Some(*position),
        _ => None,
    }));
    let mut tests = 0u64;
    let mut out = std::collections::HashSet::new();
    // In component order, so that the budget cuts off the same surfaces on every run.
    let mut roots: Vec<usize> = corners.keys().copied().filter(|r| closed[r]).collect();
    roots.sort_unstable();
    for r in roots {
        let c = &corners[&r];
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for p in c {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        let (lo, hi) = (lo + DVec3::splat(eps), hi - DVec3::splat(eps));
        tests += others.len() as u64;
        if tests > PAIR_BUDGET {
            break;
        }
        // The surface's own corners are on its box's boundary, so they fall outside the shrunk box.
        if !others
            .iter()
            .any(|p| p.cmpgt(lo).all() && p.cmplt(hi).all())
        {
            out.insert(r);
        }
    }
    out
}

/// Corner tests at most before the rest of the scene keeps the paper's rule.
const PAIR_BUDGET: u64 = 400_000_000;

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube's 12 triangles, counter-clockwise seen from outside (or inside).
    fn cube(s: &mut Scene, name: &str, offset: DVec3, inward: bool) {
        let p: Vec<DVec3> = (0..8)
            .map(|i| offset + DVec3::new((i & 1) as f64, (i >> 1 & 1) as f64, (i >> 2) as f64))
            .collect();
        let quads = [
            [0, 4, 6, 2],
            [1, 3, 7, 5],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 2, 3, 1],
            [4, 5, 7, 6],
        ];
        let mut t = Vec::new();
        for q in quads {
            let (a, b) = ([q[0], q[1], q[2]], [q[0], q[2], q[3]]);
            for mut tri in [a, b] {
                if inward {
                    tri.swap(1, 2);
                }
                t.push(tri);
            }
        }
        s.add_mesh(name, p, t, 0);
    }

    #[test]
    fn solids_rooms_and_open_surfaces() {
        let mut s = Scene::empty();
        s.add_material(crate::scene::Material::diffuse("grey", 0.5));
        cube(&mut s, "solid", DVec3::ZERO, false);
        cube(&mut s, "room", DVec3::splat(5.0), true);
        let o = DVec3::splat(-5.0);
        let p = vec![o, o + DVec3::X, o + DVec3::Y];
        s.add_mesh("open", p, vec![[0, 1, 2]], 0);
        // Something inside the room: a small triangle.
        let c = DVec3::splat(5.5);
        let p = vec![c, c + 0.1 * DVec3::X, c + 0.1 * DVec3::Y];
        s.add_mesh("content", p, vec![[0, 1, 2]], 0);
        cube(&mut s, "inside out", DVec3::new(-3.0, 0.0, 0.0), true);
        s.camera.eye = DVec3::splat(-20.0);
        let solid = solid_triangles(&s);
        assert!(solid[0].iter().all(|&b| b), "outward cube: a solid");
        assert!(
            solid[1].iter().all(|&b| !b),
            "inward cube with something in it: a room"
        );
        assert!(!solid[2][0], "a lone triangle is open");
        assert!(
            solid[4].iter().all(|&b| b),
            "empty inward cube: a solid inside out"
        );
        // The camera inside makes it a room.
        s.camera.eye = DVec3::new(-2.5, 0.5, 0.5);
        assert!(
            solid_triangles(&s)[4].iter().all(|&b| !b),
            "camera inside: a room"
        );
        // Open (one face missing): light entering at a back could leave by the gap.
        let mut s2 = Scene::empty();
        s2.add_material(crate::scene::Material::diffuse("grey", 0.5));
        cube(&mut s2, "inside out", DVec3::ZERO, true);
        s2.meshes[0].triangles.truncate(10);
        s2.meshes[0].material.truncate(10);
        s2.camera.eye = DVec3::splat(-20.0);
        assert!(
            solid_triangles(&s2)[0].iter().all(|&b| !b),
            "open inward box blocks"
        );
    }

    #[test]
    fn faces_back_to_back_are_solid() {
        let mut s = Scene::empty();
        s.add_material(crate::scene::Material::diffuse("grey", 0.5));
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
        // A quad, and behind it the same quad reversed on the other diagonal (two quads).
        s.add_mesh("front", p.clone(), vec![[0, 1, 2], [0, 2, 3]], 0);
        s.add_mesh("back", p.clone(), vec![[3, 2, 1], [3, 1, 0]], 0);
        // A lone quad elsewhere, and one with its exact twin (`add_twins`).
        let q: Vec<DVec3> = p.iter().map(|&v| v + DVec3::Z * 3.0).collect();
        s.add_mesh("lone", q, vec![[0, 1, 2], [0, 2, 3]], 0);
        let r: Vec<DVec3> = p.iter().map(|&v| v - DVec3::Z * 3.0).collect();
        s.add_mesh("two-sided", r, vec![[0, 1, 2], [0, 2, 3]], 0);
        crate::scene::add_twins(&mut s, 3..4);
        s.camera.eye = DVec3::splat(-20.0);
        let solid = solid_triangles(&s);
        assert!(solid[0].iter().chain(&solid[1]).all(|&b| b), "{solid:?}");
        assert!(
            solid[2].iter().all(|&b| !b),
            "a lone quad blocks from behind"
        );
        assert!(solid[3].iter().chain(&solid[4]).all(|&b| b), "{solid:?}");
    }
}
