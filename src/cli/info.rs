//! `antiradiance info`: what the scene becomes (elements, links, bins, memory) without solving.

use super::args::PlanArgs;
use super::output::{load, scene_name};
use antiradiance::info::Info;
use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;

// The flags of `info` (the variant's doc comment is its help).
#[derive(Args)]
pub struct InfoArgs {
    /// Scene: TOML, glTF (.gltf, .glb) or Mitsuba XML (.xml); default: the bundled Cornell box.
    pub scene: Option<PathBuf>,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub plan: PlanArgs,
}

impl InfoArgs {
    /// Prints the scene's statistics as text or JSON.
    pub fn run(self) -> Result<()> {
        let s = load(self.scene)?;
        let o = self.plan.options();
        if let Some(c) = o.resolve(&s)?.target {
            eprintln!("{}", c.summary());
        }
        let info =
            Info::of(&s, &o, &antiradiance::progress::Silent).with_context(|| scene_name(&s))?;
        if self.json {
            println!("{}", serde_json::to_string_pretty(&info)?);
        } else {
            print!("{}", info.text());
        }
        Ok(())
    }
}
