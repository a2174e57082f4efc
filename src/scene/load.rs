//! Loading and validating a TOML scene and its OBJ/MTL meshes. Every error names the file and
//! field; every number is checked against its range before any meshing or device work.

use super::animation;
use super::files::{self, FileProblem};
use super::format::{self, LightDesc, SceneFile, Xyz};
use super::object::{load_object, ObjectSource};
use super::settings::{resolve_element_size, solver_settings};
use super::{Camera, Light, Scene, MAX_COORDINATE, MAX_SOURCE};
use crate::error::{Error, Result};
use glam::{DMat3, DMat4, DVec3};
use std::collections::BTreeSet;
use std::path::Path;

/// Why a source brighter than [`MAX_SOURCE`] is refused.
pub const SOURCE_LIMIT_REASON: &str = "multiplied by areas, 1/r² and interreflection (up to 1e4×) it would overflow float32 tables and images";

/// Reads and validates a scene file: the project's TOML (mesh paths relative to it), a glTF 2.0
/// file (`.gltf`, `.glb`) or a Mitsuba 3 XML scene (`.xml`), by its extension.
pub fn load_scene(path: &Path) -> Result<Scene> {
    if super::object::is_gltf(path) {
        return load_gltf_scene(path);
    }
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("xml"))
    {
        return super::mitsuba::load_mitsuba_scene(path);
    }
    if super::bare::is_bare_mesh(path) {
        return super::bare::load_mesh_scene(path);
    }
    let text = files::read_text(path, "scene").map_err(|p| match p {
        FileProblem::Path(m) => scene_err(path, format!("scene file {m}")),
        FileProblem::Content(m) => scene_err(path, m),
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
                // Name the key the value belongs to: the last `key =` before the error on its
                // line (inside an inline table too), else the line's first key.
                let on_line = &text[start..s.start.min(text.len())];
                let last_key = on_line
                    .trim_end()
                    .strip_suffix('=')
                    .map(|k| k.trim_end())
                    .map(|k| {
                        let from = k
                            .rfind(|c: char| !(c.is_alphanumeric() || "_-\".'".contains(c)))
                            .map_or(0, |i| i + 1);
                        &k[from..]
                    });
                let key = last_key
                    .or_else(|| {
                        text[start..]
                            .lines()
                            .next()
                            .and_then(|l| l.split_once('='))
                            .map(|(k, _)| k.trim())
                    })
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
    let given_size = file
        .solver
        .as_ref()
        .is_some_and(|s| s.element_size.is_some());
    // Without a `[solver]` table too: a file's defaults ([`SolverSettings::for_file`]).
    scene.solver = solver_settings(file.solver.as_ref().unwrap_or(&Default::default()), path)?;
    if let Some(c) = &file.camera {
        scene.camera = camera(c, path)?;
    }
    if let Some(env) = &file.environment {
        scene.environment = source(env.radiance, "environment.radiance", path)?;
    }
    for (i, l) in file.light.iter().enumerate() {
        let lt = light(l, i, path)?;
        let target = l.target.map_or(DVec3::ZERO, |t| DVec3::from_array(t.0));
        scene
            .light_tracks
            .push(animation::light_track(&l.keyframe, i, &lt, target, path)?);
        scene.lights.push(lt);
    }
    if file.object.is_empty() {
        return Err(scene_err(
            path,
            "no [[object]] given: a scene needs at least one mesh".into(),
        ));
    }
    let mut warned = BTreeSet::new();
    let mut gltf_camera = None;
    for (i, o) in file.object.iter().enumerate() {
        let (transform, transform_field) = transform(o, i, path)?;
        let src = ObjectSource {
            index: i,
            scene_path: path,
            base,
            transform,
            transform_field,
            forced: None,
        };
        let first = scene.meshes.len();
        let camera = load_object(&mut scene, o, &src, &mut warned)?;
        if o.two_sided == Some(true) {
            let end = scene.meshes.len();
            super::add_twins(&mut scene, first..end);
        }
        if gltf_camera.is_none() {
            gltf_camera = camera;
        }
        let motion =
            animation::object_motion(o, i, transform.to_scale_rotation_translation(), path)?;
        scene.objects.push(animation::SceneObject {
            meshes: first..scene.meshes.len(),
            transform,
            moving: motion.is_some() || o.moving == Some(true),
            motion,
        });
    }
    // A glTF mesh's first perspective camera stands in for a missing `[camera]`.
    if let (None, Some(c)) = (&file.camera, gltf_camera) {
        scene.camera = c;
    }
    scene.duration = animation::duration(
        file.animation.as_ref().and_then(|a| a.duration),
        &scene,
        path,
    )?;
    resolve_element_size(&mut scene, given_size, path)?;
    scene.warnings = warned.into_iter().collect();
    Ok(scene)
}

/// A whole glTF file as a scene: its meshes (one unmoving object), lights and first perspective
/// camera (else one framing its bounds from +z), no environment, the default settings.
pub fn load_gltf_scene(path: &Path) -> Result<Scene> {
    let bytes = files::read_bytes(path).map_err(|p| scene_err(path, format!("glTF file {p}")))?;
    let mut scene = Scene::empty();
    scene.path = Some(path.to_path_buf());
    scene.solver = super::SolverSettings::for_file();
    let mut warned = BTreeSet::new();
    let none = Default::default();
    let place = super::gltf_scene::Placement {
        scene_path: path,
        field: "materials".into(),
        transform: DMat4::IDENTITY,
        overrides: &none,
    };
    let loaded = super::gltf_scene::load_gltf(&mut scene, path, &bytes, &place, &mut warned)?;
    scene.objects.push(animation::SceneObject {
        meshes: 0..scene.meshes.len(),
        transform: DMat4::IDENTITY,
        moving: false,
        motion: None,
    });
    scene.camera = match loaded.camera {
        Some(c) => c,
        None => framing(&scene),
    };
    if scene.lights.is_empty() && !scene.materials.iter().any(|m| m.is_emitter()) {
        warned.insert(format!(
            "{}: no lights and no emissive materials: the image is black",
            path.display()
        ));
    }
    resolve_element_size(&mut scene, false, path)?;
    scene.warnings = warned.into_iter().collect();
    Ok(scene)
}

/// A camera on +z looking down −z at the scene's bounds, which fill its 40° field of view.
pub(super) fn framing(scene: &Scene) -> Camera {
    let (lo, hi) = scene.bounds();
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-6);
    let fov = 40.0f64;
    let distance = radius / (fov.to_radians() * 0.5).sin();
    Camera {
        eye: centre + DVec3::Z * distance,
        target: centre,
        up: DVec3::Y,
        fov_y_deg: fov,
        width: 512,
        height: 512,
        supersample: 1,
        jitter: [0.0; 2],
        passes: 1,
        fov_axis: Default::default(),
    }
}

