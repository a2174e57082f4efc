//! The iteration loop shared by both backends: the convergence monitor decides when to stop,
//! and every departure from the requested run is a fallback with its reason: the symmetric
//! scheme growing (restart with the asymmetric one), float16 overflowing (restart in float32),
//! both schemes growing (keep the iterate before growth). Nothing non-finite is handed on.

use super::backend::Backend;
use super::prepared::Prepared;
use crate::error::{Error, Result};
use crate::progress::Progress;
use crate::scene::Scheme;
use crate::solver::convergence::{change, exitant_flux, max_abs, Monitor, Verdict};

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
}

/// Iterates `solver` per `prep.settings`. `initialized()` is called once, after the first
/// initial state; `frame(k, solver)` is called for the frames wanted: after every iteration
/// when `every_iteration`, else only for the result; `k` counts the iterations of the current
/// run (a restart begins again at 0 and says so in the fallbacks).
pub(crate) fn drive(
    prep: &Prepared,
    solver: &mut dyn Backend,
    every_iteration: bool,
    progress: &dyn Progress,
    initialized: &mut dyn FnMut(),
    frame: &mut dyn FnMut(usize, &mut dyn Backend) -> Result<()>,
) -> Result<Outcome> {
    let (sys, settings) = (&prep.system, &prep.settings);
    let mut first = true;
    let mut out = Outcome::default();
    let mut scheme = settings.scheme;
    let mut monitor = Monitor::new(settings);
    // Iterations to run without judging, after both schemes grew: the best iterate is re-run.
    let mut replay: Option<usize> = None;
    progress.begin("iterations", monitor.limit as u64);
    'run: loop {
        solver.initialize(prep)?;
        if std::mem::take(&mut first) {
            initialized();
        }
        let mut before = solver.i_ex()?;
        monitor.restart();
        if monitor.limit == 0 || replay == Some(0) {
            frame(0, solver)?;
            break;
        }
        for k in 1.. {
            solver.iterate(prep, scheme, settings.antiradiance_steps)?;
            let after = solver.i_ex()?;
            let peak = max_abs(&after);
            let limit = solver.overflow_limit();
            if peak > limit {
                if let Some(wider) = solver.widen(prep)? {
                    out.fallbacks.push(format!(
                        "float16 tables overflow at iteration {k} (largest |I_ex| {peak:.3e}, limit {limit:.3e} at this scale); {wider}; restarted"
                    ));
                    continue 'run;
                }
            }
            let verdict = monitor.record(change(sys, &before, &after), exitant_flux(sys, &after));
            before = after;
            progress.advance(1);
            if let Some(n) = replay {
                if k == n {
                    frame(k, solver)?;
                    break 'run;
                }
                continue;
            }
            match verdict {
                Verdict::Continue => {
                    if every_iteration {
                        frame(k, solver)?;
                    }
                }
                Verdict::Done => {
                    frame(k, solver)?;
                    break 'run;
                }
                Verdict::Cap(why) => {
                    out.warnings.push(why);
                    frame(k, solver)?;
                    break 'run;
                }
                Verdict::Diverging(why) if scheme == Scheme::Symmetric => {
                    out.fallbacks.push(format!(
                        "the symmetric scheme does not converge here ({why}); restarted with the asymmetric scheme"
                    ));
                    scheme = Scheme::Asymmetric;
                    continue 'run;
                }
                Verdict::Diverging(why) => {
                    // Keep the iterate with the smallest residual before growth took over.
                    let (best, r) = monitor
                        .residuals
                        .iter()
                        .enumerate()
                        .filter(|(_, r)| r.is_finite())
                        .min_by(|a, b| a.1.total_cmp(b.1))
                        .map_or((0, f64::NAN), |(i, r)| (i + 1, *r));
                    out.fallbacks.push(format!(
                        "the asymmetric scheme does not converge either ({why}): the discrete system has an eigenvalue of at least 1 on this scene; kept iteration {best} (residual {r:.3e}), the closest to convergence"
                    ));
                    replay = Some(best);
                    continue 'run;
                }
            }
        }
    }
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
