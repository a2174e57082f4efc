//! The path-traced reference against analytic answers: the closed uniform box with an occluder
//! (Le/(1−ρ) everywhere), a plane under a point light, a glossy plane under a constant
//! environment (the Phong lobe's sampling and density), a floor under a square emitter behind a
//! square occluder (its occlusion, in closed form); determinism for a seed.

mod common;

use antiradiance::frame::camera::View;
use antiradiance::progress::Silent;
use antiradiance::reference::{render_reference, Reference, ReferenceOptions};
use antiradiance::scene::{Light, Material, Scene};
use common::*;
use glam::DVec3;
use std::f64::consts::PI;

fn trace(s: &Scene, spp: u32, max_bounces: Option<u32>) -> Reference {
    let opts = ReferenceOptions {
        spp,
        max_bounces,
        seed: 7,
    };
    render_reference(s, &opts, &Silent).unwrap()
}

fn lum(p: [f32; 3]) -> f64 {
    (p[0] as f64 + p[1] as f64 + p[2] as f64) / 3.0
}

/// The image's mean (of [`lum`]) and the standard error of that mean, from the per-pixel
/// standard errors (pixels have independent random streams).
fn mean_and_sigma(r: &Reference) -> (f64, f64) {
    let n = r.image.pixels.len() as f64;
    let mean = r.image.pixels.iter().map(|&p| lum(p)).sum::<f64>() / n;
    let var: f64 = r
        .std_error
        .as_ref()
        .unwrap()
        .pixels
        .iter()
        .map(|&e| lum(e).powi(2))
        .sum();
    (mean, var.sqrt() / n)
}

/// Asserts that `got` is within 4 of its standard errors `sigma` (plus `slack`, the quadrature's
/// error of `want`) of `want`, and prints how many standard errors it is off.
fn within_4_sigma(what: &str, got: f64, want: f64, sigma: f64, slack: f64) {
    println!(
        "{what}: {got:.5} vs {want:.5}, off by {:.2} standard errors ({:.3}%; σ = {:.3}%)",
        (got - want).abs() / sigma,
        100.0 * (got / want - 1.0),
        100.0 * sigma / want
    );
    assert!(
        (got - want).abs() < 4.0 * sigma + slack,
        "{what}: {got} vs {want} (σ {sigma:.2e})"
    );
}

#[test]
fn closed_uniform_box_converges_to_le_over_one_minus_rho() {
    let (rho, le) = (0.6, 1.0);
    let mut s = uniform_enclosure(rho, le, 32, 0.5);
    s.camera.eye = DVec3::new(0.5, 0.6, 0.95);
    s.camera.target = DVec3::new(0.45, 0.35, 0.0);
    s.camera.fov_y_deg = 70.0;
    s.camera.width = 32;
    s.camera.height = 32;
    let want = le / (1.0 - rho);
    let r = trace(&s, 64, None);
    let (mean, sigma) = mean_and_sigma(&r);
    // Measured: 0.09% off, 0.5 σ (bound 4σ, about 0.8%).
    within_4_sigma("image mean", mean, want, sigma, 0.0);
    // Each pixel within 4 of its own standard errors (plus a float margin) of the answer.
    let outside = r
        .image
        .pixels
        .iter()
        .zip(&r.std_error.as_ref().unwrap().pixels)
        .filter(|(p, e)| (lum(**p) - want).abs() > 4.0 * lum(**e) + 1e-4)
        .count();
    assert!(
        outside <= r.image.pixels.len() / 100,
        "{outside} pixels beyond 4σ"
    );
    // The direct part is emission plus one bounce of it: Le(1+ρ) everywhere.
    // (σ of the whole image: an upper bound for its direct part's.)
    let d = r.direct.pixels.iter().map(|&p| lum(p)).sum::<f64>() / r.direct.pixels.len() as f64;
    within_4_sigma("direct part", d, le * (1.0 + rho), sigma, 0.0);
    // A bounce limit truncates the Neumann series: B reflections give Le·Σ_{k≤B} ρ^k.
    let r2 = trace(&s, 64, Some(2));
    let (m2, sigma2) = mean_and_sigma(&r2);
    within_4_sigma("2 bounces", m2, le * (1.0 + rho + rho * rho), sigma2, 0.0);
}

