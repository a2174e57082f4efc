//! A bare OBJ or PLY file as a scene (`antiradiance render model.obj`): the mesh placed as it is,
//! with its MTL (a PLY: grey diffuse, as Mitsuba loads one without a BSDF), at the default solver
//! settings, seen from a camera that frames it. Such a file carries no
//! camera and no lights, so the view is chosen here and a file with no emitting material (`Ke`)
//! gets a light so that the image is not black (a sun over a view from outside, a point light at
//! the eye of a view from inside); each choice is one warning. The view: from outside
//! the bounds toward their centre (the bounding sphere filling a 40° view; from +z, +x, −z or −x,
//! whichever probe rays meet the most front faces), unless every such view meets more back
//! faces than front ones (surfaces are one-sided: a closed room seen from outside shows only
//! backs); then from the centre outward, toward whichever side shows the most front faces.

use super::{Light, Scene};
use crate::error::Result;
use glam::DVec3;
use std::path::Path;

/// Whether `path` names an OBJ or PLY file.
pub fn is_bare_mesh(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("obj") || e.eq_ignore_ascii_case("ply"))
}

/// The scene of the OBJ or PLY file at `path` (see the module's documentation).
pub fn load_mesh_scene(path: &Path) -> Result<Scene> {
    // A missing or unreadable file is named as the scene file, as a TOML scene's would be.
    if let Err(super::files::FileProblem::Path(m) | super::files::FileProblem::Content(m)) =
        super::files::check_regular_file(path)
    {
        return Err(super::load::scene_err(path, format!("scene file {m}")));
    }
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    // One object whose mesh is the file itself (mesh paths are relative to the scene file): the
    // TOML scene's loading of an OBJ, a Mitsuba scene's of a PLY shape, checks and messages
    // unchanged.
    let ply = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ply"));
    let mut scene = if ply {
        let escaped = name
            .replace('&', "&amp;")
            .replace('"', "&quot;")
            .replace('<', "&lt;");
        let text = format!(
            "<scene version=\"3.0.0\"><shape type=\"ply\"><string name=\"filename\" value=\"{escaped}\"/></shape></scene>"
        );
        super::mitsuba::parse_mitsuba_scene(&text, path)?
    } else {
        let text = format!("[[object]]\nmesh = {}\n", toml::Value::String(name.clone()));
        super::load::parse_scene(&text, path)?
    };
    let (eye, target) = view(&scene);
    scene.camera.eye = eye;
    scene.camera.target = target;
    scene.warnings.push(format!(
        "{}: a mesh file has no camera: looking from [{:.3}, {:.3}, {:.3}] toward [{:.3}, {:.3}, {:.3}] (place it in a TOML scene with a [camera] to choose)",
        path.display(),
        eye.x,
        eye.y,
        eye.z,
        target.x,
        target.y,
        target.z
    ));
    if !scene.materials.iter().any(|m| m.is_emitter()) {
        let (lo, hi) = scene.bounds();
        let inside = (eye - (lo + hi) * 0.5).length() < 1e-9 * (hi - lo).length().max(1e-300);
        let (light, what) = if inside {
            // Irradiance π at the nearest a wall of the bounds can be (its smallest half-side).
            let r2 = ((hi - lo).min_element() * 0.5).max(1e-6).powi(2);
            let light = Light::Point {
                position: eye,
                intensity: DVec3::splat(std::f64::consts::PI * r2),
            };
            (
                light,
                format!(
                    "a point light of intensity {:.3e} at the eye",
                    std::f64::consts::PI * r2
                ),
            )
        } else {
            let direction = DVec3::new(-0.3, -1.0, -0.5).normalize();
            let light = Light::Directional {
                direction,
                irradiance: DVec3::splat(std::f64::consts::PI),
            };
            let d = direction;
            (
                light,
                format!(
                    "a sun of irradiance π travelling along [{:.3}, {:.3}, {:.3}]",
                    d.x, d.y, d.z
                ),
            )
        };
        scene.lights.push(light);
        scene.warnings.push(format!(
            "{}: no material emits (Ke) and a mesh file has no lights: added {what} (place it in a TOML scene with [[light]]s to choose)",
            path.display()
        ));
    }
    Ok(scene)
}

