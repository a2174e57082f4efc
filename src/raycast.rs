//! Ray casting against the leaf elements (the `bvh` crate's BVH, f64 triangle tests): the CPU
//! frame's camera rays, the CPU shadow maps and, later, the path-traced reference.

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
    /// Leaf slot (index into [`System::leaves`]) of the element hit.
    pub leaf: u32,
    /// Distance along the (unit) ray direction.
    pub t: f64,
    /// Barycentric weight of the element's second corner.
    pub u: f64,
    /// Barycentric weight of the element's third corner.
    pub v: f64,
}

struct Shape {
    corners: [DVec3; 3],
    node: usize,
}

impl Bounded<f32, 3> for Shape {
    fn aabb(&self) -> Aabb<f32, 3> {
        let lo = self.corners[0].min(self.corners[1]).min(self.corners[2]);
        let hi = self.corners[0].max(self.corners[1]).max(self.corners[2]);
        // Widen by an f32 ulp-scale margin so the f64 test never loses a hit to AABB rounding.
        let pad = 1e-5 * (1.0 + lo.abs().max(hi.abs()).max_element());
        Aabb::with_bounds(
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
        )
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

impl RayCaster {
    /// Builds the BVH over the leaves of `sys` (in leaf-slot order).
    pub fn new(sys: &System) -> Self {
        let mut shapes: Vec<Shape> = sys
            .leaves
            .iter()
            .map(|l| {
                let e = sys.hierarchy.element(l.node).expect("leaf has an element") as usize;
                Shape {
                    corners: sys.elements[e].corners,
                    node: 0,
                }
            })
            .collect();
        let bvh = Bvh::build(&mut shapes);
        Self { shapes, bvh }
    }

    fn candidates(&self, o: DVec3, d: DVec3, mut f: impl FnMut(usize, &Shape)) {
        let ray = Ray::new(
            Point3::new(o.x as f32, o.y as f32, o.z as f32),
            Vector3::new(d.x as f32, d.y as f32, d.z as f32),
        );
        for s in self.bvh.traverse_iterator(&ray, &self.shapes) {
            // Index of `s` in `shapes` (the iterator yields references into the slice).
            let i = (s as *const Shape as usize - self.shapes.as_ptr() as usize)
                / std::mem::size_of::<Shape>();
            f(i, s);
        }
    }

    /// Nearest hit along the unit direction `d` with `t_min < t < t_max`.
    pub fn closest(&self, o: DVec3, d: DVec3, t_min: f64, t_max: f64) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        self.candidates(o, d, |i, s| {
            if let Some((t, u, v)) = intersect(&s.corners, o, d, t_min) {
                if t < t_max && best.is_none_or(|b| t < b.t) {
                    best = Some(Hit {
                        leaf: i as u32,
                        t,
                        u,
                        v,
                    });
                }
            }
        });
        best
    }

    /// Corners of the element in leaf slot `leaf`.
    pub fn corners(&self, leaf: u32) -> &[DVec3; 3] {
        &self.shapes[leaf as usize].corners
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
}
