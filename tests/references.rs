//! Where antiradiance cancels light, against an independent answer: small scenes with occluders,
//! solved at the default settings (128 bins, τ = 1, the relative element size, the scene's
//! iterations) by the CPU solver and by the GPU passes, each image measured against the project's
//! unbiased path tracer (`src/reference/`) over the pixels that do not see an emitter.
//!
//! The bounds are the errors measured on this machine (lavapipe, 2 cores) with a small margin
//! (see the comment above the tests), so a change that makes the answer worse fails here, and one
//! that makes it better says so in the printed figure (then tighten the bound). The reference's
//! own noise is printed beside each figure and asserted to be a small part of the bound, and
//! each test checks that the solve without antiradiance breaks its bounds.

mod common;

use antiradiance::engine::{Options, Prepared};
use antiradiance::metrics::relative_errors;
use antiradiance::scene::{load_scene, Light, Material, Scene};
use antiradiance::{BackendKind as Backend, Engine};
use common::*;
use glam::DVec3;
use std::path::Path;

/// What a scene's images may be off the path tracer by (both backends), and the GPU image off
/// the CPU image.
struct Bounds {
    /// Relative RMSE (RMSE / mean) over the pixels that see no emitter.
    rel_rmse: f64,
    /// |image mean / reference mean − 1| over the same pixels.
    mean_bias: f64,
    /// Median relative error of the pixels only indirect light reaches (None: the scene has few).
    indirect_median: Option<f64>,
    /// Relative RMSE of the indirect light alone ([`Measured::indirect_rmse`]).
    indirect_rmse: f64,
    /// `metrics::relative_errors` of the GPU image against the CPU image, and the same with
    /// float16 accumulation (`common::gpu_bound`).
    gpu_vs_cpu: f64,
    gpu_vs_cpu_f16: f64,
}

/// Renders `scene` on both backends at its own settings, measures each image against `truth`
/// and asserts `bounds`; then checks that the bounds discriminate: the CPU solve without
/// antiradiance (U alone, light through every occluder) must break one of them. Records the
/// relative RMSE as figures `KEY.cpu`, `KEY.gpu`, `KEY.without` (`common::record`).
fn check(
    name: &str,
    key: &str,
    scene: &Scene,
    truth: &Truth,
    bounds: &Bounds,
) -> Vec<antiradiance::engine::Rendered> {
    let within = |m: &Measured| {
        m.rel_rmse < bounds.rel_rmse
            && m.mean_bias.abs() < bounds.mean_bias
            && bounds.indirect_median.is_none_or(|b| m.indirect_median < b)
            && m.indirect_rmse < bounds.indirect_rmse
    };
    let silent = &antiradiance::progress::Silent;
    // One linking for the five renders (the dragon's is 70% of a CPU render): every render
    // below differs from it only in what is set after linking. Fitted to the GPU's memory, as
    // `Engine::new` fits a GPU render (none of these scenes reaches it).
    let memory = Some(context().info.device_local_bytes);
    let mut prep = Prepared::new(scene, &Options::backend(Backend::Cpu), memory, silent)
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    // The sky's rays once for the five renders too (the breakfast room's: 5 s each).
    let _ = prep.sky(None);
    // `--iterations 0` applied to the prepared settings, as `Options::resolve` applies it.
    let direct_only = || {
        let mut p = prep.clone();
        p.settings = antiradiance::engine::SolverOverrides {
            iterations: Some(0),
            ..Default::default()
        }
        .apply(&p.settings);
        p
    };
    let mut renders = Vec::new();
    let mut cpu_direct = None;
    for backend in [Backend::Cpu, Backend::Gpu] {
        let t = std::time::Instant::now();
        let r = render_prepared(name, prep.clone(), Options::backend(backend));
        let direct = render_prepared(name, direct_only(), Options::backend(backend)).image;
        let m = measure(&r.image, &direct, truth);
        if backend == Backend::Cpu {
            cpu_direct = Some(direct);
        }
        println!("{name} {backend}: {m} ({:.1} s)", t.elapsed().as_secs_f64());
        record(&format!("{key}.{backend}"), m.rel_rmse, 0.02);
        assert!(
            m.noise < bounds.rel_rmse / 5.0,
            "{name}: the reference's noise {:.4} is not small against the bound {}",
            m.noise,
            bounds.rel_rmse
        );
        assert!(
            within(&m),
            "{name} {backend}: {m}; bounds: relative RMSE {}, |mean| {}, indirect median {:?}, indirect RMSE {}",
            bounds.rel_rmse,
            bounds.mean_bias,
            bounds.indirect_median,
            bounds.indirect_rmse
        );
        renders.push(r);
    }
    let (gpu_vs_cpu, _) = relative_errors(&renders[1].image, &renders[0].image).unwrap();
    println!("{name}: GPU image vs CPU image, relative RMSE {gpu_vs_cpu:.2e}");
    let limit = gpu_bound(&renders[1], bounds.gpu_vs_cpu, bounds.gpu_vs_cpu_f16);
    assert!(
        gpu_vs_cpu < limit,
        "{name}: GPU vs CPU {gpu_vs_cpu:.2e} ≥ {limit:.1e}"
    );
    let mut without = prep;
    without.plan.features.antiradiance = false;
    let r = render_prepared(name, without, Options::backend(Backend::Cpu));
    let m = measure(&r.image, cpu_direct.as_ref().unwrap(), truth);
    println!("{name} cpu without antiradiance: {m}");
    record(&format!("{key}.without"), m.rel_rmse, 0.02);
    assert!(
        !within(&m),
        "{name}: the bounds do not tell U alone from the solution"
    );
    renders
}

