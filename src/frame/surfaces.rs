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

/// Adjacent input triangles whose normals differ by more than this (and less than
/// [`SMOOTH_MAX_DEG`]) mark a smooth, vertex-interpolated mesh.
pub const COPLANAR_DEG: f64 = 2.0;
/// Creases sharper than this are edges between flat surfaces, not smooth tessellation.
pub const SMOOTH_MAX_DEG: f64 = 40.0;
/// Splat support radius relative to the element's circumradius about its center.
pub const SPLAT_RADIUS: f64 = 1.5;

/// Shading mode of an element.
pub const MODE_SPLAT: u32 = 0;
/// Vertex interpolation.
pub const MODE_VERTEX: u32 = 1;

/// Per-leaf screen-space data, in leaf-slot order.
#[derive(Debug, Clone)]
pub struct Surfaces {
    /// [`MODE_SPLAT`] or [`MODE_VERTEX`].
    pub mode: Vec<u32>,
    /// Flat-surface id (splats only blend within one).
    pub surface: Vec<u32>,
    /// Element center.
    pub center: Vec<DVec3>,
    /// Splat support radius.
    pub radius: Vec<f64>,
    /// Largest splat radius.
    pub max_radius: f64,
    /// Corner → shared vertex (vertex mode; `u32::MAX` for splatted elements).
    pub corner_vertex: Vec<[u32; 3]>,
    /// Shared vertex positions.
    pub vertices: Vec<DVec3>,
    /// CSR offsets into [`Surfaces::adjacency`], one more than vertices.
    pub adjacency_offsets: Vec<u32>,
    /// Leaf slots around each shared vertex.
    pub adjacency: Vec<u32>,
    /// Per input triangle (meshes in order): one of its leaves, or `u32::MAX` if none.
    pub triangle_leaf: Vec<u32>,
    /// Per input triangle: its corners as shared vertices (vertex mode) or `u32::MAX`.
    pub triangle_vertices: Vec<[u32; 3]>,
    /// Whether a leaf's triangle has shading normals (its mesh has `vn`); the others shade with
    /// their face normal exactly as without shading normals.
    pub shaded: Vec<bool>,
    /// Per leaf: the triangle's vertex normals interpolated to the element's corners (not
    /// normalized, so that interpolating them across the element is interpolating across the
    /// triangle); the face normal three times where not [`Surfaces::shaded`].
    pub corner_normal: Vec<[DVec3; 3]>,
    /// The shading normal of each entry of [`Surfaces::adjacency`] at its shared vertex.
    pub adjacency_normal: Vec<DVec3>,
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

impl Surfaces {
    /// Classifies the input triangles of `sys`'s scene and builds the per-leaf data.
    pub fn new(scene: &crate::Scene, sys: &System) -> Self {
        let (lo, hi) = scene.bounds();
        let quantum = ((hi - lo).length() * 1e-7).max(1e-12);
        let key = |mesh: usize, p: DVec3| {
            let q = (p / quantum).round();
            (mesh, q.x as i64, q.y as i64, q.z as i64)
        };
        // Input triangles, numbered across meshes, and the triangles around each vertex position.
        let mut first_tri = Vec::new();
        let mut normals = Vec::new();
        let mut offsets = Vec::new();
        let mut around: HashMap<(usize, i64, i64, i64), Vec<u32>> = HashMap::new();
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
                    if c >= cos_flat
                        && (offsets[a as usize] - offsets[b as usize]).abs() < plane_eps
                    {
                        uf.union(a, b);
                    } else if c > cos_smooth && c < cos_flat {
                        smooth[a as usize] = true;
                        smooth[b as usize] = true;
                    }
                }
            }
        }
        let n = sys.leaves.len();
        let mut s = Self {
            mode: Vec::with_capacity(n),
            surface: Vec::with_capacity(n),
            center: Vec::with_capacity(n),
            radius: Vec::with_capacity(n),
            max_radius: 0.0,
            corner_vertex: Vec::with_capacity(n),
            vertices: Vec::new(),
            adjacency_offsets: Vec::new(),
            adjacency: Vec::new(),
            triangle_leaf: vec![u32::MAX; normals.len()],
            triangle_vertices: vec![[u32::MAX; 3]; normals.len()],
            shaded: Vec::with_capacity(n),
            corner_normal: Vec::with_capacity(n),
            adjacency_normal: Vec::new(),
        };
        let mut vertex_ids: HashMap<(usize, i64, i64, i64), u32> = HashMap::new();
        let mut lists: Vec<Vec<(u32, DVec3)>> = Vec::new();
        for (li, leaf) in sys.leaves.iter().enumerate() {
            let e = &sys.elements[sys.hierarchy.element(leaf.node).expect("leaf") as usize];
            let tri = first_tri[e.mesh as usize] + e.triangle;
            let r = e
                .corners
                .iter()
                .map(|c| (*c - e.center).length())
                .fold(0.0, f64::max)
                * SPLAT_RADIUS;
            s.triangle_leaf[tri as usize] = s.triangle_leaf[tri as usize].min(li as u32);
            s.center.push(e.center);
            s.radius.push(r);
            s.surface.push(uf.find(tri));
            let mesh = &scene.meshes[e.mesh as usize];
            let shaded = !mesh.normals.is_empty();
            let corner_normal = if shaded {
                normals_at(mesh, e.triangle as usize, &e.corners)
            } else {
                [leaf.normal; 3]
            };
            s.shaded.push(shaded);
            s.corner_normal.push(corner_normal);
            if smooth[tri as usize] {
                s.mode.push(MODE_VERTEX);
                let mut k = 0;
                s.corner_vertex.push(e.corners.map(|c| {
                    let id = *vertex_ids
                        .entry(key(e.mesh as usize, c))
                        .or_insert_with(|| {
                            s.vertices.push(c);
                            lists.push(Vec::new());
                            (s.vertices.len() - 1) as u32
                        });
                    lists[id as usize].push((li as u32, corner_normal[k]));
                    k += 1;
                    id
                }));
            } else {
                s.mode.push(MODE_SPLAT);
                s.max_radius = s.max_radius.max(r);
                s.corner_vertex.push([u32::MAX; 3]);
            }
        }
        for (mi, m) in scene.meshes.iter().enumerate() {
            for (ti, t) in m.triangles.iter().enumerate() {
                let tri = (first_tri[mi] as usize) + ti;
                if smooth[tri] {
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
            s.adjacency_offsets.push(s.adjacency.len() as u32);
        }
        s
    }

    /// The (unnormalized) interpolated shading normal at barycentric `(u, v)` of leaf `li`
    /// (weights `1 − u − v`, `u`, `v` on its corners).
    pub fn interpolated_normal(&self, li: usize, u: f64, v: f64) -> DVec3 {
        let n = &self.corner_normal[li];
        n[0] * (1.0 - u - v) + n[1] * u + n[2] * v
    }

    /// Number of leaves splatted.
    pub fn splat_count(&self) -> usize {
        self.mode.iter().filter(|&&m| m == MODE_SPLAT).count()
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
    let b = front_bin(&sys.bins, wo, leaf.normal, 1.0);
    let cb = sys.bins.centers[b].dot(leaf.normal);
    i_total.row(leaf.node as usize)[b] / (leaf.area * leaf.cos_norm * cb)
}

/// Per-vertex values for an eye at `eye`: the area-weighted mean of the display radiance of the
/// elements around each shared vertex that face the eye, each read in the bin of
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
            for (&li, &ns) in surf.adjacency[a..b]
                .iter()
                .zip(&surf.adjacency_normal[a..b])
            {
                let leaf = &sys.leaves[li as usize];
                if wo.dot(leaf.normal) > 0.0 {
                    // The bin toward the eye as the vertex's shading normal sees it.
                    let dir = if surf.shaded[li as usize] {
                        let ns = shading_normal(ns, leaf.normal, wo);
                        eye_direction(wo, ns, leaf.normal)
                    } else {
                        wo
                    };
                    sum += display_radiance(sys, i_total, li as usize, dir) * leaf.area;
                    w += leaf.area;
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
