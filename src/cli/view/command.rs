//! `antiradiance view`'s flags and their translation into the viewer's request.

use super::super::args::{finite, positive, window_size, PlanArgs, SizeArgs, SolverArgs};
use super::super::output::{check_outputs, load, picture, scene_name, Picture};
use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;

// The flags of `view` (the variant's doc comment is its help).
#[derive(Args)]
pub struct ViewArgs {
    /// Scene: TOML, glTF (.gltf, .glb) or Mitsuba XML (.xml); default: the bundled Cornell box.
    pub scene: Option<PathBuf>,
    #[command(flatten)]
    pub solver: SolverArgs,
    /// Window and frame size (default: the scene camera's `width` × `height`).
    #[command(flatten)]
    pub size: SizeArgs,
    /// Present this many frames, then exit.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub frames: Option<u32>,
    /// With --frames: save the last presented image (PNG, window size) here.
    #[arg(long, requires = "frames")]
    pub screenshot: Option<PathBuf>,
    /// With --frames: resize the window to W×H (e.g. `192x160`) after the first frame (the
    /// swapchain follows the window; the frame is scaled to fit, keeping its aspect).
    #[arg(long, requires = "frames", value_parser = window_size)]
    pub resize: Option<(u32, u32)>,
    /// With --frames: scene seconds per frame while the animation plays (the window's own
    /// clock otherwise).
    #[arg(long, default_value_t = 1.0 / 30.0, requires = "frames", allow_negative_numbers = true, value_parser = positive)]
    pub step: f64,
    /// Shadow map side in texels.
    #[arg(long, default_value_t = 1024)]
    pub shadow_map_size: u32,
    /// Side in texels of each area-emitter sample's cube-face maps (finer: sharper contact
    /// shadows under area lights; five faces of 4-byte texels per sample).
    #[arg(long, default_value_t = antiradiance::frame::emitters::SAMPLE_MAP_SIZE)]
    pub emitter_map_size: u32,
    /// Exposure in stops at the start (the keys `-` and `=` change it by half a stop).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = finite)]
    pub exposure: f64,
    /// Vulkan device whose name contains this (default: prefer a discrete GPU).
    #[arg(long)]
    pub device: Option<String>,
    #[command(flatten)]
    pub plan: PlanArgs,
    /// Global-illumination method (a baseline's frame is drawn on the host and uploaded);
    /// keyframes and light moves need antiradiance.
    #[arg(long, value_enum, default_value_t = antiradiance::Method::Antiradiance)]
    pub method: antiradiance::Method,
    #[command(flatten)]
    pub baseline: super::super::args::BaselineArgs,
}

impl ViewArgs {
    /// Opens the window and runs until it is closed (or `--frames` are presented).
    pub fn run(self) -> Result<()> {
        if let Some(p) = &self.screenshot {
            // The presented image is 8-bit sRGB: a PNG.
            if !matches!(picture(p.clone())?, Picture::Png(_)) {
                anyhow::bail!(
                    "{}: --screenshot writes the presented 8-bit image as PNG (.png)",
                    p.display()
                );
            }
        }
        check_outputs([self.screenshot.as_ref()])?;
        let s = load(self.scene)?;
        if s.duration.is_some() && self.method != antiradiance::Method::Antiradiance {
            anyhow::bail!(
                "--method {}: the scene has keyframes, and moving objects and lights need the \
                 antiradiance method",
                self.method
            );
        }
        let mut o = self.plan.options();
        o.method = self.method;
        o.baseline = self.baseline.settings();
        o.solver = self.solver.overrides();
        o.width = self.size.width;
        o.height = self.size.height;
        o.shadow_map_size = self.shadow_map_size;
        o.emitter_map_size = self.emitter_map_size;
        o.device = self.device;
        let name = scene_name(&s);
        super::run(super::ViewRequest {
            scene: s,
            options: o,
            frames: self.frames,
            screenshot: self.screenshot,
            resize: self.resize,
            step: self.step,
            exposure: self.exposure,
        })
        .with_context(|| name)
    }
}
