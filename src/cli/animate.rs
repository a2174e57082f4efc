//! `antiradiance animate`: the frames of a scene's animation and `frames.csv` into a folder.

use super::args::{SizeArgs, SolverArgs};
use super::progress::Bars;
use antiradiance::animate::{animate, summary, FrameRecord, Sampling};
use antiradiance::engine::Options;
use antiradiance::frame::image::{check_output_path, write_atomic};
use antiradiance::{BackendKind, Scene};
use anyhow::{Context, Result};
use std::path::PathBuf;

/// What `animate` was asked for.
pub struct AnimateArgs {
    /// Output folder.
    pub out: PathBuf,
    /// Frames, if given.
    pub frames: Option<u32>,
    /// Frames per second, if given.
    pub fps: Option<f64>,
    /// Write EXR frames too.
    pub exr: bool,
    /// Iterations per frame, if given.
    pub iterations_per_frame: Option<u32>,
    /// Solver overrides.
    pub solver: SolverArgs,
    /// Image size overrides.
    pub size: SizeArgs,
    /// PNG exposure.
    pub exposure: f64,
    /// Backend.
    pub backend: BackendKind,
    /// Shadow map size.
    pub shadow_map_size: u32,
    /// Device.
    pub device: Option<String>,
}

/// Renders the frames of `scene` into `a.out`, then writes `frames.csv` and prints the rate.
pub fn run(scene: &Scene, a: AnimateArgs, name: &str) -> Result<()> {
    let sampling = Sampling::of(scene, a.frames.map(|n| n as usize), a.fps)?;
    let mut solver = a.solver.overrides();
    solver.iterations_per_frame = a.iterations_per_frame.map(|n| n as usize);
    let o = Options {
        solver,
        width: a.size.width,
        height: a.size.height,
        backend: a.backend,
        shadow_map_size: a.shadow_map_size,
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