/// The mean of `f` over the floor (y = 0) points that pixel (x, y)'s 8×8 sub-pixel rays reach:
/// the tracer's box filter, by quadrature.
fn over_pixel_on_floor(view: &View, x: u32, y: u32, mut f: impl FnMut(DVec3) -> f64) -> f64 {
    let k = 8;
    let mut sum = 0.0;
    for j in 0..k {
        for i in 0..k {
            let d = view.ray(
                x as f64 + (i as f64 + 0.5) / k as f64,
                y as f64 + (j as f64 + 0.5) / k as f64,
            );
            sum += f(view.eye + d * (-view.eye.y / d.y));
        }
    }
    sum / (k * k) as f64
}

/// A lone diffuse plane under one point light: L = kd/π · I cos θ / r² at every pixel.
#[test]
fn plane_under_a_point_light_matches_the_analytic_radiance() {
    let kd = 0.7;
    let mut s = Scene::empty();
    let m = s.add_material(Material::diffuse("plane", kd));
    let h = 40.0;
    floor(&mut s, h, m);
    let (pos, i) = (DVec3::new(0.4, 1.1, -0.2), 5.0);
    s.lights = vec![Light::Point {
        position: pos,
        intensity: DVec3::splat(i),
    }];
    s.camera.eye = DVec3::new(0.0, 3.0, 3.0);
    s.camera.target = DVec3::ZERO;
    s.camera.fov_y_deg = 50.0;
    s.camera.width = 40;
    s.camera.height = 40;
    let r = trace(&s, 64, None);
    let view = View::new(&s.camera);
    let mut worst: f64 = 0.0;
    let (mut sum_got, mut sum_want) = (0.0, 0.0);
    for y in 0..40 {
        for x in 0..40 {
            // Average the analytic radiance over the pixel (the tracer's box filter).
            let want = over_pixel_on_floor(&view, x, y, |p| {
                let v = pos - p;
                kd / PI * i * (v.y / v.length()) / v.length_squared()
            });
            // The only noise is where in the pixel each sample lands: allow 4 standard errors.
            let got = lum(r.image.at(x, y));
            let sigma = lum(r.std_error.as_ref().unwrap().at(x, y));
            worst = worst.max((got - want).abs() / (4.0 * sigma + 0.002 * want));
            sum_got += got;
            sum_want += want;
        }
    }
    println!("worst pixel at {worst:.2} of its bound");
    assert!(worst <= 1.0, "a pixel is off by {worst:.2}× (4σ + 0.2%)");
    // The image mean: within 4σ of the mean (plus 1e-4 for the 8×8 quadrature per pixel).
    let (_, sigma) = mean_and_sigma(&r);
    let n = 1600.0;
    within_4_sigma(
        "image mean",
        sum_got / n,
        sum_want / n,
        sigma,
        1e-4 * sum_want / n,
    );
}

/// A glossy plane under a constant environment, seen along its normal: L = E·(kd + ks·A) with A
/// the lobe's directional albedo there, by quadrature. Reached only by BSDF sampling, so this
/// checks the lobe's sampling and density.
#[test]
fn glossy_plane_under_environment_matches_quadrature() {
    let (kd, ks, ns, env) = (0.3, 0.5, 30.0, 2.0);
    let mut s = Scene::empty();
    let m = s.add_material(Material {
        ks: DVec3::splat(ks),
        ns,
        ..Material::diffuse("gloss", kd)
    });
    let h = 50.0;
    floor(&mut s, h, m);
    s.environment = DVec3::splat(env);
    s.camera.eye = DVec3::new(0.0, 2.0, 0.0);
    s.camera.target = DVec3::ZERO;
    s.camera.up = DVec3::Z;
    s.camera.fov_y_deg = 2.0;
    s.camera.width = 8;
    s.camera.height = 8;
    let r = trace(&s, 512, None);
    // Directional albedo of the lobe for light leaving along the normal.
    let steps = 4000;
    let mut a = 0.0;
    for k in 0..steps {
        let th = (k as f64 + 0.5) / steps as f64 * PI / 2.0;
        a += (ns + 2.0) / (2.0 * PI)
            * th.cos().powf(ns)
            * th.cos()
            * 2.0
            * PI
            * th.sin()
            * (PI / 2.0 / steps as f64);
    }
    let want = env * (kd + ks * a);
    let (mean, sigma) = mean_and_sigma(&r);
    println!("lobe albedo {a:.4}");
    within_4_sigma("glossy plane", mean, want, sigma, 1e-4 * want);
}

