//! The iteration loop shared by both backends: the convergence monitor decides when to stop,
//! and every departure from the requested run is a fallback with its reason: the symmetric
//! scheme growing (restart it damped; growing damped, restart with the asymmetric scheme),
//! float16 overflowing (restart in float32), every scheme growing (keep the iterate before
//! growth). Nothing non-finite is handed on.

use super::tail::{Checked, Tail};
use crate::backend::{Backend, Prepared};
use crate::error::{Error, Result};
use crate::progress::Progress;
use crate::scene::Scheme;
use crate::solver::convergence::{Monitor, Verdict};

/// What the loop did.
#[derive(Debug, Clone, Default)]
pub(crate) struct Outcome {
    /// Relative residual per iteration of the run that produced the result.
    pub residuals: Vec<f64>,
    /// Exitant flux per iteration of that run.
    pub energies: Vec<f64>,
    /// Departures from the requested configuration.
    pub fallbacks: Vec<String>,
    /// Things the user should know (the iteration cap was reached).
    pub warnings: Vec<String>,
    /// Scheme of the result.
    pub scheme: Option<Scheme>,
    /// Estimated distance to the fixed point, relative (see [`Monitor::error_estimate`]).
    pub estimated_error: Option<f64>,
    /// Tail extrapolations applied and kept ([`crate::solver::extrapolate`]).
    pub extrapolations: usize,
}

/// Iterations per batch: one submission and one fence wait on the GPU per batch, the
/// convergence figures of each iteration reduced on the device (16 bytes read back each). Four
/// is the paper's iterations per frame; the monitor judges after every batch, so a tolerance
/// run may do up to three iterations more than it needed.
pub const BATCH: usize = 4;

/// Most iterations one batch holds ([`crate::gpu::reduce::MAX_BATCH`]).
pub const BATCH_LIMIT: usize = crate::gpu::reduce::MAX_BATCH;

/// Growth per iteration of the last absolute changes (the geometric mean over up to three
/// steps): the modulus of the dominant eigenvalue of an iteration that diverges.
fn growth(changes: &[f64]) -> Option<f64> {
    let r: Vec<f64> = changes
        .iter()
        .copied()
        .filter(|r| r.is_finite() && *r > 0.0)
        .collect();
    let k = r.len();
    let steps = (k.max(1) - 1).min(3);
    (steps > 0).then(|| (r[k - 1] / r[k - 1 - steps]).powf(1.0 / steps as f64))
}

/// Weight ω of the damped symmetric iteration after the plain one grew by `g` per iteration.
/// Antiradiance that overshoots does so in alternating sign (the change's ratio between
/// iterations on a stack of eight boards −2.96 symmetric, −1.86 asymmetric; on the breakfast
/// room −1.30 symmetric, −0.92 asymmetric), an eigenvalue λ ≈ −g, which damping maps to
/// 1 − ω(1 + g): ω = 1.5/(1 + g) puts it at −0.5 (within 0.1..=0.75; a stall, g ≈ 1, gets 0.75).
/// On the breakfast room 16 damped iterations at ω = 0.6 left a change of 9.2e-3 where 16
/// asymmetric ones, each four times the work, left 5.3e-2 (docs/measurements.md).
pub(crate) fn damping_for(g: f64) -> f64 {
    (1.5 / (1.0 + g.max(1.0))).clamp(0.1, 0.75)
}

