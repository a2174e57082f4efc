//! `antiradiance profile`: per-pass GPU timings and memory, like Table 2 of the paper. A frame
//! is one iteration of the scene's scheme (one propagation symmetric, 1 + antiradiance_steps
//! asymmetric), timed by the timestamp scopes of every pass.

use crate::error::Result;
use crate::gpu::{Context, GpuOptions, GpuSolver};
use crate::scene::{Scene, Scheme};
use crate::system::System;
use serde::Serialize;
use std::collections::BTreeMap;
use std::sync::Arc;

/// Min / median / max of one pass over the frames.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct PassStats {
    /// Fastest frame.
    pub min_ms: f64,
    /// Median frame.
    pub median_ms: f64,
    /// Slowest frame.
    pub max_ms: f64,
}

impl PassStats {
    /// Statistics of `samples` (ms).
    pub fn of(samples: &[f64]) -> Self {
        if samples.is_empty() {
            return Self::default();
        }
        let mut s = samples.to_vec();
        s.sort_by(f64::total_cmp);
        let n = s.len();
        let median = if n % 2 == 1 {
            s[n / 2]
        } else {
            0.5 * (s[n / 2 - 1] + s[n / 2])
        };
        Self {
            min_ms: s[0],
            median_ms: median,
            max_ms: s[n - 1],
        }
    }
}

/// The profile of one scene.
#[derive(Debug, Clone, Serialize)]
pub struct ProfileReport {
    /// Scene file.
    pub scene: String,
    /// Driver name (e.g. `llvmpipe`, `NVIDIA`).
    pub device: String,
    /// Device name.
    pub device_name: String,
    /// Leaf elements.
    pub elements: usize,
    /// Links.
    pub links: usize,
    /// Bins.
    pub bins: usize,
    /// Scheme of a frame.
    pub scheme: String,
    /// Table precision.
    pub precision: String,
    /// Frames timed (after warm-up).
    pub frames: usize,
    /// CPU link construction, ms.
    pub linking_ms: f64,
    /// CPU element subdivision and hierarchy, ms.
    pub meshing_ms: f64,
    /// Pass name → per-frame time.
    pub passes: BTreeMap<String, PassStats>,
    /// Sum of the passes per frame.
    pub frame: PassStats,
    /// GPU memory by purpose, bytes.
    pub memory_bytes: BTreeMap<String, u64>,
    /// Fragments each pass draws per frame.
    pub fragments: BTreeMap<String, u64>,
    /// Departures from the requested configuration.
    pub fallbacks: Vec<String>,
}

