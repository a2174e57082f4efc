//! Ray casting against triangles (the `bvh` crate's BVH, f64 triangle tests): the leaf elements
//! for the CPU frame's camera rays and shadow maps, the input triangles for the path-traced
//! reference. Closest hits walk the BVH nearest box first and stop once no box can hold a nearer
//! hit; occlusion queries stop at the first hit.

use crate::system::System;
use bvh::aabb::{Aabb, Bounded};
use bvh::bounding_hierarchy::BHShape;
use bvh::bvh::Bvh;
use bvh::ray::Ray;
use glam::DVec3;
use nalgebra::{Point3, Vector3};

/// A ray–triangle hit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// What was hit: the leaf (index into [`System::leaves`]) for [`RayCaster::new`], the index
    /// into the list given to [`RayCaster::from_triangles`].
    pub leaf: u32,
    /// The triangle hit: the face slot ([`System::face_slots`]) for [`RayCaster::new`], as
    /// `leaf` for [`RayCaster::from_triangles`].
    pub shape: u32,
    /// Distance along the (unit) ray direction.
    pub t: f64,
    /// Barycentric weight of the element's second corner.
    pub u: f64,
    /// Barycentric weight of the element's third corner.
    pub v: f64,
}

struct Shape {
    corners: [DVec3; 3],
    /// Padded box, computed once: closest-hit queries read it for every candidate.
    bounds: Aabb<f32, 3>,
    node: usize,
}

impl Bounded<f32, 3> for Shape {
    fn aabb(&self) -> Aabb<f32, 3> {
        self.bounds
    }
}

impl Shape {
    fn new(corners: [DVec3; 3]) -> Self {
        let lo = corners[0].min(corners[1]).min(corners[2]);
        let hi = corners[0].max(corners[1]).max(corners[2]);
        // Widen by an f32 ulp-scale margin so the f64 test never loses a hit to AABB rounding.
        let pad = 1e-5 * (1.0 + lo.abs().max(hi.abs()).max_element());
        let bounds = Aabb::with_bounds(
            Point3::new(
                (lo.x - pad) as f32,
                (lo.y - pad) as f32,
                (lo.z - pad) as f32,
            ),
            Point3::new(
                (hi.x + pad) as f32,
                (hi.y + pad) as f32,
                (hi.z + pad) as f32,
            ),
        );
        Self {
            corners,
            bounds,
            node: 0,
        }
    }
}

impl BHShape<f32, 3> for Shape {
    fn set_bh_node_index(&mut self, i: usize) {
        self.node = i;
    }
    fn bh_node_index(&self) -> usize {
        self.node
    }
}

/// Closest-hit and occlusion queries over every leaf element (both faces are opaque).
pub struct RayCaster {
    shapes: Vec<Shape>,
    /// What each shape belongs to (empty: itself).
    owner: Vec<u32>,
    bvh: Bvh<f32, 3>,
}

/// Two-sided Möller–Trumbore: `(t, u, v)` for `t > t_min`.
fn intersect(c: &[DVec3; 3], o: DVec3, d: DVec3, t_min: f64) -> Option<(f64, f64, f64)> {
    let e1 = c[1] - c[0];
    let e2 = c[2] - c[0];
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-300 {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - c[0];
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > t_min).then_some((t, u, v))
}

/// Distance along `d` at which the ray enters `b` (0 when it starts inside), in f64.
fn entry(b: &Aabb<f32, 3>, o: DVec3, d: DVec3) -> f64 {
    let mut t0 = 0.0f64;
    for k in 0..3 {
        let (lo, hi) = (b.min[k] as f64, b.max[k] as f64);
        if d[k] != 0.0 {
            let (a, c) = ((lo - o[k]) / d[k], (hi - o[k]) / d[k]);
            t0 = t0.max(a.min(c));
        }
    }
    t0
}

impl RayCaster {
    /// Builds the BVH over the faces of the leaves of `sys` (in face-slot order); hits report
    /// the leaf and the face slot.
    pub fn new(sys: &System) -> Self {
        let slots = sys.face_slots();
        let mut c = Self::from_triangles(
            slots
                .iter()
                .map(|&(li, k)| sys.leaf_element(li as usize).faces[k as usize].corners)
                .collect(),
        );
        c.owner = slots.iter().map(|s| s.0).collect();
        c
    }

    /// Builds the BVH over `triangles`; hits report indices into this list.
    pub fn from_triangles(triangles: Vec<[DVec3; 3]>) -> Self {
        let mut shapes: Vec<Shape> = triangles.into_iter().map(Shape::new).collect();
        let bvh = Bvh::build(&mut shapes);
        Self {
            shapes,
            owner: Vec::new(),
            bvh,
        }
    }

    fn ray(o: DVec3, d: DVec3) -> Ray<f32, 3> {
        Ray::new(
            Point3::new(o.x as f32, o.y as f32, o.z as f32),
            Vector3::new(d.x as f32, d.y as f32, d.z as f32),
        )
    }

