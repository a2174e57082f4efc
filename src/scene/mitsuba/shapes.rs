//! Mitsuba shapes: `obj` through the OBJ loader (its BSDF for every face), `ply`, and the
//! generated `rectangle`, `cube` and `sphere`.

use super::{Reader, Value};
use crate::error::Result;
use crate::scene::animation::SceneObject;
use crate::scene::format::ObjectDesc;
use crate::scene::object::{load_object, Forced, ObjectSource};
use crate::scene::{Material, Mesh, Scene, MAX_COORDINATE, MAX_SOURCE};
use glam::{DMat3, DMat4, DVec3};
use roxmltree::Node;
use std::collections::BTreeMap;
use std::path::Path;

/// Positions, normals and triangles of a generated shape.
type Generated = (Vec<[f64; 3]>, Vec<[f64; 3]>, Vec<[u32; 3]>);

impl<'a, 'i> Reader<'a, 'i> {
    pub(super) fn shape(&mut self, scene: &mut Scene, n: Node<'a, 'i>) -> Result<()> {
        let kind = self.attr(n, "type")?;
        let id = n
            .attribute("id")
            .map_or_else(|| format!("{kind}@{}", self.line(n)), str::to_string);
        let p = self.props(n)?;
        let to_world = match p.get("toworld") {
            Some(Value::Transform(m)) => *m,
            _ => DMat4::IDENTITY,
        };
        // The material: its BSDF (by reference or inline; none: Mitsuba's grey diffuse) and the
        // radiance of an area emitter it holds.
        let bsdf_node = n
            .children()
            .find(|c| c.has_tag_name("bsdf") || c.has_tag_name("ref"));
        let bsdf_key = bsdf_node.map_or("<none>".to_string(), |b| {
            b.attribute("id")
                .map_or_else(|| format!("@{}", b.range().start), str::to_string)
        });
        let mut ke = DVec3::ZERO;
        for e in n.children().filter(|c| c.has_tag_name("emitter")) {
            let t = self.attr(e, "type")?;
            if t != "area" {
                self.skip(&format!("emitter {t} inside a shape"));
                continue;
            }
            self.within_emitter = true;
            let ep = self.props(e);
            self.within_emitter = false;
            let ep = ep?;
            ke = match ep.get("radiance") {
                Some(Value::Color(c)) => *c,
                _ => DVec3::ONE,
            };
            if !(ke.is_finite() && ke.min_element() >= 0.0 && ke.max_element() <= MAX_SOURCE) {
                return Err(self.err(
                    e,
                    format!(
                        "radiance {:?} must be non-negative and at most {MAX_SOURCE:e}",
                        ke.to_array()
                    ),
                ));
            }
        }
        let mkey = (bsdf_key.clone(), ke.to_array().map(f64::to_bits));
        let material = match self.materials.get(&mkey) {
            Some(&m) => m,
            None => {
                let name = if ke == DVec3::ZERO {
                    bsdf_key.clone()
                } else {
                    format!("{bsdf_key}__emitter_{id}")
                };
                let mut m = match bsdf_node {
                    Some(b) => self.bsdf_of(b, &name)?,
                    None => Material::diffuse(&name, 0.5),
                };
                m.ke = ke;
                scene.materials.push(m);
                let k = (scene.materials.len() - 1) as u32;
                self.materials.insert(mkey, k);
                k
            }
        };
        let flip = matches!(p.get("flipnormals"), Some(Value::Text(t)) if t == "true");
        let first = scene.meshes.len();
        match kind.as_str() {
            "obj" => {
                let Some(Value::Text(file)) = p.get("filename") else {
                    return Err(self.err(n, "an obj shape needs <string name=\"filename\">".into()));
                };
                let desc = ObjectDesc {
                    mesh: file.clone(),
                    scale: None,
                    rotate: None,
                    translate: None,
                    matrix: None,
                    materials: BTreeMap::new(),
                    keyframe: Vec::new(),
                    moving: None,
                    two_sided: None,
                };
                let src = ObjectSource {
                    index: scene.objects.len(),
                    scene_path: self.path,
                    base: self.path.parent().unwrap_or(Path::new(".")),
                    transform: to_world,
                    transform_field: format!("<shape id=\"{id}\"> to_world"),
                    forced: Some(Forced {
                        material,
                        face_normals: matches!(p.get("facenormals"), Some(Value::Text(t)) if t == "true"),
                        flip,
                    }),
                };
                load_object(scene, &desc, &src, &mut self.warned)?;
            }
            "ply" => {
                let Some(Value::Text(file)) = p.get("filename") else {
                    return Err(self.err(n, "a ply shape needs <string name=\"filename\">".into()));
                };
                let file = self.path.parent().unwrap_or(Path::new(".")).join(file);
                let bytes = crate::scene::files::read_bytes(&file)
                    .map_err(|e| self.err(n, format!("{} {e}", file.display())))?;
                let ply = crate::scene::ply::parse(&bytes)
                    .map_err(|e| crate::scene::load::mesh_err(&file, e))?;
                let face_normals =
                    matches!(p.get("facenormals"), Some(Value::Text(t)) if t == "true");
                let normals = if face_normals {
                    Vec::new()
                } else {
                    ply.normals
                };
                self.push(
                    scene,
                    n,
                    &id,
                    ply.positions,
                    normals,
                    ply.triangles,
                    to_world,
                    material,
                    flip,
                    false,
                )?;
            }
            "rectangle" | "disk" | "cube" | "sphere" => {
                // Mitsuba's own shapes, in their local frames; a sphere is placed by its centre
                // and radius before to_world.
                let (v, normals, t, m) = match kind.as_str() {
                    "rectangle" => {
                        let v = vec![
                            [-1.0, -1.0, 0.0],
                            [1.0, -1.0, 0.0],
                            [1.0, 1.0, 0.0],
                            [-1.0, 1.0, 0.0],
                        ];
                        (v, Vec::new(), vec![[0, 1, 2], [0, 2, 3]], to_world)
                    }
                    "disk" => {
                        self.note("disks (tessellated: 64 segments)");
                        let (v, t) = disk(64);
                        (v, Vec::new(), t, to_world)
                    }
                    "cube" => {
                        let (v, t) = cube();
                        (v, Vec::new(), t, to_world)
                    }
                    _ => {
                        let centre = match p.get("center") {
                            Some(Value::Vector(c)) => *c,
                            _ => DVec3::ZERO,
                        };
                        let radius = match p.get("radius") {
                            Some(Value::Number(r)) => *r,
                            _ => 1.0,
                        };
                        self.note("spheres (tessellated: 48 × 24 quads)");
                        let (v, normals, t) = sphere(48, 24);
                        let m = to_world
                            * DMat4::from_translation(centre)
                            * DMat4::from_scale(DVec3::splat(radius));
                        (v, normals, t, m)
                    }
                };
                self.push(scene, n, &id, v, normals, t, m, material, flip, true)?;
            }
            other => {
                self.skip(&format!("shape {other}"));
                return Ok(());
            }
        }
        // A `twosided` BSDF reflects on both sides; surfaces here have one front, so each face
        // gets its back-to-back twin (reversed winding, the same BSDF, no emission: Mitsuba's
        // area emitters emit from the front only). Without, a room whose walls' fronts face
        // outward renders black from inside (Veach's room did: 0.8% of Mitsuba 3's mean).
        if bsdf_node.is_some_and(|b| self.is_twosided(b)) {
            let end = scene.meshes.len();
            crate::scene::add_twins(scene, first..end);
        }
        scene.objects.push(SceneObject {
            meshes: first..scene.meshes.len(),
            transform: to_world,
            moving: false,
            motion: None,
        });
        Ok(())
    }

