//! Image-based radiosity (`--method image-based-radiosity`): a closed uniform box against its
//! closed form, the Cornell box against the project's path tracer on both backends, the GPU's
//! rasterized hemicubes building the cube the CPU's ray-cast ones build, and view independence:
//! a camera moved without rebuilding the cube draws what a cube built for that camera draws.
//!
//! Bounds are the figures measured on this machine (printed by each test) with a margin of
//! about 1.5× (the cube is deterministic: the same VPLs, the same texels).

mod common;

use antiradiance::backend::Prepared;
use antiradiance::engine::{Engine, Options};
use antiradiance::frame::Image;
use antiradiance::methods::ibr::{self, cube::Cube, gpu::GpuHemicubes};
use antiradiance::progress::Silent;
use antiradiance::scene::{load_scene, Scene};
use antiradiance::{BackendKind, Method};
use common::*;
use glam::DVec3;
use std::path::Path;

fn cornell_box(size: u32) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.toml");
    let mut s = load_scene(&path).unwrap();
    s.camera.width = size;
    s.camera.height = size;
    s
}

fn options(backend: BackendKind) -> Options {
    let mut o = Options::backend(backend);
    o.method = Method::ImageBasedRadiosity;
    o.solver.iterations = Some(1);
    o
}

fn rel_rmse(a: &Image, b: &Image) -> f64 {
    let (mut sq, mut sum) = (0.0, 0.0);
    for (x, y) in a.pixels.iter().zip(&b.pixels) {
        for k in 0..3 {
            sq += (x[k] as f64 - y[k] as f64).powi(2);
            sum += y[k] as f64;
        }
    }
    let n = 3.0 * a.pixels.len() as f64;
    (sq / n).sqrt() / (sum / n)
}

