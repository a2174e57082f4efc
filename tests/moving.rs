//! Moving objects and lights (§3.3): every animated frame, after its warm-started iterations,
//! against the same time solved from scratch (`render --time`), on both backends; a static
//! scene left as it was by an update; the engine's moving API refusing what it cannot do.

mod common;

use antiradiance::animate::{animate, Sampling};
use antiradiance::engine::{Engine, Options};
use antiradiance::frame::Image;
use antiradiance::progress::Silent;
use antiradiance::scene::{load_scene, Light};
use antiradiance::{BackendKind, Scene};
use glam::{DMat4, DVec3};
use std::path::Path;

fn bundled(name: &str) -> Scene {
    load_scene(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes")
            .join(name),
    )
    .unwrap()
}

/// RMSE of `test` against `reference` over the reference's mean (all pixels and channels).
fn rmse_over_mean(test: &Image, reference: &Image) -> f64 {
    let (mut sq, mut sum, mut n) = (0.0, 0.0, 0.0);
    for (a, b) in test.pixels.iter().zip(&reference.pixels) {
        for c in 0..3 {
            sq += (a[c] as f64 - b[c] as f64).powi(2);
            sum += b[c] as f64;
            n += 1.0;
        }
    }
    (sq / n).sqrt() / (sum / n)
}

/// Small images and shadow maps: the checks compare the solver, not the resolution.
fn options(backend: BackendKind) -> Options {
    let mut o = Options {
        backend,
        width: Some(32),
        height: Some(32),
        shadow_map_size: 256,
        ..Options::default()
    };
    if backend == BackendKind::Gpu {
        // lavapipe runs the scene's 128 bins and 0.25 elements at ~5 s per iteration: coarser
        // settings keep the test short (the CPU test runs the scene's own).
        o.context = Some(common::context());
        o.solver.bins = Some(32);
        o.solver.element_size = Some(0.5);
    }
    o
}

/// Renders `frames` frames of the moving Cornell box at `fps` and compares every animated frame
/// with a from-scratch render at its time; returns the errors.
fn frames_against_scratch(o: &Options, frames: usize, fps: f64) -> Vec<f64> {
    let scene = bundled("cornell-box-moving.toml");
    let mut images = Vec::new();
    let records = animate(
        &scene,
        o,
        Sampling {
            frames,
            fps,
            orbit: 0.0,
        },
        &Silent,
        &mut |r, image| {
            images.push((r.time, image.clone()));
            Ok(())
        },
    )
    .unwrap();
    assert_eq!(records.len(), frames);
    let mut errors = Vec::new();
    for (r, (time, image)) in records.iter().zip(&images).skip(1) {
        assert_eq!(r.iterations, 4, "the scene's iterations_per_frame");
        let scratch = Engine::new(&scene.at(*time).still(), o, &Silent)
            .unwrap()
            .render(&Silent)
            .unwrap();
        let e = rmse_over_mean(image, &scratch.image);
        println!(
            "{:?} frame {} (t = {time:.3} s): RMSE/mean {e:.4} against render --time; update {:.0} ms, solve {:.0} ms, residual {:.2e}",
            o.backend, r.frame, r.update_ms, r.solve_ms, r.residual
        );
        errors.push(e);
        if r.frame + 1 == frames {
            // Control: the same 4 iterations from the initial state instead of the previous
            // frame's solution must be further off, or the bound would not test the warm start.
            // Judged against the keyframed scene prepared at that time (its links bounded for
            // the motion, as the animation's): the still scene's hierarchy differs from the
            // bounded mesh's (the block its own subtree) by 0.006 on the CPU and 0.015 at the
            // GPU test's coarse settings, more than 4 cold iterations are off.
            let mut fresh = Engine::new(&scene.at(*time), o, &Silent).unwrap();
            let converged = fresh.render(&Silent).unwrap().image;
            fresh.initialize().unwrap();
            fresh.iterate(r.iterations).unwrap();
            let c = rmse_over_mean(&fresh.draw().unwrap(), &converged);
            let w = rmse_over_mean(image, &converged);
            println!(
                "  control against the bounded scene at {time:.3} s: warm {w:.4}, {} iterations from the initial state {c:.4}",
                r.iterations
            );
            assert!(
                c > 2.0 * w,
                "cold start {c} is not worse than the warm start {w}"
            );
        }
    }
    errors
}

