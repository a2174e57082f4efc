//! Area emitters by shadow-mapped samples (§3.3) against closed forms: a lone plane under a
//! parallel square emitter, whose irradiance has an exact expression, on both backends at the
//! default emitter sampling. GPU renders run on lavapipe with the validation layer on.

mod common;

use antiradiance::engine::Options;
use antiradiance::frame::camera::{View, SUPERSAMPLE};
use antiradiance::scene::{Material, Precision, Scene};
use antiradiance::BackendKind as Backend;
use common::*;
use glam::DVec3;
use std::f64::consts::PI;

/// Form factor from a differential area to a parallel rectangle of sides `a`, `b` at distance
/// `h`, the area lying under one of its corners (Howell's catalogue, C-3; independent of the
/// project's polygon formula).
fn corner_factor(a: f64, b: f64, h: f64) -> f64 {
    let (x, y) = (a / h, b / h);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * PI)
}

/// Form factor from a differential area at `p` (facing +y) to the square `[x0, x1] × [z0, z1]` at
/// height `h` above it (facing down), by superposition of the four corner configurations.
fn square_factor(p: DVec3, x: [f64; 2], z: [f64; 2], h: f64) -> f64 {
    let f = |u: f64, v: f64| u.signum() * v.signum() * corner_factor(u.abs(), v.abs(), h);
    let (u0, u1, v0, v1) = (x[0] - p.x, x[1] - p.x, z[0] - p.z, z[1] - p.z);
    f(u1, v1) - f(u0, v1) - f(u1, v0) + f(u0, v0)
}

/// A diffuse plane under a black unit square emitting Le = 1 downwards at height 1: every pixel
/// of the plane shows kd·Le·F (F the closed-form factor to the square; no interreflection: the
/// emitter reflects nothing), drawn from the default 32 emitter samples' shadow maps. No
/// iterations, float32 tables, so the frame shows direct light only.
///
/// Measured worst pixel (relative to the pixel, at least 2% of the peak), both backends alike:
/// −0.82% at the default 32 samples (8 samples: −3.6%, 128: −0.20%; with the samples warped
/// onto the triangles instead of at the centroids of equal cells, 32 gave +3.9%). Bound: the
/// issue's 1%.
#[test]
fn plane_under_a_square_emitter_matches_the_closed_form() {
    let (kd, half, h) = (0.5, 3.0, 1.0);
    let mut s = Scene::empty();
    let floor = s.add_material(Material::diffuse("floor", kd));
    let mut lamp = Material::diffuse("lamp", 0.0);
    lamp.ke = DVec3::ONE;
    let lamp = s.add_material(lamp);
    quad(
        &mut s,
        "floor",
        [
            DVec3::new(-half, 0.0, half),
            DVec3::new(half, 0.0, half),
            DVec3::new(half, 0.0, -half),
            DVec3::new(-half, 0.0, -half),
        ],
        floor,
    );
    let (sx, sz) = ([-0.5, 0.5], [-0.5, 0.5]);
    // Wound to face down (−y).
    quad(
        &mut s,
        "lamp",
        [
            DVec3::new(sx[0], h, sz[0]),
            DVec3::new(sx[1], h, sz[0]),
            DVec3::new(sx[1], h, sz[1]),
            DVec3::new(sx[0], h, sz[1]),
        ],
        lamp,
    );
    s.camera.eye = DVec3::new(0.0, 2.5, 4.0);
    s.camera.target = DVec3::ZERO;
    s.camera.width = 48;
    s.camera.height = 48;
    s.camera.fov_y_deg = 60.0;
    s.solver.bins = 32;
    s.solver.element_size = 1.0;
    s.solver.iterations = 0;
    s.solver.precision = Precision::F32;
    let view = View::new(&s.camera);
    // The floor point a sample ray reaches, unless the lamp is in the way or it misses the floor.
    let floor_point = |d: DVec3| -> Option<DVec3> {
        let t_lamp = (h - view.eye.y) / d.y;
        let q = view.eye + d * t_lamp;
        if t_lamp > 0.0 && q.x > sx[0] && q.x < sx[1] && q.z > sz[0] && q.z < sz[1] {
            return None;
        }
        let t = -view.eye.y / d.y;
        let p = view.eye + d * t;
        (t > 0.0 && p.x.abs() < half && p.z.abs() < half).then_some(p)
    };
    let expected = |x: u32, y: u32| -> Option<f64> {
        let mut sum = 0.0;
        for j in 0..SUPERSAMPLE {
            for i in 0..SUPERSAMPLE {
                let d = view.ray(
                    x as f64 + (i as f64 + 0.5) / SUPERSAMPLE as f64,
                    y as f64 + (j as f64 + 0.5) / SUPERSAMPLE as f64,
                );
                sum += kd * square_factor(floor_point(d)?, sx, sz, h);
            }
        }
        Some(sum / (SUPERSAMPLE * SUPERSAMPLE) as f64)
    };
    let peak = (0..48)
        .flat_map(|y| (0..48).map(move |x| (x, y)))
        .filter_map(|(x, y)| expected(x, y))
        .fold(0.0, f64::max);
    for backend in [Backend::Cpu, Backend::Gpu] {
        let r = render_checked("square emitter", &s, Options::backend(backend));
        let (mut worst, mut checked, mut signed) = (0f64, 0, 0.0);
        for y in 0..48 {
            for x in 0..48 {
                let Some(want) = expected(x, y) else {
                    continue;
                };
                for c in r.image.at(x, y) {
                    let err = (c as f64 - want) / want.max(0.02 * peak);
                    if err.abs() > worst {
                        (worst, signed) = (err.abs(), err);
                    }
                }
                checked += 1;
            }
        }
        println!("{backend:?}: {checked} pixels, worst {signed:+.3e} (peak {peak:.4})");
        assert!(checked > 1000, "{checked} pixels");
        assert!(worst < 1e-2, "{backend:?}: worst {signed:+.3e}");
    }
}