/// A closed box (and a block inside) of albedo 0.5 emitting 1 everywhere. The cube holds the
/// VPLs' light: at points over the floor (in the block's shadow too) it must equal what the
/// same VPLs deliver gathered exactly (every VPL, visibility by a ray), within the cube's
/// sampling. The image against Le/(1−ρ) = 2: the VPLs' clamp takes their near field along the
/// room's edges and in its corners (instant radiosity with the same VPLs: mean −2.5%, worst
/// 16%); the cube gathers it back (`near`), leaving the VPLs' own sampling error: their flux
/// (the roulette's), which the image's mean follows, and smooth patches of a few percent at 256
/// paths. The direct light: 32 emitter samples tile the box, each its cell's exact irradiance
/// (as point samples: 0.71 of π on the floor, the image −8.1%), shadowed by its sample point's
/// map; alone (`--iterations 0` of antiradiance) it is −0.41% from 1.5 on average and 4.1% at
/// worst, at the block's top edges (−0.44% and 4.6% in the room's creases while the maps' taps
/// past a concave corner voted shadow; before a receiver's plane cutting a cell took its front
/// part: the block's faces −2.4% to −4.5%).
#[test]
fn closed_uniform_box() {
    let mut s = uniform_enclosure(0.5, 1.0, 32, 0.25);
    view(
        &mut s,
        DVec3::new(0.5, 0.8, 0.95),
        DVec3::new(0.5, 0.2, 0.2),
        70.0,
        24,
    );
    let o = options(BackendKind::Cpu);
    let prep = Prepared::new(&s, &o, None, &Silent).unwrap();
    let (sys, surf) = (&prep.system, &prep.surfaces);
    let caster = antiradiance::raycast::RayCaster::new(sys);
    let lift = ibr::lift(sys);
    let mut rays = ibr::ray_cast(&caster, surf, o.baseline.hemicube, lift);
    let built = ibr::build(&prep.scene, sys, surf, &o.baseline, &mut rays).unwrap();
    let vpls = antiradiance::methods::instant::trace(&prep.scene, sys, &o.baseline).unwrap();
    let gather = |p: DVec3, n: DVec3| -> f64 {
        let mut e = 0.0;
        for l in &vpls.lights {
            let (x, ln) = ibr::hemicube::frame_of(l).unwrap();
            let o = x + ln * lift;
            let (d, dist) = ((p - o).normalize(), (p - o).length());
            let Some(inc) = antiradiance::frame::lights::incident(l, p) else {
                continue;
            };
            let c = -inc.travel.dot(n);
            if d.dot(ln) <= 0.0 || c <= 0.0 || caster.occluded(o, d, 0.0, dist * (1.0 - 1e-6)) {
                continue;
            }
            e += inc.irradiance.x * c;
        }
        e
    };
    // 18×18 points over the floor, away from the walls (a cell at a wall mixes both).
    let (mut worst, mut sq, mut n) = (0.0f64, 0.0, 0);
    for j in 1..19 {
        for i in 1..19 {
            let p = DVec3::new((i as f64 + 0.5) / 20.0, 0.0, (j as f64 + 0.5) / 20.0);
            let want = gather(p, DVec3::Y);
            let e = (built.cube.irradiance(p, DVec3::Y).x - want) / want;
            worst = worst.max(e.abs());
            sq += e * e;
            n += 1;
        }
    }
    let rms = (sq / n as f64).sqrt();
    println!(
        "the cube against its VPLs gathered exactly: RMS {:.2}%, worst {:.2}%",
        100.0 * rms,
        100.0 * worst
    );
    record("ibr.box.cube-rms", rms, 0.002);
    // Measured 0.52% RMS, 2.13% worst (cube 128, hemicubes 128; 0.50% / 2.67% with the grid
    // half a cell off the walls and copies only where a footprint covers a cell's centre).
    assert!(rms <= 0.0075, "{rms}");
    assert!(worst <= 0.04, "{worst}");
    let want = 2.0;
    for backend in [BackendKind::Cpu, BackendKind::Gpu] {
        let r = render_checked("image-based radiosity box", &s, options(backend));
        let mut ir = options(backend);
        ir.method = Method::InstantRadiosity;
        let ir = render_checked("instant radiosity box", &s, ir);
        let errs: Vec<f64> = r
            .image
            .pixels
            .iter()
            .map(|p| (p[0] as f64 - want) / want)
            .collect();
        let worst = errs.iter().fold(0.0f64, |m, e| m.max(e.abs()));
        let mean = errs.iter().sum::<f64>() / errs.len() as f64;
        let ir_worst = ir
            .image
            .pixels
            .iter()
            .fold(0.0f64, |m, p| m.max(((p[0] as f64 - want) / want).abs()));
        // The VPLs' flux against the reflected flux of the closed form, Φ_e·ρ/(1−ρ) with
        // Φ_e = π·Le·A (A = 6.59 m²: the room's 6 and the block's 0.59): a sampling error of
        // the light paths' roulette, which the image's mean follows.
        let f = &r
            .stats
            .method_report
            .as_ref()
            .expect("a method report")
            .figures;
        let flux = f["vpl_flux"] / (std::f64::consts::PI * 6.59) - 1.0;
        println!(
            "{backend}: against Le/(1−ρ) mean {:+.2}%, worst {:.2}%; the VPLs' flux {:+.2}%; instant radiosity's worst {:.2}%",
            100.0 * mean,
            100.0 * worst,
            100.0 * flux,
            100.0 * ir_worst
        );
        // Measured: the image's mean 0.63% from the flux's error (−0.51% and −1.14%; the
        // direct light alone is −0.41%); 0.38% (−0.76%) while the cells along the walls lost
        // lights (`hemicube::splat_cells`, `Cube::new`).
        assert!(
            (mean - flux).abs() <= 0.01,
            "{backend}: {mean} against {flux}"
        );
        record(&format!("ibr.box.{backend}"), mean.abs(), 0.01);
        record(&format!("ibr.box.{backend}.worst"), worst, 0.01);
        // Measured on both backends: mean −0.51%, worst +8.7% (too bright, where the floor
        // meets the right wall; the VPLs' sampling: it moves with the number of light paths,
        // docs/measurements.md; −0.53% and 8.3% while shadow taps past a concave corner
        // voted shadow and darkened the creases; −0.76% and 9.5% while the cells
        // along the walls lost lights; −1.29% before cut cells lit
        // their receivers; −2.62% and 15.8% with `--near-rays 0`, instant radiosity's 16.0%).
        assert!(mean.abs() <= 0.02, "{backend}: mean {mean}");
        assert!(worst <= 0.13, "{backend}: worst {worst}");
        assert!(
            worst < 0.8 * ir_worst,
            "{backend}: {worst} against {ir_worst}"
        );
    }
}

