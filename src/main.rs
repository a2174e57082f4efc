//! `antiradiance` command-line tool: parses arguments and calls the library.

use antiradiance::{info::Info, render, scene, Scene, System};
use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use std::path::{Path, PathBuf};

#[derive(Parser)]
#[command(
    name = "antiradiance",
    version,
    about = "Global illumination with implicit visibility and antiradiance"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Scene statistics: triangles, elements, links, bins, memory, linking time.
    Info {
        /// Scene TOML (default: the bundled Cornell box).
        scene: Option<PathBuf>,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
        #[command(flatten)]
        plan: PlanArgs,
    },
    /// Render the scene from its camera to PNG and/or EXR (default: out.png).
    Render {
        /// Scene TOML (default: the bundled Cornell box).
        scene: Option<PathBuf>,
        /// PNG output (tone-mapped sRGB); written when given, or when no --exr is given.
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// EXR output (linear float RGB radiance).
        #[arg(long)]
        exr: Option<PathBuf>,
        /// Write statistics as JSON to this file.
        #[arg(long)]
        json: Option<PathBuf>,
        /// Override `solver.bins`.
        #[arg(long)]
        bins: Option<usize>,
        /// Override `solver.iterations`.
        #[arg(long)]
        iterations: Option<usize>,
        /// Override `solver.scheme` (symmetric | asymmetric).
        #[arg(long)]
        scheme: Option<String>,
        /// Override `solver.precision` (f16 | f32).
        #[arg(long)]
        precision: Option<String>,
        /// Iterate until the estimated error is below this instead of a fixed count.
        #[arg(long)]
        tolerance: Option<f64>,
        /// Iteration cap with --tolerance (default: `solver.max_iterations`, 1000).
        #[arg(long)]
        max_iterations: Option<usize>,
        /// Override `camera.width`.
        #[arg(long)]
        width: Option<u32>,
        /// Override `camera.height`.
        #[arg(long)]
        height: Option<u32>,
        /// PNG exposure in stops (pixel values are multiplied by 2^exposure).
        #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
        exposure: f64,
        /// gpu (Vulkan raster passes) or cpu (the f64 reference solver and a ray-cast frame).
        #[arg(long, default_value = "gpu")]
        backend: String,
        /// Shadow map side in texels.
        #[arg(long, default_value_t = 1024)]
        shadow_map_size: u32,
        /// Vulkan device whose name contains this (default: prefer a discrete GPU).
        #[arg(long)]
        device: Option<String>,
        #[command(flatten)]
        plan: PlanArgs,
    },
    /// Path-traced ground truth (unbiased, CPU, all cores) to EXR, with its direct part and
    /// per-pixel standard error beside it (REF.direct.exr, REF.stderr.exr).
    Reference {
        /// Scene TOML (default: the bundled Cornell box).
        scene: Option<PathBuf>,
        /// Samples per pixel.
        #[arg(long, default_value_t = 256)]
        spp: u32,
        /// EXR output (linear float RGB radiance).
        #[arg(long, default_value = "reference.exr")]
        exr: PathBuf,
        /// Reflections per path (default: unlimited, ended by Russian roulette without bias).
        #[arg(long)]
        max_bounces: Option<u32>,
        /// Seed: the same seed gives the same image on any number of threads.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Override `camera.width`.
        #[arg(long)]
        width: Option<u32>,
        /// Override `camera.height`.
        #[arg(long)]
        height: Option<u32>,
        /// Also write a PNG (exposure in stops via --exposure).
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// PNG exposure in stops.
        #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
        exposure: f64,
        /// Write the convergence figures as JSON to this file.
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// Error against run time: antiradiance over a sweep of settings and the path tracer at
    /// increasing spp, measured against a reference; writes study.csv, error-vs-time.png and
    /// convergence.png into --out.
    Study {
        /// Scene TOML (default: the bundled Cornell box).
        scene: Option<PathBuf>,
        /// Reference EXR from `antiradiance reference` (its REF.direct.exr, when present, gives
        /// the indirect-only error). The study renders at the reference's size.
        #[arg(long)]
        reference: PathBuf,
        /// Output directory.
        #[arg(long)]
        out: PathBuf,
        /// Antiradiance is measured after every iteration 1..=N.
        #[arg(long, default_value_t = 16)]
        iterations: usize,
        /// Bin counts to try, comma-separated (default 32,64,128,256,512).
        #[arg(long, value_delimiter = ',')]
        bins: Option<Vec<usize>>,
        /// Element sizes to try, comma-separated (default: the scene's ×2, ×1, ×0.5).
        #[arg(long, value_delimiter = ',')]
        element_sizes: Option<Vec<f64>>,
        /// Path tracer sample counts, comma-separated (default 1,4,16,64,256).
        #[arg(long, value_delimiter = ',')]
        spp: Option<Vec<u32>>,
        /// Skip the run with the other iteration scheme.
        #[arg(long)]
        one_scheme: bool,
        /// Skip the run with the other precision.
        #[arg(long)]
        one_precision: bool,
        /// gpu or cpu (antiradiance backend).
        #[arg(long, default_value = "gpu")]
        backend: String,
        /// Vulkan device whose name contains this.
        #[arg(long)]
        device: Option<String>,
    },
    /// Error metrics of one EXR against a reference EXR (e.g. a Mitsuba 3 render).
    Compare {
        /// Image to measure.
        test: PathBuf,
        /// Reference image.
        reference: PathBuf,
        /// Write a difference picture (red: brighter, blue: darker; full at ±50%).
        #[arg(long)]
        diff: Option<PathBuf>,
    },
    /// Time the GPU passes (global, push, local, pull) per frame, like the paper's Table 2.
    Profile {
        /// Scene TOML (default: the bundled Cornell box).
        scene: Option<PathBuf>,
        /// Frames to time after warm-up.
        #[arg(long, default_value_t = 10)]
        frames: usize,
        /// Untimed warm-up frames.
        #[arg(long, default_value_t = 2)]
        warmup: usize,
        /// Override `solver.bins`.
        #[arg(long)]
        bins: Option<usize>,
        /// Override `solver.precision` (f16 | f32).
        #[arg(long)]
        precision: Option<String>,
        /// Write the report as JSON to this file.
        #[arg(long)]
        json: Option<PathBuf>,
        /// Vulkan device whose name contains this (default: prefer a discrete GPU).
        #[arg(long)]
        device: Option<String>,
        #[command(flatten)]
        plan: PlanArgs,
    },
}

