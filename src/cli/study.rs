//! `antiradiance study`: error against run time for every method over a sweep of settings.

use super::args::{positive, SizeArgs};
use super::output::{check_outputs, load};
use super::progress::Bars;
use antiradiance::{BackendKind, Method};
use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;

// The flags of `study` (the variant's doc comment is its help).
#[derive(Args)]
pub struct StudyArgs {
    /// Scene: TOML, glTF (.gltf, .glb) or Mitsuba XML (.xml); default: the bundled Cornell box.
    pub scene: Option<PathBuf>,
    /// Reference EXR from `antiradiance reference` (its REF.direct.exr, when present, gives
    /// the indirect-only error), at the size the study renders: the scene camera's, or
    /// --width/--height. Not with --animate, which makes its own per frame.
    #[arg(long, required_unless_present = "animate", conflicts_with = "animate")]
    pub reference: Option<PathBuf>,
    /// The dynamic study: over --frames frames at --fps, every frame against its own
    /// path-traced reference (cached in OUT/cache), for antiradiance warm-started at 1, 2 and 4
    /// iterations per frame, instant radiosity relit per frame, the path tracer from scratch
    /// (1, 4, 16 spp) and accumulating (4 spp a frame, reset when the scene moved); writes
    /// frames.csv, error-vs-time.png and error-over-frames.png.
    #[arg(long)]
    pub animate: bool,
    /// --animate: frames (default: the animation's duration × fps).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub frames: Option<u32>,
    /// --animate: frames per second of scene time (default 24).
    #[arg(long, value_parser = positive)]
    pub fps: Option<f64>,
    /// --animate: samples per pixel of each frame's reference.
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(1..))]
    pub reference_spp: u32,
    /// --animate: antiradiance's iterations per frame to try, comma-separated (default 1,2,4).
    #[arg(long, value_delimiter = ',')]
    pub iterations_per_frame: Option<Vec<usize>>,
    /// --animate: spp the accumulating path tracer adds per frame (0: not run).
    #[arg(long, default_value_t = 4)]
    pub accumulate_spp: u32,
    /// --animate: also write every frame's image to OUT/images (for `compare` against the
    /// references in OUT/cache).
    #[arg(long)]
    pub save_images: bool,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
    /// Antiradiance is measured after every iteration 1..=N.
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub iterations: u32,
    /// Bin counts to try, comma-separated (default 32,64,128,256,512).
    #[arg(long, value_delimiter = ',')]
    pub bins: Option<Vec<usize>>,
    /// Element sizes to try, comma-separated (default: the scene's ×2, ×1, ×0.5).
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true, value_parser = positive)]
    pub element_sizes: Option<Vec<f64>>,
    /// Path tracer sample counts, comma-separated (default 1,4,16,64,256).
    #[arg(long, value_delimiter = ',')]
    pub spp: Option<Vec<u32>>,
    /// Methods measured, comma-separated (default: all five; hierarchical and progressive
    /// radiosity run at the scene's settings, after every iteration like antiradiance;
    /// instant radiosity once per --vpls; image-based radiosity once per --vpls and --cubes).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub methods: Option<Vec<Method>>,
    /// hierarchical-radiosity: visibility rays per link to try, comma-separated (default
    /// 4,16,32,141).
    #[arg(long, value_delimiter = ',')]
    pub rays_per_link: Option<Vec<u32>>,
    /// progressive-radiosity: receiver subdivision levels to try, comma-separated (default
    /// 0,2).
    #[arg(long, value_delimiter = ',')]
    pub subdivisions: Option<Vec<u32>>,
    /// instant-radiosity and image-based-radiosity: light paths to try, comma-separated, one
    /// image each (default 16,64,256,1024).
    #[arg(long, value_delimiter = ',')]
    pub vpls: Option<Vec<u32>>,
    /// image-based-radiosity: cube resolutions to try, comma-separated, one curve each (default
    /// 64,128,256).
    #[arg(long, value_delimiter = ',')]
    pub cubes: Option<Vec<u32>>,
    /// Skip the run with the other iteration scheme.
    #[arg(long)]
    pub one_scheme: bool,
    /// Skip the run with the other precision.
    #[arg(long)]
    pub one_precision: bool,
    /// Image size: the scene camera's unless given (shrink both here and in `reference` for a
    /// quick study).
    #[command(flatten)]
    pub size: SizeArgs,
    /// Which implementation runs antiradiance.
    #[arg(long, value_enum, default_value_t = BackendKind::Gpu)]
    pub backend: BackendKind,
    /// Vulkan device whose name contains this.
    #[arg(long)]
    pub device: Option<String>,
}