/// Both backends against the path tracer on the Cornell box at 32² (1024 spp), and against
/// each other.
#[test]
fn cornell_box_against_the_path_tracer() {
    let s = cornell_box(32);
    let truth = path_traced(&s, 1024);
    let mut d = Options::backend(BackendKind::Cpu);
    d.solver.iterations = Some(0);
    let direct = render_checked("direct light", &s, d).image;
    let mut images = Vec::new();
    for backend in [BackendKind::Cpu, BackendKind::Gpu] {
        let t = std::time::Instant::now();
        let r = render_checked("image-based radiosity", &s, options(backend));
        let m = measure(&r.image, &direct, &truth);
        let f = &r
            .stats
            .method_report
            .as_ref()
            .expect("a method report")
            .figures;
        println!(
            "image-based radiosity {backend}: {m} ({:.1} s, {} VPLs, {} layers, {:.1} MB)",
            t.elapsed().as_secs_f64(),
            f["vpls"],
            f["cube_layers"],
            f["cube_bytes"] / 1e6
        );
        record(&format!("ibr.{backend}"), m.rel_rmse, 0.02);
        assert!(m.noise < 0.05, "reference noise {}", m.noise);
        // Measured 0.1442 on both (0.1480 with `--near-rays 0`; instant radiosity with the same
        // VPLs: 0.147 / 0.149).
        assert!(m.rel_rmse <= 0.21, "{backend}: {m}");
        images.push(r.image);
    }
    let d = rel_rmse(&images[1], &images[0]);
    println!("GPU against CPU: relative RMSE {d:.5}");
    // Measured 0.00015 (the cubes differ only at rasterized triangle edges).
    assert!(d <= 5e-4, "{d}");
}

/// The GPU's rasterized hemicubes and the CPU's ray-cast ones build the same cube from `s`:
/// every layer of one found in the other, irradiances within rasterization's edge texels.
/// Returns the larger share of one's layers missing in the other and the largest difference.
fn gpu_and_cpu_cubes(s: &Scene) -> (f64, f64) {
    // 128 light paths rather than 256: the cubes agree per texel, whatever the VPLs.
    let mut o = options(BackendKind::Cpu);
    o.baseline.vpls = 128;
    let prep = Prepared::new(s, &o, None, &Silent).unwrap();
    let settings = o.baseline;
    let (sys, surf) = (&prep.system, &prep.surfaces);
    let lift = ibr::lift(sys);
    let caster = antiradiance::raycast::RayCaster::new(sys);
    let mut rays = ibr::ray_cast(&caster, surf, settings.hemicube, lift);
    let cpu = ibr::build(&prep.scene, sys, surf, &settings, &mut rays).unwrap();
    let ctx = context();
    let mut raster =
        GpuHemicubes::new(&ctx, surf, settings.hemicube, ibr::chunk(settings.hemicube)).unwrap();
    let mut cast = |l: &[antiradiance::scene::Light]| raster.cast(l, surf, lift);
    let gpu = ibr::build(&prep.scene, sys, surf, &settings, &mut cast).unwrap();
    assert_clean(&ctx);
    let (c, g): (&Cube, &Cube) = (&cpu.cube, &gpu.cube);
    let (worst, missing) = c.compare(g);
    let (worst2, missing2) = g.compare(c);
    let samples = |b: &ibr::Built| b.report.figures["hemicube_samples"];
    println!(
        "layers {} / {}, samples {} / {}; largest difference {worst:.2e} / {worst2:.2e} of the peak, missing {:.4}% / {:.4}%",
        c.layers(),
        g.layers(),
        samples(&cpu),
        samples(&gpu),
        100.0 * missing,
        100.0 * missing2
    );
    assert!(samples(&cpu) > 1e6);
    assert!((samples(&cpu) / samples(&gpu) - 1.0).abs() < 1e-3);
    (missing.max(missing2), worst.max(worst2))
}

#[test]
fn gpu_cube_equals_cpu_cube() {
    let (missing, worst) = gpu_and_cpu_cubes(&cornell_box(32));
    // Measured at 128 paths: 109,552 layers in both, none missing in the other, the largest
    // difference 2.4% of the peak (a cell where one edge texel fell otherwise; 1.5% at 256
    // paths, whose cells hold more VPLs' samples).
    assert!(missing < 5e-4, "{missing}");
    assert!(worst < 0.05, "{worst}");
}