/// What runs: the scene analysis' plan unless forced, and settings chosen for an error target.
#[derive(clap::Args)]
struct PlanArgs {
    /// Run every pass and create every table (float32) whether the scene needs it or not.
    #[arg(long)]
    all_passes: bool,
    /// Choose bins, element size and iterations for this relative RMSE from measured
    /// error-vs-time data (replaces the scene's and --bins/--iterations).
    #[arg(long)]
    target_error: Option<f64>,
}

impl PlanArgs {
    fn check(&self) -> Result<()> {
        if let Some(e) = self.target_error {
            anyhow::ensure!(
                e > 0.0 && e.is_finite(),
                "--target-error must be positive, got {e}"
            );
        }
        Ok(())
    }

    /// Applies --target-error to `s` (after checking it) and says what it chose.
    fn retarget(&self, s: &mut Scene) -> Result<()> {
        self.check()?;
        if let Some(e) = self.target_error {
            let c = antiradiance::plan::target::choose(s, e);
            eprintln!("{}", c.summary());
            antiradiance::plan::target::apply(s, &c);
        }
        Ok(())
    }
}

/// Progress bars on stderr for the library's long steps.
#[derive(Default)]
struct Bars(std::cell::RefCell<Option<indicatif::ProgressBar>>);

impl render::Progress for Bars {
    fn begin(&self, step: &str, total: u64) {
        let bar = indicatif::ProgressBar::new(total).with_message(step.to_string());
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{msg:>12} [{bar:30}] {pos}/{len} {elapsed_precise} (eta {eta})",
            )
            .expect("static template")
            .progress_chars("=> "),
        );
        bar.enable_steady_tick(std::time::Duration::from_millis(200));
        *self.0.borrow_mut() = Some(bar);
    }
    fn advance(&self, n: u64) {
        if let Some(b) = self.0.borrow().as_ref() {
            b.inc(n);
        }
    }
    fn end(&self) {
        if let Some(b) = self.0.borrow_mut().take() {
            b.finish();
        }
    }
}

fn default_scene() -> PathBuf {
    let bundled = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.toml");
    if bundled.is_file() {
        bundled
    } else {
        PathBuf::from("scenes/cornell-box.toml")
    }
}

/// The scene's file, to name it in errors that arise after loading (discretization, device).
fn scene_name(s: &Scene) -> String {
    s.path
        .as_ref()
        .map_or("<scene>".into(), |p| p.display().to_string())
}

