//! Shading normals (issue 17, item 3): a tessellated sphere whose OBJ carries the exact `vn`,
//! under a directional light, against the analytic Lambert shading of the true sphere, on both
//! backends; the same sphere without `vn` (faceted) is measurably worse; unusable `vn` load
//! with one warning and render exactly as the faceted sphere; normals follow the object's
//! transform and its keyframes; the indirect light on the smooth sphere in a closed room against
//! the path tracer.

mod common;

use antiradiance::engine::{Options, Rendered, SolverOverrides};
use antiradiance::frame::camera::{View, SUPERSAMPLE};
use antiradiance::scene::{load_scene, Scene};
use antiradiance::BackendKind as Backend;
use common::*;
use glam::DVec3;
use std::f64::consts::PI;
use std::path::PathBuf;

/// Latitude bands and longitude segments of the UV sphere.
const LAT: usize = 20;
const LON: usize = 40;
/// Diffuse albedo and the light's irradiance.
const KD: f64 = 0.5;
const E: f64 = 2.0;

/// What the sphere's OBJ says about normals.
#[derive(Clone, Copy, PartialEq)]
enum Normals {
    /// `vn` = the normalized position (exact) on every corner.
    Exact,
    /// No `vn`: faceted.
    Without,
    /// Every `vn` unusable: zero, not finite, or facing away from its faces.
    Unusable,
}

/// A unit UV sphere of `LAT` × `LON` quads (triangles at the poles), counter-clockwise seen
/// from outside, with the `vn` `normals` asks for.
fn sphere_obj(normals: Normals) -> String {
    let mut v: Vec<DVec3> = vec![DVec3::Y];
    for i in 1..LAT {
        let th = PI * i as f64 / LAT as f64;
        for j in 0..LON {
            let ph = 2.0 * PI * j as f64 / LON as f64;
            v.push(DVec3::new(
                th.sin() * ph.cos(),
                th.cos(),
                th.sin() * ph.sin(),
            ));
        }
    }
    v.push(DVec3::NEG_Y);
    let ring = |i: usize, j: usize| 2 + (i - 1) * LON + j % LON; // 1-based, ring i ≥ 1
    let south = v.len();
    let mut faces: Vec<Vec<usize>> = Vec::new();
    for j in 0..LON {
        faces.push(vec![1, ring(1, j), ring(1, j + 1)]);
        faces.push(vec![south, ring(LAT - 1, j), ring(LAT - 1, j + 1)]);
        for i in 1..LAT - 1 {
            faces.push(vec![
                ring(i, j),
                ring(i + 1, j),
                ring(i + 1, j + 1),
                ring(i, j + 1),
            ]);
        }
    }
    let mut text = String::from("# UV sphere for tests/shading_normals.rs\n");
    for p in &v {
        text += &format!("v {} {} {}\n", p.x, p.y, p.z);
    }
    if normals != Normals::Without {
        for (k, p) in v.iter().enumerate() {
            text += &match (normals, k) {
                (Normals::Exact, _) => format!("vn {} {} {}\n", p.x, p.y, p.z),
                (_, 0) => "vn 0 0 0\n".to_string(),
                (_, 1) => "vn nan 0 1\n".to_string(),
                // Facing away from every face around the vertex (and not unit length).
                _ => format!("vn {} {} {}\n", -2.0 * p.x, -2.0 * p.y, -2.0 * p.z),
            };
        }
    }
    for mut f in faces {
        // Counter-clockwise seen from outside: the corners' cross product points outward.
        let c: Vec<DVec3> = f.iter().map(|&k| v[k - 1]).collect();
        let centroid = c.iter().sum::<DVec3>() / c.len() as f64;
        if (c[1] - c[0]).cross(c[2] - c[0]).dot(centroid) < 0.0 {
            f.reverse();
        }
        let corner = |k: &usize| match normals {
            Normals::Without => format!("{k}"),
            _ => format!("{k}//{k}"),
        };
        text += &format!("f {}\n", f.iter().map(corner).collect::<Vec<_>>().join(" "));
    }
    text
}

/// The light's travel direction: from the upper right front.
fn light_travel() -> DVec3 {
    DVec3::new(-1.0, -1.2, -0.8).normalize()
}

