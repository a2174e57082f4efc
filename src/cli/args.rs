//! The command line: clap definitions and their translation into library options. Flags become
//! [`Options`]; nothing is written into the scene.

use antiradiance::engine::{Options, SolverOverrides};
use antiradiance::{Precision, Scheme};
use clap::{Args, Parser, Subcommand};

/// A finite float (clap value parser): `nan` and `inf` are refused naming the flag.
pub fn finite(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(v) => Err(format!("must be a finite number, got {v}")),
        Err(e) => Err(e.to_string()),
    }
}

/// A positive finite float (element sizes, tolerances, error targets).
pub fn positive(s: &str) -> Result<f64, String> {
    match finite(s)? {
        v if v > 0.0 => Ok(v),
        v => Err(format!("must be positive, got {v}")),
    }
}

/// A window size `WxH`, each side 1..=16384.
pub fn window_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X', '×'])
        .ok_or_else(|| format!("expected WxH, got `{s}`"))?;
    let side = |v: &str| match v.trim().parse::<u32>() {
        Ok(n) if (1..=16384).contains(&n) => Ok(n),
        _ => Err(format!("each side must be 1..=16384, got `{v}`")),
    };
    Ok((side(w)?, side(h)?))
}

/// `antiradiance`: global illumination with implicit visibility and antiradiance.
#[derive(Parser)]
#[command(
    name = "antiradiance",
    version,
    about = "Global illumination with implicit visibility and antiradiance"
)]
pub struct Cli {
    /// The command.
    #[command(subcommand)]
    pub command: Command,
}

/// The commands.
#[derive(Subcommand)]
pub enum Command {
    /// Scene statistics: triangles, elements, links, bins, memory, linking time.
    Info(super::info::InfoArgs),
    /// Render the scene from its camera to PNG and/or EXR (default: out.png).
    Render(super::render::RenderArgs),
    /// Render the scene's animation headless: DIR/frame-0000.png … (and .exr with --exr) and
    /// DIR/frames.csv (frame, time, update_ms, solve_ms, draw_ms, total_ms, iterations,
    /// residual); the first frame is solved from scratch, every later one continues from the
    /// previous with `solver.iterations_per_frame` iterations.
    Animate(super::animate::AnimateArgs),
    /// Path-traced ground truth (unbiased, CPU, all cores) to EXR, with its direct part and
    /// per-pixel standard error beside it (REF.direct.exr, REF.stderr.exr).
    Reference(super::reference::ReferenceArgs),
    /// Error against run time: antiradiance over a sweep of settings, the baselines
    /// (hierarchical radiosity, progressive refinement, instant radiosity) and the path tracer at increasing spp,
    /// measured against a reference; writes study.csv, error-vs-time.png and convergence.png
    /// into --out.
    Study(super::study::StudyArgs),
    /// Error metrics of one EXR against a reference EXR (e.g. a Mitsuba 3 render).
    Compare(super::compare::CompareArgs),
    /// Open a window on the scene (GPU backend): solve, then draw from a camera you move.
    #[command(after_help = VIEW_BINDINGS)]
    View(super::view::command::ViewArgs),
    /// Time the GPU passes (global, push, local, pull) per frame, like the paper's Table 2.
    Profile(super::profile::ProfileArgs),
}

/// `view`'s key and mouse bindings, shown after its options in `--help`.
const VIEW_BINDINGS: &str = "\
Mouse: left drag turns (orbit: the eye around the target; fly: the view about the eye);
       wheel zooms (orbit) or moves forward (fly).
Keys:  W/S forward/back, A/D left/right, Q/E down/up (eye and target together, 2% of the
       scene per press); F switches orbit/fly; R resets to the scene's camera; Esc quits.
       Space plays/pauses the animation (keyframed scenes start playing), Left/Right scrub by
       5% of its duration, Home goes to its start; Tab selects the next analytic light,
       J/L, I/K, U/O move it along -x/+x, -z/+z, -y/+y by 2% of the scene (a directional
       light turns by 5°); - and = (keypad - and +) lower and raise the exposure by half a
       stop. After a change every frame runs the scene's iterations_per_frame warm-started
       iterations until its iterations are done (always while playing).
The title shows the frame rate, the frame's GPU pass times (ms, summed over its iterations),
the exposure, the animation time, the selected light and the last update's time.";

/// Solver settings that replace the scene's.
#[derive(Args)]
pub struct SolverArgs {
    /// Override `solver.bins`.
    #[arg(long)]
    pub bins: Option<usize>,
    /// Override `solver.iterations` (0: direct light and emission only).
    #[arg(long)]
    pub iterations: Option<usize>,
    /// Override `solver.scheme`.
    #[arg(long, value_enum)]
    pub scheme: Option<Scheme>,
    /// Override `solver.precision`.
    #[arg(long, value_enum)]
    pub precision: Option<Precision>,
    /// Override `solver.filter_cutoff` (cone-filter truncation, fraction of a row's peak).
    #[arg(long, value_parser = positive)]
    pub filter_cutoff: Option<f64>,
    /// Override `solver.emitter_samples` (shadow-mapped points on the emitting triangles; 0
    /// carries area emitters' light through the bins instead).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=antiradiance::scene::MAX_EMITTER_SAMPLES as i64))]
    pub emitter_samples: Option<u32>,
}

