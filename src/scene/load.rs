//! Loading and validating a TOML scene and its OBJ/MTL meshes. Every error names the file and field.

use super::format::{self, LightDesc, SceneFile};
use super::{Camera, Light, Material, Mesh, Precision, Scene, Scheme, SolverSettings};
use crate::error::{Error, Result};
use glam::{DMat3, DMat4, DVec3};
use std::collections::{BTreeSet, HashSet};
use std::path::{Path, PathBuf};

/// Reads and validates a scene file; mesh paths are relative to it.
pub fn load_scene(path: &Path) -> Result<Scene> {
    let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
        path: path.into(),
        source,
    })?;
    parse_scene(&text, path)
}

/// Parses scene text as if it had been read from `path` (used for messages and relative paths).
pub fn parse_scene(text: &str, path: &Path) -> Result<Scene> {
    let file: SceneFile = toml::from_str(text).map_err(|e| {
        let at = e
            .span()
            .map(|s| {
                let before = &text[..s.start.min(text.len())];
                let line = before.matches('\n').count() + 1;
                let start = before.rfind('\n').map_or(0, |i| i + 1);
                let col = before.len() - start + 1;
                // Name the key written on that line, when there is one (`key = value`).
                let key = text[start..]
                    .lines()
                    .next()
                    .and_then(|l| l.split_once('='))
                    .map(|(k, _)| k.trim())
                    .filter(|k| !k.is_empty() && !k.starts_with('['))
                    .map_or(String::new(), |k| format!(" (`{k}`)"));
                format!("line {line}, column {col}{key}: ")
            })
            .unwrap_or_default();
        scene_err(path, format!("{at}{}", e.message().replace('\n', " ")))
    })?;
    let base = path.parent().unwrap_or(Path::new("."));
    let mut scene = Scene::empty();
    scene.path = Some(path.to_path_buf());
    if let Some(s) = &file.solver {
        scene.solver = solver_settings(s, path)?;
    }
    if let Some(c) = &file.camera {
        scene.camera = camera(c, path)?;
    }
    if let Some(env) = &file.environment {
        scene.environment = color(env.radiance, "environment.radiance", path)?;
    }
    for (i, l) in file.light.iter().enumerate() {
        scene.lights.push(light(l, i, path)?);
    }
    if file.object.is_empty() {
        return Err(scene_err(
            path,
            "no [[object]] given: a scene needs at least one mesh".into(),
        ));
    }
    let mut warned = BTreeSet::new();
    for (i, o) in file.object.iter().enumerate() {
        load_object(&mut scene, o, i, base, path, &mut warned)?;
    }
    scene.warnings = warned.into_iter().collect();
    Ok(scene)
}

fn scene_err(path: &Path, message: String) -> Error {
    Error::Scene {
        path: path.into(),
        message,
    }
}

fn mesh_err(path: &Path, message: String) -> Error {
    Error::Mesh {
        path: path.into(),
        message,
    }
}

fn vec3(v: [f64; 3], field: &str, path: &Path) -> Result<DVec3> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(DVec3::from_array(v))
    } else {
        Err(scene_err(
            path,
            format!("`{field}` must be finite, got {v:?}"),
        ))
    }
}

fn color(c: format::Rgb, field: &str, path: &Path) -> Result<DVec3> {
    let v = c.channels();
    if v.iter().all(|x| x.is_finite() && *x >= 0.0) {
        Ok(DVec3::from_array(v))
    } else {
        Err(scene_err(
            path,
            format!("`{field}` must be finite and non-negative, got {v:?}"),
        ))
    }
}

fn positive_int(v: Option<i64>, default: usize, field: &str, path: &Path) -> Result<usize> {
    match v {
        None => Ok(default),
        Some(x) if x >= 1 => Ok(x as usize),
        Some(x) => Err(scene_err(
            path,
            format!("`{field}` must be at least 1, got {x}"),
        )),
    }
}

fn positive(v: Option<f64>, default: f64, field: &str, path: &Path) -> Result<f64> {
    match v {
        None => Ok(default),
        Some(x) if x.is_finite() && x > 0.0 => Ok(x),
        Some(x) => Err(scene_err(
            path,
            format!("`{field}` must be a positive finite number, got {x}"),
        )),
    }
}