#[test]
fn same_seed_same_image() {
    let mut s = uniform_enclosure(0.5, 1.0, 32, 0.5);
    s.camera.eye = DVec3::new(0.5, 0.5, 0.9);
    s.camera.target = DVec3::new(0.5, 0.5, 0.0);
    s.camera.width = 16;
    s.camera.height = 12;
    let a = trace(&s, 4, None);
    let b = trace(&s, 4, None);
    assert_eq!(a.image, b.image);
    let c = render_reference(
        &s,
        &ReferenceOptions {
            spp: 4,
            max_bounces: None,
            seed: 8,
        },
        &Silent,
    )
    .unwrap();
    assert_ne!(a.image, c.image, "another seed gives other samples");
}

/// A square emitter above a glossy plane, one bounce: the radiance toward the camera is the
/// integral over the emitter of f·Le·cos θ·cos θ_l / r², by quadrature. Light sampling and BSDF
/// sampling meet here through MIS.
#[test]
fn area_light_on_a_glossy_plane_matches_quadrature() {
    let (kd, ks, ns, le) = (0.4, 0.4, 20.0, 3.0);
    let mut s = Scene::empty();
    let m = s.add_material(Material {
        ks: DVec3::splat(ks),
        ns,
        ..Material::diffuse("gloss", kd)
    });
    let e = s.add_material(Material {
        ke: DVec3::splat(le),
        ..Material::diffuse("lamp", 0.0)
    });
    let h = 20.0;
    floor(&mut s, h, m);
    // Facing down (counter-clockwise seen from below), centered above (0.3, ·, 0).
    let (c, half, y) = (DVec3::new(0.3, 1.0, 0.0), 0.25, 1.0);
    quad(
        &mut s,
        "lamp",
        [
            DVec3::new(c.x - half, y, c.z - half),
            DVec3::new(c.x + half, y, c.z - half),
            DVec3::new(c.x + half, y, c.z + half),
            DVec3::new(c.x - half, y, c.z + half),
        ],
        e,
    );
    let eye = DVec3::new(-0.6, 0.5, 0.0);
    s.camera.eye = eye;
    s.camera.target = DVec3::ZERO;
    s.camera.fov_y_deg = 0.2;
    s.camera.width = 4;
    s.camera.height = 4;
    let r = trace(&s, 4096, Some(1));
    let wo = (eye - DVec3::ZERO).normalize();
    let (n, k) = (DVec3::Y, 400);
    let mut want = 0.0;
    for i in 0..k {
        for j in 0..k {
            let q = DVec3::new(
                c.x - half + (i as f64 + 0.5) / k as f64 * 2.0 * half,
                y,
                c.z - half + (j as f64 + 0.5) / k as f64 * 2.0 * half,
            );
            let v = q.normalize();
            let r2 = q.length_squared();
            let travel = -v;
            let refl = travel - 2.0 * travel.dot(n) * n;
            let lobe = (ns + 2.0) / (2.0 * PI) * refl.dot(wo).max(0.0).powf(ns);
            let f = kd / PI + ks * lobe;
            want += f * le * v.dot(n) * v.y / r2 * (2.0 * half / k as f64).powi(2);
        }
    }
    let (got, sigma) = mean_and_sigma(&r);
    within_4_sigma(
        "area light on a glossy plane",
        got,
        want,
        sigma,
        1e-4 * want,
    );
}

/// Form factor from a differential area to a parallel rectangle of sides `a`, `b` at distance
/// `h`, lying under one of its corners (Howell's catalogue, C-3).
fn corner_factor(a: f64, b: f64, h: f64) -> f64 {
    let (x, y) = (a / h, b / h);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * PI)
}

/// Form factor from a point `p` of the floor (facing +y) to the rectangle `x × z` at height `h`
/// above the floor, parallel to it (superposition of corner configurations); 0 when empty.
fn rect_factor(p: DVec3, x: [f64; 2], z: [f64; 2], h: f64) -> f64 {
    if x[1] <= x[0] || z[1] <= z[0] {
        return 0.0;
    }
    let f = |u: f64, v: f64| u.signum() * v.signum() * corner_factor(u.abs(), v.abs(), h - p.y);
    let (u0, u1, v0, v1) = (x[0] - p.x, x[1] - p.x, z[0] - p.z, z[1] - p.z);
    f(u1, v1) - f(u0, v1) - f(u1, v0) + f(u0, v0)
}

