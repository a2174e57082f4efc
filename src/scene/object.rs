//! One `[[object]]`: its OBJ and MTL files read and checked, its materials (with the scene's
//! overrides) and its triangles placed in world space.

use super::files::{self, FileProblem};
use super::format::ObjectDesc;
use super::load::{color, mesh_err, scene_err, source};
use super::obj::{self, ObjScan};
use super::{Material, Mesh, Scene, MAX_COORDINATE};
use crate::error::{Error, Result};
use glam::{DMat3, DMat4, DVec3};
use std::cell::RefCell;
use std::collections::{BTreeSet, HashMap};
use std::path::{Path, PathBuf};

/// Where an object comes from, for messages.
pub struct ObjectSource<'a> {
    /// Index of the `[[object]]`.
    pub index: usize,
    /// The scene file.
    pub scene_path: &'a Path,
    /// The folder mesh paths are relative to.
    pub base: &'a Path,
    /// The object-to-world transform.
    pub transform: DMat4,
    /// The transform's fields as written (for messages about where it takes vertices).
    pub transform_field: String,
    /// Set by a Mitsuba scene: one material for every face, the MTL unread.
    pub forced: Option<Forced>,
}

/// How a Mitsuba `obj` shape reads its file: its BSDF for every face (Mitsuba reads no MTL),
/// `face_normals` dropping the `vn`, `flip_normals` turning the front round.
#[derive(Debug, Clone, Copy)]
pub struct Forced {
    /// Index into the scene's materials.
    pub material: u32,
    /// Ignore the file's `vn`.
    pub face_normals: bool,
    /// Reverse every face (and its normals).
    pub flip: bool,
}

/// The name of the grey diffuse material of faces without one (`materials.default` overrides
/// it where the MTL has no material of that name).
pub const DEFAULT_MATERIAL: &str = "default";