    fn index(&self, s: &Shape) -> usize {
        // The iterators yield references into `shapes`.
        (s as *const Shape as usize - self.shapes.as_ptr() as usize) / std::mem::size_of::<Shape>()
    }

    /// Nearest hit along the unit direction `d` with `t_min < t < t_max`.
    pub fn closest(&self, o: DVec3, d: DVec3, t_min: f64, t_max: f64) -> Option<Hit> {
        if self.shapes.is_empty() {
            return None;
        }
        let ray = Self::ray(o, d);
        let mut best: Option<Hit> = None;
        // Shapes come in order of their boxes' entry distance: once a box starts beyond the
        // best hit, none of the rest can be nearer.
        // Back-to-back twins (a two-sided surface's two faces) meet the ray at one t: the face
        // turned toward the ray's origin wins the tie, as in the G-buffer (gbuffer.frag).
        let faces = |c: &[DVec3; 3]| (c[1] - c[0]).cross(c[2] - c[0]).dot(d) < 0.0;
        let mut best_faces = false;
        for s in self.bvh.nearest_traverse_iterator(&ray, &self.shapes) {
            let limit = best.map_or(t_max, |b| b.t);
            let tie = limit * (1.0 + 1e-6) + 1e-12;
            if entry(&s.bounds, o, d) > tie {
                break;
            }
            if let Some((t, u, v)) = intersect(&s.corners, o, d, t_min) {
                let f = faces(&s.corners);
                let wins = t < limit && !(best_faces && !f && t > limit * (1.0 - 1e-6));
                let ties_better =
                    best.is_some() && f && !best_faces && t <= tie && t >= limit * (1.0 - 1e-6);
                if wins || ties_better {
                    best_faces = f;
                    let shape = self.index(s) as u32;
                    best = Some(Hit {
                        leaf: self.owner.get(shape as usize).copied().unwrap_or(shape),
                        shape,
                        t,
                        u,
                        v,
                    });
                }
            }
        }
        best
    }

    /// True when something lies along the unit direction `d` with `t_min < t < t_max`.
    pub fn occluded(&self, o: DVec3, d: DVec3, t_min: f64, t_max: f64) -> bool {
        if self.shapes.is_empty() {
            return false;
        }
        let ray = Self::ray(o, d);
        self.bvh
            .traverse_iterator(&ray, &self.shapes)
            .any(|s| intersect(&s.corners, o, d, t_min).is_some_and(|(t, _, _)| t < t_max))
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.shapes.len()
    }

    /// True when there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.shapes.is_empty()
    }

    /// Corners of triangle `shape` ([`Hit::shape`]).
    pub fn corners(&self, shape: u32) -> &[DVec3; 3] {
        &self.shapes[shape as usize].corners
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_sided_intersection_and_barycentrics() {
        let c = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let (t, u, v) = intersect(&c, DVec3::new(0.25, 0.5, 2.0), -DVec3::Z, 0.0).unwrap();
        assert!((t - 2.0).abs() < 1e-12 && (u - 0.25).abs() < 1e-12 && (v - 0.5).abs() < 1e-12);
        assert!(intersect(&c, DVec3::new(0.25, 0.5, -2.0), DVec3::Z, 0.0).is_some());
        assert!(intersect(&c, DVec3::new(0.75, 0.5, 2.0), -DVec3::Z, 0.0).is_none());
    }

    #[test]
    fn closest_hit_is_the_nearest_of_many_and_matches_brute_force() {
        // A stack of 40 parallel squares, randomly jittered, queried along many rays.
        let mut tris = Vec::new();
        for k in 0..40 {
            let z = k as f64 * 0.1 + 0.013 * ((k * 7 % 5) as f64);
            let q = [
                DVec3::new(-1.0, -1.0, z),
                DVec3::new(1.0, -1.0, z),
                DVec3::new(1.0, 1.0, z),
                DVec3::new(-1.0, 1.0, z),
            ];
            tris.push([q[0], q[1], q[2]]);
            tris.push([q[0], q[2], q[3]]);
        }
        let rc = RayCaster::from_triangles(tris.clone());
        for i in 0..200 {
            let a = i as f64 * 0.61;
            let o = DVec3::new(0.3 * a.sin(), 0.3 * a.cos(), -1.0 + 6.0 * ((i % 3) as f64));
            let d = DVec3::new(
                0.2 * a.cos(),
                0.15 * a.sin(),
                if i % 3 == 0 { 1.0 } else { -1.0 },
            )
            .normalize();
            let brute = tris
                .iter()
                .filter_map(|c| intersect(c, o, d, 1e-9))
                .map(|h| h.0)
                .fold(f64::INFINITY, f64::min);
            let got = rc
                .closest(o, d, 1e-9, f64::INFINITY)
                .map_or(f64::INFINITY, |h| h.t);
            assert!(
                (got - brute).abs() < 1e-12 || got == brute,
                "ray {i}: {got} vs {brute}"
            );
            assert_eq!(rc.occluded(o, d, 1e-9, f64::INFINITY), brute.is_finite());
            if brute.is_finite() {
                assert!(!rc.occluded(o, d, 1e-9, brute * 0.999));
            }
        }
    }
}