/// Writes the sphere scene (OBJ, MTL and TOML) into a folder of its own and returns the TOML's
/// path. `object` is extra TOML for the `[[object]]` (a transform, keyframes).
fn write_scene(name: &str, normals: Normals, object: &str) -> (Scratch, PathBuf) {
    let dir = Scratch::new(&format!("shading-{name}"));
    std::fs::write(
        dir.join("sphere.obj"),
        format!("mtllib sphere.mtl\nusemtl grey\n{}", sphere_obj(normals)),
    )
    .unwrap();
    std::fs::write(
        dir.join("sphere.mtl"),
        format!("newmtl grey\nKd {KD} {KD} {KD}\n"),
    )
    .unwrap();
    let t = light_travel();
    let toml = format!(
        "[camera]\neye = [0.6, 0.8, 3.6]\ntarget = [0.0, 0.0, 0.0]\nfov_y_deg = 36.0\n\
         width = 64\nheight = 64\n\n[solver]\nbins = 32\n\n\
         [[light]]\ntype = \"directional\"\ndirection = [{}, {}, {}]\nirradiance = {E}\n\n\
         [[object]]\nmesh = \"sphere.obj\"\n{object}",
        t.x, t.y, t.z
    );
    let path = dir.join("sphere.toml");
    std::fs::write(&path, toml).unwrap();
    (dir, path)
}

fn load(name: &str, normals: Normals) -> Scene {
    let (_dir, path) = write_scene(name, normals, "");
    load_scene(&path).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Direct light only (no iterations: a convex sphere exchanges no light anyway), 1024² shadow
/// map.
fn render(scene: &Scene, backend: Backend) -> Rendered {
    let options = Options {
        backend,
        shadow_map_size: 1024,
        solver: SolverOverrides {
            iterations: Some(0),
            ..Default::default()
        },
        ..Default::default()
    };
    render_checked("shading normals", scene, options)
}

/// The analytic pixel values: the mean over a pixel's 2×2 sample rays of `Kd/π·E·max(0, n·l)`
/// at the true unit sphere's normal where the ray meets it, for pixels whose every sample ray
/// meets the sphere inscribed in the tessellation (radius 0.98: the faces lie at least
/// cos(π/20) ≈ 0.988 from the center), so that every sample hits the mesh; `None` elsewhere.
fn analytic(scene: &Scene) -> Vec<Option<f64>> {
    let view = View::new(&scene.camera);
    let l = -light_travel();
    let hit = |d: DVec3, r: f64| {
        // |eye + t d|² = r², nearest t.
        let (b, c) = (view.eye.dot(d), view.eye.length_squared() - r * r);
        let disc = b * b - c;
        (disc > 0.0).then(|| view.eye + d * (-b - disc.sqrt()))
    };
    let (w, h) = (scene.camera.width, scene.camera.height);
    let mut out = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let mut sum = 0.0;
            let mut inside = true;
            for sy in 0..SUPERSAMPLE {
                for sx in 0..SUPERSAMPLE {
                    let d = view.ray(
                        x as f64 + (sx as f64 + 0.5) / SUPERSAMPLE as f64,
                        y as f64 + (sy as f64 + 0.5) / SUPERSAMPLE as f64,
                    );
                    inside &= hit(d, 0.98).is_some();
                    if let Some(p) = hit(d, 1.0) {
                        sum += KD / PI * E * p.normalize().dot(l).max(0.0);
                    }
                }
            }
            out.push(inside.then_some(sum / (SUPERSAMPLE * SUPERSAMPLE) as f64));
        }
    }
    out
}

/// Relative RMSE (over the analytic mean) and worst pixel (relative to the analytic peak) of
/// `img`'s first channel over the pixels `reference` covers.
fn error(name: &str, r: &Rendered, reference: &[Option<f64>]) -> (f64, f64) {
    let (mut se, mut sum, mut n, mut worst, mut peak) = (0.0, 0.0, 0usize, 0f64, 0f64);
    for (p, want) in r.image.pixels.iter().zip(reference) {
        if let Some(want) = want {
            let d = p[0] as f64 - want;
            se += d * d;
            sum += want;
            n += 1;
            worst = worst.max(d.abs());
            peak = peak.max(*want);
        }
    }
    assert!(n > 1000, "{name}: only {n} pixels checked");
    let rmse = (se / n as f64).sqrt() / (sum / n as f64);
    println!(
        "{name}: {n} pixels, relative RMSE {rmse:.4e}, worst pixel {:.4e} of the peak",
        worst / peak
    );
    (rmse, worst / peak)
}

