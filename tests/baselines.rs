//! The baseline methods against independent answers: hierarchical radiosity with explicit
//! visibility on the same links and progressive refinement radiosity (hemicube item buffer on
//! the GPU, rays on the CPU), each on both backends (GPU on lavapipe, validation on): the closed
//! uniform box with an occluder against Le/(1−ρ), two parallel unit squares against the analytic
//! form factor, progressive refinement's unshot energy per shot, and the bundled Cornell box
//! against the project's path tracer.
//!
//! Bounds are the figures measured on this machine (printed by each test) with a small margin:
//! a change that makes an answer worse fails, one that makes it better shows in the figure.

mod common;

use antiradiance::engine::{Options, Rendered};
use antiradiance::scene::{load_scene, Material, Scene};
use antiradiance::{BackendKind, Method};
use common::*;
use glam::DVec3;
use std::f64::consts::PI;
use std::path::Path;

const BASELINES: [Method; 2] = [Method::HierarchicalRadiosity, Method::ProgressiveRadiosity];
const BACKENDS: [BackendKind; 2] = [BackendKind::Cpu, BackendKind::Gpu];

fn options(method: Method, backend: BackendKind, iterations: usize) -> Options {
    let mut o = Options::backend(backend);
    o.method = method;
    o.solver.iterations = Some(iterations);
    o.shadow_map_size = 128;
    o
}

/// Exitant radiance of every leaf: emission plus what the display table I_total holds (light
/// reflected from what arrived through links or shots; no analytic lights in these scenes).
fn radiances(r: &Rendered, scene: &Scene, o: &Options) -> Vec<DVec3> {
    // The same discretization as the engine's (leaf order, areas, bins).
    let prep = antiradiance::engine::Prepared::new(scene, o, None, &antiradiance::progress::Silent)
        .unwrap();
    let sys = &prep.system;
    sys.leaves
        .iter()
        .map(|l| {
            let row = r.i_total.row(l.node as usize);
            let s: DVec3 = sys
                .bins
                .centers
                .iter()
                .zip(row)
                .filter(|(c, _)| c.dot(l.normal) > 0.0)
                .map(|(_, v)| *v)
                .sum();
            sys.materials[l.material as usize].ke + s * sys.bins.omega / (l.area * PI)
        })
        .collect()
}

/// The closed box with a floating block (albedo `rho`, emission `le`), seen from inside.
fn box_from_inside(rho: f64, le: f64) -> Scene {
    let mut scene = uniform_enclosure(rho, le, 128, 0.25);
    view(
        &mut scene,
        DVec3::new(0.5, 0.8, 0.95),
        DVec3::new(0.5, 0.2, 0.2),
        70.0,
        24,
    );
    scene
}

/// A closed unit box of albedo 0.4 emitting 1 everywhere, with a floating block: every element
/// converges to Le/(1−ρ) whatever the visibility, so occlusion errors show as departures.
/// Measured (worst element): hierarchical radiosity −1.17% (CPU), progressive refinement
/// −0.59% (CPU) / −0.37% (GPU); bound 2% (the issue's), every pixel too.
#[test]
fn uniform_box_with_an_occluder_converges_to_le_over_one_minus_rho() {
    let (rho, le) = (0.4, 1.0);
    let mut scene = box_from_inside(rho, le);
    // τ = 0.5 at 128 bins: mostly leaf links near the block (cluster links lose up to 2.3% at τ = 1).
    scene.solver.oracle = 0.5;
    let want = le / (1.0 - rho);
    for method in BASELINES {
        for backend in BACKENDS {
            // Hierarchical radiosity: one bounce per iteration; progressive: 5 sweeps of shots.
            let mut o = options(method, backend, 30);
            o.baseline.rays_per_link = 16;
            if method == Method::ProgressiveRadiosity {
                o.solver.iterations = Some(20);
            }
            let r = render_checked(&format!("{method} box"), &scene, o.clone());
            let (lo, hi) = radiances(&r, &scene, &o)
                .iter()
                .map(|l| (l.x - want) / want)
                .fold((f64::MAX, f64::MIN), |(lo, hi), e| (lo.min(e), hi.max(e)));
            let pixels = r
                .image
                .pixels
                .iter()
                .map(|p| ((p[0] as f64 - want) / want).abs())
                .fold(0.0, f64::max);
            println!(
                "{method} {backend}: elements {:+.3}% … {:+.3}% from Le/(1−ρ), worst pixel {:.3}%",
                lo * 100.0,
                hi * 100.0,
                pixels * 100.0
            );
            assert!(
                lo > -0.02 && hi < 0.02 && pixels < 0.02,
                "{method} {backend}: {lo:.4} … {hi:.4}, pixel {pixels:.4}"
            );
        }
    }
}

