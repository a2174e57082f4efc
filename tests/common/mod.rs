//! Generated test scenes shared by the integration tests.
#![allow(dead_code)]

use antiradiance::gpu::{Context, ContextOptions};
use antiradiance::scene::{Material, Scene};
use glam::DVec3;
use std::sync::{Arc, OnceLock};

/// One headless Vulkan context per test binary, validation on (lavapipe in CI): a validation
/// message fails the test that reads it.
pub fn context() -> Arc<Context> {
    static CTX: OnceLock<Arc<Context>> = OnceLock::new();
    CTX.get_or_init(fresh_context).clone()
}

/// A context of its own, validation on (for a test that hands its device and queue to a second
/// context, as an embedding host does: the two must not share a queue with other tests).
pub fn fresh_context() -> Arc<Context> {
    let ctx = Context::headless(&ContextOptions {
        validation: true,
        device_name: None,
        no_pipeline_cache: false,
    })
    .expect("a Vulkan device (lavapipe: apt-get install mesa-vulkan-drivers)");
    assert!(ctx.validation_enabled(), "validation layer must be active");
    ctx
}

/// Asserts that `ctx`'s validation layer has reported nothing.
pub fn assert_clean(ctx: &Context) {
    let msgs = ctx.validation_messages();
    assert!(msgs.is_empty(), "validation errors:\n{}", msgs.join("\n"));
}

/// Adds a quad `a b c d` (counter-clockwise seen from its front) as two triangles.
pub fn quad(s: &mut Scene, name: &str, p: [DVec3; 4], mat: u32) {
    s.add_mesh(name, p.to_vec(), vec![[0, 1, 2], [0, 2, 3]], mat);
}

/// Adds an axis-aligned box; `inward` makes its faces look into the box (an enclosure).
pub fn add_box(s: &mut Scene, name: &str, lo: DVec3, hi: DVec3, mat: u32, inward: bool) {
    let c = |x: usize, y: usize, z: usize| {
        DVec3::new(
            if x == 0 { lo.x } else { hi.x },
            if y == 0 { lo.y } else { hi.y },
            if z == 0 { lo.z } else { hi.z },
        )
    };
    // Outward-facing faces, counter-clockwise seen from outside.
    let faces = [
        [c(0, 0, 0), c(0, 0, 1), c(0, 1, 1), c(0, 1, 0)], // -x
        [c(1, 0, 0), c(1, 1, 0), c(1, 1, 1), c(1, 0, 1)], // +x
        [c(0, 0, 0), c(1, 0, 0), c(1, 0, 1), c(0, 0, 1)], // -y
        [c(0, 1, 0), c(0, 1, 1), c(1, 1, 1), c(1, 1, 0)], // +y
        [c(0, 0, 0), c(0, 1, 0), c(1, 1, 0), c(1, 0, 0)], // -z
        [c(0, 0, 1), c(1, 0, 1), c(1, 1, 1), c(0, 1, 1)], // +z
    ];
    for (i, mut f) in faces.into_iter().enumerate() {
        if inward {
            f.reverse();
        }
        quad(s, &format!("{name}{i}"), f, mat);
    }
}

/// A closed unit box of albedo `rho` emitting `le` everywhere, with a floating block inside that
/// does the same (it occludes the floor from the ceiling).
pub fn uniform_enclosure(rho: f64, le: f64, bins: usize, element_size: f64) -> Scene {
    let mut s = Scene::empty();
    let m = s.add_material(Material {
        ke: DVec3::splat(le),
        ..Material::diffuse("uniform", rho)
    });
    add_box(&mut s, "room", DVec3::ZERO, DVec3::ONE, m, true);
    add_box(
        &mut s,
        "block",
        DVec3::new(0.3, 0.2, 0.35),
        DVec3::new(0.7, 0.5, 0.6),
        m,
        false,
    );
    s.solver.bins = bins;
    s.solver.element_size = element_size;
    s
}

/// Adds a square floor of half-size `half` at y = 0, facing up.
pub fn floor(s: &mut Scene, half: f64, mat: u32) {
    quad(
        s,
        "floor",
        [
            DVec3::new(-half, 0.0, half),
            DVec3::new(half, 0.0, half),
            DVec3::new(half, 0.0, -half),
            DVec3::new(-half, 0.0, -half),
        ],
        mat,
    );
}

/// Adds a square emitter of half-size `half` at height `y`, facing down (−y).
pub fn lamp(s: &mut Scene, half: f64, y: f64, mat: u32) {
    let p = |x: f64, z: f64| DVec3::new(x, y, z);
    quad(
        s,
        "lamp",
        [
            p(-half, -half),
            p(half, -half),
            p(half, half),
            p(-half, half),
        ],
        mat,
    );
}

/// Renders `scene` with `options` (on the shared validated context for the GPU backend) and
/// checks what every render must satisfy: validation silent, every pixel and display texel
/// finite and non-negative, finite residuals. Prints the run's statistics.
pub fn render_checked(
    name: &str,
    scene: &antiradiance::Scene,
    options: antiradiance::Options,
) -> antiradiance::engine::Rendered {
    let gpu = options.backend == antiradiance::BackendKind::Gpu;
    let ctx = gpu.then(context);
    let options = antiradiance::Options {
        context: ctx.clone(),
        ..options
    };
    let backend = options.backend;
    let r = antiradiance::engine::render(scene, &options, &antiradiance::progress::Silent)
        .unwrap_or_else(|e| panic!("{name} {backend}: {e}"));
    if let Some(ctx) = &ctx {
        assert_clean(ctx);
    }
    let bad: Vec<_> = r
        .image
        .pixels
        .iter()
        .enumerate()
        .filter(|(_, p)| p.iter().any(|v| !v.is_finite() || *v < 0.0))
        .take(5)
        .collect();
    assert!(bad.is_empty(), "{name} {backend}: bad pixels {bad:?}");
    assert!(
        r.i_total.data.iter().all(|v| v.is_finite()),
        "{name} {backend}: non-finite I_total"
    );
    assert!(r.stats.residuals.iter().all(|v| v.is_finite()));
    println!(
        "{name} {backend}: {} elements, {} links, {} iterations ({} scheme, {} tables), last residual {:.2e}, estimated error {:.2e}, fallbacks {:?}, warnings {:?}",
        r.stats.elements,
        r.stats.links,
        r.stats.iterations,
        r.stats.scheme,
        r.stats.precision,
        r.stats.residuals.last().copied().unwrap_or(0.0),
        r.stats.estimated_error.unwrap_or(0.0),
        r.stats.fallbacks,
        r.stats.warnings
    );
    r
}

/// Points the camera from `eye` at `target` with a square image of `size` pixels.
pub fn view(s: &mut Scene, eye: DVec3, target: DVec3, fov: f64, size: u32) {
    s.camera.eye = eye;
    s.camera.target = target;
    s.camera.fov_y_deg = fov;
    s.camera.width = size;
    s.camera.height = size;
}

/// [`render_checked`] with `backend` and shadow maps of 128² (the stability suites).
pub fn render_with(
    name: &str,
    scene: &antiradiance::Scene,
    backend: antiradiance::BackendKind,
) -> antiradiance::engine::Rendered {
    let options = antiradiance::Options {
        backend,
        shadow_map_size: 128,
        ..Default::default()
    };
    render_checked(name, scene, options)
}