/// The smooth sphere matches the analytic shading of the true sphere; the faceted one (no
/// `vn`) is several times further off, on both backends, and the two backends agree.
#[test]
fn a_smooth_sphere_matches_analytic_lambert_shading() {
    let smooth = load("smooth", Normals::Exact);
    let faceted = load("faceted", Normals::Without);
    assert!(smooth.meshes.iter().all(|m| !m.normals.is_empty()));
    assert!(faceted.meshes.iter().all(|m| m.normals.is_empty()));
    let reference = analytic(&smooth);
    let mut images = Vec::new();
    for backend in [Backend::Cpu, Backend::Gpu] {
        let r = render(&smooth, backend);
        let s = error(&format!("smooth {backend:?}"), &r, &reference);
        let f = error(
            &format!("faceted {backend:?}"),
            &render(&faceted, backend),
            &reference,
        );
        // Measured (64², 2196 pixels inside the sphere, both backends alike): smooth relative
        // RMSE 6.64e-3, worst pixel 5.6e-2 of the peak (at the terminator, where a face turned
        // from the light is dark though its interpolated normal still sees it: light must
        // reach the face's front); faceted 4.69e-2 and 9.1e-2, 7.1× the smooth RMSE.
        assert!(s.0 < 1e-2, "{backend:?}: smooth relative RMSE {:.3e}", s.0);
        assert!(s.1 < 8e-2, "{backend:?}: smooth worst pixel {:.3e}", s.1);
        assert!(
            f.0 > 4.0 * s.0,
            "{backend:?}: smooth {s:?} vs faceted {f:?}"
        );
        images.push(r.image);
    }
    // Measured: the GPU's pixels within 2.3e-6 of the CPU's, relative to the peak (float32).
    let peak = images[0].pixels.iter().map(|p| p[0]).fold(0f32, f32::max);
    let diff = images[0]
        .pixels
        .iter()
        .zip(&images[1].pixels)
        .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).abs()).fold(0f32, f32::max))
        .fold(0f32, f32::max);
    println!("GPU vs CPU: worst pixel {:.3e} of the peak", diff / peak);
    assert!(diff / peak < 1e-5, "GPU vs CPU: {:.3e}", diff / peak);
}

/// `vn` that are zero, not finite or face away from their faces are dropped with one warning
/// naming the file, and the sphere renders exactly as without `vn` (both backends).
#[test]
fn unusable_normals_warn_once_and_render_faceted() {
    let bad = load("unusable", Normals::Unusable);
    let faceted = load("faceted-twin", Normals::Without);
    let warnings: Vec<&String> = bad.warnings.iter().filter(|w| w.contains("vn")).collect();
    println!("{warnings:?}");
    assert_eq!(warnings.len(), 1, "{:?}", bad.warnings);
    assert!(warnings[0].contains("sphere.obj"), "{}", warnings[0]);
    assert!(
        warnings[0].contains(&format!(
            "{} triangles have unusable `vn`",
            2 * LON * (LAT - 1)
        )),
        "{}",
        warnings[0]
    );
    assert!(bad.meshes.iter().all(|m| m.normals.is_empty()));
    for backend in [Backend::Cpu, Backend::Gpu] {
        let a = render(&bad, backend).image;
        let b = render(&faceted, backend).image;
        assert!(
            a == b,
            "{backend:?}: the unusable-vn sphere differs from the faceted one"
        );
    }
}

/// Every corner's shading normal of `s` against `want(position)`, within float32 rounding.
fn check_normals(s: &Scene, what: &str, want: impl Fn(DVec3) -> DVec3) {
    let mut worst = 0f64;
    for m in &s.meshes {
        assert_eq!(m.normals.len(), m.triangles.len(), "{what}");
        for (t, n) in m.triangles.iter().zip(&m.normals) {
            for k in 0..3 {
                let w = want(m.positions[t[k] as usize]).normalize();
                worst = worst.max((n[k] - w).length());
            }
        }
    }
    println!("{what}: worst normal {worst:.2e} off");
    // Measured: 9.4e-16 (the `vn` and the positions are the same float32 values).
    assert!(worst < 1e-12, "{what}: {worst:.2e}");
}

/// Normals go by the inverse transpose of the object's transform (a scaled sphere's normals
/// are an ellipsoid's), and move with its keyframes.
#[test]
fn normals_follow_the_transform_and_the_keyframes() {
    let c = DVec3::new(0.5, -0.25, 0.1);
    let (_dir, path) = write_scene(
        "scaled",
        Normals::Exact,
        &format!(
            "scale = [2.0, 1.0, 0.5]
translate = [{}, {}, {}]
",
            c.x, c.y, c.z
        ),
    );
    let s = load_scene(&path).unwrap();
    // On the ellipsoid x²/4 + y² + 4z² = 1 (centred at c) the normal is ∝ (x/4, y, 4z).
    check_normals(&s, "scaled", |p| {
        let q = p - c;
        DVec3::new(q.x / 4.0, q.y, 4.0 * q.z)
    });
    let keys = "[[object.keyframe]]\ntime = 0.0\ntranslate = [0.0, 0.0, 0.0]\n\
                [[object.keyframe]]\ntime = 1.0\ntranslate = [0.4, 0.2, 0.0]\n\
                rotate = { axis = [0, 0, 1], angle_deg = 60 }\n";
    let s = load_scene(&write_scene("moving", Normals::Exact, keys).1).unwrap();
    for t in [0.0, 0.5, 1.0] {
        let at = s.at(t);
        // A rigid motion: the normals stay radial about the moved center (the vertices' mean
        // over the sphere's symmetric rings is its center); normals left where they were
        // would not be radial at the rotated vertices.
        let m = &at.meshes[0];
        let center = m.positions.iter().sum::<DVec3>() / m.positions.len() as f64;
        check_normals(&at, &format!("moving at t = {t}"), |p| p - center);
    }
}