/// Two-sided surfaces (`two_sided`, glTF doubleSided, Mitsuba twosided) are back-to-back twins
/// at one depth: the hemicube's item buffer must keep the twin that faces the VPL, as the ray
/// caster does, or the VPL's light lands on the black back (Veach's room: GPU against CPU 0.61
/// relative RMSE before the tie-break; here 0.18% of the samples differed and the largest
/// difference was 12% of the peak with a push of 4e-7 of the depth).
#[test]
fn gpu_cube_equals_cpu_cube_with_twins() {
    let mut s = cornell_box(32);
    let n = s.meshes.len();
    antiradiance::scene::add_twins(&mut s, 0..n);
    let (missing, worst) = gpu_and_cpu_cubes(&s);
    // Measured at 128 paths: 110,742 / 110,766 layers, samples equal, the largest difference
    // 2.3% of the peak, 0.022% of the GPU's layers missing in the CPU's (at 256 paths 1.5% and
    // 0.25%): a texel that slips through a closed block's edge meets the inner twin's front and
    // gives a sample (one-sided, a back: none), and the two backends' edge texels slip in
    // different places (both add such layers: the CPU's cube has 1,190 more than without
    // twins). The bound is the 256 paths' figure with a margin: where texels slip varies.
    assert!(missing < 4e-3, "{missing}");
    assert!(worst < 0.05, "{worst}");
}

/// The cube is built once: a camera moved on an engine draws, without rebuilding it, the image
/// an engine made for that camera draws.
#[test]
fn moved_camera_reads_the_same_cube() {
    let s = cornell_box(24);
    let mut moved = s.camera.clone();
    moved.eye += DVec3::new(0.6, -0.4, -1.0);
    moved.target += DVec3::new(-0.3, 0.2, 0.0);
    // A small cube of few VPLs (three are built): what is tested is that a draw reads it.
    let mut o = options(BackendKind::Cpu);
    (o.baseline.vpls, o.baseline.hemicube, o.baseline.cube) = (32, 32, 32);
    let mut e = Engine::new(&s, &o, &Silent).unwrap();
    e.draw().unwrap();
    e.take_timings();
    e.set_camera(moved.clone()).unwrap();
    let a = e.draw().unwrap();
    let timings: Vec<String> = e.take_timings().into_iter().map(|(k, _)| k).collect();
    assert!(
        !timings.iter().any(|k| k == "hemicube" || k == "warp"),
        "{timings:?}"
    );
    let mut s2 = s.clone();
    s2.camera = moved;
    let b = Engine::new(&s2, &o, &Silent).unwrap().draw().unwrap();
    assert_eq!(a.pixels, b.pixels);
    // And the view did change.
    let first = Engine::new(&s, &o, &Silent).unwrap().draw().unwrap();
    assert!(rel_rmse(&first, &b) > 0.05);
}

/// `animate --orbit` walks a still scene: every frame after the first is only a draw (no
/// update, no rebuild), and the last frame is what an engine made at the orbited camera draws.
#[test]
fn an_orbit_only_draws() {
    use antiradiance::animate::{animate, orbited, Sampling};
    let s = cornell_box(16);
    let mut sampling = Sampling::of(&s, Some(3), None).unwrap();
    sampling.orbit = 30.0;
    let mut last = None;
    // A small cube of few VPLs: the walk is what is tested.
    let mut o = options(BackendKind::Cpu);
    (o.baseline.vpls, o.baseline.hemicube, o.baseline.cube) = (32, 32, 32);
    let records = animate(&s, &o, sampling, &Silent, &mut |_, img| {
        last = Some(img.clone());
        Ok(())
    })
    .unwrap();
    assert_eq!(records.len(), 3);
    for r in &records[1..] {
        // The iterations do nothing (microseconds); the draw is the frame.
        assert!(r.solve_ms < 0.01 * r.draw_ms, "{r:?}");
        assert!(r.update_parts.lights_ms == 0.0 && r.update_parts.backend_ms == 0.0);
    }
    let mut s2 = s.clone();
    s2.camera = orbited(&s.camera, 30f64.to_radians());
    let want = Engine::new(&s2, &o, &Silent).unwrap().draw().unwrap();
    assert_eq!(last.unwrap().pixels, want.pixels);
}
