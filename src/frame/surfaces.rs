//! How indirect light reaches the screen (§4.3). Elements of smooth shared-vertex meshes are
//! interpolated per vertex; elements of flat surfaces are splatted: a fan around each element
//! center, weighted by a smooth fall-off, blended only onto pixels of the same flat surface, then
//! normalized. Both read the display radiance of an element in the bin toward the eye, so glossy
//! surfaces are view dependent. `glsl/frame.glsl` mirrors [`display_radiance`] and [`splat_weight`].

use super::lights::front_bin;
use super::shading::{eye_direction, shading_normal};
use crate::solver::Table;
use crate::system::System;
use glam::DVec3;
use std::collections::HashMap;

pub use crate::clusters::{COPLANAR_DEG, SMOOTH_MAX_DEG};
/// Splat support radius relative to the element's circumradius about its center.
pub const SPLAT_RADIUS: f64 = 1.5;

/// Shading mode of an element.
pub const MODE_SPLAT: u32 = 0;
/// Vertex interpolation.
pub const MODE_VERTEX: u32 = 1;

/// Per-face screen-space data, in face-slot order. A slot is one face of a leaf (a triangle the
/// frame draws): slot `li` is the first face of leaf `li` (so a scene without face clusters has
/// one slot per leaf, in leaf order), the other faces of face clusters follow.
#[derive(Debug, Clone)]
pub struct Surfaces {
    /// The leaf (index into [`System::leaves`]) each slot's face belongs to.
    pub leaf: Vec<u32>,
    /// The face's corners.
    pub corners: Vec<[DVec3; 3]>,
    /// The face's unit normal (its leaf's normal where the leaf has one face).
    pub normal: Vec<DVec3>,
    /// [`MODE_SPLAT`] or [`MODE_VERTEX`].
    pub mode: Vec<u32>,
    /// Flat-surface id (splats only blend within one).
    pub surface: Vec<u32>,
    /// Whether the splat sums are drawn per 2×2 sample (`solver.splat_per_sample`) rather than
    /// once per pixel ([`crate::frame::splat`]).
    pub splat_per_sample: bool,
    /// Pixels per side of the blocks sharing the area emitters' direct light
    /// (`solver.direct_block`, [`crate::frame::direct::block_for`]; `None`: by the frame's size).
    pub direct_block: Option<u32>,
    /// The leaf's center (splats are drawn once per leaf, from its first slot).
    pub center: Vec<DVec3>,
    /// The leaf's splat support radius.
    pub radius: Vec<f64>,
    /// Largest splat radius.
    pub max_radius: f64,
    /// Corner → shared vertex (vertex mode; `u32::MAX` for splatted faces).
    pub corner_vertex: Vec<[u32; 3]>,
    /// Shared vertex positions.
    pub vertices: Vec<DVec3>,
    /// CSR offsets into [`Surfaces::adjacency`], one more than vertices.
    pub adjacency_offsets: Vec<u32>,
    /// Slots whose leaves' display radiance blends at each shared vertex: the faces around it,
    /// and for face clusters every cluster whose splat support holds the vertex.
    pub adjacency: Vec<u32>,
    /// Per input triangle (meshes in order): one of its slots, or `u32::MAX` if none.
    pub triangle_leaf: Vec<u32>,
    /// Per input triangle: its corners as shared vertices (vertex mode) or `u32::MAX`.
    pub triangle_vertices: Vec<[u32; 3]>,
    /// Whether a slot's triangle has shading normals (its mesh has `vn`); the others shade with
    /// their face normal exactly as without shading normals.
    pub shaded: Vec<bool>,
    /// Per slot: the triangle's vertex normals interpolated to the face's corners (not
    /// normalized, so that interpolating them across the face is interpolating across the
    /// triangle); the face normal three times where not [`Surfaces::shaded`].
    pub corner_normal: Vec<[DVec3; 3]>,
    /// The shading normal of each entry of [`Surfaces::adjacency`] at its shared vertex.
    pub adjacency_normal: Vec<DVec3>,
    /// The weight of each entry of [`Surfaces::adjacency`]: the face's leaf area, and for a
    /// cluster's support also the splat fall-off at the vertex, so that the display radiance of
    /// a dense mesh blends smoothly from cluster to cluster.
    pub adjacency_weight: Vec<f64>,
}