/// Reads object `o`, appending its materials and meshes to `scene`; warnings go to `warned`.
pub fn load_object(
    scene: &mut Scene,
    o: &ObjectDesc,
    src: &ObjectSource,
    warned: &mut BTreeSet<String>,
) -> Result<Option<super::Camera>> {
    let i = src.index;
    let obj_path: PathBuf = src.base.join(&o.mesh);
    let shown = obj_path.display();
    if is_gltf(&obj_path) {
        let bytes = files::read_bytes(&obj_path)
            .map_err(|p| scene_err(src.scene_path, format!("{}: {shown} {p}", mesh_field(src))))?;
        let place = super::gltf_scene::Placement {
            scene_path: src.scene_path,
            field: format!("object[{i}].materials"),
            transform: src.transform,
            overrides: &o.materials,
        };
        let loaded = super::gltf_scene::load_gltf(scene, &obj_path, &bytes, &place, warned)?;
        return Ok(loaded.camera);
    }
    let text = files::read_text(&obj_path, "OBJ").map_err(|p| match p {
        FileProblem::Path(m) => {
            scene_err(src.scene_path, format!("{}: {shown} {m}", mesh_field(src)))
        }
        FileProblem::Content(m) => mesh_err(&obj_path, m),
    })?;
    let scan = obj::scan_obj(&text, &obj_path)?;
    let forced = src.forced;
    let (models, mtl) = parse(&scan, &obj_path, forced.is_none())?;
    // Faces without a material get the grey default, which `materials.default` may override.
    let no_material = models.iter().any(|m| m.mesh.material_id.is_none());
    let default_override = no_material && !mtl.iter().any(|m| m.name.trim() == DEFAULT_MATERIAL);
    for name in o.materials.keys() {
        if !(mtl.iter().any(|m| m.name.trim() == name)
            || (default_override && name == DEFAULT_MATERIAL))
        {
            return Err(scene_err(
                src.scene_path,
                format!("`object[{i}].materials.{name}`: no material of that name in {shown}"),
            ));
        }
    }
    let first = scene.materials.len() as u32;
    for m in &mtl {
        let mat = material(m, o, i, src.scene_path, &obj_path, warned)?;
        scene.materials.push(mat);
    }
    if !scan.polylines.is_empty() {
        warned.insert(format!(
            "{shown}: {} ignored (first at line {}): they are not surfaces",
            match scan.polylines.len() {
                1 => "1 polyline (`l` element)".to_string(),
                n => format!("{n} polylines (`l` elements)"),
            },
            scan.polylines[0]
        ));
    }
    if forced.is_none()
        && scan.faces_without_usemtl
        && !(default_override && o.materials.contains_key(DEFAULT_MATERIAL))
    {
        warned.insert(format!(
            "{shown}: faces without usemtl get a grey diffuse material (Kd 0.5)"
        ));
    }
    for (name, line) in &scan.usemtl {
        if forced.is_none() && !mtl.iter().any(|m| m.name == *name) {
            warned.insert(format!(
                "{shown}: line {line}: usemtl {name}: no material of that name in its MTL library; its faces get the default grey diffuse material (Kd 0.5), as in other renderers"
            ));
        }
    }
    let total: usize = models.iter().map(|m| m.mesh.indices.len() / 3).sum();
    // Lines for messages, when the scan's triangles are tobj's (they always should be).
    let lines = (scan.triangle_lines.len() == total).then_some(&scan.triangle_lines);
    let describe = |t: usize| match lines {
        Some(l) => format!("line {}", l[t]),
        None => format!("triangle {}", t + 1),
    };
    let mut default_mat = None;
    // Every triangle kept so far, by its corners, with its index in the file.
    let mut seen: HashMap<[[u64; 3]; 3], usize> = HashMap::new();
    let (mut duplicates, mut first_duplicate) = (0usize, None);
    let (mut zero_area, mut first_zero) = (0usize, None);
    let mut kept = 0usize;
    let mut t_file = 0usize;
    // Normals go by the inverse transpose; a mirroring transform turns the face's winding, and
    // so its front, around, and the shading normals with it.
    let linear = DMat3::from_mat4(src.transform);
    let normal_matrix = linear.inverse().transpose() * linear.determinant().signum();
    let (mut bad_normals, mut first_bad) = (0usize, None);
    for model in &models {
        let mesh = &model.mesh;
        let positions: Vec<DVec3> = mesh
            .positions
            .chunks_exact(3)
            .map(|p| {
                let v = DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
                src.transform.transform_point3(v)
            })
            .collect();
        let mat = match mesh.material_id {
            _ if forced.is_some() => forced.map_or(0, |f| f.material),
            Some(id) if id < mtl.len() => first + id as u32,
            Some(id) => {
                return Err(mesh_err(
                    &obj_path,
                    format!("model '{}': material index {id} out of range", model.name),
                ))
            }
            None => match default_mat {
                Some(m) => m,
                None => {
                    let grey = tobj::Material {
                        name: DEFAULT_MATERIAL.into(),
                        diffuse: Some([0.5; 3]),
                        ..Default::default()
                    };
                    let mat = if default_override {
                        material(&grey, o, i, src.scene_path, &obj_path, warned)?
                    } else {
                        Material::diffuse(DEFAULT_MATERIAL, 0.5)
                    };
                    scene.materials.push(mat);
                    *default_mat.insert((scene.materials.len() - 1) as u32)
                }
            },
        };
        let mut triangles = Vec::with_capacity(mesh.indices.len() / 3);
        let mut normals: Vec<Option<[DVec3; 3]>> = Vec::with_capacity(mesh.indices.len() / 3);
        for idx in mesh.indices.chunks_exact(3) {
            let t = t_file;
            t_file += 1;
            let tri = match forced {
                Some(f) if f.flip => [idx[0], idx[2], idx[1]],
                _ => [idx[0], idx[1], idx[2]],
            };
            if tri.iter().any(|&v| v as usize >= positions.len()) {
                return Err(mesh_err(
                    &obj_path,
                    format!("{}: a vertex index is out of range", describe(t)),
                ));
            }
            let corners = tri.map(|v| positions[v as usize]);
            check_placed(&corners, || describe(t), &obj_path, src)?;
            let [a, b, c] = corners;
            let longest = (b - a).length().max((c - b).length()).max((a - c).length());
            let area2 = (b - a).cross(c - a).length();
            if !(area2 > 1e-9 * longest * longest) {
                // Dropped, as other renderers load such files (issue 35): one warning per mesh.
                zero_area += 1;
                first_zero.get_or_insert((t, corners));
                continue;
            }
            // The same corners in the same cyclic order are the same one-sided surface twice
            // (a whole face repeated, or one of its triangles); reversed winding is the
            // back-to-back twin of a two-sided wall, and is kept.
            let key = canonical(corners.map(|p| p.to_array().map(f64::to_bits)));
            let repeated = lines
                .and_then(|l| scan.repeated_faces.get(&l[t]))
                .map(|&earlier| Repeat::Face(earlier))
                .or_else(|| seen.get(&key).map(|&e| Repeat::Triangle(e)));
            if let Some(r) = repeated {
                duplicates += 1;
                first_duplicate.get_or_insert((t, r));
                continue;
            }
            seen.insert(key, t);
            triangles.push(tri);
            // The scan's normals are tobj's triangles only when the counts agree (`lines`).
            let vn = lines
                .and(scan.triangle_normals.get(t).copied().flatten())
                .filter(|_| !forced.is_some_and(|f| f.face_normals))
                .map(|vn| match forced {
                    Some(f) if f.flip => [vn[0], vn[2], vn[1]],
                    _ => vn,
                });
            let turn = if forced.is_some_and(|f| f.flip) {
                -1.0
            } else {
                1.0
            };
            let face = (b - a).cross(c - a).normalize();
            normals.push(vn.and_then(|vn| {
                let placed = vn.map(|i| {
                    let [x, y, z] = scan.normals[i as usize];
                    normal_matrix * DVec3::new(x as f64, y as f64, z as f64) * turn
                });
                let usable = |n: &DVec3| {
                    let len = n.length();
                    len.is_finite() && len > 0.0 && n.dot(face) >= 0.0
                };
                if placed.iter().all(usable) {
                    Some(placed.map(DVec3::normalize))
                } else {
                    bad_normals += 1;
                    first_bad.get_or_insert(t);
                    None
                }
            }));
        }
        let n = triangles.len();
        kept += n;
        // Faces without (usable) `vn` get their face normal; a mesh with none keeps none.
        let normals = if normals.iter().any(Option::is_some) {
            triangles
                .iter()
                .zip(normals)
                .map(|(tri, vn)| {
                    vn.unwrap_or_else(|| {
                        let [a, b, c] = tri.map(|v| positions[v as usize]);
                        [(b - a).cross(c - a).normalize(); 3]
                    })
                })
                .collect()
        } else {
            Vec::new()
        };
        scene.meshes.push(Mesh {
            name: if model.name.is_empty() {
                format!("object{i}")
            } else {
                model.name.clone()
            },
            source: obj_path.clone(),
            positions,
            triangles,
            material: vec![mat; n],
            normals,
        });
    }
    if let Some(t) = first_bad {
        warned.insert(format!(
            "{shown}: {bad_normals} {} unusable `vn` (zero length, not finite, or facing more than 90° away from the face; first: {}): shaded with the face normal",
            if bad_normals == 1 { "triangle has" } else { "triangles have" },
            describe(t),
        ));
    }
    if total == 0 {
        return Err(mesh_err(&obj_path, "mesh has no faces".into()));
    }
    if let Some((t, corners)) = first_zero {
        if kept == 0 {
            return Err(mesh_err(
                &obj_path,
                format!(
                    "every face is degenerate (zero area; first: {}, corners {:?})",
                    describe(t),
                    corners.map(|p| p.to_array())
                ),
            ));
        }
        warned.insert(format!(
            "{shown}: {zero_area} degenerate (zero-area) {} dropped (collinear or coincident corners; first: {})",
            if zero_area == 1 { "triangle" } else { "triangles" },
            describe(t),
        ));
    }
    if let Some((t, earlier)) = first_duplicate {
        let earlier = match earlier {
            Repeat::Face(line) => format!("line {line}"),
            Repeat::Triangle(e) => describe(e),
        };
        warned.insert(format!(
            "{shown}: {duplicates} duplicate {} dropped (the same corners in the same winding as an earlier face; first: {} repeats {earlier})",
            if duplicates == 1 { "triangle" } else { "triangles" },
            describe(t),
        ));
    }
    Ok(None)
}