/// An error in the scene file.
pub(super) fn scene_err(path: &Path, message: String) -> Error {
    Error::Scene {
        path: path.into(),
        message,
    }
}

/// An error in a mesh (OBJ or MTL) file.
pub(super) fn mesh_err(path: &Path, message: String) -> Error {
    Error::Mesh {
        path: path.into(),
        message,
    }
}

/// A position or vector: finite, components of magnitude at most [`MAX_COORDINATE`].
pub(super) fn vec3(v: Xyz, field: &str, path: &Path) -> Result<DVec3> {
    let v = v.0;
    if !v.iter().all(|x| x.is_finite()) {
        return Err(scene_err(
            path,
            format!("`{field}` must be finite, got {v:?}"),
        ));
    }
    if v.iter().any(|x| x.abs() > MAX_COORDINATE) {
        return Err(scene_err(
            path,
            format!("`{field}` = {v:?} is beyond ±{MAX_COORDINATE:e} (the largest coordinate magnitude float32 tables handle)"),
        ));
    }
    Ok(DVec3::from_array(v))
}

/// An albedo-like colour: finite and non-negative.
pub(super) fn color(c: format::Rgb, field: &str, path: &Path) -> Result<DVec3> {
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

/// A radiance, intensity or irradiance: a colour of at most [`MAX_SOURCE`].
pub(super) fn source(c: format::Rgb, field: &str, path: &Path) -> Result<DVec3> {
    let v = color(c, field, path)?;
    if v.max_element() > MAX_SOURCE {
        return Err(scene_err(
            path,
            format!(
                "`{field}` = {:?} exceeds {MAX_SOURCE:e}: {SOURCE_LIMIT_REASON}",
                v.max_element()
            ),
        ));
    }
    Ok(v)
}

fn camera(c: &format::CameraDesc, path: &Path) -> Result<Camera> {
    let eye = vec3(c.eye, "camera.eye", path)?;
    let target = vec3(c.target, "camera.target", path)?;
    let up = vec3(
        c.up.unwrap_or(format::Exactly([0.0, 1.0, 0.0])),
        "camera.up",
        path,
    )?;
    let fov = c.fov_y_deg.unwrap_or(40.0);
    if !(fov.is_finite() && fov > 0.0 && fov < 180.0) {
        return Err(scene_err(
            path,
            format!("`camera.fov_y_deg` must be in (0, 180), got {fov}"),
        ));
    }
    let forward = target - eye;
    // Relative to the positions' magnitude: the same camera in any units.
    let apart = forward.length() > 1e-12 * eye.abs().max(target.abs()).max_element();
    if !apart || up == DVec3::ZERO || forward.normalize().cross(up.normalize()).length() < 1e-9 {
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
        supersample: match c.supersample {
            None => 1,
            Some(k) if (1..=super::MAX_SUPERSAMPLE as i64).contains(&k) => k as u32,
            Some(k) => {
                return Err(scene_err(
                    path,
                    format!(
                        "`camera.supersample` must be in 1..={}, got {k}",
                        super::MAX_SUPERSAMPLE
                    ),
                ))
            }
        },
        jitter: [0.0; 2],
        passes: match c.passes {
            None => 1,
            Some(k) if (1..=super::MAX_PASSES as i64).contains(&k) => k as u32,
            Some(k) => {
                return Err(scene_err(
                    path,
                    format!(
                        "`camera.passes` must be in 1..={}, got {k}",
                        super::MAX_PASSES
                    ),
                ))
            }
        },
        fov_axis: Default::default(),
    })
}