/// A block resting on a floor in front of a back wall, under a square area emitter.
fn block_on_floor() -> Scene {
    let mut s = Scene::empty();
    let e = s.add_material(Material {
        ke: DVec3::splat(10.0),
        ..Material::diffuse("lamp", 0.0)
    });
    let f = s.add_material(Material::diffuse("floor", 0.5));
    let w = s.add_material(Material::diffuse("wall", 0.6));
    let b = s.add_material(Material::diffuse("block", 0.6));
    floor(&mut s, 1.0, f);
    let p = DVec3::new;
    quad(
        &mut s,
        "wall",
        [
            p(-1.0, 0.0, -1.0),
            p(1.0, 0.0, -1.0),
            p(1.0, 1.5, -1.0),
            p(-1.0, 1.5, -1.0),
        ],
        w,
    );
    add_box(
        &mut s,
        "block",
        p(-0.1, 0.0, -0.4),
        p(0.4, 0.5, 0.1),
        b,
        false,
    );
    lamp(&mut s, 0.25, 1.5, e);
    default_solver(&mut s, 8);
    view(&mut s, p(0.0, 1.3, 2.6), p(0.0, 0.3, 0.0), 50.0, 32);
    s
}

/// A black slab above a grey one (albedo 0.5) between a small area emitter and a floor, in front
/// of a back wall. Both slabs are wider than the emitter's shadow footprint, so the floor under
/// them is reached only by light reflected from the wall and the floor around them; the
/// unoccluded transport U sends the emitter's light through both, which antiradiance cancels.
fn slabs() -> Scene {
    let mut s = Scene::empty();
    let e = s.add_material(Material {
        ke: DVec3::splat(20.0),
        ..Material::diffuse("lamp", 0.0)
    });
    let f = s.add_material(Material::diffuse("floor", 0.5));
    let w = s.add_material(Material::diffuse("wall", 0.6));
    let black = s.add_material(Material::diffuse("black slab", 0.0));
    let grey = s.add_material(Material::diffuse("grey slab", 0.5));
    floor(&mut s, 1.0, f);
    let p = DVec3::new;
    quad(
        &mut s,
        "wall",
        [
            p(-1.0, 0.0, -1.0),
            p(1.0, 0.0, -1.0),
            p(1.0, 1.8, -1.0),
            p(-1.0, 1.8, -1.0),
        ],
        w,
    );
    lamp(&mut s, 0.2, 1.8, e);
    add_box(
        &mut s,
        "black",
        p(-0.45, 1.1, -0.45),
        p(0.45, 1.14, 0.45),
        black,
        false,
    );
    add_box(
        &mut s,
        "grey",
        p(-0.45, 0.55, -0.45),
        p(0.45, 0.59, 0.45),
        grey,
        false,
    );
    default_solver(&mut s, 8);
    view(&mut s, p(0.0, 0.6, 2.6), p(0.0, 0.35, 0.0), 50.0, 32);
    s
}