impl Surfaces {
    /// Classifies the input triangles of `sys`'s scene and builds the per-slot data.
    pub fn new(scene: &crate::Scene, sys: &System) -> Self {
        let classes = crate::clusters::classify(scene);
        let quantum = crate::clusters::vertex_quantum(scene);
        let key = |mesh: usize, p: DVec3| {
            let q = (p / quantum).round();
            (mesh, q.x as i64, q.y as i64, q.z as i64)
        };
        let first_tri = &classes.first_tri;
        let n = sys.leaves.len();
        let element_of = |li: usize| sys.leaf_element(li);
        let slots = sys.face_slots();
        let ns = slots.len();
        let mut s = Self {
            leaf: Vec::with_capacity(ns),
            corners: Vec::with_capacity(ns),
            normal: Vec::with_capacity(ns),
            mode: Vec::with_capacity(ns),
            surface: Vec::with_capacity(ns),
            splat_per_sample: scene.solver.splat_per_sample,
            direct_block: scene.solver.direct_block,
            center: Vec::with_capacity(ns),
            radius: Vec::with_capacity(ns),
            max_radius: 0.0,
            corner_vertex: Vec::with_capacity(ns),
            vertices: Vec::new(),
            adjacency_offsets: Vec::new(),
            adjacency: Vec::new(),
            triangle_leaf: vec![u32::MAX; classes.normals.len()],
            triangle_vertices: vec![[u32::MAX; 3]; classes.normals.len()],
            shaded: Vec::with_capacity(ns),
            corner_normal: Vec::with_capacity(ns),
            adjacency_normal: Vec::new(),
            adjacency_weight: Vec::new(),
        };
        let radius: Vec<f64> = (0..n)
            .map(|li| {
                let e = element_of(li);
                e.corner_points()
                    .map(|c| (c - e.center).length())
                    .fold(0.0, f64::max)
                    * SPLAT_RADIUS
            })
            .collect();
        let mut vertex_ids: HashMap<(usize, i64, i64, i64), u32> = HashMap::new();
        let mut lists: Vec<Vec<(u32, DVec3, f64)>> = Vec::new();
        // Shared vertices that a face cluster touches: their values come from the clusters'
        // supports (below), not only from the faces around them.
        let mut cluster_vertex: Vec<bool> = Vec::new();
        for (slot, &(li, k)) in slots.iter().enumerate() {
            let e = element_of(li as usize);
            let leaf = &sys.leaves[li as usize];
            let face = &e.faces[k as usize];
            let tri = first_tri[e.mesh as usize] + face.triangle;
            s.triangle_leaf[tri as usize] = s.triangle_leaf[tri as usize].min(slot as u32);
            s.leaf.push(li);
            s.corners.push(face.corners);
            s.normal.push(if e.is_cluster() {
                face.normal()
            } else {
                leaf.normal
            });
            s.center.push(e.center);
            s.radius.push(radius[li as usize]);
            s.surface.push(classes.surface[tri as usize]);
            let mesh = &scene.meshes[e.mesh as usize];
            let shaded = !mesh.normals.is_empty();
            let corner_normal = if shaded {
                normals_at(mesh, face.triangle as usize, &face.corners)
            } else {
                [s.normal[slot]; 3]
            };
            s.shaded.push(shaded);
            s.corner_normal.push(corner_normal);
            // A face cluster's faces blend by vertex interpolation whatever their kind: its
            // leaf is not one flat piece to splat.
            if classes.smooth[tri as usize] || e.is_cluster() {
                s.mode.push(MODE_VERTEX);
                let mut c = 0;
                s.corner_vertex.push(face.corners.map(|p| {
                    let id = *vertex_ids
                        .entry(key(e.mesh as usize, p))
                        .or_insert_with(|| {
                            s.vertices.push(p);
                            lists.push(Vec::new());
                            cluster_vertex.push(false);
                            (s.vertices.len() - 1) as u32
                        });
                    if e.is_cluster() {
                        cluster_vertex[id as usize] = true;
                    } else {
                        lists[id as usize].push((slot as u32, corner_normal[c], leaf.area));
                    }
                    c += 1;
                    id
                }));
            } else {
                s.mode.push(MODE_SPLAT);
                if slot < n {
                    s.max_radius = s.max_radius.max(radius[li as usize]);
                }
                s.corner_vertex.push([u32::MAX; 3]);
            }
        }
        s.add_cluster_supports(sys, &mut lists, &cluster_vertex);
        for (mi, m) in scene.meshes.iter().enumerate() {
            for (ti, t) in m.triangles.iter().enumerate() {
                let tri = (first_tri[mi] as usize) + ti;
                let slot = s.triangle_leaf[tri];
                if slot != u32::MAX && s.mode[slot as usize] == MODE_VERTEX {
                    s.triangle_vertices[tri] = t.map(|v| {
                        vertex_ids
                            .get(&key(mi, m.positions[v as usize]))
                            .copied()
                            .unwrap_or(u32::MAX)
                    });
                }
            }
        }
        s.adjacency_offsets.push(0);
        for l in lists {
            s.adjacency.extend(l.iter().map(|e| e.0));
            s.adjacency_normal.extend(l.iter().map(|e| e.1));
            s.adjacency_weight.extend(l.iter().map(|e| e.2));
            s.adjacency_offsets.push(s.adjacency.len() as u32);
        }
        s
    }

