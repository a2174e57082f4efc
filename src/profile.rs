//! `antiradiance profile`: per-pass GPU timings and memory, like Table 2 of the paper. A frame
//! is one iteration of the scene's scheme (one propagation symmetric, 1 + antiradiance_steps
//! asymmetric), timed by the timestamp scopes of every pass.

use crate::engine::{Engine, Options, Prepared};
use crate::error::Result;
use crate::gpu::memory::MemoryReport;
use crate::gpu::solver::Fragments;
use crate::progress::Silent;
use crate::scene::{Precision, Scene, Scheme};
use crate::settings::BackendKind;
use serde::Serialize;
use std::collections::BTreeMap;

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
    pub scheme: Scheme,
    /// Table precision.
    pub precision: Precision,
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
    /// The passes the scene's plan runs (README, "Passes a scene needs").
    pub plan: Vec<String>,
    /// What the scene analysis decided and why.
    pub decisions: Vec<String>,
    /// The plan against every pass on (absent with `--all-passes`).
    pub savings: Option<Savings>,
}

/// The same scene profiled with every pass on (at the plan's table precision): what the plan saves.
#[derive(Debug, Clone, Serialize)]
pub struct Savings {
    /// Median frame with every pass on (at the plan's table precision), ms.
    pub all_passes_median_ms: f64,
    /// Median frame of the plan, ms.
    pub plan_median_ms: f64,
    /// Their difference, ms per frame (positive: the plan is faster).
    pub saved_ms: f64,
    /// GPU memory with every pass on, bytes.
    pub all_passes_bytes: u64,
    /// GPU memory of the plan, bytes.
    pub plan_bytes: u64,
}

struct Timed {
    per_pass: BTreeMap<String, Vec<f64>>,
    totals: Vec<f64>,
    memory: MemoryReport,
    fragments: Fragments,
}

/// Warms up and times `frames` iterations of the engine's scheme, one submission each.
fn time_frames(engine: &mut Engine, frames: usize, warmup: usize, label: &str) -> Result<Timed> {
    engine.initialize()?;
    engine.iterate(warmup)?;
    engine.take_timings();
    let mut per_pass: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    let mut totals = Vec::with_capacity(frames);
    for f in 0..frames {
        engine.iterate(1)?;
        let mut frame: BTreeMap<String, f64> = BTreeMap::new();
        for (name, ms) in engine.take_timings() {
            *frame.entry(name).or_default() += ms;
        }
        totals.push(frame.values().sum());
        for (name, ms) in frame {
            per_pass.entry(name).or_default().push(ms);
        }
        eprint!("\rprofile{label}: frame {}/{frames}", f + 1);
    }
    if frames > 0 {
        eprintln!();
    }
    Ok(Timed {
        per_pass,
        totals,
        memory: engine.memory(),
        fragments: engine.fragments().unwrap_or_default(),
    })
}

/// Prepares the scene with `options` (GPU backend), warms up, then times `frames` frames.
/// Unless `options.all_passes` (then only everything-on is timed), the same frames are also
/// timed with every pass on at the plan's precision, and the report says what the plan saved.
pub fn profile(
    scene: &Scene,
    options: &Options,
    frames: usize,
    warmup: usize,
) -> Result<ProfileReport> {
    let options = Options {
        backend: BackendKind::Gpu,
        context: Some(crate::engine::context_for(options)?),
        ..options.clone()
    };
    let mut engine = Engine::new(scene, &options, &Silent)?;
    let t = time_frames(&mut engine, frames, warmup, "")?;
    let prep: &Prepared = engine.prepared();
    let median = |v: &[f64]| PassStats::of(v).median_ms;
    let savings = if options.all_passes {
        None
    } else {
        // Every pass on at the plan's precision: the figure is what leaving passes out saves
        // (float16 against float32 is a device property: lavapipe converts on the CPU).
        let mut all = Engine::from_prepared(prep.with_every_pass(), &options, &Silent)?;
        let a = time_frames(&mut all, frames, warmup, " (all passes)")?;
        Some(Savings {
            all_passes_median_ms: median(&a.totals),
            plan_median_ms: median(&t.totals),
            saved_ms: median(&a.totals) - median(&t.totals),
            all_passes_bytes: a.memory.total(),
            plan_bytes: t.memory.total(),
        })
    };
    let st = &prep.settings;
    let sys = &prep.system;
    // Propagations per frame: the asymmetric scheme's antiradiance steps only where planned.
    let props = match st.scheme {
        Scheme::Asymmetric if prep.plan.features.antiradiance => 1 + st.antiradiance_steps as u64,
        _ => 1,
    };
    let fr = &t.fragments;
    let fragments = BTreeMap::from([
        ("global".to_string(), fr.global * props),
        ("push".to_string(), fr.push * props),
        ("local".to_string(), fr.local * props),
        ("pull".to_string(), fr.pull * props),
    ]);
    let ctx = options.context.as_ref().expect("set above");
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
        scheme: st.scheme,
        precision: prep.plan.precision,
        frames,
        linking_ms: sys.links.linking_ms,
        meshing_ms: sys.meshing_ms,
        passes: t
            .per_pass
            .iter()
            .map(|(k, v)| (k.clone(), PassStats::of(v)))
            .collect(),
        frame: PassStats::of(&t.totals),
        memory_bytes: t.memory.by_name(),
        fragments,
        fallbacks: engine.fallbacks().to_vec(),
        plan: prep.plan.passes(),
        decisions: prep.plan.decisions.clone(),
        savings,
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
        s += &format!("plan: {}\n", self.plan.join(", "));
        for d in &self.decisions {
            s += &format!("  - {d}\n");
        }
        if let Some(v) = &self.savings {
            s += &format!(
                "all passes: {:.2} ms per frame, {:.1} MB; plan: {:.2} ms, {:.1} MB; saved {:.2} ms per frame ({:.0}%), {:.1} MB\n",
                v.all_passes_median_ms,
                v.all_passes_bytes as f64 / (1 << 20) as f64,
                v.plan_median_ms,
                v.plan_bytes as f64 / (1 << 20) as f64,
                v.saved_ms,
                100.0 * v.saved_ms / v.all_passes_median_ms.max(1e-9),
                (v.all_passes_bytes as f64 - v.plan_bytes as f64) / (1 << 20) as f64
            );
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