/// Every animated frame at 6 fps (the block moves 4 cm and turns 2.5° per frame) within 0.018
/// RMSE/mean of `render --time` (the still scene at that time, from scratch). Measured (CPU,
/// bounded link mesh): 0.0061 and 0.0060, of which 0.0060 is the bounded mesh's hierarchy
/// against the still scene's (the same at rest); against the bounded scene at that time 0.0012
/// warm, 0.0135 cold. Bound 3× the measured (the issue asked for 0.05).
#[test]
fn cpu_frames_match_render_at_their_time() {
    let errors = frames_against_scratch(&options(BackendKind::Cpu), 3, 6.0);
    common::record(
        "moving.cpu",
        errors.iter().copied().fold(0.0, f64::max),
        0.05,
    );
    for e in &errors {
        assert!(*e < 0.018, "frame error {e} (all: {errors:?})");
    }
}

/// The same on the GPU (lavapipe, validation on; 32 bins, elements 0.5) for two animated
/// frames. Measured: 0.0141 and 0.0138, of which 0.015 is the bounded mesh's hierarchy against
/// the still scene's at these coarse settings (0.016 at rest on the CPU); against the bounded
/// scene at that time 0.0006 warm, 0.0108 cold. Bound 3× the measured.
#[test]
fn gpu_frames_match_render_at_their_time() {
    let o = options(BackendKind::Gpu);
    let errors = frames_against_scratch(&o, 3, 6.0);
    common::record(
        "moving.gpu",
        errors.iter().copied().fold(0.0, f64::max),
        0.05,
    );
    for e in &errors {
        assert!(*e < 0.042, "frame error {e} (all: {errors:?})");
    }
    common::assert_clean(o.context.as_ref().unwrap());
}

/// The bounded link mesh (§3.3): the keyframed block is linked once for its whole motion, so
/// updates follow it without relinking — the same link pairs at every frame, as many as the
/// bound made — and a warm-started frame is close to the converged solution of the same
/// links, far closer than as many iterations from the initial state. A pose a host sets
/// outside the keyframes is prepared anew (relinked).
#[test]
fn bounded_updates_do_not_relink() {
    let scene = bundled("cornell-box-moving.toml");
    let o = options(BackendKind::Cpu);
    let mut engine = Engine::new(&scene, &o, &Silent).unwrap();
    engine.render(&Silent).unwrap();
    let sys = &engine.prepared().system;
    let bound = sys
        .bound
        .as_ref()
        .expect("a keyframed scene is linked for its motion");
    let pairs: Vec<(u32, u32)> = sys
        .links
        .links
        .iter()
        .map(|l| (l.receiver, l.sender))
        .collect();
    let still = Engine::new(&scene.still(), &o, &Silent).unwrap();
    println!(
        "links: bounded {} ({} touch the moving block, {} sampled poses), still at t = 0: {}",
        pairs.len(),
        bound.moving_links.len(),
        bound.times.len(),
        still.prepared().system.links.len()
    );
    let n = engine.prepared().settings.iterations_per_frame;
    for t in [0.2, 0.4, 1.3] {
        engine.set_time(t).unwrap();
        engine.update().unwrap();
        assert!(!engine.relinked() && engine.warm_started(), "t = {t}");
        let sys = &engine.prepared().system;
        let now: Vec<(u32, u32)> = sys
            .links
            .links
            .iter()
            .map(|l| (l.receiver, l.sender))
            .collect();
        assert_eq!(now, pairs, "t = {t}: the link set changed");
        // The shadow maps kept their texels away from the block: equal to casting every ray.
        let mut full = engine.prepared().maps.clone();
        full.render_cpu(&antiradiance::raycast::RayCaster::new(sys));
        assert!(
            full.data == engine.prepared().maps.data,
            "t = {t}: stale shadow texels"
        );
        let u = engine.update_times();
        println!(
            "t = {t}: update {:.0} ms (follow {:.0}, backend {:.0}, shadow maps and direct light {:.0}, carry {:.0})",
            u.total_ms, u.prepare_ms, u.backend_ms, u.lights_ms, u.carry_ms
        );
        engine.iterate(n).unwrap();
    }
    // At the last time: the warm frame against the same links converged (16 more iterations),
    // and the control, n iterations from the initial state.
    let warm = engine.draw().unwrap();
    engine.iterate(16).unwrap();
    let converged = engine.draw().unwrap();
    engine.initialize().unwrap();
    engine.iterate(n).unwrap();
    let cold = engine.draw().unwrap();
    let (w, c) = (
        rmse_over_mean(&warm, &converged),
        rmse_over_mean(&cold, &converged),
    );
    println!("t = 1.3 against the same links converged: warm start {w:.4}, cold start {c:.4}");
    // Measured: warm 0.0005, cold 0.0146; the warm bound 3× the measured.
    assert!(w < 0.0015 && c > 2.0 * w, "warm {w}, cold {c}");
    // A host's pose outside the keyframes: prepared anew for it.
    let m = scene.objects[1].transform * DMat4::from_translation(DVec3::new(0.0, 0.2, 0.0));
    engine.set_object_transform(1, m).unwrap();
    engine.update().unwrap();
    assert!(engine.relinked());
}