/// Three parallel walls (thin closed boxes) on a ground plane make two open-topped corridors;
/// a directional light falls across them at 50° from the vertical, so both corridor floors are in
/// full shadow. Light reaches them only after reflection; the unoccluded transport U sends the
/// lit ground outside through one wall (two faces) into the near corridor and through two walls
/// (four faces) into the far one, which antiradiance must cancel.
fn corridors() -> Scene {
    let mut s = Scene::empty();
    let g = s.add_material(Material::diffuse("ground", 0.5));
    let w = s.add_material(Material::diffuse("wall", 0.6));
    let p = DVec3::new;
    quad(
        &mut s,
        "ground",
        [
            p(-1.0, 0.0, 0.4),
            p(1.0, 0.0, 0.4),
            p(1.0, 0.0, -0.4),
            p(-1.0, 0.0, -0.4),
        ],
        g,
    );
    for (k, x) in [-0.5, 0.0, 0.5].into_iter().enumerate() {
        add_box(
            &mut s,
            &format!("wall{k}"),
            p(x - 0.02, 0.0, -0.4),
            p(x + 0.02, 0.8, 0.4),
            w,
            false,
        );
    }
    let th = 50f64.to_radians();
    s.lights = vec![Light::Directional {
        direction: DVec3::new(th.sin(), -th.cos(), 0.0),
        irradiance: DVec3::splat(3.0),
    }];
    default_solver(&mut s, 8);
    view(&mut s, p(0.0, 1.5, 1.9), p(0.0, 0.1, -0.2), 45.0, 32);
    s
}

// Bounds: the figures measured on this machine (lavapipe; the GPU is within 1e-3 of the CPU
// figure) times 1.5 for the relative RMSE and the indirect median, 3 for the mean bias (a small
// difference of two means) and 3 for GPU vs CPU. With float16 accumulation (lavapipe truncating,
// `ANTIRADIANCE_TEST_F16_ACCUMULATION=1`) the GPU's figures against the path tracer stay inside
// the same bounds; GPU vs CPU measured 3.9e-3 (block), 4.2e-2 (slabs), 5.6e-2 (corridors),
// 3.0e-2 (Cornell box), bounds 3× those. The errors are bias, not noise (the reference is fixed
// by its seed, and its noise is printed beside each figure): a change of the method moves them,
// so when one improves, tighten its bound to the new figure. Area emitters light by shadow-mapped
// samples (§3.3), so the direct light is close to exact and the indirect light's own relative
// RMSE (the image less its direct-only render against the reference less its direct part) is
// what tells antiradiance from U alone; it is bounded 1.5× too.

/// Measured: relative RMSE 0.079 (CPU and GPU), mean −1.5%, indirect light 0.170; GPU vs CPU
/// 9.4e-5. Without antiradiance: 0.082, mean +0.4%, indirect light 0.292. (With the emitter's
/// light through the bins, before issue 17: 0.245, mean −1.3%.)
#[test]
fn block_on_a_floor_under_an_emitter() {
    let s = block_on_floor();
    let truth = path_traced(&s, 1024);
    let bounds = Bounds {
        rel_rmse: 0.12,
        mean_bias: 0.036,
        indirect_median: None,
        indirect_rmse: 0.26,
        gpu_vs_cpu: 5e-4,
        gpu_vs_cpu_f16: 1.2e-2,
    };
    check("block on a floor", "block", &s, &truth, &bounds);
}

/// Measured: relative RMSE 0.200, mean +1.0%, indirect light 0.253, and the floor under the
/// slabs (121 pixels reached only by indirect light) 10.9% off at the median; GPU vs CPU
/// 4.1e-5. Without antiradiance: 0.212, mean +0.4%, indirect light 0.673, median 62%. (With
/// the emitter's light through the bins, before issue 17: 0.722, median 418%: the stacked
/// occluders leaked the direct light, a leak that shrank with the bins and τ, so the directional
/// discretization of the cancellation.)
#[test]
fn black_and_grey_slabs_between_an_emitter_and_a_floor() {
    let s = slabs();
    let truth = path_traced(&s, 1024);
    let bounds = Bounds {
        rel_rmse: 0.31,
        mean_bias: 0.042,
        indirect_rmse: 0.44,
        indirect_median: Some(0.21),
        // Measured 4.3e-5, 4.1e-5 after the receiver-plane shadow lookup (float16 tables).
        gpu_vs_cpu: 1.3e-4,
        gpu_vs_cpu_f16: 0.125,
    };
    check("slabs", "slabs", &s, &truth, &bounds);
}