/// The sphere scene made a closed room (walls of albedo 0.7 around it, the camera inside) lit by
/// a point light high on one side, at 32²: the sphere's indirect light (the image less its
/// direct-only image, against the path tracer's image less its direct part, which uses the same
/// shading normals) over the pixels wholly on the sphere, smooth and faceted, both backends.
fn sphere_in_a_room(normals: Normals) -> Scene {
    use antiradiance::scene::{Light, Material};
    let mut s = load(&format!("room-{}", normals as u8), normals);
    let wall = s.add_material(Material::diffuse("wall", 0.7));
    add_box(
        &mut s,
        "room",
        DVec3::new(-3.0, -1.2, -3.0),
        DVec3::new(3.0, 3.0, 4.2),
        wall,
        true,
    );
    s.lights = vec![Light::Point {
        position: DVec3::new(-2.2, 2.6, 1.0),
        intensity: DVec3::splat(12.0),
    }];
    s.camera.width = 32;
    s.camera.height = 32;
    s
}

/// Relative RMSE (over the reference's mean) of the indirect light on the sphere's pixels, and
/// its mean's bias.
fn indirect_on_sphere(
    image: &Rendered,
    direct: &Rendered,
    truth: &Truth,
    on: &[bool],
) -> (f64, f64) {
    let r = &truth.reference;
    let (mut se, mut sum, mut n, mut got_sum) = (0.0, 0.0, 0.0, 0.0);
    for i in (0..on.len()).filter(|&i| on[i]) {
        for c in 0..3 {
            let got = (image.image.pixels[i][c] - direct.image.pixels[i][c]) as f64;
            let want = (r.image.pixels[i][c] - r.direct.pixels[i][c]) as f64;
            se += (got - want).powi(2);
            sum += want;
            got_sum += got;
            n += 1.0;
        }
    }
    ((se / n).sqrt() / (sum / n), got_sum / sum - 1.0)
}

/// Iterations for the room (ρ = 0.7): the scene's 4 leave a residual of 7%.
const ITERATIONS: usize = 16;

#[test]
fn indirect_light_on_a_smooth_sphere_against_the_path_tracer() {
    let smooth = sphere_in_a_room(Normals::Exact);
    let on: Vec<bool> = analytic(&smooth).iter().map(Option::is_some).collect();
    let pixels = on.iter().filter(|&&b| b).count();
    assert!(pixels > 200, "{pixels} sphere pixels");
    let truth = path_traced(&smooth, 2048);
    let noise = {
        let e = truth.reference.std_error.as_ref().unwrap();
        let (mut v, mut sum, mut n) = (0.0, 0.0, 0.0);
        for i in (0..on.len()).filter(|&i| on[i]) {
            for c in 0..3 {
                v += (e.pixels[i][c] as f64).powi(2);
                sum += (truth.reference.image.pixels[i][c] - truth.reference.direct.pixels[i][c])
                    as f64;
                n += 1.0;
            }
        }
        (v / n).sqrt() / (sum / n)
    };
    println!("the reference's noise on the sphere, over its indirect light: {noise:.4}");
    let options = |backend, iterations| Options {
        backend,
        solver: SolverOverrides {
            iterations,
            ..Default::default()
        },
        ..Default::default()
    };
    // The faceted sphere (no `vn`) measured the same figures to four digits: the diffuse
    // indirect light is the leaves' (face clusters'), read in the bin toward the eye, which a
    // Lambertian surface does not vary; the shading normals enter through the direct light.
    for backend in [Backend::Cpu, Backend::Gpu] {
        let r = render_checked("smooth", &smooth, options(backend, Some(ITERATIONS)));
        let d = render_checked("smooth", &smooth, options(backend, Some(0)));
        let (rmse, bias) = indirect_on_sphere(&r, &d, &truth, &on);
        println!(
            "{backend:?}: indirect light on the sphere's {pixels} pixels, relative RMSE {rmse:.4}, mean {:+.2}%",
            100.0 * bias
        );
        // Measured: relative RMSE 0.1245 on both backends (of it the reference's noise 0.065),
        // mean +1.27% (the mean's own noise about 0.2%). With the receiver calibration of the
        // push (issue 36), which this scene's 21,448 leaves are now past (receivers::MAX_LEAVES),
        // 0.1325 and +2.82%. Bounds 1.5× of the latter.
        assert!(rmse < 0.2, "{backend:?}: {rmse}");
        assert!(bias.abs() < 0.043, "{backend:?}: {bias}");
    }
}
