//! Generated test scenes shared by the integration tests.
#![allow(dead_code)]

use antiradiance::gpu::{Context, ContextOptions};
use antiradiance::scene::{Material, Scene};
use glam::DVec3;
use std::sync::{Arc, OnceLock};

mod figures;
mod stored;
#[allow(unused_imports)]
pub use figures::{measurements_dir, record};
#[allow(unused_imports)]
pub use stored::reference;

/// A folder for one test's files under the system's temporary directory
/// (`antiradiance-NAME-PID`), emptied when made and removed when dropped, unless the test is
/// failing: then it is left to look at.
pub struct Scratch(std::path::PathBuf);

impl Scratch {
    pub fn new(name: &str) -> Self {
        let d = std::env::temp_dir().join(format!("antiradiance-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        Self(d)
    }
}

impl std::ops::Deref for Scratch {
    type Target = std::path::Path;
    fn deref(&self) -> &std::path::Path {
        &self.0
    }
}

impl AsRef<std::path::Path> for Scratch {
    fn as_ref(&self) -> &std::path::Path {
        &self.0
    }
}

impl AsRef<std::ffi::OsStr> for Scratch {
    fn as_ref(&self) -> &std::ffi::OsStr {
        self.0.as_os_str()
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

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
    checked_render(name, options, |options| {
        antiradiance::engine::render(scene, options, &antiradiance::progress::Silent)
    })
}

/// [`render_checked`] of a scene already prepared: renders that differ only in what a
/// [`antiradiance::engine::Prepared`] carries after linking (the iteration count, the plan's
/// features, the backend) share one linking.
pub fn render_prepared(
    name: &str,
    prep: antiradiance::engine::Prepared,
    options: antiradiance::Options,
) -> antiradiance::engine::Rendered {
    checked_render(name, options, |options| {
        let silent = &antiradiance::progress::Silent;
        antiradiance::Engine::from_prepared(prep, options, silent)?.render(silent)
    })
}

/// Runs `render` with `options` on the shared context (GPU) and float16 accumulation where the
/// environment forces it, then applies [`render_checked`]'s checks.
fn checked_render(
    name: &str,
    options: antiradiance::Options,
    render: impl FnOnce(
        &antiradiance::Options,
    ) -> antiradiance::error::Result<antiradiance::engine::Rendered>,
) -> antiradiance::engine::Rendered {
    let gpu = options.backend == antiradiance::BackendKind::Gpu;
    let ctx = gpu.then(context);
    let options = antiradiance::Options {
        context: ctx.clone(),
        gpu: antiradiance::engine::GpuTuning {
            force_table_accumulation: options.gpu.force_table_accumulation
                || force_f16_accumulation(),
            ..options.gpu
        },
        ..options
    };
    let backend = options.backend;
    let r = render(&options).unwrap_or_else(|e| panic!("{name} {backend}: {e}"));
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

/// `ANTIRADIANCE_TEST_F16_ACCUMULATION=1`: every GPU solve in the tests accumulates L_in and
/// L_push in float16 tables as on a device that rounds float16 blending. lavapipe truncates float16
/// blending, so by default the solver accumulates in float32 there and says so in `fallbacks`;
/// with this set, lavapipe runs the float16 path (with truncation, worse than a rounding device)
/// and the tests apply their float16-accumulation bounds, which were measured this way.
pub fn force_f16_accumulation() -> bool {
    std::env::var("ANTIRADIANCE_TEST_F16_ACCUMULATION").is_ok_and(|v| v == "1")
}

/// Whether a GPU solve with these `fallbacks` and `precision` accumulated in float16 (a device
/// that rounds float16 blending, or [`force_f16_accumulation`]); false for float32 tables and
/// where the solver fell back to float32 accumulation (lavapipe).
pub fn accumulated_f16(precision: antiradiance::Precision, fallbacks: &[String]) -> bool {
    precision == antiradiance::Precision::F16
        && !fallbacks
            .iter()
            .any(|f| f.contains("truncates float16 blending"))
}

/// A bound for a GPU figure: `table` where the tables are float32 or L_in and L_push accumulate
/// in float32 (lavapipe's fallback), `f16` where they accumulate in float16 (measured on lavapipe
/// with truncation, [`force_f16_accumulation`]; a device that rounds should stay well inside).
pub fn gpu_bound(r: &antiradiance::engine::Rendered, table: f64, f16: f64) -> f64 {
    if accumulated_f16(r.stats.precision, &r.stats.fallbacks) {
        f16
    } else {
        table
    }
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

/// The solver settings a scene file without a `[solver]` table gets: 128 bins, τ = 1, the scene's
/// symmetric scheme and float16 tables, and the relative element size
/// (`RELATIVE_ELEMENT_SIZE` × the bounding-box diagonal). `iterations` is the scene's own.
pub fn default_solver(s: &mut Scene, iterations: usize) {
    s.solver = antiradiance::scene::SolverSettings {
        iterations,
        ..Default::default()
    };
    let (lo, hi) = s.bounds();
    s.solver.element_size = antiradiance::scene::RELATIVE_ELEMENT_SIZE * (hi - lo).length();
}

/// A path-traced reference with the pixels that see an emitter (or the environment) marked.
pub struct Truth {
    /// The unbiased reference: image, its direct part and its per-pixel standard error.
    pub reference: antiradiance::reference::Reference,
    /// Pixels measured: none of their samples saw an emitter directly, nor did their 8
    /// neighbours' (antiradiance samples a pixel at 2×2 fixed positions, the path tracer at
    /// random ones, so an emitter's edge is excluded with a margin).
    pub measured: Vec<bool>,
}

/// Path-traces `scene` at `spp` samples per pixel (unlimited bounces, Russian roulette) and marks
/// the pixels that see no emitter (from a 0-bounce trace at 64 spp).
pub fn path_traced(scene: &Scene, spp: u32) -> Truth {
    use antiradiance::reference::{render_reference, ReferenceOptions};
    let silent = &antiradiance::progress::Silent;
    let t = std::time::Instant::now();
    let reference = stored::reference(
        scene,
        &ReferenceOptions {
            spp,
            max_bounces: None,
            seed: 21,
        },
    );
    let seen = render_reference(
        scene,
        &ReferenceOptions {
            spp: 64,
            max_bounces: Some(0),
            seed: 22,
        },
        silent,
    )
    .unwrap();
    let (w, h) = (seen.image.width as i64, seen.image.height as i64);
    let lit = |x: i64, y: i64| {
        x >= 0
            && y >= 0
            && x < w
            && y < h
            && seen.image.pixels[(y * w + x) as usize]
                .iter()
                .any(|&v| v > 0.0)
    };
    let measured = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| !(-1..=1).any(|dy| (-1..=1).any(|dx| lit(x + dx, y + dy))))
        .collect();
    println!(
        "reference: {spp} spp in {:.1} s, standard error {:.2}% of the image mean",
        t.elapsed().as_secs_f64(),
        100.0 * reference.stats.mean_relative_std_error.unwrap_or(0.0)
    );
    Truth {
        reference,
        measured,
    }
}

/// Error of an image against a [`Truth`], over its measured pixels.
#[derive(Debug, Clone, Copy)]
pub struct Measured {
    /// Pixels measured.
    pub pixels: usize,
    /// RMSE over pixels and channels divided by the reference's mean over the same.
    pub rel_rmse: f64,
    /// What the reference's own noise contributes to `rel_rmse`: √(mean σ²) / mean.
    pub noise: f64,
    /// The image's mean over the reference's, minus 1 (the bias of the whole image).
    pub mean_bias: f64,
    /// Pixels reached only by indirect light (the reference's direct part is zero there).
    pub indirect_pixels: usize,
    /// Median and 90th percentile of |x − r| / r (luminance) over those pixels.
    pub indirect_median: f64,
    pub indirect_p90: f64,
    /// Relative RMSE of the indirect light alone: the image less the same renderer's
    /// direct-only image against the reference less its direct part, over the measured pixels
    /// (the error antiradiance is responsible for, now that direct light is shadow-mapped).
    pub indirect_rmse: f64,
}

impl std::fmt::Display for Measured {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "relative RMSE {:.4} over {} pixels (reference noise {:.4}), mean {:+.2}%; indirect light: relative RMSE {:.4}; indirect-only pixels {}: median {:.1}%, 90th percentile {:.1}%",
            self.rel_rmse,
            self.pixels,
            self.noise,
            100.0 * self.mean_bias,
            self.indirect_rmse,
            self.indirect_pixels,
            100.0 * self.indirect_median,
            100.0 * self.indirect_p90
        )
    }
}

/// Measures `image` against `truth` (see [`Measured`]).
pub fn measure(
    image: &antiradiance::frame::Image,
    direct: &antiradiance::frame::Image,
    truth: &Truth,
) -> Measured {
    let r = &truth.reference;
    let sigma = r
        .std_error
        .as_ref()
        .expect("a reference of more than 1 spp");
    let lum = |p: [f32; 3]| antiradiance::metrics::luminance(p) as f64;
    let (mut n, mut sq, mut sum_r, mut sum_x, mut var) = (0usize, 0.0, 0.0, 0.0, 0.0);
    let mut indirect = Vec::new();
    let (mut sq_ind, mut sum_ind) = (0.0, 0.0);
    for i in 0..r.image.pixels.len() {
        if !truth.measured[i] {
            continue;
        }
        let (x, y, s) = (image.pixels[i], r.image.pixels[i], sigma.pixels[i]);
        let (xd, yd) = (direct.pixels[i], r.direct.pixels[i]);
        for c in 0..3 {
            sq += (x[c] as f64 - y[c] as f64).powi(2);
            sum_r += y[c] as f64;
            sum_x += x[c] as f64;
            var += (s[c] as f64).powi(2);
            let (xi, yi) = (x[c] as f64 - xd[c] as f64, y[c] as f64 - yd[c] as f64);
            sq_ind += (xi - yi).powi(2);
            sum_ind += yi;
        }
        n += 1;
        if lum(r.direct.pixels[i]) == 0.0 && lum(y) > 0.0 {
            indirect.push((lum(x) - lum(y)).abs() / lum(y));
        }
    }
    assert!(n > 0, "no pixel to measure");
    let mean = sum_r / (3 * n) as f64;
    indirect.sort_by(f64::total_cmp);
    let pct = |q: f64| {
        indirect
            .get(((indirect.len().max(1) - 1) as f64 * q) as usize)
            .copied()
            .unwrap_or(0.0)
    };
    Measured {
        pixels: n,
        rel_rmse: (sq / (3 * n) as f64).sqrt() / mean,
        indirect_rmse: (sq_ind / (3 * n) as f64).sqrt() / (sum_ind / (3 * n) as f64),
        noise: (var / (3 * n) as f64).sqrt() / mean,
        mean_bias: sum_x / sum_r - 1.0,
        indirect_pixels: indirect.len(),
        indirect_median: pct(0.5),
        indirect_p90: pct(0.9),
    }
}

/// A closed room 3 × 2 × 3 (white, albedo 0.7, looking inward) with a sphere of radius 0.5
/// (albedo 0.6) subdivided `level` times standing in it (the last mesh), at element size 0.25.
pub fn room_with_sphere(level: usize) -> Scene {
    let mut s = Scene::empty();
    let w = s.add_material(Material::diffuse("w", 0.7));
    add_box(
        &mut s,
        "room",
        DVec3::new(-1.5, 0.0, -1.5),
        DVec3::new(1.5, 2.0, 1.5),
        w,
        true,
    );
    let m = s.add_material(Material::diffuse("s", 0.6));
    let (p, t) = icosphere(level, 0.5, DVec3::new(0.0, 0.6, 0.0));
    s.add_mesh("sphere", p, t, m);
    s.solver.element_size = 0.25;
    s
}

/// The vertices and triangles of an icosphere subdivided `level` times, of `radius` at `center`,
/// wound counter-clockwise seen from outside.
pub fn icosphere(level: usize, radius: f64, center: DVec3) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut v: Vec<DVec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
    .collect();
    let mut f: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut mid = std::collections::HashMap::new();
        let mut m = |a: u32, b: u32, v: &mut Vec<DVec3>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                v.push(((v[a as usize] + v[b as usize]) / 2.0).normalize());
                v.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(f.len() * 4);
        for [a, b, c] in f {
            let (ab, bc, ca) = (m(a, b, &mut v), m(b, c, &mut v), m(c, a, &mut v));
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = next;
    }
    (v.iter().map(|p| center + *p * radius).collect(), f)
}