/// Iterates `solver` per `prep.settings`, in batches of [`BATCH`] (one when a frame is wanted
/// after every iteration). `initialized()` is called once, after the first initial state;
/// `frame(k, solver, prep)` is called for the frames wanted (it may shift `prep`'s camera for
/// the frame's passes, [`super::draw_frame`]): after every iteration when
/// `every_iteration`, else only for the result; `k` counts the iterations of the current run
/// (a restart begins again at 0 and says so in the fallbacks).
pub(crate) fn drive(
    prep: &mut Prepared,
    solver: &mut dyn Backend,
    every_iteration: bool,
    progress: &dyn Progress,
    initialized: &mut dyn FnMut(),
    frame: &mut dyn FnMut(usize, &mut dyn Backend, &mut Prepared) -> Result<()>,
) -> Result<Outcome> {
    let settings = &prep.settings.clone();
    let mut first = true;
    let mut out = Outcome::default();
    let mut scheme = settings.scheme;
    let mut monitor = Monitor::new(settings);
    let batch = if every_iteration { 1 } else { BATCH };
    // Iterations to run without judging, after both schemes grew: the best iterate is re-run.
    let mut replay: Option<usize> = None;
    // The damping in use, and whether damping was tried (it is tried once).
    let mut damping: Option<f64> = None;
    let mut damped_once = false;
    let mut tail: Tail;
    progress.begin("iterations", monitor.limit as u64);
    'run: loop {
        // Every run states its damping (a widened solver is a new one).
        solver.damp(damping.unwrap_or(1.0));
        solver.initialize(prep)?;
        if std::mem::take(&mut first) {
            initialized();
        }
        monitor.restart();
        monitor.rounding = solver.precision().unit_roundoff();
        // Frames after every iteration show the plain iteration; a replay re-runs it exactly.
        tail = Tail::new(
            settings.extrapolate && solver.resumable() && !every_iteration && replay.is_none(),
        );
        let end = replay.unwrap_or(monitor.limit);
        if end == 0 {
            frame(0, solver, prep)?;
            break;
        }
        let mut k = 0;
        while k < end {
            let n = (end - k).min(batch);
            let figures = solver.iterate_batch(prep, scheme, settings.antiradiance_steps, n)?;
            // The first verdict that ends the run decides; the batch's later iterations are
            // recorded too (their state is the one drawn).
            let mut decided: Option<Verdict> = None;
            for f in figures {
                k += 1;
                let limit = solver.overflow_limit();
                if f.peak > limit {
                    if let Some(wider) = solver.widen(prep)? {
                        out.fallbacks.push(format!(
                            "float16 tables overflow at iteration {k} (largest |I_ex| {:.3e}, limit {limit:.3e} at this scale); {wider}; restarted",
                            f.peak
                        ));
                        continue 'run;
                    }
                }
                let verdict = monitor.record(f.change, f.flux);
                progress.advance(1);
                if replay.is_none() && decided.is_none() && verdict != Verdict::Continue {
                    decided = Some(verdict);
                }
            }
            if let Checked::Undone { at, why } = tail.check(solver, prep, &mut monitor)? {
                out.fallbacks.push(why);
                k = at;
                continue;
            }
            match decided {
                None if replay.is_some() || k < end => {
                    if every_iteration && replay.is_none() {
                        frame(k, solver, prep)?;
                    }
                    tail.step(solver, prep, &mut monitor, k, end)?;
                }
                None | Some(Verdict::Done) | Some(Verdict::Continue) => {
                    frame(k, solver, prep)?;
                    break 'run;
                }
                Some(Verdict::Cap(why)) => {
                    out.warnings.push(why);
                    frame(k, solver, prep)?;
                    break 'run;
                }
                Some(Verdict::Diverging(why)) if replay.is_none() && !damped_once => {
                    // Damping keeps the fixed point and contracts an alternating overshoot:
                    // first remedy (measured cheaper than the asymmetric scheme, see
                    // `damping_for`), from whichever scheme grew.
                    let plain = scheme == Scheme::Symmetric;
                    let which = if plain { "symmetric" } else { "asymmetric" };
                    // The growth of the scheme that grew (a stall measures about 1); with too
                    // few changes to tell, 3 (ω = 0.375).
                    let measured = growth(&monitor.changes);
                    let g = measured.unwrap_or(3.0);
                    let w = damping_for(g);
                    damped_once = true;
                    if solver.damp(w) {
                        let grew = match measured {
                            Some(g) => format!(
                                "the {which} iteration grew about {g:.2}× per iteration; damped, an eigenvalue of −{g:.2} becomes {:+.2}",
                                1.0 - w * (1.0 + g)
                            ),
                            None => "its growth was not measured".to_string(),
                        };
                        out.fallbacks.push(format!(
                            "the {which} scheme does not converge here ({why}); restarted with the symmetric scheme damped: each iterate {w:.2} of the new and {:.2} of the last ({grew})",
                            1.0 - w
                        ));
                        damping = Some(w);
                        scheme = Scheme::Symmetric;
                        continue 'run;
                    }
                    if plain {
                        out.fallbacks.push(format!(
                            "the symmetric scheme does not converge here ({why}); restarted with the asymmetric scheme"
                        ));
                        scheme = Scheme::Asymmetric;
                        continue 'run;
                    }
                    keep_best(&mut out, &monitor, &why, &mut replay);
                    continue 'run;
                }
                Some(Verdict::Diverging(why))
                    if replay.is_none() && scheme == Scheme::Symmetric =>
                {
                    // The damped scheme grew too: the asymmetric one, undamped.
                    out.fallbacks.push(format!(
                        "the damped symmetric scheme does not converge either ({why}); restarted with the asymmetric scheme"
                    ));
                    damping = None;
                    scheme = Scheme::Asymmetric;
                    continue 'run;
                }
                Some(Verdict::Diverging(why)) => {
                    keep_best(&mut out, &monitor, &why, &mut replay);
                    continue 'run;
                }
            }
        }
        // A replay ends at the iteration it re-ran to.
        frame(k, solver, prep)?;
        break;
    }
    out.extrapolations = tail.applied;
    progress.end();
    out.residuals = monitor.residuals.clone();
    out.energies = monitor.energies.clone();
    out.estimated_error = monitor.error_estimate();
    out.scheme = Some(scheme);
    if out.energies.iter().any(|e| !e.is_finite()) {
        return Err(Error::Numerical(
            "the iteration produced non-finite values and no fallback recovered".into(),
        ));
    }
    Ok(out)
}

/// Every scheme grew: keeps the iterate with the smallest residual before growth took over (the
/// run is replayed to it).
fn keep_best(out: &mut Outcome, monitor: &Monitor, why: &str, replay: &mut Option<usize>) {
    let (best, r) = monitor
        .residuals
        .iter()
        .enumerate()
        .filter(|(_, r)| r.is_finite())
        .min_by(|a, b| a.1.total_cmp(b.1))
        .map_or((0, f64::NAN), |(i, r)| (i + 1, *r));
    out.fallbacks.push(format!(
        "the iteration does not converge ({why}): the discrete system has an eigenvalue of at least 1 on this scene; kept iteration {best} (residual {r:.3e}), the closest to convergence"
    ));
    *replay = Some(best);
}
