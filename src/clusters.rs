//! The mesh stage and face clusters: how input triangles meet (flat surfaces, smooth
//! tessellation), and the grouping of a dense mesh's small triangles into face clusters that are
//! the solver's leaves (after Willmott, Heckbert and Garland, "Face Cluster Radiosity", and the
//! higher-order face-cluster paper in `shared/papers`). Without clusters a 69K-triangle scan
//! makes 72K leaves and tens of millions of links; with them a mesh makes about its area over the
//! element area in leaves, whatever its triangle count.
//!
//! A cluster is connected (triangles sharing an edge that is no crease sharper than
//! [`SMOOTH_MAX_DEG`]), of one material and one solid side, within a normal cone (every face
//! within 60° of the seed, the area-weighted mean normal at least [`MIN_COHERENCE`] long), and of
//! bounded extent (every corner within [`CLUSTER_RADIUS`] × the element size of the seed's
//! centroid). Its faces are shown by vertex interpolation whatever their kind
//! ([`crate::frame::surfaces`]), blending from cluster to cluster. Emitters are never clustered
//! (their triangles are sampled one by one). A triangle larger than the element size is bisected
//! ([`crate::elements`]) and never clustered.
//!
//! meshoptimizer's meshlets bound a cluster's vertex and triangle counts, not its extent or
//! area, which is what the solver's accuracy depends on; this grouping stays ours.

use crate::scene::Scene;
use glam::DVec3;
use std::collections::{HashMap, VecDeque};

/// Adjacent input triangles whose normals differ by more than this (and less than
/// [`SMOOTH_MAX_DEG`]) mark a smooth, vertex-interpolated mesh.
pub const COPLANAR_DEG: f64 = 2.0;
/// Creases sharper than this are edges between flat surfaces, not smooth tessellation.
pub const SMOOTH_MAX_DEG: f64 = 40.0;
/// A cluster's corners lie within this fraction of the element size of its seed's centroid
/// (a disc of about the area bisection gives an element, π·0.5² ≈ 0.8 size²).
pub const CLUSTER_RADIUS: f64 = 0.5;
/// Smallest length of a cluster's area-weighted mean unit normal (1 for a flat cluster; 0.9 is
/// a spherical cap of about 50° across), so the solver may treat it as one plane.
pub const MIN_COHERENCE: f64 = 0.9;
/// The same for glossy materials, whose lobe the local pass reflects about the leaf's one
/// normal (0.99: a cap of about 16° across). With 0.9 the glossy Cornell box's sphere was
/// 0.124 off the path tracer instead of 0.120.
pub const MIN_COHERENCE_GLOSSY: f64 = 0.99;
/// Every face of a cluster is within this angle of its seed's normal (cos 60°).
const MIN_SEED_COSINE: f64 = 0.5;

/// How the input triangles meet, numbered across meshes in order.
#[derive(Debug, Clone)]
pub struct TriangleClasses {
    /// Index of each mesh's first triangle in the numbering.
    pub first_tri: Vec<u32>,
    /// Unit face normal per triangle (zero for a degenerate one).
    pub normals: Vec<DVec3>,
    /// Whether the triangle meets a neighbour at a smooth angle (between [`COPLANAR_DEG`] and
    /// [`SMOOTH_MAX_DEG`]): shaded by vertex interpolation.
    pub smooth: Vec<bool>,
    /// Flat-surface id: triangles sharing a vertex within [`COPLANAR_DEG`] and in one plane share
    /// it (splats only blend within one).
    pub surface: Vec<u32>,
}

struct UnionFind(Vec<u32>);

impl UnionFind {
    fn find(&mut self, mut i: u32) -> u32 {
        while self.0[i as usize] != i {
            let p = self.0[self.0[i as usize] as usize];
            self.0[i as usize] = p;
            i = p;
        }
        i
    }
    fn union(&mut self, a: u32, b: u32) {
        let (a, b) = (self.find(a), self.find(b));
        if a != b {
            self.0[a.max(b) as usize] = a.min(b);
        }
    }
}