fn solver_settings(s: &format::SolverDesc, path: &Path) -> Result<SolverSettings> {
    let d = SolverSettings::default();
    let bins = positive_int(s.bins, d.bins, "solver.bins", path)?;
    crate::bins::Bins::new(bins).map_err(|e| scene_err(path, format!("`solver.bins`: {e}")))?;
    let scheme = match s.scheme.as_deref() {
        None | Some("symmetric") => Scheme::Symmetric,
        Some("asymmetric") => Scheme::Asymmetric,
        Some(x) => {
            return Err(scene_err(
                path,
                format!("`solver.scheme` must be \"symmetric\" or \"asymmetric\", got {x:?}"),
            ))
        }
    };
    let precision = match s.precision.as_deref() {
        None | Some("f16") => Precision::F16,
        Some("f32") => Precision::F32,
        Some(x) => {
            return Err(scene_err(
                path,
                format!("`solver.precision` must be \"f16\" or \"f32\", got {x:?}"),
            ))
        }
    };
    Ok(SolverSettings {
        bins,
        iterations: positive_int(s.iterations, d.iterations, "solver.iterations", path)?,
        scheme,
        element_size: positive(s.element_size, d.element_size, "solver.element_size", path)?,
        oracle: positive(s.oracle, d.oracle, "solver.oracle", path)?,
        antiradiance_steps: positive_int(
            s.antiradiance_steps,
            d.antiradiance_steps,
            "solver.antiradiance_steps",
            path,
        )?,
        precision,
        max_elements: positive_int(s.max_elements, d.max_elements, "solver.max_elements", path)?,
        tolerance: match s.tolerance {
            None => None,
            Some(t) if t.is_finite() && t > 0.0 && t < 1.0 => Some(t),
            Some(t) => {
                return Err(scene_err(
                    path,
                    format!("`solver.tolerance` must be in (0, 1), got {t}"),
                ))
            }
        },
        max_iterations: positive_int(
            s.max_iterations,
            d.max_iterations,
            "solver.max_iterations",
            path,
        )?,
    })
}

fn camera(c: &format::CameraDesc, path: &Path) -> Result<Camera> {
    let eye = vec3(c.eye, "camera.eye", path)?;
    let target = vec3(c.target, "camera.target", path)?;
    let up = vec3(c.up.unwrap_or([0.0, 1.0, 0.0]), "camera.up", path)?;
    let fov = c.fov_y_deg.unwrap_or(40.0);
    if !(fov.is_finite() && fov > 0.0 && fov < 180.0) {
        return Err(scene_err(
            path,
            format!("`camera.fov_y_deg` must be in (0, 180), got {fov}"),
        ));
    }
    let forward = target - eye;
    if forward.length() < 1e-12 || forward.normalize().cross(up).length() < 1e-9 {
        return Err(scene_err(path, "`camera.up` must not be parallel to the view direction, and `camera.target` must differ from `camera.eye`".into()));
    }
    let dim = |v: Option<i64>, f: &str| -> Result<u32> {
        match v {
            None => Ok(512),
            Some(x) if (1..=16384).contains(&x) => Ok(x as u32),
            Some(x) => Err(scene_err(
                path,
                format!("`{f}` must be in 1..=16384, got {x}"),
            )),
        }
    };
    Ok(Camera {
        eye,
        target,
        up,
        fov_y_deg: fov,
        width: dim(c.width, "camera.width")?,
        height: dim(c.height, "camera.height")?,
    })
}

fn unit(v: [f64; 3], field: &str, path: &Path) -> Result<DVec3> {
    let d = vec3(v, field, path)?;
    if d.length() < 1e-12 {
        return Err(scene_err(path, format!("`{field}` must be non-zero")));
    }
    Ok(d.normalize())
}

