//! Which triangles bound a closed solid from outside. A surface is opaque from both sides
//! (light arriving at its back is blocked, `src/solver/local.rs`), but the back of a closed
//! solid's surface faces only the solid's inside, where the light U carries in through one face
//! is already cancelled by that face's antiradiance: blocking it again at the far face only
//! amplifies the discretization's imperfect cancellation (a closed box with a floating block:
//! elements +50% off at τ = 1 when the block's faces blocked from behind). So those faces keep the
//! paper's rule (light from behind ignored); open surfaces (thin walls) and enclosures whose
//! faces look inward (a room: its backs face the world outside) block it.

use crate::scene::Scene;
use glam::DVec3;
use std::collections::HashMap;

/// Per mesh, per triangle: true when the triangle lies on a closed, consistently oriented
/// connected surface that encloses a positive volume with its normals pointing out (a solid
/// seen from outside). Connectivity and closure go by shared edges at exact coordinates, as
/// [`crate::system::closed_surfaces`] judges the whole scene.
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
    // Union-find over triangles sharing an (undirected) edge.
    let mut parent: Vec<usize> = (0..tris.len()).collect();
    fn find(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    let mut first: HashMap<([u64; 3], [u64; 3]), usize> = HashMap::new();
    // Directed edge balance per undirected edge: +1 one way, −1 the other.
    let mut balance: HashMap<([u64; 3], [u64; 3]), i64> = HashMap::new();
    for (t, c) in tris.iter().enumerate() {
        for i in 0..3 {
            let (a, b) = (key(c[i]), key(c[(i + 1) % 3]));
            if a == b {
                continue;
            }
            let (e, s) = if a < b { ((a, b), 1) } else { ((b, a), -1) };
            *balance.entry(e).or_default() += s;
            match first.get(&e) {
                Some(&o) => {
                    let (x, y) = (find(&mut parent, o), find(&mut parent, t));
                    parent[x.max(y)] = x.min(y);
                }
                None => {
                    first.insert(e, t);
                }
            }
        }
    }
    // Per component: open (an unbalanced edge) and signed volume (divergence theorem).
    let mut open = vec![false; tris.len()];
    for (e, &b) in &balance {
        if b != 0 {
            let r = find(&mut parent, first[e]);
            open[r] = true;
        }
    }
    let mut volume = vec![0.0; tris.len()];
    for (t, c) in tris.iter().enumerate() {
        let r = find(&mut parent, t);
        volume[r] += c[0].dot(c[1].cross(c[2])) / 6.0;
    }
    let mut out = Vec::with_capacity(scene.meshes.len());
    let mut t = 0;
    for m in &scene.meshes {
        let mut v = Vec::with_capacity(m.triangles.len());
        for _ in &m.triangles {
            let r = find(&mut parent, t);
            v.push(!open[r] && volume[r] > 0.0);
            t += 1;
        }
        out.push(v);
    }
    out
}

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
        let solid = solid_triangles(&s);
        assert!(solid[0].iter().all(|&b| b), "outward cube: a solid");
        assert!(solid[1].iter().all(|&b| !b), "inward cube: a room");
        assert!(!solid[2][0], "a lone triangle is open");
    }
}