    /// For every vertex-mode face cluster, an entry at each shared vertex within its splat
    /// support that its faces reach through vertex-mode faces facing its way (a walk over the
    /// faces sharing vertices, so that support does not jump across a gap to another part of the
    /// mesh): weight the splat fall-off × the cluster's area, normal the face's shading normal at
    /// the vertex. A dense mesh's indirect light then blends smoothly between cluster centers
    /// instead of being constant over each cluster.
    fn add_cluster_supports(
        &self,
        sys: &System,
        lists: &mut [Vec<(u32, DVec3, f64)>],
        cluster_vertex: &[bool],
    ) {
        // Vertex-mode slots around each shared vertex.
        let mut around: Vec<Vec<u32>> = vec![Vec::new(); self.vertices.len()];
        for (slot, cv) in self.corner_vertex.iter().enumerate() {
            if self.mode[slot] == MODE_VERTEX {
                for &v in cv {
                    around[v as usize].push(slot as u32);
                }
            }
        }
        let n = sys.leaves.len();
        let mut first_of: Vec<Vec<u32>> = vec![Vec::new(); n];
        for (slot, &li) in self.leaf.iter().enumerate() {
            first_of[li as usize].push(slot as u32);
        }
        let mut seen_face = vec![u32::MAX; self.leaf.len()];
        let mut seen_vertex = vec![u32::MAX; self.vertices.len()];
        let mut stack = Vec::new();
        for (li, faces) in first_of.iter().enumerate() {
            if faces.len() < 2 || self.mode[li] != MODE_VERTEX {
                continue;
            }
            let leaf = &sys.leaves[li];
            let (c, r) = (self.center[li], self.radius[li]);
            stack.clear();
            for &f in faces {
                seen_face[f as usize] = li as u32;
                stack.push(f);
            }
            while let Some(f) = stack.pop() {
                for (k, &v) in self.corner_vertex[f as usize].iter().enumerate() {
                    let d = (self.vertices[v as usize] - c).length();
                    let w = splat_weight(d, r);
                    if w <= 0.0 {
                        continue;
                    }
                    if seen_vertex[v as usize] != li as u32 {
                        seen_vertex[v as usize] = li as u32;
                        if cluster_vertex[v as usize] {
                            let normal = self.corner_normal[f as usize][k];
                            lists[v as usize].push((li as u32, normal, w * leaf.area));
                        }
                    }
                    for &g in &around[v as usize] {
                        if seen_face[g as usize] != li as u32
                            && self.normal[g as usize].dot(leaf.normal) > 0.0
                        {
                            seen_face[g as usize] = li as u32;
                            stack.push(g);
                        }
                    }
                }
            }
        }
    }

    /// The (unnormalized) interpolated shading normal at barycentric `(u, v)` of slot `li`
    /// (weights `1 − u − v`, `u`, `v` on its corners).
    pub fn interpolated_normal(&self, li: usize, u: f64, v: f64) -> DVec3 {
        let n = &self.corner_normal[li];
        n[0] * (1.0 - u - v) + n[1] * u + n[2] * v
    }

    /// Number of leaves splatted (one splat per leaf, from its first slot).
    pub fn splat_count(&self) -> usize {
        self.splat_slots().count()
    }

    /// The slots splatted: the first slot of every splatted leaf.
    pub fn splat_slots(&self) -> impl Iterator<Item = u32> + '_ {
        (0..self.mode.len() as u32)
            .filter(|&i| self.leaf[i as usize] == i && self.mode[i as usize] == MODE_SPLAT)
    }
}