    /// Whether a `<bsdf>` (or the one a `<ref>` names) is `twosided`.
    fn is_twosided(&self, b: Node) -> bool {
        let node = if b.has_tag_name("ref") {
            match b.attribute("id").and_then(|id| self.named.get(id)) {
                Some(n) => *n,
                None => return false,
            }
        } else {
            b
        };
        node.attribute("type")
            .and_then(|t| self.substitute(node, t).ok())
            .is_some_and(|t| t == "twosided")
    }

    /// A generated or PLY mesh placed by `m`. `keep_front`: Mitsuba's own shapes keep their
    /// normal under a mirroring transform (it transforms the normal), so the winding turns.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn push(
        &mut self,
        scene: &mut Scene,
        n: Node,
        id: &str,
        local: Vec<[f64; 3]>,
        normals: Vec<[f64; 3]>,
        triangles: Vec<[u32; 3]>,
        m: DMat4,
        material: u32,
        flip: bool,
        keep_front: bool,
    ) -> Result<()> {
        let lin = DMat3::from_mat4(m);
        let det = lin.determinant();
        if !(det.abs() > 0.0) {
            return Err(self.err(n, "to_world is singular".into()));
        }
        let turn = flip ^ (keep_front && det < 0.0);
        let sign = if keep_front { 1.0 } else { det.signum() } * if flip { -1.0 } else { 1.0 };
        let nm = lin.inverse().transpose() * sign;
        let positions: Vec<DVec3> = local
            .iter()
            .map(|p| m.transform_point3(DVec3::from_array(*p)))
            .collect();
        if positions
            .iter()
            .any(|p| !(p.is_finite() && p.abs().max_element() <= MAX_COORDINATE))
        {
            return Err(self.err(
                n,
                format!("to_world places a vertex beyond ±{MAX_COORDINATE:e}"),
            ));
        }
        let mut tris = Vec::with_capacity(triangles.len());
        let mut corner_normals = Vec::new();
        let mut dropped = 0;
        for t in triangles {
            let t = if turn { [t[0], t[2], t[1]] } else { t };
            let [a, b, c] = t.map(|v| positions[v as usize]);
            let cross = (b - a).cross(c - a);
            let longest = (b - a).length().max((c - b).length()).max((a - c).length());
            if !(cross.length() > 1e-9 * longest * longest) {
                dropped += 1;
                continue;
            }
            tris.push(t);
            if normals.len() == local.len() {
                let face = cross.normalize();
                let placed = t.map(|v| nm * DVec3::from_array(normals[v as usize]));
                corner_normals.push(
                    if placed
                        .iter()
                        .all(|q| q.length() > 0.0 && q.dot(face) >= 0.0)
                    {
                        placed.map(DVec3::normalize)
                    } else {
                        [face; 3]
                    },
                );
            }
        }
        if dropped > 0 {
            self.warned.insert(format!(
                "{}: shape {id}: {dropped} degenerate (zero-area) triangles dropped",
                self.path.display()
            ));
        }
        let count = tris.len();
        scene.meshes.push(Mesh {
            name: id.to_string(),
            source: self.path.to_path_buf(),
            positions,
            triangles: tris,
            material: vec![material; count],
            normals: corner_normals,
        });
        Ok(())
    }
}

