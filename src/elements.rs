//! Leaf elements: input triangles split by longest-edge bisection until no edge exceeds the
//! element size. Bisection keeps angles bounded, so sliver input faces get better, not worse.

use crate::error::{Error, Result};
use crate::scene::{Scene, SolverSettings};
use glam::DVec3;

/// One input triangle (or a bisected piece of one) of an element.
#[derive(Debug, Clone, PartialEq)]
pub struct Face {
    /// Corners (world space, counter-clockwise seen from the front).
    pub corners: [DVec3; 3],
    /// Triangle of the element's mesh the face came from.
    pub triangle: u32,
}

impl Face {
    /// Area-weighted normal: the cross product of two edges, halved (its length is the area).
    pub fn area_normal(&self) -> DVec3 {
        let [a, b, c] = self.corners;
        0.5 * (b - a).cross(c - a)
    }

    /// Area.
    pub fn area(&self) -> f64 {
        self.area_normal().length()
    }

    /// Unit front normal.
    pub fn normal(&self) -> DVec3 {
        self.area_normal().normalize_or_zero()
    }

    /// Centroid.
    pub fn center(&self) -> DVec3 {
        (self.corners[0] + self.corners[1] + self.corners[2]) / 3.0
    }
}

/// A leaf element of the finite-element discretization: a piece of one input triangle cut by
/// bisection, or a face cluster of a dense mesh's small triangles ([`crate::clusters`]), which
/// the solver treats as one plane through its area-weighted centroid with its area-weighted
/// mean normal.
#[derive(Debug, Clone, PartialEq)]
pub struct Element {
    /// The faces (at least one; one for a bisected piece).
    pub faces: Vec<Face>,
    /// Area-weighted centroid: the collocation point.
    pub center: DVec3,
    /// Unit front normal (the faces' area-weighted mean).
    pub normal: DVec3,
    /// Area (of all faces).
    pub area: f64,
    /// Index into the scene's materials.
    pub material: u32,
    /// Mesh the element came from.
    pub mesh: u32,
    /// Whether light arriving at its back is blocked: false on the surface of a closed solid
    /// seen from outside ([`crate::solids`]).
    pub blocks_back: bool,
}

impl Element {
    fn new(corners: [DVec3; 3], material: u32, mesh: u32, triangle: u32) -> Self {
        Self::from_faces(vec![Face { corners, triangle }], material, mesh)
    }

    /// The element over `faces` (at least one), its center, normal and area derived from them.
    pub fn from_faces(faces: Vec<Face>, material: u32, mesh: u32) -> Self {
        let mut e = Self {
            faces,
            center: DVec3::ZERO,
            normal: DVec3::ZERO,
            area: 0.0,
            material,
            mesh,
            blocks_back: true,
        };
        e.update_geometry();
        e
    }

    /// Recomputes center, normal and area from the faces (after they moved).
    pub fn update_geometry(&mut self) {
        if let [f] = self.faces.as_slice() {
            // One face: exactly the triangle's own centroid, normal and area.
            let [a, b, c] = f.corners;
            let cr = (b - a).cross(c - a);
            self.area = 0.5 * cr.length();
            self.center = (a + b + c) / 3.0;
            self.normal = cr.normalize();
            return;
        }
        let (mut an, mut area, mut moment) = (DVec3::ZERO, 0.0, DVec3::ZERO);
        for f in &self.faces {
            let v = f.area_normal();
            let a = v.length();
            an += v;
            area += a;
            moment += f.center() * a;
        }
        self.area = area;
        self.center = moment / area;
        self.normal = an.normalize();
    }

    /// Every face corner.
    pub fn corner_points(&self) -> impl Iterator<Item = DVec3> + '_ {
        self.faces.iter().flat_map(|f| f.corners)
    }

    /// The first face's triangle (the element's only one unless it is a cluster).
    pub fn triangle(&self) -> u32 {
        self.faces[0].triangle
    }

    /// Whether `other` is made of the same input triangles (the same element, maybe moved).
    pub fn same_faces(&self, other: &Element) -> bool {
        self.mesh == other.mesh
            && self.faces.len() == other.faces.len()
            && self
                .faces
                .iter()
                .zip(&other.faces)
                .all(|(a, b)| a.triangle == b.triangle)
    }

    /// A point on the element for `(u, v)` in the unit square: uniform by area over its faces
    /// (`u` picks the face, then is stretched back to [0, 1) for the point on it).
    pub fn point(&self, u: f64, v: f64) -> DVec3 {
        let pick = |c: &[DVec3; 3], u: f64| {
            let s = u.sqrt();
            c[0] * (1.0 - s) + c[1] * (s * (1.0 - v)) + c[2] * (s * v)
        };
        if let [f] = self.faces.as_slice() {
            return pick(&f.corners, u);
        }
        let mut t = u * self.area;
        for f in &self.faces {
            let a = f.area();
            if t < a || std::ptr::eq(f, self.faces.last().unwrap()) {
                return pick(&f.corners, (t / a).clamp(0.0, 1.0));
            }
            t -= a;
        }
        unreachable!("an element has at least one face")
    }

    /// Whether the element is a face cluster of several triangles.
    pub fn is_cluster(&self) -> bool {
        self.faces.len() > 1
    }
}