/// `mesh`'s vertex normals of triangle `t` interpolated (barycentrically, not normalized) to
/// `points` on it.
fn normals_at(mesh: &crate::scene::Mesh, t: usize, points: &[DVec3; 3]) -> [DVec3; 3] {
    let [a, b, c] = mesh.triangles[t].map(|v| mesh.positions[v as usize]);
    let n = mesh.normals[t];
    let cross = (b - a).cross(c - a);
    let area2 = cross.length_squared();
    points.map(|p| {
        let wb = (p - a).cross(c - a).dot(cross) / area2;
        let wc = (b - a).cross(p - a).dot(cross) / area2;
        n[0] * (1.0 - wb - wc) + n[1] * wb + n[2] * wc
    })
}

/// Smooth fall-off of a splat: `(1 − (d/R)²)²` inside the support, 0 outside.
pub fn splat_weight(d: f64, r: f64) -> f64 {
    let x = d / r;
    if x >= 1.0 {
        0.0
    } else {
        (1.0 - x * x) * (1.0 - x * x)
    }
}

/// Indirect radiance leaving leaf `li` toward the eye along `wo` (unit, exitant), read from
/// `I_total` in the bin toward the eye (0 behind the element).
pub fn display_radiance(sys: &System, i_total: &Table, li: usize, wo: DVec3) -> DVec3 {
    let leaf = &sys.leaves[li];
    if wo.dot(leaf.normal) <= 0.0 {
        return DVec3::ZERO;
    }
    display_radiance_in(sys, i_total, li, front_bin(&sys.bins, wo, leaf.normal, 1.0))
}

/// The bin toward the eye of a splatted sample whose face has unit normal `n`, seen along `dir`
/// (the eye direction for its shading normal); `None` where `dir` is behind the face. Found
/// once per sample: every leaf splatted onto it lies in its plane (the G-buffer stores it).
pub fn display_bin(sys: &System, dir: DVec3, n: DVec3) -> Option<usize> {
    (dir.dot(n) > 0.0).then(|| front_bin(&sys.bins, dir, n, 1.0))
}

/// [`display_radiance`] of leaf `li` in the bin `b` that [`display_bin`] found for the pixel.
pub fn display_radiance_in(sys: &System, i_total: &Table, li: usize, b: usize) -> DVec3 {
    let leaf = &sys.leaves[li];
    let cb = sys.bins.centers[b].dot(leaf.normal);
    if cb <= 0.0 {
        return DVec3::ZERO;
    }
    i_total.row(leaf.node as usize)[b] / (leaf.area * leaf.cos_norm * cb)
}

/// Per-vertex values for an eye at `eye`: the weighted mean ([`Surfaces::adjacency_weight`]) of
/// the display radiance of the leaves listed at each shared vertex that face the eye, each read in the bin of
/// [`eye_direction`] for its shading normal at the vertex.
pub fn vertex_values(surf: &Surfaces, sys: &System, i_total: &Table, eye: DVec3) -> Vec<DVec3> {
    (0..surf.vertices.len())
        .map(|v| {
            let wo = (eye - surf.vertices[v]).normalize_or_zero();
            let (a, b) = (
                surf.adjacency_offsets[v] as usize,
                surf.adjacency_offsets[v + 1] as usize,
            );
            let (mut sum, mut w) = (DVec3::ZERO, 0.0);
            for ((&slot, &ns), &weight) in surf.adjacency[a..b]
                .iter()
                .zip(&surf.adjacency_normal[a..b])
                .zip(&surf.adjacency_weight[a..b])
            {
                let li = surf.leaf[slot as usize] as usize;
                let leaf = &sys.leaves[li];
                if wo.dot(leaf.normal) > 0.0 {
                    // The bin toward the eye as the vertex's shading normal sees it.
                    let dir = if surf.shaded[slot as usize] {
                        let ns = shading_normal(ns, leaf.normal, wo);
                        eye_direction(wo, ns, leaf.normal)
                    } else {
                        wo
                    };
                    sum += display_radiance(sys, i_total, li, dir) * weight;
                    w += weight;
                }
            }
            if w > 0.0 {
                sum / w
            } else {
                DVec3::ZERO
            }
        })
        .collect()
}