/// The same box with every surface two-sided (back-to-back twins at one depth): progressive
/// refinement's hemicube must keep the twin that faces the shooter, as the CPU's rays do, or a
/// shot lands on a back and its energy is lost. The twins face outward or into the block and
/// receive nothing, so the check is the image from inside. Measured: worst pixel 0.25% (CPU),
/// 0.17% (GPU); the same before the item buffer's tie-break (here the rounding favoured the
/// right twin; in Veach's room image-based radiosity's hemicubes did not, tests/image_based.rs).
#[test]
fn progressive_refinement_with_two_sided_surfaces() {
    let (rho, le) = (0.4, 1.0);
    let mut scene = box_from_inside(rho, le);
    let n = scene.meshes.len();
    antiradiance::scene::add_twins(&mut scene, 0..n);
    // The twins first: the depth test alone would keep the first drawn of a tie, a back.
    let backs = scene.meshes.split_off(n);
    scene.meshes.splice(0..0, backs);
    let want = le / (1.0 - rho);
    for backend in BACKENDS {
        let o = options(Method::ProgressiveRadiosity, backend, 20);
        let r = render_checked("progressive two-sided box", &scene, o);
        let (worst, mean) = r.image.pixels.iter().fold((0.0f64, 0.0), |(w, m), p| {
            let e = (p[0] as f64 - want) / want;
            (w.max(e.abs()), m + e / r.image.pixels.len() as f64)
        });
        println!(
            "progressive refinement {backend}, two-sided: worst pixel {:.3}%, mean {:+.3}%",
            worst * 100.0,
            mean * 100.0
        );
        assert!(worst < 0.02, "{backend}: worst pixel {worst:.4}");
    }
}

/// Flux a unit emitter (radiance 1, black) sends into a grey receiver, from the receiver's
/// converged radiosity (ρ·E: nothing comes back from the black emitter).
fn exchanged_flux(
    method: Method,
    backend: BackendKind,
    emitter: [DVec3; 4],
    receiver: [DVec3; 4],
) -> f64 {
    let rho = 0.5;
    let mut s = Scene::empty();
    let e = s.add_material(Material {
        ke: DVec3::ONE,
        ..Material::diffuse("emitter", 0.0)
    });
    let r = s.add_material(Material::diffuse("receiver", rho));
    quad(&mut s, "emitter", emitter, e);
    quad(&mut s, "receiver", receiver, r);
    s.solver.bins = 256;
    s.solver.element_size = 0.1;
    view(
        &mut s,
        DVec3::new(0.5, 0.5, 3.0),
        DVec3::new(0.5, 0.5, 0.5),
        40.0,
        8,
    );
    let mut o = options(method, backend, 2);
    o.baseline.rays_per_link = 4;
    let rendered = render_checked(&format!("{method} squares"), &s, o.clone());
    let radiance = radiances(&rendered, &s, &o);
    let prep =
        antiradiance::engine::Prepared::new(&s, &o, None, &antiradiance::progress::Silent).unwrap();
    prep.system
        .leaves
        .iter()
        .zip(&radiance)
        .filter(|(l, _)| l.material == r)
        .map(|(l, b)| b.x * PI / rho * l.area)
        .sum()
}

/// Two unit squares facing each other one unit apart: F = 0.199825. Measured: hierarchical
/// radiosity +1.5% (the antiradiance links, fully visible), progressive refinement −0.03% (exact
/// point-to-triangle kernels at each receiver's 4 sub-triangle centroids); bound 2%.
#[test]
fn parallel_unit_squares_exchange_the_analytic_flux() {
    let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let want = PI * 0.199_825;
    for method in BASELINES {
        for backend in BACKENDS {
            let phi = exchanged_flux(
                method,
                backend,
                [v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)],
                [v(0., 0., 1.), v(0., 1., 1.), v(1., 1., 1.), v(1., 0., 1.)],
            );
            let e = (phi - want) / want;
            println!(
                "{method} {backend}: parallel squares {phi:.5} vs {want:.5} ({:+.2}%)",
                e * 100.0
            );
            // Measured +0.04% … +0.10%; bound 3× the largest.
            assert!(e.abs() < 0.003, "{method} {backend}: {phi} vs {want}");
        }
    }
}