fn longest_edge(t: &[DVec3; 3]) -> (usize, f64) {
    let len = |i: usize| (t[(i + 1) % 3] - t[i]).length();
    let longest = len(0).max(len(1)).max(len(2));
    // Edges equal but for rounding (legs of right isosceles triangles) are a tie, broken by
    // position (the last), so that the same mesh in other units splits the same way.
    let i = (0..3)
        .rev()
        .find(|&i| len(i) >= longest * (1.0 - 1e-9))
        .unwrap_or(0);
    (i, longest)
}

/// Bisections below one input triangle never go deeper than this. float64 tells midpoints
/// apart down to ~2^-52 of the coordinates' magnitude, about 53 halvings of the longest edge
/// at a few levels each; a deeper path cannot reach the size (sizes the loader accepts, at
/// least 1e-9 of the magnitude, need some 100 levels at most).
pub const MAX_BISECTION_DEPTH: usize = 1024;

/// A lower bound on the leaves bisection makes of a triangle with longest edge `longest` and
/// area `area`: a leaf has no edge over `size`, so at most the equilateral area √3/4·size², and
/// the longest edge alone is cut into at least `longest / size` pieces. Used to refuse absurd
/// sizes before anything is subdivided.
pub fn leaf_lower_bound(longest: f64, area: f64, size: f64) -> f64 {
    let leaf_area = 3f64.sqrt() / 4.0 * size * size;
    (area / leaf_area).max(longest / size).max(1.0)
}

/// A lower bound on the elements of `scene` at element size `size`: [`leaf_lower_bound`] summed
/// over the triangles bisection cuts, and for the small ones (which may join face clusters) their
/// share of the largest cluster's area.
pub fn estimate_elements(scene: &Scene, size: f64) -> f64 {
    scene
        .triangle_corners()
        .map(|[a, b, c]| {
            let longest = (b - a).length().max((c - b).length()).max((a - c).length());
            let area = 0.5 * (b - a).cross(c - a).length();
            if longest <= size {
                // It may join a face cluster: a disc of radius CLUSTER_RADIUS·size at most.
                let r = crate::clusters::CLUSTER_RADIUS * size;
                (area / (std::f64::consts::PI * r * r)).min(1.0)
            } else {
                leaf_lower_bound(longest, area, size)
            }
        })
        .sum()
}

/// The two halves of `t` cut at the midpoint of edge `i`, or `None` when the midpoint rounds
/// onto an end (the coordinates cannot resolve a finer split).
fn split(t: [DVec3; 3], i: usize) -> Option<([DVec3; 3], [DVec3; 3])> {
    let (p, q, r) = (t[i], t[(i + 1) % 3], t[(i + 2) % 3]);
    let m = (p + q) * 0.5;
    (m != p && m != q).then_some(([p, m, r], [m, q, r]))
}

/// Why a triangle cannot be bisected down to `size`.
fn unreachable_size(size: f64, t: &[DVec3; 3]) -> Error {
    Error::Setting {
        field: "element_size",
        message: format!(
            "element size {size:?} is finer than float64 coordinates can bisect the triangle {:?} to; use a larger element size",
            t.map(|p| p.to_array())
        ),
    }
}

/// Bisects `t` until no edge exceeds `size`, calling `leaf` on each piece in depth-first order
/// (first half before second); stops with `Ok(false)` once `leaf` returns false. An explicit
/// stack (not recursion): the depth depends on the input.
fn bisect(t: [DVec3; 3], size: f64, mut leaf: impl FnMut([DVec3; 3]) -> bool) -> Result<bool> {
    let mut stack = vec![(t, 0usize)];
    while let Some((t, depth)) = stack.pop() {
        let (i, len) = longest_edge(&t);
        if len <= size {
            if !leaf(t) {
                return Ok(false);
            }
            continue;
        }
        match split(t, i) {
            Some((a, b)) if depth < MAX_BISECTION_DEPTH && len.is_finite() => {
                stack.push((b, depth + 1));
                stack.push((a, depth + 1));
            }
            _ => return Err(unreachable_size(size, &t)),
        }
    }
    Ok(true)
}