/// The GPU backend follows keyframed moves in place (§3.3): the same backend keeps its tables
/// and solution and uploads only the moved link records, normals and lobe factors; after each
/// update and 4 warm-started iterations its frame stays as close to the CPU backend's (the
/// specification, following the same moves) as it was after the first solve.
#[test]
fn gpu_follows_keyframed_moves_in_place() {
    let scene = bundled("cornell-box-moving.toml");
    let o = options(BackendKind::Gpu);
    let mut c = options(BackendKind::Cpu);
    c.solver = o.solver.clone();
    let mut gpu = Engine::new(&scene, &o, &Silent).unwrap();
    let mut cpu = Engine::new(&scene, &c, &Silent).unwrap();
    let start = rmse_over_mean(
        &gpu.render(&Silent).unwrap().image,
        &cpu.render(&Silent).unwrap().image,
    );
    let backend = gpu.gpu_internals().unwrap() as *const antiradiance::engine::gpu::GpuBackend;
    let n = gpu.prepared().settings.iterations_per_frame;
    for t in [0.2, 0.4] {
        for e in [&mut gpu, &mut cpu] {
            e.set_time(t).unwrap();
            e.update().unwrap();
            assert!(!e.relinked() && e.warm_started());
            e.iterate(n).unwrap();
        }
        let g = gpu.gpu_internals().unwrap();
        assert_eq!(
            backend, g as *const antiradiance::engine::gpu::GpuBackend,
            "t = {t}: the GPU backend was made anew"
        );
        let f = g.last_follow();
        assert!(f.in_place && f.uploaded_bytes > 0, "t = {t}: {f:?}");
        // The views not drawn again kept maps equal to drawing every view.
        g.frame().render_shadow_maps().unwrap();
        let atlas = g.frame().read_shadow_maps().unwrap();
        let mut full = gpu.prepared().maps.clone();
        full.set_from_atlas(&atlas);
        assert!(
            full.data == gpu.prepared().maps.data,
            "t = {t}: stale shadow views"
        );
        let e = rmse_over_mean(&gpu.draw().unwrap(), &cpu.draw().unwrap());
        println!(
            "t = {t}: GPU against CPU {e:.4} (after the first solve {start:.4}); uploaded {} bytes, shadow views drawn {:?}; update {:?}",
            f.uploaded_bytes,
            f.shadow_views,
            gpu.update_times()
        );
        assert!(e < 1.5 * start + 0.005, "t = {t}: {e} (start {start})");
    }
    common::assert_clean(o.context.as_ref().unwrap());
}