/// A quantized vertex position within one mesh (`quantum` of the scene's diagonal, so that
/// positions written with rounding still meet).
type VertexKey = (usize, i64, i64, i64);

fn vertex_key(quantum: f64) -> impl Fn(usize, DVec3) -> VertexKey {
    move |mesh, p| {
        let q = (p / quantum).round();
        (mesh, q.x as i64, q.y as i64, q.z as i64)
    }
}

/// The quantum of [`vertex_key`] for `scene`.
pub fn vertex_quantum(scene: &Scene) -> f64 {
    let (lo, hi) = scene.bounds();
    ((hi - lo).length() * 1e-7).max(1e-12)
}

/// Classifies every input triangle of `scene` ([`TriangleClasses`]).
pub fn classify(scene: &Scene) -> TriangleClasses {
    let quantum = vertex_quantum(scene);
    let key = vertex_key(quantum);
    let mut first_tri = Vec::new();
    let mut normals = Vec::new();
    let mut offsets = Vec::new();
    let mut around: HashMap<VertexKey, Vec<u32>> = HashMap::new();
    for (mi, m) in scene.meshes.iter().enumerate() {
        first_tri.push(normals.len() as u32);
        for t in &m.triangles {
            let [a, b, c] = t.map(|v| m.positions[v as usize]);
            let n = (b - a).cross(c - a).normalize_or_zero();
            let id = normals.len() as u32;
            normals.push(n);
            offsets.push(n.dot(a));
            for p in [a, b, c] {
                around.entry(key(mi, p)).or_default().push(id);
            }
        }
    }
    let (cos_flat, cos_smooth) = (
        COPLANAR_DEG.to_radians().cos(),
        SMOOTH_MAX_DEG.to_radians().cos(),
    );
    let plane_eps = quantum * 100.0;
    let mut smooth = vec![false; normals.len()];
    let mut uf = UnionFind((0..normals.len() as u32).collect());
    for tris in around.values() {
        for (i, &a) in tris.iter().enumerate() {
            for &b in &tris[i + 1..] {
                let c = normals[a as usize].dot(normals[b as usize]);
                if c >= cos_flat && (offsets[a as usize] - offsets[b as usize]).abs() < plane_eps {
                    uf.union(a, b);
                } else if c > cos_smooth && c < cos_flat {
                    smooth[a as usize] = true;
                    smooth[b as usize] = true;
                }
            }
        }
    }
    let surface = (0..normals.len() as u32).map(|t| uf.find(t)).collect();
    TriangleClasses {
        first_tri,
        normals,
        smooth,
        surface,
    }
}

