//! `antiradiance profile`: the GPU passes timed per frame (the paper's Table 2).

use super::args::PlanArgs;
use super::output::{check_outputs, load, scene_name, write_json};
use antiradiance::Precision;
use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;

// The flags of `profile` (the variant's doc comment is its help).
#[derive(Args)]
pub struct ProfileArgs {
    /// Scene: TOML, glTF (.gltf, .glb) or Mitsuba XML (.xml); default: the bundled Cornell box.
    pub scene: Option<PathBuf>,
    /// Frames to time after warm-up (at least 1).
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub frames: u32,
    /// Untimed warm-up frames.
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(0..=100_000))]
    pub warmup: u32,
    /// Override `solver.bins`.
    #[arg(long)]
    pub bins: Option<usize>,
    /// Override `solver.precision`.
    #[arg(long, value_enum)]
    pub precision: Option<Precision>,
    /// Write the report as JSON to this file.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Write the timed run as a Chrome trace-event file (JSON; open it in Perfetto or
    /// chrome://tracing): a device track with every pass, a host track with setup and batches.
    #[arg(long)]
    pub trace: Option<PathBuf>,
    /// Vulkan device whose name contains this (default: prefer a discrete GPU).
    #[arg(long)]
    pub device: Option<String>,
    #[command(flatten)]
    pub plan: PlanArgs,
}

impl ProfileArgs {
    /// Times the frames and prints the table (and writes JSON if asked).
    pub fn run(self) -> Result<()> {
        check_outputs([self.json.as_ref(), self.trace.as_ref()])?;
        let s = load(self.scene)?;
        let mut o = self.plan.options();
        o.solver.bins = self.bins;
        o.solver.precision = self.precision;
        o.device = self.device;
        if let Some(c) = o.resolve(&s)?.target {
            eprintln!("{}", c.summary());
        }
        let report =
            antiradiance::profile::profile(&s, &o, self.frames as usize, self.warmup as usize)
                .with_context(|| scene_name(&s))?;
        print!("{}", report.text());
        if let Some(path) = &self.trace {
            let text = serde_json::to_string(&report.trace())?;
            std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))?;
            eprintln!("wrote {}", path.display());
        }
        write_json(&self.json, &report)
    }
}
