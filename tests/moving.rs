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
        Sampling { frames, fps },
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
        let scratch = Engine::new(&scene.at(*time), o, &Silent)
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
            let mut cold = Engine::new(&scene.at(*time), o, &Silent).unwrap();
            cold.initialize().unwrap();
            cold.iterate(r.iterations).unwrap();
            let c = rmse_over_mean(&cold.draw().unwrap(), &scratch.image);
            println!(
                "  control: {} iterations from the initial state: RMSE/mean {c:.4}",
                r.iterations
            );
            assert!(
                c > 2.0 * e,
                "cold start {c} is not worse than the warm start {e}"
            );
        }
    }
    errors
}

/// Every animated frame at 6 fps (the block moves 4 cm and turns 2.5° per frame) within 0.05
/// RMSE/mean of `render --time`. Measured (CPU): see the test output; the bound is the issue's.
#[test]
fn cpu_frames_match_render_at_their_time() {
    let errors = frames_against_scratch(&options(BackendKind::Cpu), 3, 6.0);
    for e in &errors {
        assert!(*e < 0.05, "frame error {e} (all: {errors:?})");
    }
}

/// The same on the GPU (lavapipe, validation on; 32 bins, elements 0.5) for two animated
/// frames.
#[test]
fn gpu_frames_match_render_at_their_time() {
    let o = options(BackendKind::Gpu);
    let errors = frames_against_scratch(&o, 3, 6.0);
    for e in &errors {
        assert!(*e < 0.05, "frame error {e} (all: {errors:?})");
    }
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
    let o = options(BackendKind::Cpu);
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
    engine.update().unwrap();
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
    println!("point light moved by 0.32: RMSE/mean {e:.4} after 4 warm-started iterations");
    assert!(e < 0.05, "{e}");
}