fn load(path: Option<PathBuf>) -> Result<Scene> {
    let path = path.unwrap_or_else(default_scene);
    let s = scene::load_scene(&path)?;
    for w in &s.warnings {
        eprintln!("warning: {w}");
    }
    Ok(s)
}

/// Command-line flags override the scene's `[solver]` settings.
fn apply_overrides(
    s: &mut Scene,
    iterations: Option<usize>,
    bins: Option<usize>,
    scheme: Option<String>,
    precision: Option<String>,
) -> Result<()> {
    if let Some(i) = iterations {
        s.solver.iterations = i.max(1);
    }
    if let Some(b) = bins {
        s.solver.bins = b;
    }
    if let Some(sc) = scheme {
        s.solver.scheme = match sc.as_str() {
            "symmetric" => scene::Scheme::Symmetric,
            "asymmetric" => scene::Scheme::Asymmetric,
            x => anyhow::bail!("--scheme must be symmetric or asymmetric, got {x}"),
        };
    }
    if let Some(p) = precision {
        s.solver.precision = match p.as_str() {
            "f16" => scene::Precision::F16,
            "f32" => scene::Precision::F32,
            x => anyhow::bail!("--precision must be f16 or f32, got {x}"),
        };
    }
    Ok(())
}

fn set_size(s: &mut Scene, width: Option<u32>, height: Option<u32>) -> Result<()> {
    if let Some(w) = width {
        anyhow::ensure!((1..=16384).contains(&w), "--width must be 1..=16384");
        s.camera.width = w;
    }
    if let Some(h) = height {
        anyhow::ensure!((1..=16384).contains(&h), "--height must be 1..=16384");
        s.camera.height = h;
    }
    Ok(())
}

fn write_json(path: &Option<PathBuf>, value: &impl serde::Serialize) -> Result<()> {
    if let Some(p) = path {
        std::fs::write(p, serde_json::to_string_pretty(value)?)
            .with_context(|| format!("writing {}", p.display()))?;
    }
    Ok(())
}

fn parse_backend(b: &str) -> Result<render::Backend> {
    Ok(match b {
        "gpu" => render::Backend::Gpu,
        "cpu" => render::Backend::Cpu,
        x => anyhow::bail!("--backend must be gpu or cpu, got {x}"),
    })
}