/// Mitsuba's `disk`: the unit disk in z = 0 facing +z, as a fan of `seg` triangles.
fn disk(seg: u32) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let mut v = vec![[0.0, 0.0, 0.0]];
    for k in 0..seg {
        let a = 2.0 * std::f64::consts::PI * k as f64 / seg as f64;
        v.push([a.cos(), a.sin(), 0.0]);
    }
    let t = (0..seg).map(|k| [0, 1 + k, 1 + (k + 1) % seg]).collect();
    (v, t)
}

/// Mitsuba's `cube`: [−1, 1]³, faces outward.
fn cube() -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let mut v = Vec::new();
    let mut t = Vec::new();
    for axis in 0..3 {
        for s in [-1.0, 1.0] {
            let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
            let base = v.len() as u32;
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                let mut p = [0.0; 3];
                p[axis] = s;
                p[u] = a;
                p[w] = b * s;
                v.push(p);
            }
            t.push([base, base + 1, base + 2]);
            t.push([base, base + 2, base + 3]);
        }
    }
    (v, t)
}

/// A unit sphere of `seg` × `rings` quads, faces outward, normals radial.
fn sphere(seg: u32, rings: u32) -> Generated {
    let mut v = Vec::new();
    for r in 0..=rings {
        let th = std::f64::consts::PI * r as f64 / rings as f64;
        for s in 0..=seg {
            let ph = 2.0 * std::f64::consts::PI * s as f64 / seg as f64;
            v.push([th.sin() * ph.cos(), th.cos(), -th.sin() * ph.sin()]);
        }
    }
    let mut t = Vec::new();
    let row = seg + 1;
    for r in 0..rings {
        for s in 0..seg {
            let (a, b, c, d) = (
                r * row + s,
                (r + 1) * row + s,
                (r + 1) * row + s + 1,
                r * row + s + 1,
            );
            // The first and last rings meet at the poles: one triangle each there.
            if r + 1 < rings {
                t.push([a, b, c]);
            }
            if r > 0 {
                t.push([a, c, d]);
            }
        }
    }
    (v.clone(), v, t)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn outward(v: &[[f64; 3]], t: &[[u32; 3]]) -> bool {
        t.iter().all(|t| {
            let [a, b, c] = t.map(|i| DVec3::from_array(v[i as usize]));
            let n = (b - a).cross(c - a);
            n.length() < 1e-12 || n.dot((a + b + c) / 3.0) > 0.0
        })
    }

    #[test]
    fn the_disk_faces_up() {
        let (v, t) = disk(16);
        assert_eq!(t.len(), 16);
        for tri in &t {
            let [a, b, c] = tri.map(|i| DVec3::from_array(v[i as usize]));
            assert!((b - a).cross(c - a).z > 0.0);
        }
    }

    #[test]
    fn generated_shapes_face_outward() {
        let (v, t) = cube();
        assert_eq!(t.len(), 12);
        assert!(outward(&v, &t));
        let (v, _, t) = sphere(8, 4);
        assert!(outward(&v, &t));
        assert_eq!(super::super::key("toWorld"), super::super::key("to_world"));
    }
}
