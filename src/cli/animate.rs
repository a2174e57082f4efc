//! `antiradiance animate`: the frames of a scene's animation and `frames.csv` into a folder.

use super::args::{finite, positive, SizeArgs, SolverArgs};
use super::output::{load, scene_name};
use super::progress::Bars;
use antiradiance::animate::{animate, summary, FrameRecord, Sampling};
use antiradiance::engine::Options;
use antiradiance::frame::image::{check_output_path, write_atomic};
use antiradiance::{BackendKind, Method, Scene};
use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;

// The flags of `animate` (the variant's doc comment is its help).
#[derive(Args)]
pub struct AnimateArgs {
    /// Scene with keyframes (TOML; glTF and Mitsuba XML scenes have none).
    pub scene: PathBuf,
    /// Output directory (created if missing).
    #[arg(long)]
    pub out: PathBuf,
    /// Number of frames (default: the animation's duration × fps).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub frames: Option<u32>,
    /// Frames per second of scene time (default 24).
    #[arg(long, value_parser = positive)]
    pub fps: Option<f64>,
    /// Also write each frame as EXR (linear radiance).
    #[arg(long)]
    pub exr: bool,
    /// Override `solver.iterations_per_frame`.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=antiradiance::scene::MAX_ITERATIONS as i64))]
    pub iterations_per_frame: Option<u32>,
    #[command(flatten)]
    pub solver: SolverArgs,
    #[command(flatten)]
    pub size: SizeArgs,
    /// Override `camera.supersample`: each pixel the box-filtered mean of K×K frame pixels
    /// (the frame drawn at K× the size; anti-aliases sub-pixel edges and shadows, K² the
    /// frame's cost), 1..=8.
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u32).range(1..=antiradiance::scene::MAX_SUPERSAMPLE as i64))]
    pub supersample: Option<u32>,
    /// Override `camera.passes`: the frame drawn N times, each pass's samples shifted along
    /// the pixel's diagonal by 1/N of their spacing, and averaged (hard edges along the image's
    /// rows and columns integrated in N× finer steps; N× the frame's cost), 1..=16.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=antiradiance::scene::MAX_PASSES as i64))]
    pub passes: Option<u32>,
    /// PNG exposure in stops.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = finite)]
    pub exposure: f64,
    /// Which implementation solves and draws.
    #[arg(long, value_enum, default_value_t = BackendKind::Gpu)]
    pub backend: BackendKind,
    /// Global-illumination method; a scene with keyframes needs antiradiance, a still scene
    /// (walked with --orbit) takes any.
    #[arg(long, value_enum, default_value_t = Method::Antiradiance)]
    pub method: Method,
    /// Degrees the camera turns about its target over the frames (a walk around the scene;
    /// nothing is re-solved for it).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = finite)]
    pub orbit: f64,
    #[command(flatten)]
    pub baseline: super::args::BaselineArgs,
    /// Shadow map side in texels.
    #[arg(long, default_value_t = 1024)]
    pub shadow_map_size: u32,
    /// Side in texels of each area-emitter sample's cube-face maps (finer: sharper contact
    /// shadows under area lights; five faces of 4-byte texels per sample).
    #[arg(long, default_value_t = antiradiance::frame::emitters::SAMPLE_MAP_SIZE)]
    pub emitter_map_size: u32,
    /// Vulkan device whose name contains this (default: prefer a discrete GPU).
    #[arg(long)]
    pub device: Option<String>,
}

impl AnimateArgs {
    /// Loads the scene, renders its frames into `--out` and writes `frames.csv`.
    pub fn run(self) -> Result<()> {
        let s = load(Some(self.scene.clone()))?;
        let name = scene_name(&s);
        run(&s, self, &name)
    }
}

/// Renders the frames of `scene` into `a.out`, then writes `frames.csv` and prints the rate.
fn run(scene: &Scene, a: AnimateArgs, name: &str) -> Result<()> {
    let mut sampling = Sampling::of(scene, a.frames.map(|n| n as usize), a.fps)?;
    sampling.orbit = a.orbit;
    let mut solver = a.solver.overrides();
    solver.iterations_per_frame = a.iterations_per_frame.map(|n| n as usize);
    let o = Options {
        solver,
        width: a.size.width,
        height: a.size.height,
        supersample: a.supersample,
        passes: a.passes,
        backend: a.backend,
        method: a.method,
        baseline: a.baseline.settings(),
        shadow_map_size: a.shadow_map_size,
        emitter_map_size: a.emitter_map_size,
        device: a.device,
        ..Options::default()
    };
    o.resolve(scene)?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("{}", a.out.display()))?;
    let csv = a.out.join("frames.csv");
    let frame_path = |k: usize, ext: &str| a.out.join(format!("frame-{k:04}.{ext}"));
    check_output_path(&csv)?;
    check_output_path(&frame_path(0, "png"))?;
    let bars = Bars::default();
    let records = animate(scene, &o, sampling, &bars, &mut |r: &FrameRecord, image| {
        image.write_png(&frame_path(r.frame, "png"), a.exposure)?;
        if a.exr {
            image.write_exr(&frame_path(r.frame, "exr"))?;
        }
        Ok(())
    })
    .with_context(|| name.to_string())?;
    let text: String = std::iter::once(FrameRecord::HEADER.to_string())
        .chain(records.iter().map(FrameRecord::csv))
        .map(|l| l + "\n")
        .collect();
    write_atomic(&csv, |w| std::io::Write::write_all(w, text.as_bytes()))?;
    eprintln!("{}", summary(&records));
    eprintln!(
        "wrote {}/frame-0000.png … frame-{:04}.png{}, frames.csv",
        a.out.display(),
        records.len() - 1,
        if a.exr { " (and .exr)" } else { "" }
    );
    Ok(())
}