/// A direction: non-zero, normalized.
pub(super) fn unit(v: Xyz, field: &str, path: &Path) -> Result<DVec3> {
    let d = vec3(v, field, path)?;
    if d == DVec3::ZERO {
        return Err(scene_err(path, format!("`{field}` must be non-zero")));
    }
    Ok(d.normalize())
}

/// The fields each light type takes (`type` aside).
const LIGHT_FIELDS: [(&str, &[&str]); 3] = [
    ("directional", &["direction", "irradiance"]),
    ("point", &["position", "intensity"]),
    (
        "spot",
        &[
            "position",
            "target",
            "intensity",
            "cutoff_deg",
            "beam_width_deg",
        ],
    ),
];

fn light(l: &LightDesc, i: usize, path: &Path) -> Result<Light> {
    let f = |name: &str| format!("light[{i}].{name}");
    let Some(&(kind, fields)) = LIGHT_FIELDS.iter().find(|(k, _)| *k == l.kind) else {
        return Err(scene_err(
            path,
            format!(
                "`{}` must be \"directional\", \"point\" or \"spot\", got {:?}",
                f("type"),
                l.kind
            ),
        ));
    };
    let given = [
        ("direction", l.direction.is_some()),
        ("irradiance", l.irradiance.is_some()),
        ("position", l.position.is_some()),
        ("intensity", l.intensity.is_some()),
        ("target", l.target.is_some()),
        ("cutoff_deg", l.cutoff_deg.is_some()),
        ("beam_width_deg", l.beam_width_deg.is_some()),
    ];
    for (name, present) in given {
        let wanted = fields.contains(&name);
        if present != wanted {
            return Err(scene_err(
                path,
                format!(
                    "`{}` {}: a {kind} light takes {}",
                    f(name),
                    if present {
                        "does not apply"
                    } else {
                        "is missing"
                    },
                    fields.join(", ")
                ),
            ));
        }
    }
    // Every field the type takes is present (checked above).
    let get = |v: Option<Xyz>| v.unwrap_or(format::Exactly([0.0; 3]));
    let get_rgb = |v: Option<format::Rgb>| v.unwrap_or(format::Rgb::Grey(0.0));
    Ok(match kind {
        "directional" => Light::Directional {
            direction: unit(get(l.direction), &f("direction"), path)?,
            irradiance: source(get_rgb(l.irradiance), &f("irradiance"), path)?,
        },
        "point" => Light::Point {
            position: vec3(get(l.position), &f("position"), path)?,
            intensity: source(get_rgb(l.intensity), &f("intensity"), path)?,
        },
        _ => {
            let p = vec3(get(l.position), &f("position"), path)?;
            let t = vec3(get(l.target), &f("target"), path)?;
            if !((t - p).length() > 1e-12 * p.abs().max(t.abs()).max_element()) {
                return Err(scene_err(
                    path,
                    format!("`{}` must differ from `{}`", f("target"), f("position")),
                ));
            }
            let axis = (t - p).normalize();
            let cutoff_deg = l.cutoff_deg.unwrap_or(0.0);
            let beam_width_deg = l.beam_width_deg.unwrap_or(0.0);
            if !(cutoff_deg.is_finite() && cutoff_deg > 0.0 && cutoff_deg <= 180.0) {
                return Err(scene_err(
                    path,
                    format!(
                        "`{}` must be in (0, 180], got {cutoff_deg}",
                        f("cutoff_deg")
                    ),
                ));
            }
            if !(beam_width_deg.is_finite()
                && beam_width_deg >= 0.0
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
                intensity: source(get_rgb(l.intensity), &f("intensity"), path)?,
                cutoff: cutoff_deg.to_radians(),
                beam_width: beam_width_deg.to_radians(),
            }
        }
    })
}