/// How the mesh's path is named in messages: the TOML field, or the Mitsuba shape.
fn mesh_field(src: &ObjectSource) -> String {
    match src.forced {
        Some(_) => src.transform_field.replace("to_world", "filename"),
        None => format!("`object[{}].mesh`", src.index),
    }
}

/// Whether `path` names a glTF file (`.gltf`, `.glb`, any case).
pub fn is_gltf(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}

/// What a dropped triangle repeats: a face (by its line) or an earlier triangle (by index).
#[derive(Clone, Copy)]
enum Repeat {
    Face(u32),
    Triangle(usize),
}

/// The rotation of a triangle's corners that starts with the smallest: equal for the same
/// triangle in the same winding, different for the reversed one.
fn canonical(c: [[u64; 3]; 3]) -> [[u64; 3]; 3] {
    let start = (0..3).min_by_key(|&k| c[k]).unwrap_or(0);
    [c[start], c[(start + 1) % 3], c[(start + 2) % 3]]
}

/// Refuses a triangle its object's transform placed beyond [`MAX_COORDINATE`] (or made
/// non-finite), naming the transform when there is one.
fn check_placed(
    corners: &[DVec3; 3],
    at: impl Fn() -> String,
    obj_path: &Path,
    src: &ObjectSource,
) -> Result<()> {
    let Some(p) = corners
        .iter()
        .find(|p| !(p.is_finite() && p.abs().max_element() <= MAX_COORDINATE))
    else {
        return Ok(());
    };
    let why = "the largest coordinate magnitude float32 tables handle";
    let p = p.to_array();
    Err(if src.transform == DMat4::IDENTITY {
        mesh_err(
            obj_path,
            format!(
                "{}: vertex {p:?} is beyond ±{MAX_COORDINATE:e} ({why})",
                at()
            ),
        )
    } else {
        scene_err(
            src.scene_path,
            format!(
                "`{}` places a vertex of {} ({}) at {p:?}, beyond ±{MAX_COORDINATE:e} ({why})",
                src.transform_field,
                obj_path.display(),
                at()
            ),
        )
    })
}