/// Probe rays per side of a candidate view.
const PROBES: usize = 8;

/// The view of `scene` that sees the most front faces (see the module's documentation), as
/// (eye, target).
fn view(scene: &Scene) -> (DVec3, DVec3) {
    let (lo, hi) = scene.bounds();
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-6);
    let half = (scene.camera.fov_y_deg * 0.5).to_radians();
    let distance = radius / half.sin();
    let axes = [DVec3::Z, DVec3::X, -DVec3::Z, -DVec3::X];
    let outside = axes.map(|a| (centre + a * distance, centre));
    let inside = axes.map(|a| (centre, centre - a * radius));
    let triangles: Vec<[DVec3; 3]> = scene.triangle_corners().collect();
    let score = |v| front_and_back_hits(v, half, &triangles);
    let best = |views: [(DVec3, DVec3); 4], key: &dyn Fn((usize, usize)) -> i64| {
        let scored = views.map(|v| (v, score(v)));
        // The first of the best: +z wins ties.
        let top = scored.iter().map(|&(_, s)| key(s)).max().unwrap_or(0);
        scored.into_iter().find(|&(_, s)| key(s) == top).unwrap()
    };
    let (view, (front, back)) = best(outside, &|(f, b)| f as i64 - b as i64);
    if front >= back {
        return view;
    }
    best(inside, &|(f, _)| f as i64).0
}

/// How many of a `PROBES × PROBES` grid of rays over the view (eye, target) with vertical half
/// angle `half` first meet a triangle from its front (counter-clockwise) side, and how many
/// from its back.
fn front_and_back_hits(
    (eye, target): (DVec3, DVec3),
    half: f64,
    triangles: &[[DVec3; 3]],
) -> (usize, usize) {
    let forward = (target - eye).normalize();
    let right = forward.cross(DVec3::Y).normalize();
    let up = right.cross(forward);
    let t = half.tan();
    let (mut front, mut back) = (0, 0);
    for j in 0..PROBES {
        for i in 0..PROBES {
            let u = ((i as f64 + 0.5) / PROBES as f64 * 2.0 - 1.0) * t;
            let v = ((j as f64 + 0.5) / PROBES as f64 * 2.0 - 1.0) * t;
            let d = (forward + right * u + up * v).normalize();
            let mut nearest = (f64::INFINITY, None);
            for &[a, b, c] in triangles {
                // Möller–Trumbore.
                let (e1, e2) = (b - a, c - a);
                let p = d.cross(e2);
                let det = e1.dot(p);
                if det.abs() < 1e-300 {
                    continue;
                }
                let s = eye - a;
                let bu = s.dot(p) / det;
                if !(0.0..=1.0).contains(&bu) {
                    continue;
                }
                let q = s.cross(e1);
                let bv = d.dot(q) / det;
                if bv < 0.0 || bu + bv > 1.0 {
                    continue;
                }
                let dist = e2.dot(q) / det;
                if dist > 0.0 && dist < nearest.0 {
                    nearest = (dist, Some(e1.cross(e2).dot(d) < 0.0));
                }
            }
            match nearest.1 {
                Some(true) => front += 1,
                Some(false) => back += 1,
                None => {}
            }
        }
    }
    (front, back)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bundled Cornell box's OBJ alone: its emitter is kept (no sun added), the camera
    /// frames the box from +z, and the choice is a warning naming the file.
    #[test]
    fn an_obj_file_is_a_scene_framed_from_plus_z() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes/cornell-box/CornellBox-Original.obj");
        let s = super::super::load_scene(&path).unwrap();
        assert!(s.lights.is_empty(), "{:?}", s.lights);
        assert!(s.materials.iter().any(|m| m.is_emitter()));
        let (lo, hi) = s.bounds();
        let c = (lo + hi) * 0.5;
        assert!((s.camera.target - c).length() < 1e-12);
        let to_eye = s.camera.eye - c;
        assert!(to_eye.x.abs() < 1e-12 && to_eye.y.abs() < 1e-12 && to_eye.z > 0.0);
        // The bounding sphere fits the vertical field of view.
        let r = (hi - lo).length() * 0.5;
        let half = (s.camera.fov_y_deg * 0.5).to_radians();
        assert!((r / to_eye.z - half.sin()).abs() < 1e-12);
        // The file's own warning (duplicate faces), then the camera's; no sun.
        let camera: Vec<_> = s
            .warnings
            .iter()
            .filter(|w| w.contains("no camera"))
            .collect();
        assert_eq!(camera.len(), 1, "{:?}", s.warnings);
        assert!(camera[0].contains("CornellBox-Original.obj"));
        assert!(
            !s.warnings.iter().any(|w| w.contains("sun")),
            "{:?}",
            s.warnings
        );
    }
}