/// A finite number of magnitude at most [`MAX_COORDINATE`] (scale factors, matrix entries).
fn bounded(x: f64, field: &str, path: &Path) -> Result<f64> {
    if x.is_finite() && x.abs() <= MAX_COORDINATE {
        Ok(x)
    } else {
        Err(scene_err(
            path,
            format!("`{field}` entry {x:?} must be finite and within ±{MAX_COORDINATE:e} (the largest coordinate magnitude float32 tables handle)"),
        ))
    }
}

/// Object-to-world transform (`matrix`, or translate · rotate · scale) and the fields that
/// gave it, for messages.
fn transform(o: &format::ObjectDesc, i: usize, path: &Path) -> Result<(DMat4, String)> {
    let f = |name: &str| format!("object[{i}].{name}");
    let (m, field) = if let Some(rows) = o.matrix {
        if o.scale.is_some() || o.rotate.is_some() || o.translate.is_some() {
            return Err(scene_err(
                path,
                format!("`{}` excludes scale, rotate and translate", f("matrix")),
            ));
        }
        let rows = rows.0.map(|r| r.0);
        for x in rows.iter().flatten() {
            bounded(*x, &f("matrix"), path)?;
        }
        if rows[3] != [0.0, 0.0, 0.0, 1.0] {
            return Err(scene_err(
                path,
                format!(
                    "`{}`: the last row must be [0, 0, 0, 1] (an affine transform), got {:?}",
                    f("matrix"),
                    rows[3]
                ),
            ));
        }
        (DMat4::from_cols_array_2d(&rows).transpose(), f("matrix"))
    } else {
        let s = match o.scale {
            None => DVec3::ONE,
            Some(format::Scale::Uniform(k)) => DVec3::splat(k),
            Some(format::Scale::Axes(a)) => DVec3::from_array(a),
        };
        for k in s.to_array() {
            bounded(k, &f("scale"), path)?;
        }
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
        let t = vec3(
            o.translate.unwrap_or(format::Exactly([0.0; 3])),
            &f("translate"),
            path,
        )?;
        let given: Vec<String> = [
            ("scale", o.scale.is_some()),
            ("rotate", o.rotate.is_some()),
            ("translate", o.translate.is_some()),
        ]
        .iter()
        .filter(|(_, g)| *g)
        .map(|(n, _)| f(n))
        .collect();
        (
            DMat4::from_scale_rotation_translation(s, r, t),
            given.join("`, `"),
        )
    };
    // Invertible relative to the columns' lengths, so that any units pass alike.
    let m3 = DMat3::from_mat4(m);
    let det = m3.determinant();
    let norms = m3.x_axis.length() * m3.y_axis.length() * m3.z_axis.length();
    if !m.is_finite() || !det.is_finite() || !(det.abs() > 1e-12 * norms) {
        return Err(scene_err(
            path,
            format!("object[{i}]: transform must be finite and invertible"),
        ));
    }
    Ok((m, field))
}
