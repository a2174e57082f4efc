//! Leaf elements: input triangles split by longest-edge bisection until no edge exceeds the
//! element size. Bisection keeps angles bounded, so sliver input faces get better, not worse.

use crate::error::{Error, Result};
use crate::scene::{Scene, SolverSettings};
use glam::DVec3;

/// A leaf element of the finite-element discretization.
#[derive(Debug, Clone, PartialEq)]
pub struct Element {
    /// Triangle corners (world space, counter-clockwise seen from the front).
    pub corners: [DVec3; 3],
    /// Centroid: the collocation point.
    pub center: DVec3,
    /// Unit front normal.
    pub normal: DVec3,
    /// Area.
    pub area: f64,
    /// Index into the scene's materials.
    pub material: u32,
    /// Mesh the element came from.
    pub mesh: u32,
    /// Triangle of that mesh the element came from.
    pub triangle: u32,
}

impl Element {
    fn new(corners: [DVec3; 3], material: u32, mesh: u32, triangle: u32) -> Self {
        let [a, b, c] = corners;
        let cr = (b - a).cross(c - a);
        let area = 0.5 * cr.length();
        Self {
            corners,
            center: (a + b + c) / 3.0,
            normal: cr.normalize(),
            area,
            material,
            mesh,
            triangle,
        }
    }
}

fn longest_edge(t: &[DVec3; 3]) -> (usize, f64) {
    (0..3)
        .map(|i| (i, (t[(i + 1) % 3] - t[i]).length()))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap()
}

/// Number of leaves bisection produces for one triangle (without building them).
fn count_leaves(t: [DVec3; 3], size: f64, limit: usize) -> usize {
    let (i, len) = longest_edge(&t);
    if len <= size || limit <= 1 {
        return 1;
    }
    let (a, b) = split(t, i);
    let na = count_leaves(a, size, limit);
    na + count_leaves(b, size, limit.saturating_sub(na))
}

fn split(t: [DVec3; 3], i: usize) -> ([DVec3; 3], [DVec3; 3]) {
    let (p, q, r) = (t[i], t[(i + 1) % 3], t[(i + 2) % 3]);
    let m = (p + q) * 0.5;
    ([p, m, r], [m, q, r])
}

fn subdivide(t: [DVec3; 3], size: f64, out: &mut Vec<[DVec3; 3]>) {
    let (i, len) = longest_edge(&t);
    if len <= size {
        out.push(t);
    } else {
        let (a, b) = split(t, i);
        subdivide(a, size, out);
        subdivide(b, size, out);
    }
}

/// Splits every triangle of the scene into elements no longer than `settings.element_size`.
/// Refuses (before allocating) if the count would exceed `settings.max_elements`.
pub fn build_elements(scene: &Scene, settings: &SolverSettings) -> Result<Vec<Element>> {
    let size = settings.element_size;
    let limit = settings.max_elements;
    let mut count = 0usize;
    for m in &scene.meshes {
        for tri in &m.triangles {
            count += count_leaves(
                tri.map(|v| m.positions[v as usize]),
                size,
                limit + 1 - count.min(limit),
            );
            if count > limit {
                return Err(Error::Setting {
                    field: "element_size",
                    message: format!(
                        "element size {size} would create more than {limit} elements (solver.max_elements); use a larger element size"
                    ),
                });
            }
        }
    }
    let mut elements = Vec::with_capacity(count);
    let mut pieces = Vec::new();
    for (mi, m) in scene.meshes.iter().enumerate() {
        for (ti, tri) in m.triangles.iter().enumerate() {
            pieces.clear();
            subdivide(tri.map(|v| m.positions[v as usize]), size, &mut pieces);
            for p in &pieces {
                elements.push(Element::new(*p, m.material[ti], mi as u32, ti as u32));
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
            assert!(longest_edge(&e.corners).1 <= 0.3 + 1e-12);
            assert!(
                (e.normal - n0).length() < 1e-9,
                "bisection keeps orientation"
            );
        }
        s.solver.max_elements = 10;
        let err = build_elements(&s, &s.solver).unwrap_err().to_string();
        assert!(err.contains("element_size"), "{err}");
    }
}