/// Errors are one line (`Error: ...`, causes joined with `: `), whatever RUST_BACKTRACE says.
fn main() -> std::process::ExitCode {
    match run(Cli::parse()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("Error: {}", format!("{e:#}").replace('\n', " "));
            std::process::ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Compare {
            test,
            reference,
            diff,
        } => {
            let (t, r) = (
                antiradiance::frame::Image::read_exr(&test)?,
                antiradiance::frame::Image::read_exr(&reference)?,
            );
            let m = antiradiance::metrics::compare(&t, &r)?;
            println!("{}", serde_json::to_string_pretty(&m)?);
            if let Some(p) = diff {
                antiradiance::metrics::difference_map(&t, &r, 0.5)?.write_png(&p, 0.0)?;
                eprintln!("wrote {}", p.display());
            }
        }
        Command::Study {
            scene,
            reference,
            out,
            iterations,
            bins,
            element_sizes,
            spp,
            one_scheme,
            one_precision,
            backend,
            device,
        } => {
            let s = load(scene)?;
            let truth = antiradiance::study::Truth::load(&reference)?;
            if truth.direct.is_none() {
                eprintln!("note: no REF.direct.exr beside the reference; no indirect-only error");
            }
            let mut o = antiradiance::study::StudyOptions::defaults(&s, out.clone());
            o.iterations = iterations;
            o.bins = bins.unwrap_or(o.bins);
            o.element_sizes = element_sizes.unwrap_or(o.element_sizes);
            o.spp = spp.unwrap_or(o.spp);
            o.both_schemes = !one_scheme;
            o.both_precisions = !one_precision;
            o.render.backend = parse_backend(&backend)?;
            o.render.device = device;
            let rows = antiradiance::study::run(&s, &truth, &o, &Bars::default(), &mut |r| {
                eprintln!("{}", r.summary());
            })?;
            let cross = antiradiance::study::write(&rows, &out)?;
            eprintln!("full image, relative RMSE: {cross}");
            eprintln!(
                "wrote {}/study.csv, error-vs-time.png, convergence.png",
                out.display()
            );
        }
        Command::Reference {
            scene,
            spp,
            exr,
            max_bounces,
            seed,
            width,
            height,
            output,
            exposure,
            json,
        } => {
            let mut s = load(scene)?;
            set_size(&mut s, width, height)?;
            let opts = antiradiance::reference::ReferenceOptions {
                spp,
                max_bounces,
                seed,
            };
            let r = antiradiance::reference::render_reference(&s, &opts, &Bars::default())?;
            eprintln!("{}", r.stats.summary());
            for p in r.write(&exr)? {
                eprintln!("wrote {}", p.display());
            }
            if let Some(p) = output {
                r.image.write_png(&p, exposure)?;
                eprintln!("wrote {}", p.display());
            }
            write_json(&json, &r.stats)?;
        }
        Command::Profile {
            scene,
            frames,
            warmup,
            bins,
            precision,
            json,
            device,
            plan,
        } => {
            let mut s = load(scene)?;
            apply_overrides(&mut s, None, bins, None, precision)?;
            plan.retarget(&mut s)?;
            let ctx = antiradiance::gpu::Context::headless(&antiradiance::gpu::ContextOptions {
                validation: false,
                device_name: device,
            })?;
            let report = antiradiance::profile::profile(ctx, &s, frames, warmup, plan.all_passes)
                .with_context(|| scene_name(&s))?;
            print!("{}", report.text());
            write_json(&json, &report)?;
        }
        Command::Info { scene, json, plan } => {
            let mut s = load(scene)?;
            plan.retarget(&mut s)?;
            let sys = System::build(&s).with_context(|| scene_name(&s))?;
            let info = Info::of(&s, &sys, plan.all_passes).with_context(|| scene_name(&s))?;
            if json {
                println!("{}", serde_json::to_string_pretty(&info)?);
            } else {
                print!("{}", info.text());
            }
        }
        Command::Render {
            scene,
            output,
            exr,
            json,
            bins,
            iterations,
            scheme,
            precision,
            tolerance,
            max_iterations,
            width,
            height,
            exposure,
            backend,
            shadow_map_size,
            device,
            plan,
        } => {
            let mut s = load(scene)?;
            apply_overrides(&mut s, iterations, bins, scheme, precision)?;
            plan.check()?;
            if let Some(t) = tolerance {
                anyhow::ensure!(t > 0.0 && t < 1.0, "--tolerance must be in (0, 1), got {t}");
                s.solver.tolerance = Some(t);
            }
            if let Some(n) = max_iterations {
                anyhow::ensure!(n >= 1, "--max-iterations must be at least 1");
                s.solver.max_iterations = n;
            }
            set_size(&mut s, width, height)?;
            let backend = parse_backend(&backend)?;
            anyhow::ensure!(
                (16..=8192).contains(&shadow_map_size),
                "--shadow-map-size must be 16..=8192"
            );
            let opts = render::RenderOptions {
                context: None,
                backend,
                shadow_map_size,
                device,
                validation: false,
                all_passes: plan.all_passes,
                target_error: plan.target_error,
            };
            let r = render::render(&s, &opts, &Bars::default()).with_context(|| scene_name(&s))?;
            if let Some(c) = &r.stats.target {
                eprintln!("{}", c.summary());
            }
            for f in &r.stats.fallbacks {
                eprintln!("fallback: {f}");
            }
            for (i, (res, e)) in r.stats.residuals.iter().zip(&r.stats.energies).enumerate() {
                eprintln!(
                    "iteration {:>3}: residual {res:.3e}, exitant flux {e:.4e} W",
                    i + 1
                );
            }
            for w in &r.stats.warnings {
                eprintln!("warning: {w}");
            }
            if let Some(e) = r.stats.estimated_error {
                eprintln!(
                    "estimated error {e:.2e} ({} scheme, {} tables)",
                    r.stats.scheme, r.stats.precision
                );
            }
            eprintln!(
                "{} elements, {} links, {} bins on {}; {:.0} ms in all",
                r.stats.elements, r.stats.links, r.stats.bins, r.stats.device, r.stats.total_ms
            );
            if let Some(p) = &exr {
                r.image.write_exr(p)?;
                eprintln!("wrote {}", p.display());
            }
            if output.is_some() || exr.is_none() {
                let p = output.unwrap_or_else(|| PathBuf::from("out.png"));
                r.image.write_png(&p, exposure)?;
                eprintln!("wrote {}", p.display());
            }
            write_json(&json, &r.stats)?;
        }
    }
    Ok(())
}
