//! `antiradiance compare`: error metrics of one EXR against another.

use super::output::{check_outputs, wrote};
use antiradiance::frame::Image;
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

// The flags of `compare` (the variant's doc comment is its help).
#[derive(Args)]
pub struct CompareArgs {
    /// Image to measure.
    pub test: PathBuf,
    /// Reference image.
    pub reference: PathBuf,
    /// Write a difference picture (red: brighter, blue: darker; full at ±50%).
    #[arg(long)]
    pub diff: Option<PathBuf>,
}

impl CompareArgs {
    /// Prints the metrics as JSON (and writes the difference picture if asked).
    pub fn run(self) -> Result<()> {
        check_outputs([self.diff.as_ref()])?;
        let (test, reference) = (&self.test, &self.reference);
        let (t, r) = (Image::read_exr(test)?, Image::read_exr(reference)?);
        t.check_finite(test)?;
        r.check_finite(reference)?;
        let m = antiradiance::metrics::compare(&t, &r)?;
        println!("{}", serde_json::to_string_pretty(&m)?);
        if let Some(p) = self.diff {
            antiradiance::metrics::difference_map(&t, &r, 0.5)?.write_png(&p, 0.0)?;
            wrote(&p);
        }
        Ok(())
    }
}