#[cfg(test)]
mod sun_tests {
    use glam::DVec3;

    /// Loads OBJ text as a bare scene.
    fn load(name: &str, text: &str) -> crate::scene::Scene {
        let dir =
            std::env::temp_dir().join(format!("antiradiance-bare-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(format!("{name}.obj"));
        std::fs::write(&path, text).unwrap();
        let s = super::super::load_scene(&path).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        s
    }

    /// An OBJ without an emitting material gets the sun, and says so.
    #[test]
    fn an_obj_without_emitters_gets_a_sun() {
        let s = load("plane", "v 0 0 0\nv 1 0 0\nv 1 0 -1\nv 0 0 -1\nf 1 2 3 4\n");
        assert_eq!(s.lights.len(), 1);
        assert!(
            s.warnings.iter().any(|w| w.contains("added a sun")),
            "{:?}",
            s.warnings
        );
    }

    /// A PLY file (ASCII here; binary goes through the same parser as Mitsuba's ply shapes) is
    /// a scene too: grey diffuse, framed from +z, lit by the sun.
    #[test]
    fn a_ply_file_is_a_scene() {
        let text = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
        let dir =
            std::env::temp_dir().join(format!("antiradiance-bare-ply-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("quad.ply");
        std::fs::write(&path, text).unwrap();
        let s = super::super::load_scene(&path).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(s.meshes.iter().map(|m| m.triangles.len()).sum::<usize>(), 2);
        assert!(s.materials.iter().all(|m| !m.is_emitter()));
        assert!(s.camera.eye.z > 1.0, "{:?}", s.camera.eye);
        assert!(matches!(
            s.lights[..],
            [crate::scene::Light::Directional { .. }]
        ));
    }

    /// A closed room (faces turned inward) is seen from its centre, not from outside, where
    /// every ray would meet a back face.
    #[test]
    fn a_closed_room_is_seen_from_inside() {
        let v = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n";
        let f = "f 2 3 4 1\nf 8 7 6 5\nf 5 6 2 1\nf 3 7 8 4\nf 4 8 5 1\nf 6 7 3 2\n";
        let s = load("room", &format!("{v}{f}"));
        assert!(
            (s.camera.eye - DVec3::splat(0.5)).length() < 1e-12,
            "{:?}",
            s.camera.eye
        );
        // The same cube turned outward is seen from +z.
        let out = "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 4 8 7 3\nf 1 5 8 4\nf 2 3 7 6\n";
        let s = load("cube", &format!("{v}{out}"));
        assert!(
            s.camera.eye.z > 1.0 && (s.camera.eye.x - 0.5).abs() < 1e-12,
            "{:?}",
            s.camera.eye
        );
    }
}