/// Measured: relative RMSE 0.318, mean −0.1%, indirect light 0.299, the corridor floors (215
/// pixels reached only by indirect light) 11.1% off at the median, 46% at the 90th percentile.
/// No setting moved the relative RMSE (0.314–0.319 for 128/256 bins, τ 1/0.25, elements ×1/×½,
/// 8/24 iterations, before cluster links were calibrated). GPU vs CPU 9.2e-4. Without
/// antiradiance: 0.409, mean +11.5%, median 70%, indirect light 1.30.
#[test]
fn open_topped_corridors_lit_only_after_reflection() {
    let s = corridors();
    let truth = path_traced(&s, 1024);
    let bounds = Bounds {
        rel_rmse: 0.48,
        mean_bias: 0.01,
        indirect_rmse: 0.45,
        indirect_median: Some(0.17),
        gpu_vs_cpu: 2.5e-3,
        gpu_vs_cpu_f16: 0.17,
    };
    check("corridors", "corridors", &s, &truth, &bounds);
}

/// The bundled default scene at its own settings (128 bins, elements 0.25, τ = 1, 8
/// iterations), 32×32. Measured: relative RMSE 0.0935 (CPU) / 0.0953 (GPU) (docs/measurements.json;
/// 0.091 / 0.093 at 5444d1c), mean +0.2% / +0.0%,
/// indirect light 0.110, the 214 indirect-only pixels 5.7% off at the median, the floor beside
/// the short block −2.3% (+10.0% with shadow lookups offset along the normal); GPU vs CPU
/// 2.4e-2 (raster against ray cast at the blocks' edges). Without antiradiance: 0.291, mean
/// +18%, indirect light 0.585, median 38%. (With the lamp's light through the bins and cluster
/// links uncalibrated, before issue 17: 0.300, median 19.9%.) The reference at 2048 spp keeps
/// its noise a fifth of the bound.
#[test]
fn cornell_box_at_low_resolution() {
    let mut s =
        load_scene(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.toml")).unwrap();
    s.camera.width = 32;
    s.camera.height = 32;
    let truth = path_traced(&s, 2048);
    let bounds = Bounds {
        rel_rmse: 0.15,
        mean_bias: 0.01,
        indirect_rmse: 0.17,
        indirect_median: Some(0.1),
        gpu_vs_cpu: 7e-2,
        gpu_vs_cpu_f16: 9e-2,
    };
    let renders = check("cornell box", "cornell", &s, &truth, &bounds);
    // The floor beside the short block (between it and the right wall), where its shadow and
    // the red wall's bleeding meet: the pixels whose center ray reaches the floor at
    // x ∈ [0.74, 0.95], z ∈ [0.2, 0.95] (9 pixels at 32×32, none of them seeing the block); the issue's
    // bound, 10% of the reference there.
    let view = antiradiance::frame::camera::View::new(&s.camera);
    let region: Vec<usize> = (0..s.camera.height)
        .flat_map(|y| (0..s.camera.width).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let d = view.ray(x as f64 + 0.5, y as f64 + 0.5);
            let p = view.eye + d * (-view.eye.y / d.y);
            d.y < 0.0 && (0.74..0.95).contains(&p.x) && (0.2..0.95).contains(&p.z)
        })
        .map(|(x, y)| (y * s.camera.width + x) as usize)
        .collect();
    assert!(region.len() >= 4, "{} floor pixels", region.len());
    let mean = |img: &antiradiance::frame::Image| {
        region
            .iter()
            .map(|&i| antiradiance::metrics::luminance(img.pixels[i]) as f64)
            .sum::<f64>()
            / region.len() as f64
    };
    let want = mean(&truth.reference.image);
    for r in &renders {
        let got = mean(&r.image);
        println!(
            "cornell box {}: floor beside the short block ({} pixels) {:+.2}% off the reference",
            r.stats.backend,
            region.len(),
            100.0 * (got / want - 1.0)
        );
        assert!((got / want - 1.0).abs() < 0.1, "{} vs {want}", got);
    }
}

