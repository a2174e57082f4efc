//! `antiradiance profile`: per-pass GPU timings, raster work and memory, like Table 2 of the
//! paper. Iterations run in the solve's batches (one submission and one fence wait per batch,
//! the convergence figures reduced on the device); every pass is a timestamped scope, and the
//! batch's wall time, submission and synchronization included, is measured too. Beside the
//! milliseconds: fragments, blended fragments and primitives per pass (lavapipe rasterizes on
//! the CPU, so these are the hardware-independent figures), the setup split into linking,
//! uploads and pipelines, and the paper's own per-iteration figures for scale.

use crate::engine::planned::{
    DeviceLimits, MemoryReport, PassWork, Work, READBACK_BYTES_PER_ITERATION,
};
use crate::engine::{Engine, Options, Prepared, Setup};
use crate::error::Result;
use crate::progress::Silent;
use crate::scene::{Precision, Scene, Scheme};
use crate::settings::BackendKind;
use crate::trace::{chrome_trace, Batch, Phase};
use serde::Serialize;
use std::collections::BTreeMap;
use std::time::Instant;

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

/// One pass's raster work per iteration, with its cost per link.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct PassFigures {
    /// Fragments shaded per iteration.
    pub fragments: u64,
    /// Fragments blended per iteration.
    pub blended: u64,
    /// Primitives drawn per iteration.
    pub primitives: u64,
    /// Fragments per link.
    pub fragments_per_link: f64,
    /// Median GPU time per link, nanoseconds.
    pub ns_per_link: f64,
}

/// The paper's Table 2 (GeForce 8800 GTX, office scene: 632K links, 128 bins), divided by its
/// 4 iterations per frame: global 63.4, push-pull 14.0, local 7.1 ms per frame.
pub const PAPER_TABLE2_MS_PER_ITERATION: [(&str, f64); 4] = [
    ("global", 63.4 / 4.0),
    ("push_pull", 14.0 / 4.0),
    ("local", 7.1 / 4.0),
    ("iteration", (63.4 + 14.0 + 7.1) / 4.0),
];

/// The profile of one scene.
#[derive(Debug, Clone, Serialize)]
pub struct ProfileReport {
    /// Scene file.
    pub scene: String,
    /// The timed batches, for `--trace` ([`ProfileReport::trace`]); not in the JSON report.
    #[serde(skip)]
    pub timeline: Vec<Batch>,
    /// Driver name (e.g. `llvmpipe`, `NVIDIA`).
    pub device: String,
    /// Device name.
    pub device_name: String,
    /// The limits the resources were sized by on this device (what `info` assumes for
    /// lavapipe and a discrete GPU).
    pub device_limits: DeviceLimits,
    /// Leaf elements.
    pub elements: usize,
    /// Links.
    pub links: usize,
    /// Bins.
    pub bins: usize,
    /// Scheme of an iteration.
    pub scheme: Scheme,
    /// Table precision.
    pub precision: Precision,
    /// Iterations timed (after warm-up).
    pub frames: usize,
    /// Iterations per submission (one fence wait each).
    pub batch: usize,
    /// CPU link construction, ms.
    pub linking_ms: f64,
    /// CPU element subdivision and hierarchy, ms.
    pub meshing_ms: f64,
    /// Setup by part (linking, uploads, pipelines, other, lights).
    pub setup: Setup,
    /// Pass name → GPU time per iteration.
    pub passes: BTreeMap<String, PassStats>,
    /// Sum of the passes per iteration (GPU time).
    pub frame: PassStats,
    /// Wall time per iteration, submission and fence wait included.
    pub iteration_wall: PassStats,
    /// GPU memory by purpose, bytes.
    pub memory_bytes: BTreeMap<String, u64>,
    /// Fragments each pass draws per iteration.
    pub fragments: BTreeMap<String, u64>,
    /// Fragments, blended fragments, primitives per pass and iteration, and cost per link.
    pub work: BTreeMap<String, PassFigures>,
    /// Phong-sum terms per iteration.
    pub glossy_terms: u64,
    /// Bytes read back per iteration (the reduced convergence figures).
    pub readback_bytes_per_iteration: f64,
    /// Fence waits per iteration.
    pub fence_waits_per_iteration: f64,
    /// The paper's per-iteration times (ms), for scale.
    pub paper_ms_per_iteration: BTreeMap<String, f64>,
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
    /// Median iteration with every pass on (at the plan's table precision), ms.
    pub all_passes_median_ms: f64,
    /// Median iteration of the plan, ms.
    pub plan_median_ms: f64,
    /// Their difference, ms per iteration (positive: the plan is faster).
    pub saved_ms: f64,
    /// GPU memory with every pass on, bytes.
    pub all_passes_bytes: u64,
    /// GPU memory of the plan, bytes.
    pub plan_bytes: u64,
}