impl StudyArgs {
    /// `study --animate`: the per-frame study of a moving scene.
    fn run_dynamic(self) -> Result<()> {
        let s = load(self.scene)?;
        let sampling =
            antiradiance::animate::Sampling::of(&s, self.frames.map(|f| f as usize), self.fps)?;
        let out = self.out;
        let mut o = antiradiance::study::dynamic::DynamicOptions::defaults(
            out.clone(),
            sampling.frames,
            sampling.fps,
        );
        o.reference_spp = self.reference_spp;
        o.iterations_per_frame = self.iterations_per_frame.unwrap_or(o.iterations_per_frame);
        if let Some(spp) = self.spp {
            o.spp = spp;
        }
        if let Some(v) = self.vpls.and_then(|v| v.first().copied()) {
            o.vpls = v;
        }
        o.accumulate_spp = self.accumulate_spp;
        o.save_images = self.save_images;
        o.render.backend = self.backend;
        o.render.device = self.device;
        o.render.width = self.size.width;
        o.render.height = self.size.height;
        std::fs::create_dir_all(&out).with_context(|| format!("{}", out.display()))?;
        check_outputs([Some(&out.join("frames.csv"))])?;
        let run = antiradiance::study::dynamic::run(&s, &o, &Bars::default())?;
        antiradiance::study::dynamic::write(&run.rows, &out)?;
        for (m, setting, ms, e) in antiradiance::study::dynamic::means(&run.rows) {
            eprintln!("{m}, {setting}: {ms:.1} ms per frame, relative RMSE {e:.4}");
        }
        eprintln!(
            "{} of {} references from the cache; wrote {}/frames.csv, error-vs-time.png, error-over-frames.png",
            run.cached_references,
            sampling.frames,
            out.display()
        );
        Ok(())
    }

    /// Runs the sweep against the reference and writes study.csv and the plots.
    pub fn run(self) -> Result<()> {
        if self.animate {
            return self.run_dynamic();
        }
        let s = load(self.scene)?;
        let out = self.out;
        let reference = self
            .reference
            .context("--reference is required without --animate")?;
        let truth = antiradiance::study::Truth::load(&reference)?;
        let mut o = antiradiance::study::StudyOptions::defaults(&s, out.clone());
        o.iterations = self.iterations as usize;
        o.bins = self.bins.unwrap_or(o.bins);
        o.element_sizes = self.element_sizes.unwrap_or(o.element_sizes);
        o.spp = self.spp.unwrap_or(o.spp);
        o.methods = self.methods.unwrap_or(o.methods);
        o.rays_per_link = self.rays_per_link.unwrap_or(o.rays_per_link);
        o.subdivisions = self.subdivisions.unwrap_or(o.subdivisions);
        o.vpls = self.vpls.unwrap_or(o.vpls);
        o.cubes = self.cubes.unwrap_or(o.cubes);
        o.both_schemes = !self.one_scheme;
        o.both_precisions = !self.one_precision;
        o.render.backend = self.backend;
        o.render.device = self.device;
        o.render.width = self.size.width;
        o.render.height = self.size.height;
        let (w, h) = antiradiance::study::study_size(&s, &o.render)?;
        let (tw, th) = (truth.image.width, truth.image.height);
        if (tw, th) != (w, h) {
            anyhow::bail!(
                "{}: the reference is {tw}×{th} but the study renders at {w}×{h} (the scene camera's size, or --width/--height); render the reference with `reference --width {w} --height {h}`, or give the study --width {tw} --height {th}",
                reference.display()
            );
        }
        std::fs::create_dir_all(&out).with_context(|| format!("{}", out.display()))?;
        check_outputs([Some(&out.join("study.csv"))])?;
        if let Some(why) = truth.no_indirect_reason() {
            eprintln!("note: {why}; the indirect-only columns stay empty");
        }
        let rows = antiradiance::study::run(&s, &truth, &o, &Bars::default(), &mut |r| {
            eprintln!("{}", r.summary());
        })?;
        let cross = antiradiance::study::write(&rows, &out)?;
        eprintln!("full image, relative RMSE: {cross}");
        eprintln!(
            "wrote {}/study.csv, error-vs-time.png, convergence.png",
            out.display()
        );
        Ok(())
    }
}