/// The glossy variant of the bundled box at its own settings, 32×32 (the issue asks ≤ 0.20).
/// Measured: relative RMSE 0.123 (CPU and GPU), mean −0.5%, indirect light 0.146, the 142
/// indirect-only pixels 6.6% off at the median; GPU vs CPU 1.2e-2 (with every triangle at least
/// one leaf, before face clusters: 0.120, 0.137, 6.1%). Without antiradiance:
/// 0.385, mean +26%. Before the OBJ's `vn` were shading normals (in the frame and the path
/// tracer alike; its sphere was faceted): 0.173 / 0.160, indirect light 0.121, median 6.5%, GPU
/// vs CPU 1.8e-2.
#[test]
fn glossy_cornell_box_at_low_resolution() {
    let mut s =
        load_scene(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box-glossy.toml"))
            .unwrap();
    s.camera.width = 32;
    s.camera.height = 32;
    let truth = path_traced(&s, 2048);
    let bounds = Bounds {
        // Not tightened to the 0.120 measured with shading normals: the reference's noise
        // (0.036 at 2048 spp) must stay under a fifth of the bound.
        rel_rmse: 0.19,
        mean_bias: 0.01,
        indirect_rmse: 0.15,
        indirect_median: Some(0.09),
        gpu_vs_cpu: 3e-2,
        gpu_vs_cpu_f16: 9e-2,
    };
    check("glossy cornell box", "glossy", &s, &truth, &bounds);
}

/// MNRoom at its own settings, 40×30 (the issue asks ≤ 0.15). Measured: relative RMSE 0.090
/// (CPU and GPU), mean −0.2%, indirect light 0.103, the 192 indirect-only pixels 4.4% off at the
/// median; GPU vs CPU 1.2e-4 (before the OBJ's `vn` were shading normals, in the frame and the
/// path tracer alike, its sphere faceted: 0.092, indirect light 0.101, median 5.3%). Its table is modelled inside out; while its faces blocked light at their backs (before
/// `solids.rs` counted an empty inward-looking closed surface as a solid) it was 0.120, indirect
/// light 0.226, median 14.5%. Without antiradiance: 0.223 (docs/measurements.json; 0.292 before).
#[test]
fn mnroom_at_low_resolution() {
    let mut s =
        load_scene(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/mnroom.toml")).unwrap();
    s.camera.width = 40;
    s.camera.height = 30;
    let truth = path_traced(&s, 2048);
    let bounds = Bounds {
        rel_rmse: 0.10,
        mean_bias: 0.01,
        indirect_rmse: 0.115,
        indirect_median: Some(0.065),
        gpu_vs_cpu: 4e-4,
        gpu_vs_cpu_f16: 9e-2,
    };
    check("mnroom", "mnroom", &s, &truth, &bounds);
}

/// The bundled dragon room (issue 35: a scanned mesh of 100,000 triangles, without normals, in a
/// closed room), at its own settings, 40×30: its triangles in face clusters (7,786 leaves, 2.36M
/// links). Measured: relative RMSE 0.0942 (CPU) / 0.0918 (GPU) (docs/measurements.json; 0.0918 /
/// 0.0893 before), mean −2.0% / −2.0%, indirect
/// light 0.086; GPU vs CPU 4.3e-3 (float32 tables: the plan's range analysis). Without
/// antiradiance: 0.528, mean +37%. Before the receiver-plane shadow lookup (issue 36):
/// 0.0965 / 0.0941, mean −0.00%, but its direct light alone was 0.91 relative RMSE from the
/// path tracer's (leaks through the scan's contacts with the floor, +1.3% in the mean), now 0.17
/// (−1.3%): the old mean was right by compensation.
#[test]
fn dragon_room_at_low_resolution() {
    let mut s =
        load_scene(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/dragon-room.toml")).unwrap();
    s.camera.width = 40;
    s.camera.height = 30;
    let truth = path_traced(&s, 2048);
    let bounds = Bounds {
        // The reference's noise (0.016 at 2048 spp) must stay under a fifth of the bound.
        rel_rmse: 0.12,
        mean_bias: 0.03,
        indirect_rmse: 0.11,
        // Nine pixels only, too few for a median.
        indirect_median: None,
        gpu_vs_cpu: 1.3e-2,
        gpu_vs_cpu_f16: 9e-2,
    };
    check("dragon room", "dragon", &s, &truth, &bounds);
}

/// The bundled breakfast room (issue 35: 269,538 triangles as converted from its Mitsuba file,
/// fitted to the link budget at τ 16) lit by its sun and its sky, 32×18 drawn at 4× and
/// box-filtered (`camera.supersample`, the path tracer's pixel): the sunlit stripes through the
/// blinds, the sky through the windows (shadowed by rays, `frame::environment`) and the light
/// they bounce. Measured: relative RMSE 0.137 on both backends (the reference's noise 0.030 at
/// 8192 spp), mean −2.5%, indirect light 0.448, the 54 indirect-only pixels 32% off at the
/// median; GPU vs CPU 2.6e-2. Without the supersampling it was 0.56: at 32×18 a frame pixel's
/// 2×2 samples alias the stripes' edges, which the path tracer integrates over the pixel
/// (measured 0.56 / 0.22 / 0.14 at 1× / 2× / 4×). The target 0.20 is the bound; the
/// indirect bounds are 1.3× the measured. With the sky carried unoccluded into the room and
/// cancelled by antiradiance, as before, the frame was 1.9× too bright.
#[test]
fn breakfast_room_at_low_resolution() {
    let mut s =
        load_scene(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/breakfast-room.toml"))
            .unwrap();
    s.camera.width = 32;
    s.camera.height = 18;
    s.camera.supersample = 4;
    let truth = path_traced(&s, 8192);
    let bounds = Bounds {
        rel_rmse: 0.20,
        mean_bias: 0.05,
        indirect_rmse: 0.6,
        indirect_median: Some(0.4),
        gpu_vs_cpu: 6e-2,
        // Not measured here (lavapipe accumulates in float32); 8.8e-2 at 1× on float16 tables.
        gpu_vs_cpu_f16: 0.13,
    };
    check("breakfast room", "breakfast", &s, &truth, &bounds);
}

/// A moved pose against the path tracer (not against the project's own `render --time`): the
/// moving Cornell box solved at t = 0, then moved along its keys to t = 1.5 s in six steps of
/// the scene's `iterations_per_frame` warm-started iterations each (the engine's update →
/// iterate → draw), its last frame measured against the path tracer's image of the scene as it
/// stands at 1.5 s. Measured on both backends: see the bound's comment.
#[test]
fn a_moved_pose_against_the_path_tracer() {
    let scene =
        load_scene(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box-moving.toml"))
            .unwrap();
    let mut s = scene.clone();
    s.camera.width = 32;
    s.camera.height = 32;
    let t = 1.5;
    let still = s.at(t).still();
    let truth = path_traced(&still, 2048);
    let silent = &antiradiance::progress::Silent;
    for backend in [Backend::Cpu, Backend::Gpu] {
        let options = Options {
            context: (backend == Backend::Gpu).then(context),
            ..Options::backend(backend)
        };
        let mut engine = Engine::new(&s, &options, silent).unwrap();
        let at_rest = engine.render(silent).unwrap().image;
        let k = engine.prepared().settings.iterations_per_frame;
        for step in 1..=6 {
            engine.set_time(t * step as f64 / 6.0).unwrap();
            engine.update().unwrap();
            engine.iterate(k).unwrap();
        }
        let image = engine.draw().unwrap();
        drop(engine);
        let direct = render_checked(
            "moved pose, direct",
            &still,
            Options {
                solver: antiradiance::engine::SolverOverrides {
                    iterations: Some(0),
                    ..Default::default()
                },
                ..Options::backend(backend)
            },
        )
        .image;
        let m = measure(&image, &direct, &truth);
        let unmoved = measure(&at_rest, &direct, &truth);
        println!("moved pose at {t} s {backend}: {m}; the pose at 0 s against it: {unmoved}");
        record(&format!("moved.{backend}"), m.rel_rmse, 0.02);
        // Measured: relative RMSE 0.106 on both backends, mean −0.9% (the Cornell box at rest:
        // 0.0935 / 0.0953); the pose at 0 s is 0.316 off. Bounds 1.4× and 2.2× the measured
        // (the reference's noise, 0.028, is part of the figure).
        assert!(m.noise < 0.03, "reference noise {}", m.noise);
        assert!(m.rel_rmse < 0.15, "{backend}: {m}");
        assert!(m.mean_bias.abs() < 0.02, "{backend}: {m}");
        assert!(
            unmoved.rel_rmse > 0.15,
            "the bound does not tell the poses apart"
        );
    }
}
