//! `antiradiance` command-line tool: parses arguments and calls the library.

use antiradiance::{info::Info, scene, CpuSolver, Scene, System};
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
    },
    /// Solve the scene with the CPU reference solver and report residuals.
    Render {
        /// Scene TOML (default: the bundled Cornell box).
        scene: Option<PathBuf>,
        /// Override `solver.iterations`.
        #[arg(long)]
        iterations: Option<usize>,
        /// Override `solver.bins`.
        #[arg(long)]
        bins: Option<usize>,
        /// Override `solver.scheme` (symmetric | asymmetric).
        #[arg(long)]
        scheme: Option<String>,
        /// Write statistics as JSON to this file.
        #[arg(long)]
        json: Option<PathBuf>,
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
    },
}

fn default_scene() -> PathBuf {
    let bundled = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.toml");
    if bundled.is_file() {
        bundled
    } else {
        PathBuf::from("scenes/cornell-box.toml")
    }
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

fn main() -> Result<()> {
    match Cli::parse().command {
        Command::Profile {
            scene,
            frames,
            warmup,
            bins,
            precision,
            json,
            device,
        } => {
            let mut s = load(scene)?;
            apply_overrides(&mut s, None, bins, None, precision)?;
            let ctx = antiradiance::gpu::Context::headless(&antiradiance::gpu::ContextOptions {
                validation: false,
                device_name: device,
            })?;
            let report = antiradiance::profile::profile(ctx, &s, frames, warmup)?;
            print!("{}", report.text());
            if let Some(p) = json {
                std::fs::write(&p, serde_json::to_string_pretty(&report)?)
                    .with_context(|| format!("writing {}", p.display()))?;
            }
        }
        Command::Info { scene, json } => {
            let s = load(scene)?;
            let sys = System::build(&s)?;
            let info = Info::new(&s, &sys);
            if json {
                println!("{}", serde_json::to_string_pretty(&info)?);
            } else {
                print!("{}", info.text());
            }
        }
        Command::Render {
            scene,
            iterations,
            bins,
            scheme,
            json,
        } => {
            let mut s = load(scene)?;
            apply_overrides(&mut s, iterations, bins, scheme, None)?;
            let sys = System::build(&s)?;
            let info = Info::new(&s, &sys);
            eprint!("{}", info.text());
            let t0 = std::time::Instant::now();
            let mut solver = CpuSolver::new(&sys);
            solver.set_environment(s.environment);
            solver.solve(
                s.solver.scheme,
                s.solver.iterations,
                s.solver.antiradiance_steps,
            );
            let solve_ms = t0.elapsed().as_secs_f64() * 1e3;
            for (i, (r, e)) in solver.residuals.iter().zip(&solver.energies).enumerate() {
                eprintln!(
                    "iteration {:>3}: residual {r:.3e}, exitant flux {e:.4e} W",
                    i + 1
                );
            }
            eprintln!("CPU solve {solve_ms:.1} ms (images arrive with the frame issue)");
            if let Some(p) = json {
                let v = serde_json::json!({
                    "elements": info.elements, "links": info.links, "bins": info.bins,
                    "iterations": s.solver.iterations, "linking_ms": info.linking_ms,
                    "total_ms": solve_ms + info.linking_ms + info.meshing_ms,
                    "passes": { "cpu_solve": solve_ms }, "residuals": solver.residuals,
                    "fallbacks": Vec::<String>::new(),
                });
                std::fs::write(&p, serde_json::to_string_pretty(&v)?)
                    .with_context(|| format!("writing {}", p.display()))?;
            }
        }
    }
    Ok(())
}