struct Timed {
    per_pass: BTreeMap<String, Vec<f64>>,
    batches: Vec<Batch>,
    totals: Vec<f64>,
    walls: Vec<f64>,
    memory: MemoryReport,
    work: Work,
}

/// Warms up, then times `frames` iterations of the engine's scheme in batches of `batch`:
/// per-pass GPU time and wall time, both per iteration.
fn time_frames(
    engine: &mut Engine,
    frames: usize,
    warmup: usize,
    batch: usize,
    label: &str,
    clock: Instant,
) -> Result<Timed> {
    engine.initialize()?;
    engine.iterate(warmup)?;
    engine.take_timings();
    let mut per_pass: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    let (mut totals, mut walls) = (Vec::new(), Vec::new());
    let mut batches = Vec::new();
    let mut done = 0;
    while done < frames {
        let n = (frames - done).min(batch);
        let t = Instant::now();
        let start_ms = t.duration_since(clock).as_secs_f64() * 1e3;
        engine.iterate(n)?;
        let wall = t.elapsed().as_secs_f64() * 1e3 / n as f64;
        let mut frame: BTreeMap<String, f64> = BTreeMap::new();
        // One iteration's passes in recording order (the batch repeats them n times).
        let mut order: Vec<(String, f64)> = Vec::new();
        for (name, ms) in engine.take_timings() {
            *frame.entry(name.clone()).or_default() += ms / n as f64;
            match order.iter_mut().find(|(k, _)| *k == name) {
                Some((_, v)) => *v += ms / n as f64,
                None => order.push((name, ms / n as f64)),
            }
        }
        batches.push(Batch {
            start_ms,
            wall_ms: wall,
            iterations: n,
            passes: order,
        });
        for _ in 0..n {
            totals.push(frame.values().sum());
            walls.push(wall);
            for (name, ms) in &frame {
                per_pass.entry(name.clone()).or_default().push(*ms);
            }
        }
        done += n;
        eprint!("\rprofile{label}: iteration {done}/{frames}");
    }
    eprintln!();
    Ok(Timed {
        per_pass,
        batches,
        totals,
        walls,
        memory: engine.memory(),
        work: engine.work().unwrap_or_default(),
    })
}

/// Prepares the scene with `options` (GPU backend), warms up, then times `frames` iterations.
/// Unless `options.all_passes` (then only everything-on is timed), the same iterations are
/// also timed with every pass on at the plan's precision, and the report says what the plan
/// saved.
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
    let batch = crate::engine::BATCH;
    let clock = Instant::now();
    let mut engine = Engine::new(scene, &options, &Silent)?;
    let t = time_frames(&mut engine, frames, warmup, batch, "", clock)?;
    let prep: &Prepared = engine.prepared();
    let median = |v: &[f64]| PassStats::of(v).median_ms;
    let savings = if options.all_passes {
        None
    } else {
        // Every pass on at the plan's precision: the figure is what leaving passes out saves
        // (float16 against float32 is a device property: lavapipe converts on the CPU).
        let mut all = Engine::from_prepared(prep.with_every_pass(), &options, &Silent)?;
        let a = time_frames(&mut all, frames, warmup, batch, " (all passes)", clock)?;
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
    // Propagations per iteration: the asymmetric scheme's antiradiance steps only where planned.
    let props = match st.scheme {
        Scheme::Asymmetric if prep.plan.features.antiradiance => 1 + st.antiradiance_steps as u64,
        _ => 1,
    };
    let work = t.work.times(props);
    let links = sys.links.links.len().max(1) as f64;
    let figures = |name: &str, p: PassWork| {
        let ms = t.per_pass.get(name).map_or(0.0, |v| median(v));
        PassFigures {
            fragments: p.fragments,
            blended: p.blended,
            primitives: p.primitives,
            fragments_per_link: p.fragments as f64 / links,
            ns_per_link: ms * 1e6 / links,
        }
    };
    let ctx = options.context.as_ref().expect("set above");
    Ok(ProfileReport {
        scene: scene
            .path
            .as_ref()
            .map(|p| p.display().to_string())
            .unwrap_or_default(),
        device: ctx.info.driver.clone(),
        device_name: ctx.info.name.clone(),
        device_limits: DeviceLimits::of(ctx),
        elements: sys.leaves.len(),
        links: sys.links.links.len(),
        bins: sys.bins.count,
        scheme: st.scheme,
        precision: prep.plan.precision,
        frames,
        batch,
        linking_ms: sys.links.linking_ms,
        meshing_ms: sys.meshing_ms,
        setup: engine.setup(),
        passes: t
            .per_pass
            .iter()
            .map(|(k, v)| (k.clone(), PassStats::of(v)))
            .collect(),
        frame: PassStats::of(&t.totals),
        iteration_wall: PassStats::of(&t.walls),
        memory_bytes: t.memory.by_name(),
        fragments: work
            .passes()
            .iter()
            .map(|(k, p)| (k.to_string(), p.fragments))
            .collect(),
        work: work
            .passes()
            .iter()
            .map(|(k, p)| (k.to_string(), figures(k, *p)))
            .collect(),
        glossy_terms: work.glossy_terms,
        readback_bytes_per_iteration: READBACK_BYTES_PER_ITERATION as f64,
        fence_waits_per_iteration: 1.0 / batch as f64,
        paper_ms_per_iteration: PAPER_TABLE2_MS_PER_ITERATION
            .iter()
            .map(|(k, v)| (k.to_string(), *v))
            .collect(),
        fallbacks: engine.fallbacks().to_vec(),
        plan: prep.plan.passes(),
        decisions: prep.plan.decisions.clone(),
        savings,
        timeline: t.batches,
    })
}

