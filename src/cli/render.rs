//! `antiradiance render`: one frame of the scene to PNG and/or EXR.

use super::args::{finite, positive, BaselineArgs, PlanArgs, SizeArgs, SolverArgs};
use super::output::{
    check_outputs, load, picture, picture_path, report, scene_name, write_json, write_picture,
    wrote, Picture,
};
use super::progress::Bars;
use antiradiance::engine::Engine;
use antiradiance::{BackendKind, Method};
use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;

// The flags of `render` (the variant's doc comment is its help).
#[derive(Args)]
pub struct RenderArgs {
    /// Scene: TOML, glTF (.gltf, .glb) or Mitsuba XML (.xml); default: the bundled Cornell box.
    pub scene: Option<PathBuf>,
    /// PNG output (tone-mapped sRGB; a name ending in .exr writes linear EXR instead);
    /// written when given, or when no --exr is given.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// EXR output (linear float RGB radiance).
    #[arg(long)]
    pub exr: Option<PathBuf>,
    /// Write statistics as JSON to this file.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Scene time in seconds: keyframed objects and lights as they stand then, solved from
    /// scratch (the check for `animate`'s frames).
    #[arg(long, allow_negative_numbers = true, value_parser = finite)]
    pub time: Option<f64>,
    #[command(flatten)]
    pub solver: SolverArgs,
    /// Iterate until the estimated error (distance to the discrete system's fixed point, not
    /// to the true answer) is below this instead of a fixed count.
    #[arg(long, allow_negative_numbers = true, value_parser = positive)]
    pub tolerance: Option<f64>,
    /// Iteration cap with --tolerance (default: `solver.max_iterations`, 1000).
    #[arg(long)]
    pub max_iterations: Option<usize>,
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
    /// PNG exposure in stops (pixel values are multiplied by 2^exposure).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = finite)]
    pub exposure: f64,
    /// Which implementation solves and draws.
    #[arg(long, value_enum, default_value_t = BackendKind::Gpu)]
    pub backend: BackendKind,
    /// How global illumination is computed: the paper's method, or a baseline on the same
    /// scene, direct light and frame (README, "Baselines").
    #[arg(long, value_enum, default_value_t = Method::Antiradiance)]
    pub method: Method,
    #[command(flatten)]
    pub baseline: BaselineArgs,
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
    #[command(flatten)]
    pub plan: PlanArgs,
}

impl RenderArgs {
    /// Solves and draws one frame, then writes the pictures and the statistics.
    pub fn run(self) -> Result<()> {
        let picture = match self.output.clone() {
            Some(p) => Some(picture(p)?),
            None => self
                .exr
                .is_none()
                .then(|| Picture::Png(PathBuf::from("out.png"))),
        };
        check_outputs([
            picture_path(&picture),
            self.exr.as_ref(),
            self.json.as_ref(),
        ])?;
        let mut s = load(self.scene)?;
        if let Some(t) = self.time {
            s.move_to(t);
        }
        // One frame: linked for where things stand, not for the keyframes' motion.
        let s = s.still();
        let mut o = self.plan.options();
        o.solver = self.solver.overrides();
        o.solver.tolerance = self.tolerance;
        o.solver.max_iterations = self.max_iterations;
        o.width = self.size.width;
        o.height = self.size.height;
        o.supersample = self.supersample;
        o.passes = self.passes;
        o.backend = self.backend;
        o.method = self.method;
        o.baseline = self.baseline.settings();
        o.shadow_map_size = self.shadow_map_size;
        o.emitter_map_size = self.emitter_map_size;
        o.device = self.device;
        let bars = Bars::default();
        let r = Engine::new(&s, &o, &bars)
            .and_then(|mut e| e.render(&bars))
            .with_context(|| scene_name(&s))?;
        report(&r.stats);
        if let Some(p) = &self.exr {
            r.image.write_exr(p)?;
            wrote(p);
        }
        if let Some(p) = &picture {
            write_picture(&r.image, p, self.exposure)?;
        }
        write_json(&self.json, &r.stats)
    }
}