impl SolverArgs {
    /// The overrides these flags give.
    pub fn overrides(&self) -> SolverOverrides {
        SolverOverrides {
            bins: self.bins,
            iterations: self.iterations,
            scheme: self.scheme,
            precision: self.precision,
            filter_cutoff: self.filter_cutoff,
            emitter_samples: self.emitter_samples.map(|n| n as usize),
            ..Default::default()
        }
    }
}

/// Settings of the baseline methods.
#[derive(Args)]
pub struct BaselineArgs {
    /// hierarchical-radiosity: visibility rays per link.
    #[arg(long, default_value_t = antiradiance::methods::DEFAULT_RAYS_PER_LINK)]
    pub rays_per_link: u32,
    /// progressive-radiosity: side of a hemicube face of the item buffer (texels);
    /// image-based-radiosity: side of a VPL's hemicube face.
    #[arg(long, default_value_t = antiradiance::methods::DEFAULT_HEMICUBE)]
    pub hemicube: u32,
    /// progressive-radiosity: deepest adaptive subdivision of a receiver (0: its centroid; L:
    /// up to 4^L sub-triangles where one shot's light varies across it).
    #[arg(long, default_value_t = antiradiance::methods::DEFAULT_SUBDIVISION)]
    pub subdivision: u32,
    /// progressive-radiosity: subdivide a receiver further when its samples spread by more than
    /// this fraction of their largest.
    #[arg(long, default_value_t = antiradiance::methods::DEFAULT_GRADIENT, value_parser = finite)]
    pub gradient: f64,
    /// progressive-radiosity: shots per iteration (default: a quarter of the elements).
    #[arg(long)]
    pub shots_per_iteration: Option<u32>,
    /// instant-radiosity: light paths traced from the lights (each leaves a VPL at every
    /// surface it reaches until Russian roulette ends it).
    #[arg(long, default_value_t = antiradiance::methods::DEFAULT_VPLS)]
    pub vpls: u32,
    /// instant-radiosity: a VPL's light is bounded as from a disc of this many times the
    /// surface area per VPL (0: the bare 1/r²).
    #[arg(long, default_value_t = antiradiance::methods::DEFAULT_VPL_CLAMP, value_parser = finite)]
    pub vpl_clamp: f64,
    /// image-based-radiosity: cells of the layered depth cube along the scene's longest side.
    #[arg(long, default_value_t = antiradiance::methods::DEFAULT_CUBE)]
    pub cube: u32,
    /// image-based-radiosity: rays per cube layer that gather back the light the VPLs' clamp
    /// takes from their near field (0: the clamped cube).
    #[arg(long, default_value_t = antiradiance::methods::DEFAULT_NEAR_RAYS)]
    pub near_rays: u32,
}

impl BaselineArgs {
    /// The settings these flags give.
    pub fn settings(&self) -> antiradiance::methods::MethodSettings {
        antiradiance::methods::MethodSettings {
            rays_per_link: self.rays_per_link,
            hemicube: self.hemicube,
            subdivision: self.subdivision,
            gradient: self.gradient,
            shots_per_iteration: self.shots_per_iteration,
            vpls: self.vpls,
            vpl_clamp: self.vpl_clamp,
            cube: self.cube,
            near_rays: self.near_rays,
        }
    }
}

/// Image size overrides.
#[derive(Args)]
pub struct SizeArgs {
    /// Override `camera.width`.
    #[arg(long)]
    pub width: Option<u32>,
    /// Override `camera.height`.
    #[arg(long)]
    pub height: Option<u32>,
}

/// What runs: the scene analysis' plan unless forced, and settings chosen for an error target.
#[derive(Args)]
pub struct PlanArgs {
    /// Run every pass and create every table (float32) whether the scene needs it or not.
    #[arg(long)]
    pub all_passes: bool,
    /// Choose bins, element size and iterations for this relative RMSE from measured
    /// error-vs-time data (replaces the scene's and --bins/--iterations).
    #[arg(long, allow_negative_numbers = true, value_parser = positive)]
    pub target_error: Option<f64>,
    /// Link budget: a scene whose links would pass it is linked coarser (a larger τ, then a
    /// larger element size) until it fits, as the decisions state [default: 4000000].
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub max_links: Option<u64>,
    /// Memory budget for the solver's tables, in bytes or with a K, M or G suffix (powers of
    /// 1024), e.g. 1.5G: a scene whose tables would pass it gets a larger element size until
    /// they fit [default: the device's memory on the GPU backend].
    #[arg(long, value_parser = bytes)]
    pub memory_budget: Option<u64>,
}

/// A byte count: a number with an optional K, M or G suffix (powers of 1024).
fn bytes(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let (num, scale) = match t.char_indices().last() {
        Some((i, c)) if c.eq_ignore_ascii_case(&'k') => (&t[..i], 1u64 << 10),
        Some((i, c)) if c.eq_ignore_ascii_case(&'m') => (&t[..i], 1 << 20),
        Some((i, c)) if c.eq_ignore_ascii_case(&'g') => (&t[..i], 1 << 30),
        _ => (t, 1),
    };
    match num.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 1.0 / scale as f64 && v * (scale as f64) < 1.8e19 => {
            Ok((v * scale as f64) as u64)
        }
        _ => Err(format!(
            "expected a positive byte count such as 800M or 1.5G, got '{s}'"
        )),
    }
}

impl PlanArgs {
    /// Options with these flags, everything else default.
    pub fn options(&self) -> Options {
        Options {
            all_passes: self.all_passes,
            target_error: self.target_error,
            max_links: self.max_links,
            memory_budget: self.memory_budget,
            ..Options::default()
        }
    }
}