/// A light made 64× brighter moves the GPU solver's power-of-two source scale: the solution it
/// holds is rescaled with it, and the warm-started frame matches a fresh render.
#[test]
fn gpu_rescales_the_held_solution_when_a_light_brightens() {
    let mut scene = bundled("cornell-box.toml");
    let light = |i: f64| Light::Point {
        position: DVec3::new(0.0, 1.5, 0.5),
        intensity: DVec3::splat(i),
    };
    scene.lights.push(light(0.5));
    let o = options(BackendKind::Gpu);
    let mut engine = Engine::new(&scene, &o, &Silent).unwrap();
    engine.render(&Silent).unwrap();
    let before = engine.gpu_internals().unwrap().solver().scale();
    engine.set_light(0, light(32.0)).unwrap();
    engine.update().unwrap();
    let after = engine.gpu_internals().unwrap().solver().scale();
    assert!(engine.gpu_internals().unwrap().last_follow().in_place);
    assert_ne!(before, after, "the scale did not change: nothing tested");
    engine.iterate(4).unwrap();
    let frame = engine.draw().unwrap();
    scene.lights[0] = light(32.0);
    let scratch = Engine::new(&scene, &o, &Silent)
        .unwrap()
        .render(&Silent)
        .unwrap();
    let e = rmse_over_mean(&frame, &scratch.image);
    println!("scale {before} -> {after}: RMSE/mean {e:.4} against a fresh render");
    // Measured 0.0208 (the rescaled float16 solution's rounding); bound 2.4× that.
    assert!(e < 0.05, "{e}");
    common::assert_clean(o.context.as_ref().unwrap());
}

/// A point light turned into a narrow spot by `set_light`: its 6 shadow views become 1, the
/// views' squares in the atlas move, and the GPU frame is made anew rather than reading squares
/// never drawn; the frame matches a fresh render with the spot there.
#[test]
fn gpu_light_changing_its_views_matches_a_fresh_render() {
    let mut scene = bundled("cornell-box.toml");
    scene.lights.push(Light::Point {
        position: DVec3::new(0.0, 1.5, 0.5),
        intensity: DVec3::splat(0.5),
    });
    let o = options(BackendKind::Gpu);
    let mut engine = Engine::new(&scene, &o, &Silent).unwrap();
    engine.render(&Silent).unwrap();
    let views = engine.prepared().maps.views.len();
    let spot = Light::Spot {
        position: DVec3::new(0.0, 1.5, 0.5),
        axis: DVec3::NEG_Y,
        intensity: DVec3::splat(0.5),
        cutoff: 0.6,
        beam_width: 0.4,
    };
    engine.set_light(0, spot.clone()).unwrap();
    engine.update().unwrap();
    assert_eq!(engine.prepared().maps.views.len(), views - 5);
    let f = engine.gpu_internals().unwrap().last_follow();
    println!("point light to spot: {views} -> {} views, {f:?}", views - 5);
    engine.iterate(4).unwrap();
    let frame = engine.draw().unwrap();
    scene.lights[0] = spot;
    let scratch = Engine::new(&scene, &o, &Silent)
        .unwrap()
        .render(&Silent)
        .unwrap();
    let e = rmse_over_mean(&frame, &scratch.image);
    println!("point light to spot: RMSE/mean {e:.4} against a fresh render");
    // Measured 0.0106; bound 3× that.
    assert!(e < 0.032, "{e}");
    common::assert_clean(o.context.as_ref().unwrap());
}