impl ProfileReport {
    /// The run as a Chrome trace-event document ([`crate::trace`]): the setup phases and each
    /// batch on the host track, every timed pass on the device track.
    pub fn trace(&self) -> serde_json::Value {
        let su = &self.setup;
        let phases: Vec<Phase> = [
            ("linking", su.linking_ms),
            ("uploads", su.uploads_ms),
            ("pipelines", su.pipelines_ms),
            ("method setup", su.method_ms),
            ("other setup", su.other_ms),
            ("lights", su.lights_ms),
        ]
        .into_iter()
        .filter(|(_, ms)| *ms > 0.0)
        .map(|(name, ms)| Phase {
            name: name.into(),
            ms,
        })
        .collect();
        chrome_trace(&self.device_name, &phases, &self.timeline)
    }

    /// The Table 2-style text report.
    pub fn text(&self) -> String {
        let mb = |k: &str| self.memory_bytes.get(k).copied().unwrap_or(0) as f64 / (1 << 20) as f64;
        let su = &self.setup;
        let mut s = format!(
            "{}\ndevice: {} ({})\n{} elements, {} links, {} bins, {} scheme, {} tables, {} iterations in batches of {}\n\
             setup: linking {:.0} ms (meshing {:.1} ms), uploads {:.0} ms, pipelines {:.0} ms, other {:.0} ms, lights {:.0} ms\n\n\
             {:<8} {:>9} {:>9} {:>9} {:>12} {:>12} {:>11} {:>7} {:>8}\n",
            self.scene, self.device_name, self.device, self.elements, self.links, self.bins,
            self.scheme, self.precision, self.frames, self.batch, su.linking_ms, self.meshing_ms,
            su.uploads_ms, su.pipelines_ms, su.other_ms, su.lights_ms,
            "pass", "min ms", "median", "max ms", "fragments", "blended", "primitives", "fr/link", "ns/link"
        );
        for name in ["global", "push", "local", "pull", "reduce"] {
            if let Some(p) = self.passes.get(name) {
                let w = self.work.get(name).copied().unwrap_or_default();
                s += &format!(
                    "{:<8} {:>9.2} {:>9.2} {:>9.2} {:>12} {:>12} {:>11} {:>7.1} {:>8.0}\n",
                    name,
                    p.min_ms,
                    p.median_ms,
                    p.max_ms,
                    w.fragments,
                    w.blended,
                    w.primitives,
                    w.fragments_per_link,
                    w.ns_per_link
                );
            }
        }
        let fr: u64 = self.work.values().map(|w| w.fragments).sum();
        s += &format!(
            "{:<8} {:>9.2} {:>9.2} {:>9.2} {:>12}\n{:<8} {:>9.2} {:>9.2} {:>9.2}   (wall, submission and sync included)\n",
            "GPU", self.frame.min_ms, self.frame.median_ms, self.frame.max_ms, fr,
            "wall", self.iteration_wall.min_ms, self.iteration_wall.median_ms, self.iteration_wall.max_ms,
        );
        let p = &self.paper_ms_per_iteration;
        s += &format!(
            "glossy terms {} per iteration; read back {} bytes and {:.2} fence waits per iteration\n\
             paper (8800 GTX, 632K links): {:.1} ms per iteration (global {:.1}, push-pull {:.1}, local {:.1})\n\n\
             memory: tables {:.1} MB, links {:.1} MB, filter tables {:.1} MB, attributes {:.1} MB, \
             push/pull primitives {:.1} MB, total {:.1} MB\n",
            self.glossy_terms, self.readback_bytes_per_iteration, self.fence_waits_per_iteration,
            p["iteration"], p["global"], p["push_pull"], p["local"],
            mb("tables"), mb("links"), mb("filter_tables"), mb("element_attributes"),
            mb("push_pull_primitives"), mb("total")
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
                "all passes: {:.2} ms per iteration, {:.1} MB; plan: {:.2} ms, {:.1} MB; saved {:.2} ms per iteration ({:.0}%), {:.1} MB\n",
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