/// The path tracer's own occlusion, in closed form: a diffuse floor under a parallel square
/// emitter (Le = 1, height 1) with a black square occluder parallel between them (height 0.5).
/// From a floor point p the occluder covers, on the emitter's plane, its own square scaled by 2
/// about p, so the visible emitter is the emitter less that rectangle and the floor's direct
/// radiance is kd·Le·(F(emitter) − F(emitter ∩ shadow)), a penumbra that moves across every pixel.
/// A tracer that ignored occluders, or let rays through an edge, would be off by up to the whole
/// occluded part (about 60% at the center).
#[test]
fn floor_under_an_occluded_square_emitter_matches_the_closed_form() {
    let (kd, h, ho) = (0.8, 1.0, 0.5);
    let (ex, ez) = ([-0.5, 0.5], [-0.5, 0.5]);
    let (ox, oz) = ([-0.15, 0.25], [-0.2, 0.2]);
    let mut s = Scene::empty();
    let m = s.add_material(Material::diffuse("floor", kd));
    let lamp_m = s.add_material(Material {
        ke: DVec3::ONE,
        ..Material::diffuse("lamp", 0.0)
    });
    let black = s.add_material(Material::diffuse("occluder", 0.0));
    floor(&mut s, 4.0, m);
    lamp(&mut s, 0.5, h, lamp_m);
    // Facing down (the floor sees its front).
    quad(
        &mut s,
        "occluder",
        [
            DVec3::new(ox[0], ho, oz[0]),
            DVec3::new(ox[1], ho, oz[0]),
            DVec3::new(ox[1], ho, oz[1]),
            DVec3::new(ox[0], ho, oz[1]),
        ],
        black,
    );
    // Looking straight down from under the occluder: every camera ray goes down to the floor.
    s.camera.eye = DVec3::new(0.0, 0.4, 0.0);
    s.camera.target = DVec3::ZERO;
    s.camera.up = DVec3::NEG_Z;
    s.camera.fov_y_deg = 100.0;
    let n = 32u32;
    s.camera.width = n;
    s.camera.height = n;
    let r = trace(&s, 256, Some(1));
    let view = View::new(&s.camera);
    // The occluder's extent [a, b] along one axis seen from coordinate c, on the emitter's plane.
    let shadow =
        |c: f64, e: [f64; 2]| -> [f64; 2] { [c + (e[0] - c) * h / ho, c + (e[1] - c) * h / ho] };
    let visible = |p: DVec3| -> f64 {
        let (sx, sz) = (shadow(p.x, ox), shadow(p.z, oz));
        let ix = [sx[0].max(ex[0]), sx[1].min(ex[1])];
        let iz = [sz[0].max(ez[0]), sz[1].min(ez[1])];
        rect_factor(p, ex, ez, h) - rect_factor(p, ix, iz, h)
    };
    let (mut worst, mut min_frac) = (0f64, 1f64);
    let (mut sum_got, mut sum_want) = (0.0, 0.0);
    for y in 0..n {
        for x in 0..n {
            // The pixel's box filter.
            let want = over_pixel_on_floor(&view, x, y, |p| {
                min_frac = min_frac.min(visible(p) / rect_factor(p, ex, ez, h));
                kd * visible(p)
            });
            let got = lum(r.image.at(x, y));
            let sigma = lum(r.std_error.as_ref().unwrap().at(x, y));
            worst = worst.max((got - want).abs() / (4.0 * sigma + 0.003 * want));
            sum_got += got;
            sum_want += want;
        }
    }
    println!("least visible fraction {min_frac:.3}; worst pixel at {worst:.2} of its bound");
    assert!(
        min_frac < 0.5,
        "the occluder must hide much of the emitter somewhere"
    );
    assert!(worst <= 1.0, "a pixel is off by {worst:.2}× (4σ + 0.3%)");
    let (_, sigma) = mean_and_sigma(&r);
    let px = (n * n) as f64;
    within_4_sigma(
        "image mean",
        sum_got / px,
        sum_want / px,
        sigma,
        2e-4 * sum_want / px,
    );
}