fn light(l: &LightDesc, i: usize, path: &Path) -> Result<Light> {
    let f = |name: &str| format!("light[{i}].{name}");
    Ok(match l {
        LightDesc::Directional {
            direction,
            irradiance,
        } => Light::Directional {
            direction: unit(*direction, &f("direction"), path)?,
            irradiance: color(*irradiance, &f("irradiance"), path)?,
        },
        LightDesc::Point {
            position,
            intensity,
        } => Light::Point {
            position: vec3(*position, &f("position"), path)?,
            intensity: color(*intensity, &f("intensity"), path)?,
        },
        LightDesc::Spot {
            position,
            target,
            intensity,
            cutoff_deg,
            beam_width_deg,
        } => {
            let p = vec3(*position, &f("position"), path)?;
            let t = vec3(*target, &f("target"), path)?;
            let axis = unit((t - p).to_array(), &f("target (minus position)"), path)?;
            if !(cutoff_deg.is_finite() && *cutoff_deg > 0.0 && *cutoff_deg <= 180.0) {
                return Err(scene_err(
                    path,
                    format!(
                        "`{}` must be in (0, 180], got {cutoff_deg}",
                        f("cutoff_deg")
                    ),
                ));
            }
            if !(beam_width_deg.is_finite()
                && *beam_width_deg >= 0.0
                && beam_width_deg <= cutoff_deg)
            {
                return Err(scene_err(
                    path,
                    format!(
                        "`{}` must be in [0, cutoff_deg], got {beam_width_deg}",
                        f("beam_width_deg")
                    ),
                ));
            }
            Light::Spot {
                position: p,
                axis,
                intensity: color(*intensity, &f("intensity"), path)?,
                cutoff: cutoff_deg.to_radians(),
                beam_width: beam_width_deg.to_radians(),
            }
        }
    })
}

/// Object-to-world transform: `matrix`, or translate · rotate · scale.
fn transform(o: &format::ObjectDesc, i: usize, path: &Path) -> Result<DMat4> {
    let f = |name: &str| format!("object[{i}].{name}");
    let m = if let Some(rows) = o.matrix {
        if o.scale.is_some() || o.rotate.is_some() || o.translate.is_some() {
            return Err(scene_err(
                path,
                format!("`{}` excludes scale, rotate and translate", f("matrix")),
            ));
        }
        DMat4::from_cols_array_2d(&rows).transpose()
    } else {
        let s = match o.scale {
            None => DVec3::ONE,
            Some(format::Scale::Uniform(k)) => DVec3::splat(k),
            Some(format::Scale::Axes(a)) => DVec3::from_array(a),
        };
        let r = match o.rotate {
            None => glam::DQuat::IDENTITY,
            Some(r) => {
                if !r.angle_deg.is_finite() {
                    return Err(scene_err(
                        path,
                        format!("`{}` must be finite", f("rotate.angle_deg")),
                    ));
                }
                glam::DQuat::from_axis_angle(
                    unit(r.axis, &f("rotate.axis"), path)?,
                    r.angle_deg.to_radians(),
                )
            }
        };
        let t = vec3(o.translate.unwrap_or([0.0; 3]), &f("translate"), path)?;
        DMat4::from_scale_rotation_translation(s, r, t)
    };
    let det = DMat3::from_mat4(m).determinant();
    if !m.is_finite() || det.abs() < 1e-300 || !det.is_finite() {
        return Err(scene_err(
            path,
            format!("object[{i}]: transform must be finite and invertible"),
        ));
    }
    Ok(m)
}