/// Parses the scanned text with `tobj`, reading MTL libraries through [`obj::read_mtl`] and
/// [`obj::parse_mtl`].
fn parse(
    scan: &ObjScan,
    obj_path: &Path,
    read_mtl: bool,
) -> Result<(Vec<tobj::Model>, Vec<tobj::Material>)> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let dir = obj_path.parent().unwrap_or(Path::new("."));
    // tobj's loader callback can only return tobj's errors: keep ours aside.
    let mtl_error: RefCell<Option<Error>> = RefCell::new(None);
    let loaded = tobj::load_obj_buf(&mut scan.text.as_bytes(), &opts, |lib| {
        if !read_mtl {
            return Ok(Default::default());
        }
        let line = scan
            .mtllibs
            .iter()
            .find(|(name, _)| Path::new(name) == lib)
            .map_or(0, |(_, l)| *l);
        let path = dir.join(lib);
        obj::read_mtl(&path, obj_path, line)
            .and_then(|text| {
                obj::parse_mtl(&text, &path, obj_path, line, |t| {
                    tobj::load_mtl_buf(&mut t.as_bytes())
                })
            })
            .map_err(|e| {
                mtl_error.borrow_mut().get_or_insert(e);
                tobj::LoadError::OpenFileFailed
            })
    });
    if let Some(e) = mtl_error.into_inner() {
        return Err(e);
    }
    let (models, mtl) = loaded.map_err(|e| mesh_err(obj_path, format!("cannot parse OBJ: {e}")))?;
    let mtl = mtl.map_err(|e| mesh_err(obj_path, format!("cannot load its MTL library: {e}")))?;
    Ok((models, mtl))
}

/// One MTL material with the scene's overrides applied, checked.
fn material(
    m: &tobj::Material,
    o: &ObjectDesc,
    i: usize,
    scene_path: &Path,
    obj_path: &Path,
    warned: &mut BTreeSet<String>,
) -> Result<Material> {
    let name = m.name.trim().to_string();
    let shown = obj_path.display();
    let get = |v: Option<[f32; 3]>| {
        v.map_or(DVec3::ZERO, |c| {
            DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64)
        })
    };
    let mut mat = Material {
        name: name.clone(),
        kd: get(m.diffuse),
        ks: get(m.specular),
        ns: m.shininess.unwrap_or(0.0) as f64,
        ke: get(m.emissive),
    };
    if m.diffuse_texture.is_some() || m.specular_texture.is_some() || m.normal_texture.is_some() {
        warned.insert(format!(
            "{shown}: material {name}: textures are not supported; using its Kd"
        ));
    }
    if m.dissolve.is_some_and(|d| d < 1.0) || m.dissolve_texture.is_some() {
        warned.insert(format!(
            "{shown}: material {name}: transparency is not supported; treated as opaque"
        ));
    }
    if let Some(ov) = o.materials.get(&name) {
        let f = |k: &str| format!("object[{i}].materials.{name}.{k}");
        if let Some(c) = ov.kd {
            mat.kd = color(c, &f("kd"), scene_path)?;
        }
        if let Some(c) = ov.ks {
            mat.ks = color(c, &f("ks"), scene_path)?;
        }
        if let Some(c) = ov.ke {
            mat.ke = source(c, &f("ke"), scene_path)?;
        }
        if let Some(n) = ov.ns {
            if !(n.is_finite() && n >= 0.0) {
                return Err(scene_err(
                    scene_path,
                    format!("`{}` must be finite and >= 0", f("ns")),
                ));
            }
            mat.ns = n;
        }
    }
    for (v, what) in [(mat.kd, "Kd"), (mat.ks, "Ks"), (mat.ke, "Ke")] {
        if !(v.is_finite() && v.min_element() >= 0.0) {
            return Err(mesh_err(
                obj_path,
                format!("material {name}: {what} must be finite and non-negative"),
            ));
        }
    }
    if mat.ke.max_element() > super::MAX_SOURCE {
        return Err(mesh_err(
            obj_path,
            format!(
                "material {name}: Ke {:?} exceeds {:e}: {}",
                mat.ke.max_element(),
                super::MAX_SOURCE,
                super::load::SOURCE_LIMIT_REASON
            ),
        ));
    }
    if !(mat.ns.is_finite() && mat.ns >= 0.0) {
        return Err(mesh_err(
            obj_path,
            format!("material {name}: Ns must be finite and non-negative"),
        ));
    }
    if (mat.kd + mat.ks).max_element() > 1.0 {
        warned.insert(format!(
            "{shown}: material {name}: Kd + Ks exceeds 1 (not energy conserving)"
        ));
    }
    Ok(mat)
}