/// Every shot removes the shooter's unshot power and hands on at most ρ_max of it: the unshot
/// power falls after every shot, on both backends, and the iterations' residuals with it.
#[test]
fn progressive_refinement_unshot_energy_decreases_monotonically() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.toml");
    let mut s = load_scene(&path).unwrap();
    s.solver.element_size = 0.5;
    s.camera.width = 16;
    s.camera.height = 16;
    for backend in BACKENDS {
        let r = render_checked(
            "monotone",
            &s,
            options(Method::ProgressiveRadiosity, backend, 4),
        );
        let report = r.stats.method_report.as_ref().expect("a method report");
        let unshot: Vec<f64> = report.shots.iter().map(|s| s.unshot).collect();
        let rises = unshot
            .windows(2)
            .filter(|w| w[1] > w[0] * (1.0 + 1e-6))
            .count();
        println!(
            "{backend}: {} shots, unshot {:.4e} → {:.4e} W, residuals {:?}, {rises} rises",
            unshot.len(),
            unshot[0],
            unshot.last().unwrap(),
            r.stats.residuals
        );
        assert!(unshot.len() > 100 && rises == 0, "{backend}: {rises} rises");
        assert!(r.stats.residuals.windows(2).all(|w| w[1] < w[0]));
        assert!(*r.stats.residuals.last().unwrap() < 0.5);
    }
}

/// The bundled Cornell box at 32×32 against the path tracer (1024 spp), over the pixels that see
/// no emitter (`common::measure`), at the scene's own settings (128 bins), each baseline on both
/// backends. Hierarchical
/// radiosity takes the lamp's direct light from the same shadow-mapped samples as
/// antiradiance (before them, through the bins, it measured 0.280 at 128 bins and needed 512
/// for 0.109); rays per link hardly move it (4 … 141: 0.1360 … 0.1369 at 64×64, before the
/// samples). Progressive refinement shoots the lamp with exact point-to-triangle kernels,
/// its direct light at element resolution. The "indirect light" figure subtracts antiradiance's
/// direct-only image, so for progressive refinement it also holds its direct light's error.
#[test]
fn cornell_box_against_the_path_tracer() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.toml");
    let mut s = load_scene(&path).unwrap();
    s.camera.width = 32;
    s.camera.height = 32;
    let truth = path_traced(&s, 1024);
    let direct = render_checked(
        "cornell box, direct light",
        &s,
        options(Method::Antiradiance, BackendKind::Cpu, 0),
    )
    .image;
    // Measured (relative RMSE, mean): hierarchical radiosity 0.0989 / −1.31% (CPU), 0.1007 /
    // −1.38% (GPU); progressive refinement 0.1117 / −3.02% (CPU), 0.1130 / −3.02% (GPU). The
    // reference's noise (0.040) is part of each figure, so the bounds are 1.3× the measured
    // RMSE and 1.5× the mean's bias.
    for (method, backend, bound, bias) in [
        (Method::HierarchicalRadiosity, BackendKind::Cpu, 0.13, 0.02),
        (Method::HierarchicalRadiosity, BackendKind::Gpu, 0.13, 0.02),
        (Method::ProgressiveRadiosity, BackendKind::Cpu, 0.15, 0.045),
        (Method::ProgressiveRadiosity, BackendKind::Gpu, 0.15, 0.045),
    ] {
        let t = std::time::Instant::now();
        let r = render_checked(
            &format!("{method} cornell box"),
            &s,
            options(method, backend, 8),
        );
        let m = measure(&r.image, &direct, &truth);
        println!(
            "{method} {backend}: {m} ({:.1} s)",
            t.elapsed().as_secs_f64()
        );
        assert!(m.noise < bound / 3.0, "reference noise {}", m.noise);
        assert!(m.rel_rmse <= bound, "{method} {backend}: {m}");
        assert!(m.mean_bias.abs() <= bias, "{method} {backend}: {m}");
    }
}