/// Per mesh, per triangle: the cluster it belongs to, as the index (within the mesh) of the
/// cluster's seed, its first triangle; `None` for a triangle that stays its own element(s)
/// (larger than `size`, emitting, or with no neighbour to join). `solid` is
/// [`crate::solids::solid_triangles`].
pub fn face_clusters(
    scene: &Scene,
    classes: &TriangleClasses,
    solid: &[Vec<bool>],
    size: f64,
) -> Vec<Vec<Option<u32>>> {
    let key = vertex_key(vertex_quantum(scene));
    let radius = CLUSTER_RADIUS * size;
    scene
        .meshes
        .iter()
        .enumerate()
        .map(|(mi, m)| {
            let n = m.triangles.len();
            let first = classes.first_tri[mi] as usize;
            let corners = |t: usize| m.triangles[t].map(|v| m.positions[v as usize]);
            let area = |t: usize| {
                let [a, b, c] = corners(t);
                0.5 * (b - a).cross(c - a).length()
            };
            let small = |t: usize| {
                let [a, b, c] = corners(t);
                let longest = (b - a).length().max((c - b).length()).max((a - c).length());
                longest <= size
                    && area(t) > 0.0
                    && scene.materials[m.material[t] as usize].ke.max_element() <= 0.0
            };
            // Triangles across each (undirected) edge.
            let mut edges: HashMap<(VertexKey, VertexKey), Vec<u32>> = HashMap::new();
            for t in 0..n {
                let c = corners(t);
                for i in 0..3 {
                    let (a, b) = (key(mi, c[i]), key(mi, c[(i + 1) % 3]));
                    if a != b {
                        let e = if a < b { (a, b) } else { (b, a) };
                        edges.entry(e).or_default().push(t as u32);
                    }
                }
            }
            let neighbours = |t: usize, out: &mut Vec<u32>| {
                let c = corners(t);
                for i in 0..3 {
                    let (a, b) = (key(mi, c[i]), key(mi, c[(i + 1) % 3]));
                    let e = if a < b { (a, b) } else { (b, a) };
                    if let Some(v) = edges.get(&e) {
                        out.extend(v.iter().copied().filter(|&u| u as usize != t));
                    }
                }
            };
            let cos_crease = SMOOTH_MAX_DEG.to_radians().cos();
            let mut of = vec![None; n];
            let mut members = Vec::new();
            let mut queue = VecDeque::new();
            let mut next = Vec::new();
            for seed in 0..n {
                if of[seed].is_some() || !small(seed) {
                    continue;
                }
                let gs = first + seed;
                let seed_normal = classes.normals[gs];
                let coherence = if scene.materials[m.material[seed] as usize].is_glossy() {
                    MIN_COHERENCE_GLOSSY
                } else {
                    MIN_COHERENCE
                };
                let [a, b, c] = corners(seed);
                let center = (a + b + c) / 3.0;
                let mut sum = seed_normal * area(seed);
                let mut total = area(seed);
                members.clear();
                members.push(seed);
                of[seed] = Some(seed as u32);
                queue.clear();
                next.clear();
                neighbours(seed, &mut next);
                queue.extend(next.drain(..).map(|u| (u, seed)));
                while let Some((u, from)) = queue.pop_front() {
                    let u = u as usize;
                    let gu = first + u;
                    if of[u].is_some()
                        || !small(u)
                        || m.material[u] != m.material[seed]
                        || solid[mi][u] != solid[mi][seed]
                        || classes.normals[gu].dot(classes.normals[first + from]) < cos_crease
                        || classes.normals[gu].dot(seed_normal) < MIN_SEED_COSINE
                        || corners(u).iter().any(|p| (*p - center).length() > radius)
                    {
                        continue;
                    }
                    let (s, t) = (sum + classes.normals[gu] * area(u), total + area(u));
                    if s.length() < coherence * t {
                        continue;
                    }
                    (sum, total) = (s, t);
                    of[u] = Some(seed as u32);
                    members.push(u);
                    neighbours(u, &mut next);
                    queue.extend(next.drain(..).map(|v| (v, u)));
                }
                if members.len() == 1 {
                    of[seed] = None;
                }
            }
            // A small triangle left alone (its neighbours were taken by clusters first) joins
            // the neighbouring cluster whose seed it faces most alike, past the radius if need
            // be: a leaf of one tiny triangle costs a table row and float16 range for nothing.
            for t in 0..n {
                if of[t].is_some() || !small(t) {
                    continue;
                }
                let gt = first + t;
                next.clear();
                neighbours(t, &mut next);
                let best = next
                    .iter()
                    .filter_map(|&u| of[u as usize].map(|seed| (u as usize, seed as usize)))
                    .filter(|&(u, seed)| {
                        m.material[u] == m.material[t]
                            && solid[mi][u] == solid[mi][t]
                            && classes.normals[first + u].dot(classes.normals[gt]) >= cos_crease
                            && classes.normals[first + seed].dot(classes.normals[gt])
                                >= MIN_SEED_COSINE
                    })
                    .max_by(|a, b| {
                        let c =
                            |seed: usize| classes.normals[first + seed].dot(classes.normals[gt]);
                        c(a.1).total_cmp(&c(b.1))
                    });
                if let Some((_, seed)) = best {
                    of[t] = Some(seed as u32);
                }
            }
            of
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Material;

    /// A flat grid of `k`×`k` squares (two triangles each) of side `1/k` in z = 0.
    fn grid(s: &mut Scene, k: usize, z: impl Fn(f64, f64) -> f64) {
        let mat = s.add_material(Material::diffuse("w", 0.5));
        let mut p = Vec::new();
        for j in 0..=k {
            for i in 0..=k {
                let (x, y) = (i as f64 / k as f64, j as f64 / k as f64);
                p.push(DVec3::new(x, y, z(x, y)));
            }
        }
        let id = |i: usize, j: usize| (j * (k + 1) + i) as u32;
        let mut t = Vec::new();
        for j in 0..k {
            for i in 0..k {
                t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        s.add_mesh("grid", p, t, mat);
    }

    fn clusters_of(s: &Scene, size: f64) -> Vec<Vec<Option<u32>>> {
        let classes = classify(s);
        let solid = crate::solids::solid_triangles(s);
        face_clusters(s, &classes, &solid, size)
    }

    #[test]
    fn a_fine_flat_grid_groups_into_discs_of_the_element_size() {
        let mut s = Scene::empty();
        grid(&mut s, 40, |_, _| 0.0);
        let of = &clusters_of(&s, 0.25)[0];
        let mut seeds: Vec<u32> = of.iter().flatten().copied().collect();
        seeds.sort();
        seeds.dedup();
        assert!(
            of.iter().all(|c| c.is_some()),
            "every small triangle joins a cluster"
        );
        // 3,200 triangles on a unit square; a disc of radius 0.125 holds about 0.05 of it.
        assert!(
            (20..=120).contains(&seeds.len()),
            "{} clusters",
            seeds.len()
        );
        let m = &s.meshes[0];
        for (t, c) in of.iter().enumerate() {
            let seed = c.unwrap() as usize;
            let cen = |t: usize| {
                m.triangles[t]
                    .map(|v| m.positions[v as usize])
                    .iter()
                    .sum::<DVec3>()
                    / 3.0
            };
            // Within the radius, or one triangle past it for a left-over triangle that joined
            // a neighbouring cluster (its legs are 1/40).
            for v in m.triangles[t] {
                assert!((m.positions[v as usize] - cen(seed)).length() <= 0.125 + 0.036);
            }
        }
        // Triangles larger than the size stay alone.
        assert!(clusters_of(&s, 0.01)[0].iter().all(|c| c.is_none()));
    }

    #[test]
    fn clusters_keep_within_a_normal_cone() {
        // A fine half-cylinder: normals turn through 180°, so no cluster may span it.
        let mut s = Scene::empty();
        grid(&mut s, 60, |_, _| 0.0);
        let m = &mut s.meshes[0];
        for p in &mut m.positions {
            let a = p.x * std::f64::consts::PI;
            *p = DVec3::new(-a.cos() * 0.3, p.y, a.sin() * 0.3);
        }
        let classes = classify(&s);
        assert!(classes.smooth.iter().all(|&b| b));
        let of = &clusters_of(&s, 1.0)[0];
        let mut by: HashMap<u32, (DVec3, f64)> = HashMap::new();
        for (t, c) in of.iter().enumerate() {
            let c = c.expect("clustered");
            let m = &s.meshes[0];
            let [a, b, d] = m.triangles[t].map(|v| m.positions[v as usize]);
            let cr = (b - a).cross(d - a);
            let e = by.entry(c).or_default();
            e.0 += cr * 0.5;
            e.1 += 0.5 * cr.length();
        }
        for (sum, area) in by.values() {
            assert!(sum.length() >= MIN_COHERENCE * area - 1e-12);
        }
        assert!(by.len() >= 4, "{}", by.len());
    }
}