/// A static scene: setting a time and updating changes nothing — not relinked, the same links,
/// the same solution carried over exactly, the same frame.
#[test]
fn static_scene_is_unchanged_by_an_update() {
    let scene = bundled("cornell-box.toml");
    assert!(!scene.is_animated());
    let mut engine = Engine::new(&scene, &options(BackendKind::Cpu), &Silent).unwrap();
    let before = engine.render(&Silent).unwrap();
    let links = engine.prepared().system.links.links.clone();
    let i_ex = engine.i_ex().unwrap();
    engine.set_time(1.0).unwrap();
    engine.update().unwrap();
    assert!(engine.warm_started() && !engine.relinked());
    assert_eq!(engine.prepared().system.links.links, links);
    assert_eq!(engine.i_ex().unwrap(), i_ex);
    // Converged: four more iterations move the frame by rounding only.
    engine.iterate(4).unwrap();
    let after = engine.draw().unwrap();
    let e = rmse_over_mean(&after, &before.image);
    println!("static box: RMSE/mean {e:.2e} after update and 4 iterations");
    assert!(e < 0.01, "{e}");
}

/// Lights and objects moved by a host: a light moved with `set_light` gives the frame of a
/// scene written with the light there; objects not marked moving are refused.
#[test]
fn host_moves_lights_and_refuses_fixed_objects() {
    let mut scene = bundled("cornell-box.toml");
    scene.lights.push(Light::Point {
        position: DVec3::new(0.0, 1.5, 0.5),
        intensity: DVec3::splat(0.5),
    });
    // Both backends keep their tables where only a light moved (the GPU makes only its frame
    // anew): measured 0.0021 (CPU) and 0.0017 (GPU) against a fresh render.
    for backend in [BackendKind::Cpu, BackendKind::Gpu] {
        let o = options(backend);
        let mut engine = Engine::new(&scene, &o, &Silent).unwrap();
        engine.render(&Silent).unwrap();
        let moved = Light::Point {
            position: DVec3::new(0.3, 1.4, 0.4),
            intensity: DVec3::splat(0.5),
        };
        let e = engine
            .set_object_transform(0, DMat4::from_translation(DVec3::X))
            .unwrap_err()
            .to_string();
        assert!(e.contains("not marked moving"), "{e}");
        assert!(engine.set_light(5, moved.clone()).is_err());
        let links = engine.prepared().system.links.links.clone();
        engine.set_light(0, moved.clone()).unwrap();
        // The GPU backend before the update (a backend made anew is allocated while the old one
        // still lives, so its address differs).
        let before = (backend == BackendKind::Gpu).then(|| {
            engine.gpu_internals().unwrap() as *const antiradiance::engine::gpu::GpuBackend
        });
        engine.update().unwrap();
        if let Some(b) = before {
            let g = engine.gpu_internals().unwrap();
            let f = g.last_follow();
            println!("{backend:?}: follow {f:?}");
            assert_eq!(
                b, g as *const _,
                "the GPU backend was made anew for a light move"
            );
            // Only the moved point light's cube is drawn again; the lamp's samples keep theirs.
            assert!(f.in_place && f.uploaded_bytes == 0, "{f:?}");
            assert_eq!(f.shadow_views.0, 6, "{f:?}");
            assert!(f.shadow_views.1 > 6, "{f:?}");
        }
        println!("{backend:?}: update {:?}", engine.update_times());
        // Only a light moved: the links are kept, not remade.
        assert!(!engine.relinked() && engine.warm_started());
        assert_eq!(engine.prepared().system.links.links, links);
        engine.iterate(4).unwrap();
        let frame = engine.draw().unwrap();
        let mut there = scene.clone();
        there.lights[0] = moved;
        let scratch = Engine::new(&there, &o, &Silent)
            .unwrap()
            .render(&Silent)
            .unwrap();
        let e = rmse_over_mean(&frame, &scratch.image);
        println!(
            "{backend:?}: point light moved by 0.32: RMSE/mean {e:.4} after 4 warm-started iterations"
        );
        // Measured: CPU 0.0021, GPU 0.0017; bound 3× the larger.
        assert!(e < 0.0065, "{backend:?}: {e}");
    }
}