fn load_object(
    scene: &mut Scene,
    o: &format::ObjectDesc,
    i: usize,
    base: &Path,
    scene_path: &Path,
    warned: &mut BTreeSet<String>,
) -> Result<()> {
    let xf = transform(o, i, scene_path)?;
    let obj_path: PathBuf = base.join(&o.mesh);
    if !obj_path.is_file() {
        return Err(scene_err(
            scene_path,
            format!("`object[{i}].mesh`: file {} not found", obj_path.display()),
        ));
    }
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let (models, mtl) = tobj::load_obj(&obj_path, &opts)
        .map_err(|e| mesh_err(&obj_path, format!("cannot parse OBJ: {e}")))?;
    let mtl = match mtl {
        Ok(m) => m,
        // No `mtllib`: tobj reports an empty list as an error on some paths; treat as no materials.
        Err(tobj::LoadError::GenericFailure) | Err(tobj::LoadError::OpenFileFailed)
            if !mentions_mtllib(&obj_path) =>
        {
            Vec::new()
        }
        Err(e) => {
            return Err(mesh_err(
                &obj_path,
                format!("cannot load its MTL library: {e}"),
            ))
        }
    };
    for name in o.materials.keys() {
        if !mtl.iter().any(|m| m.name.trim() == name) {
            return Err(scene_err(
                scene_path,
                format!(
                    "`object[{i}].materials.{name}`: no material of that name in {}",
                    obj_path.display()
                ),
            ));
        }
    }
    // Materials of this OBJ, appended to the scene's list with overrides applied.
    let first = scene.materials.len() as u32;
    for m in &mtl {
        let name = m.name.trim().to_string();
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
        if let Some(ke) = m.unknown_param.get("Ke").filter(|_| m.emissive.is_none()) {
            let v: Vec<f64> = ke
                .split_whitespace()
                .filter_map(|x| x.parse().ok())
                .collect();
            if v.len() == 3 {
                mat.ke = DVec3::new(v[0], v[1], v[2]);
            }
        }
        if m.diffuse_texture.is_some() || m.specular_texture.is_some() || m.normal_texture.is_some()
        {
            warned.insert(format!(
                "{}: material {name}: textures are not supported; using its Kd",
                obj_path.display()
            ));
        }
        if m.dissolve.is_some_and(|d| d < 1.0) || m.dissolve_texture.is_some() {
            warned.insert(format!(
                "{}: material {name}: transparency is not supported; treated as opaque",
                obj_path.display()
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
                mat.ke = color(c, &f("ke"), scene_path)?;
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
                    &obj_path,
                    format!("material {name}: {what} must be finite and non-negative"),
                ));
            }
        }
        if !(mat.ns.is_finite() && mat.ns >= 0.0) {
            return Err(mesh_err(
                &obj_path,
                format!("material {name}: Ns must be finite and non-negative"),
            ));
        }
        if (mat.kd + mat.ks).max_element() > 1.0 {
            warned.insert(format!(
                "{}: material {name}: Kd + Ks exceeds 1 (not energy conserving)",
                obj_path.display()
            ));
        }
        scene.materials.push(mat);
    }
    let mut default_mat = None;
    let mut seen: HashSet<[[u64; 3]; 3]> = HashSet::new();
    let mut total = 0usize;
    for model in &models {
        let mesh = &model.mesh;
        let mut positions = Vec::with_capacity(mesh.positions.len() / 3);
        for (k, p) in mesh.positions.chunks_exact(3).enumerate() {
            let v = DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
            if !v.is_finite() {
                return Err(mesh_err(
                    &obj_path,
                    format!(
                        "model '{}': vertex {} is not finite: {v}",
                        model.name,
                        k + 1
                    ),
                ));
            }
            positions.push(xf.transform_point3(v));
        }
        let mat = match mesh.material_id {
            Some(id) if id < mtl.len() => first + id as u32,
            Some(id) => {
                return Err(mesh_err(
                    &obj_path,
                    format!("model '{}': material index {id} out of range", model.name),
                ))
            }
            None => *default_mat.get_or_insert_with(|| {
                warned.insert(format!(
                    "{}: faces without usemtl get a grey diffuse material (Kd 0.5)",
                    obj_path.display()
                ));
                scene.materials.push(Material::diffuse("default", 0.5));
                (scene.materials.len() - 1) as u32
            }),
        };
        let mut triangles = Vec::with_capacity(mesh.indices.len() / 3);
        for (t, idx) in mesh.indices.chunks_exact(3).enumerate() {
            let tri = [idx[0], idx[1], idx[2]];
            if tri.iter().any(|&v| v as usize >= positions.len()) {
                return Err(mesh_err(
                    &obj_path,
                    format!(
                        "model '{}': triangle {} has a vertex index out of range",
                        model.name,
                        t + 1
                    ),
                ));
            }
            let [a, b, c] = tri.map(|v| positions[v as usize]);
            let longest = (b - a).length().max((c - b).length()).max((a - c).length());
            let area2 = (b - a).cross(c - a).length();
            if !(area2 > 1e-9 * longest * longest) {
                return Err(mesh_err(
                    &obj_path,
                    format!(
                        "model '{}': triangle {} is degenerate (zero area): {a}, {b}, {c}",
                        model.name,
                        t + 1
                    ),
                ));
            }
            let mut key = [a, b, c].map(|p| p.to_array().map(f64::to_bits));
            key.sort();
            if !seen.insert(key) {
                return Err(mesh_err(
                    &obj_path,
                    format!(
                        "model '{}': triangle {} duplicates an earlier face at {a}, {b}, {c}",
                        model.name,
                        t + 1
                    ),
                ));
            }
            triangles.push(tri);
        }
        total += triangles.len();
        let n = triangles.len();
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
        });
    }
    if total == 0 {
        return Err(mesh_err(&obj_path, "mesh has no faces".into()));
    }
    Ok(())
}

fn mentions_mtllib(obj: &Path) -> bool {
    std::fs::read_to_string(obj)
        .map(|t| t.lines().any(|l| l.trim_start().starts_with("mtllib")))
        .unwrap_or(false)
}