/// Builds the scene's system, warms up, then times `frames` frames.
pub fn profile(
    ctx: Arc<Context>,
    scene: &Scene,
    frames: usize,
    warmup: usize,
) -> Result<ProfileReport> {
    let sys = System::build_within(scene, Some(ctx.info.device_local_bytes))?;
    let st = &scene.solver;
    let mut gpu = GpuSolver::new(
        ctx.clone(),
        &sys,
        GpuOptions {
            precision: st.precision,
            ..Default::default()
        },
    )?;
    gpu.set_environment(scene.environment)?;
    gpu.initialize()?;
    for _ in 0..warmup {
        gpu.iterate(st.scheme, st.antiradiance_steps)?;
    }
    let mut per_pass: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    let mut totals = Vec::with_capacity(frames);
    for f in 0..frames {
        gpu.iterate(st.scheme, st.antiradiance_steps)?;
        let mut frame: BTreeMap<String, f64> = BTreeMap::new();
        for (name, ms) in gpu.timings() {
            *frame.entry(name.clone()).or_default() += ms;
        }
        totals.push(frame.values().sum());
        for (name, ms) in frame {
            per_pass.entry(name).or_default().push(ms);
        }
        eprint!("\rprofile: frame {}/{frames}", f + 1);
    }
    if frames > 0 {
        eprintln!();
    }
    let props = match st.scheme {
        Scheme::Symmetric => 1,
        Scheme::Asymmetric => 1 + st.antiradiance_steps as u64,
    };
    let fr = gpu.fragments();
    let mem = gpu.memory();
    let memory_bytes = BTreeMap::from([
        ("tables".to_string(), mem.tables),
        ("links".to_string(), mem.links),
        ("filter_tables".to_string(), mem.filter_tables),
        ("element_attributes".to_string(), mem.element_attributes),
        ("push_pull_primitives".to_string(), mem.push_pull_primitives),
        ("total".to_string(), mem.total),
    ]);
    let fragments = BTreeMap::from([
        ("global".to_string(), fr.global * props),
        ("push".to_string(), fr.push * props),
        ("local".to_string(), fr.local * props),
        ("pull".to_string(), fr.pull * props),
    ]);
    Ok(ProfileReport {
        scene: scene
            .path
            .as_ref()
            .map(|p| p.display().to_string())
            .unwrap_or_default(),
        device: ctx.info.driver.clone(),
        device_name: ctx.info.name.clone(),
        elements: sys.leaves.len(),
        links: sys.links.links.len(),
        bins: sys.bins.count,
        scheme: format!("{:?}", st.scheme).to_lowercase(),
        precision: format!("{:?}", st.precision).to_lowercase(),
        frames,
        linking_ms: sys.links.linking_ms,
        meshing_ms: sys.meshing_ms,
        passes: per_pass
            .iter()
            .map(|(k, v)| (k.clone(), PassStats::of(v)))
            .collect(),
        frame: PassStats::of(&totals),
        memory_bytes,
        fragments,
        fallbacks: gpu.fallbacks().to_vec(),
    })
}

impl ProfileReport {
    /// The Table 2-style text report.
    pub fn text(&self) -> String {
        let mb = |k: &str| self.memory_bytes.get(k).copied().unwrap_or(0) as f64 / (1 << 20) as f64;
        let mut s = format!(
            "{}\ndevice: {} ({})\n{} elements, {} links, {} bins, {} scheme, {} tables, {} frames\n\
             linking {:.2} s (meshing {:.1} ms)\n\n{:<8} {:>10} {:>10} {:>10} {:>14}\n",
            self.scene, self.device_name, self.device, self.elements, self.links, self.bins,
            self.scheme, self.precision, self.frames, self.linking_ms / 1e3, self.meshing_ms,
            "pass", "min ms", "median ms", "max ms", "fragments"
        );
        for name in ["global", "push", "local", "pull"] {
            if let Some(p) = self.passes.get(name) {
                s += &format!(
                    "{:<8} {:>10.2} {:>10.2} {:>10.2} {:>14}\n",
                    name,
                    p.min_ms,
                    p.median_ms,
                    p.max_ms,
                    self.fragments.get(name).copied().unwrap_or(0)
                );
            }
        }
        s += &format!(
            "{:<8} {:>10.2} {:>10.2} {:>10.2}\n\nmemory: tables {:.1} MB, links {:.1} MB, filter tables {:.1} MB, \
             attributes {:.1} MB, push/pull primitives {:.1} MB, total {:.1} MB\n",
            "frame", self.frame.min_ms, self.frame.median_ms, self.frame.max_ms, mb("tables"), mb("links"),
            mb("filter_tables"), mb("element_attributes"), mb("push_pull_primitives"), mb("total")
        );
        for f in &self.fallbacks {
            s += &format!("fallback: {f}\n");
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pass_stats() {
        let p = PassStats::of(&[3.0, 1.0, 2.0, 10.0]);
        assert_eq!((p.min_ms, p.median_ms, p.max_ms), (1.0, 2.5, 10.0));
        let p = PassStats::of(&[5.0]);
        assert_eq!((p.min_ms, p.median_ms, p.max_ms), (5.0, 5.0, 5.0));
    }
}