/// Splits every triangle of the scene into elements no longer than `settings.element_size`.
/// Refuses (before allocating) if the count would exceed `settings.max_elements` or what this
/// machine can hold ([`crate::scene::max_elements_limit`]).
pub fn build_elements(scene: &Scene, settings: &SolverSettings) -> Result<Vec<Element>> {
    let size = settings.element_size;
    if !(size.is_finite() && size > 0.0) {
        return Err(Error::Setting {
            field: "element_size",
            message: format!("element size must be a positive finite number, got {size:?}"),
        });
    }
    let limit = settings
        .max_elements
        .min(crate::scene::max_elements_limit());
    let too_many = |at_least: f64| {
        Error::Setting {
        field: "element_size",
        message: format!(
            "element size {size:?} would create {} elements, more than {limit} (solver.max_elements, or what this machine can hold); use a larger element size",
            if at_least.is_finite() { format!("at least {at_least:.3e}") } else { "unboundedly many".into() }
        ),
    }
    };
    // The area bound first: counting leaf by leaf would take as long as the count is large.
    let estimate = estimate_elements(scene, size);
    if !(estimate <= limit as f64) {
        return Err(too_many(estimate));
    }
    // Small triangles of dense meshes join face clusters, one element each.
    let solid = crate::solids::solid_triangles(scene);
    let groups = if settings.face_clusters {
        crate::clusters::face_clusters(scene, &crate::clusters::classify(scene), &solid, size)
    } else {
        scene
            .meshes
            .iter()
            .map(|m| vec![None; m.triangles.len()])
            .collect()
    };
    let mut count = 0usize;
    for (mi, m) in scene.meshes.iter().enumerate() {
        for (ti, tri) in m.triangles.iter().enumerate() {
            if let Some(seed) = groups[mi][ti] {
                count += (seed as usize == ti) as usize;
                if count > limit {
                    return Err(too_many((limit + 1) as f64));
                }
                continue;
            }
            let complete = bisect(tri.map(|v| m.positions[v as usize]), size, |_| {
                count += 1;
                count <= limit
            })?;
            if !complete {
                return Err(too_many((limit + 1) as f64));
            }
        }
    }
    let mut elements = Vec::with_capacity(count);
    for (mi, m) in scene.meshes.iter().enumerate() {
        // Each cluster's faces, gathered under its seed.
        let mut members: std::collections::HashMap<u32, Vec<Face>> = Default::default();
        for (ti, g) in groups[mi].iter().enumerate() {
            if let Some(seed) = g {
                members.entry(*seed).or_default().push(Face {
                    corners: m.triangles[ti].map(|v| m.positions[v as usize]),
                    triangle: ti as u32,
                });
            }
        }
        for (ti, tri) in m.triangles.iter().enumerate() {
            match groups[mi][ti] {
                Some(seed) if seed as usize == ti => {
                    let faces = members.remove(&seed).unwrap_or_default();
                    let mut e = Element::from_faces(faces, m.material[ti], mi as u32);
                    e.blocks_back = !solid[mi][ti];
                    elements.push(e);
                }
                Some(_) => {}
                None => {
                    bisect(tri.map(|v| m.positions[v as usize]), size, |p| {
                        let mut e = Element::new(p, m.material[ti], mi as u32, ti as u32);
                        e.blocks_back = !solid[mi][ti];
                        elements.push(e);
                        true
                    })?;
                }
            }
        }
    }
    Ok(elements)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Material;

    #[test]
    fn subdivision_preserves_area_and_respects_size() {
        let mut s = Scene::empty();
        let mat = s.add_material(Material::diffuse("w", 0.5));
        let p = vec![
            DVec3::ZERO,
            DVec3::new(3.0, 0.0, 0.0),
            DVec3::new(0.0, 0.1, 2.0),
        ];
        s.add_mesh("t", p.clone(), vec![[0, 1, 2]], mat);
        s.solver.element_size = 0.3;
        let els = build_elements(&s, &s.solver).unwrap();
        let area: f64 = els.iter().map(|e| e.area).sum();
        let want = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length();
        assert!((area - want).abs() < 1e-12 * want.max(1.0));
        let n0 = els[0].normal;
        for e in &els {
            assert!(longest_edge(&e.faces[0].corners).1 <= 0.3 + 1e-12);
            assert!(
                (e.normal - n0).length() < 1e-9,
                "bisection keeps orientation"
            );
        }
        s.solver.max_elements = 10;
        let err = build_elements(&s, &s.solver).unwrap_err().to_string();
        assert!(err.contains("element_size"), "{err}");
    }

    /// The recursion `build_elements` replaced; its leaf order is what the goldens depend on.
    fn recursive(t: [DVec3; 3], size: f64, out: &mut Vec<[DVec3; 3]>) {
        let (i, len) = longest_edge(&t);
        if len <= size {
            out.push(t);
        } else {
            let (a, b) = split(t, i).unwrap();
            recursive(a, size, out);
            recursive(b, size, out);
        }
    }

    #[test]
    fn explicit_stack_keeps_the_recursive_leaf_order() {
        let tris = [
            [
                DVec3::ZERO,
                DVec3::new(3.0, 0.0, 0.0),
                DVec3::new(0.0, 0.1, 2.0),
            ],
            // A sliver and an obtuse triangle.
            [
                DVec3::ZERO,
                DVec3::new(5.0, 0.0, 0.0),
                DVec3::new(2.5, 1e-3, 0.0),
            ],
            [
                DVec3::new(-1.0, 0.0, 0.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(0.1, 0.2, 0.3),
            ],
        ];
        for t in tris {
            let mut s = Scene::empty();
            let mat = s.add_material(Material::diffuse("w", 0.5));
            s.add_mesh("t", t.to_vec(), vec![[0, 1, 2]], mat);
            s.solver.element_size = 0.07;
            let got: Vec<[DVec3; 3]> = build_elements(&s, &s.solver)
                .unwrap()
                .iter()
                .map(|e| e.faces[0].corners)
                .collect();
            let mut want = Vec::new();
            recursive(t, 0.07, &mut want);
            assert!(got.len() > 50, "{}", got.len());
            assert_eq!(got, want);
        }
    }

    /// Sizes no bisection can reach are errors, quickly, never a stack overflow or a hang.
    #[test]
    fn unreachable_sizes_are_refused() {
        let mut s = Scene::empty();
        let mat = s.add_material(Material::diffuse("w", 0.5));
        let tri = |s: &mut Scene, k: f64, at: f64| {
            let p = [DVec3::ZERO, DVec3::X, DVec3::Y].map(|v| v * k + DVec3::splat(at));
            s.meshes.clear();
            s.add_mesh("t", p.to_vec(), vec![[0, 1, 2]], mat);
        };
        s.solver.max_elements = usize::MAX;
        let cases = [
            (1e30, 0.0, 0.25, "more than"),
            (1.0, 0.0, 5e-324, "more than"),
            (1.0, 0.0, 1e-6, "more than"),
            (1.0, 0.0, -0.5, "positive"),
            (1.0, 0.0, f64::NAN, "positive"),
            // Edges of 100 at 1e17, where float64 steps by 16: bisection stalls above size 1.
            (100.0, 1e17, 1.0, "finer than float64"),
        ];
        for (k, at, size, want) in cases {
            tri(&mut s, k, at);
            s.solver.element_size = size;
            // The refusal comes from the estimate or the size check, before any element is
            // made: the message says which (no wall-clock bound).
            let e = build_elements(&s, &s.solver).unwrap_err().to_string();
            assert!(
                e.contains(want) && e.contains("element_size"),
                "{k} {size}: {e}"
            );
        }
    }

    #[test]
    fn the_estimate_never_exceeds_the_count() {
        let mut s = Scene::empty();
        let mat = s.add_material(Material::diffuse("w", 0.5));
        let p = vec![
            DVec3::ZERO,
            DVec3::new(3.0, 0.0, 0.0),
            DVec3::new(0.0, 0.1, 2.0),
            DVec3::new(1.0, 1.0, 1.0),
        ];
        s.add_mesh("t", p, vec![[0, 1, 2], [0, 1, 3], [1, 2, 3]], mat);
        // (Sizes above the edges would let the triangles cluster, where the bound is looser.)
        for size in [1.0, 0.3, 0.05, 0.01] {
            s.solver.element_size = size;
            let n = build_elements(&s, &s.solver).unwrap().len() as f64;
            let est = estimate_elements(&s, size);
            assert!(
                est <= n && est >= 0.2 * n,
                "size {size}: estimate {est}, count {n}"
            );
        }
    }
}
