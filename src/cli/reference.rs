//! `antiradiance reference`: the path-traced ground truth and its standard error.

use super::args::{finite, SizeArgs};
use super::output::{check_outputs, load, picture, picture_path, write_json, write_picture, wrote};
use super::progress::Bars;
use antiradiance::engine::Options;
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

// The flags of `reference` (the variant's doc comment is its help).
#[derive(Args)]
pub struct ReferenceArgs {
    /// Scene: TOML, glTF (.gltf, .glb) or Mitsuba XML (.xml); default: the bundled Cornell box.
    pub scene: Option<PathBuf>,
    /// Samples per pixel.
    #[arg(long, default_value_t = 256)]
    pub spp: u32,
    /// EXR output (linear float RGB radiance).
    #[arg(long, default_value = "reference.exr")]
    pub exr: PathBuf,
    /// Reflections per path (default: unlimited, ended by Russian roulette without bias).
    #[arg(long)]
    pub max_bounces: Option<u32>,
    /// Seed: the same seed gives the same image on any number of threads.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[command(flatten)]
    pub size: SizeArgs,
    /// Also write a PNG (exposure in stops via --exposure; a name ending in .exr writes
    /// linear EXR instead).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// PNG exposure in stops.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = finite)]
    pub exposure: f64,
    /// Write the convergence figures as JSON to this file.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

impl ReferenceArgs {
    /// Path-traces the scene's camera and writes the EXRs (and a picture, and JSON if asked).
    pub fn run(self) -> Result<()> {
        let exr = self.exr;
        let (direct, stderr) = antiradiance::reference::sibling_paths(&exr);
        let output = self.output.map(picture).transpose()?;
        check_outputs([
            Some(&exr),
            Some(&direct),
            Some(&stderr),
            picture_path(&output),
            self.json.as_ref(),
        ])?;
        let mut s = load(self.scene)?;
        // The path tracer renders the scene's camera at the requested size.
        let camera = Options {
            width: self.size.width,
            height: self.size.height,
            ..Options::default()
        }
        .resolve(&s)?
        .camera;
        s.camera = camera;
        let opts = antiradiance::reference::ReferenceOptions {
            spp: self.spp,
            max_bounces: self.max_bounces,
            seed: self.seed,
        };
        let r = antiradiance::reference::render_reference(&s, &opts, &Bars::default())?;
        eprintln!("{}", r.stats.summary());
        for p in r.write(&exr)? {
            wrote(&p);
        }
        if let Some(p) = &output {
            write_picture(&r.image, p, self.exposure)?;
        }
        write_json(&self.json, &r.stats)
    }
}
