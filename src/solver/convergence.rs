//! Watching the iterations of either backend: residual and total energy every iteration, when to
//! stop (a fixed count, or a residual target with an iteration cap), and when the iteration grows
//! instead of converging. The paper warns that the symmetric scheme is not proven to converge
//! (§2.2); [`Monitor`] is what notices, so that the caller can fall back to the asymmetric scheme.

use super::Table;
use crate::scene::SolverSettings;
use crate::system::System;

/// How one iteration changed I_ex on the leaves.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Change {
    /// `‖after − before‖ / ‖after‖` (the residual printed and stored per iteration).
    pub relative: f64,
    /// `‖after − before‖`.
    pub absolute: f64,
}

/// What one iteration did, measured where the tables live (the CPU's tables, or a reduction on
/// the GPU): its change, the exitant flux after it and the largest |I_ex| (infinite when a value
/// is not finite).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Figures {
    /// How I_ex changed on the leaves.
    pub change: Change,
    /// Flux leaving the leaves' front bins ([`exitant_flux`]).
    pub flux: f64,
    /// Largest |I_ex| on the leaves (the rows stored in the table format; clusters are
    /// float32 everywhere).
    pub peak: f64,
}

impl Figures {
    /// The figures of an iteration from `before` to `after` (the CPU's definition).
    pub fn between(sys: &System, before: &Table, after: &Table) -> Self {
        let peak = sys
            .leaves
            .iter()
            .flat_map(|l| after.row(l.node as usize))
            .fold(0.0, |m: f64, v| {
                if v.is_finite() {
                    m.max(v.abs().max_element())
                } else {
                    f64::INFINITY
                }
            });
        Self {
            change: change(sys, before, after),
            flux: exitant_flux(sys, after),
            peak,
        }
    }
}

/// The change between two I_ex tables over the leaves' rows.
pub fn change(sys: &System, before: &Table, after: &Table) -> Change {
    let (mut diff, mut norm) = (0.0, 0.0);
    for l in &sys.leaves {
        let r = l.node as usize;
        for (a, b) in after.row(r).iter().zip(before.row(r)) {
            diff += (*a - *b).length_squared();
            norm += a.length_squared();
        }
    }
    let absolute = diff.sqrt();
    Change {
        relative: if norm > 0.0 {
            absolute / norm.sqrt()
        } else {
            absolute
        },
        absolute,
    }
}

/// Flux (W, mean of RGB) leaving all leaves through their front bins.
pub fn exitant_flux(sys: &System, i_ex: &Table) -> f64 {
    let w = sys.bins.omega;
    sys.leaves
        .iter()
        .map(|l| {
            let row = i_ex.row(l.node as usize);
            sys.bins
                .centers
                .iter()
                .zip(row)
                .filter(|(c, _)| c.dot(l.normal) > 0.0)
                .map(|(_, v)| v.element_sum() / 3.0)
                .sum::<f64>()
                * w
        })
        .sum()
}

/// Largest |value| of a table, or infinity when any value is not finite.
pub fn max_abs(t: &Table) -> f64 {
    t.data.iter().fold(0.0, |m: f64, v| {
        if v.is_finite() {
            m.max(v.abs().max_element())
        } else {
            f64::INFINITY
        }
    })
}

/// What the monitor says after an iteration.
#[derive(Debug, Clone, PartialEq)]
pub enum Verdict {
    /// Keep iterating.
    Continue,
    /// The fixed count is done, or the residual target was reached.
    Done,
    /// Stopped above the residual target (the iteration cap, or changes at the tables'
    /// rounding); the sentence says which.
    Cap(String),
    /// The iteration grows or stalls instead of converging; the sentence says how.
    Diverging(String),
}

/// Stopping and divergence rules over the per-iteration residuals and energies.
#[derive(Debug, Clone)]
pub struct Monitor {
    /// Residual target (`solver.tolerance`); `None` runs exactly `iterations`.
    pub tolerance: Option<f64>,
    /// Fixed count, or the cap when a tolerance is given.
    pub limit: usize,
    /// Relative residual per iteration.
    pub residuals: Vec<f64>,
    /// Absolute change per iteration.
    pub changes: Vec<f64>,
    /// Exitant flux after every iteration.
    pub energies: Vec<f64>,
    /// Index of the first change after the last tail extrapolation (0 without one): earlier
    /// changes belong to another trajectory and are not compared with later ones.
    epoch: usize,
    /// The dominant contraction ratio measured before the last extrapolation: what the error
    /// left in that mode still contracts at, whatever the few changes since suggest.
    dominant: Option<f64>,
    /// Unit roundoff of the tables being iterated ([`crate::Precision::unit_roundoff`]): the
    /// relative change below which a change is rounding, not progress. f64 by default.
    pub rounding: f64,
}

/// Iterations before growth is judged (light reaching new elements legitimately grows the change).
const WARMUP: usize = 4;
/// Consecutive growing changes that mean divergence.
/// Long enough that the transient of deep occlusion (antiradiance reaching one more layer per
/// iteration, ten layers grow for several iterations before they settle) is not mistaken for it.
const GROWING_RUN: usize = 8;
/// Window of the stall test.
const STALL: usize = 16;
/// Relative residual below which growth is rounding noise, not divergence.
const NOISE: f64 = 0.02;

impl Monitor {
    /// A monitor for the scene's settings.
    pub fn new(s: &SolverSettings) -> Self {
        Self {
            tolerance: s.tolerance,
            limit: if s.tolerance.is_some() {
                s.max_iterations
            } else {
                s.iterations
            },
            residuals: Vec::new(),
            changes: Vec::new(),
            energies: Vec::new(),
            epoch: 0,
            dominant: None,
            rounding: f64::EPSILON / 2.0,
        }
    }

    /// Forgets the history (after a restart with another scheme or precision).
    pub fn restart(&mut self) {
        self.truncate(0);
    }

    /// Forgets the iterations after the first `n` (an extrapolation undone).
    pub fn truncate(&mut self, n: usize) {
        self.residuals.truncate(n);
        self.changes.truncate(n);
        self.energies.truncate(n);
        if self.epoch > n {
            self.epoch = 0;
            self.dominant = None;
        }
    }

    /// Notes that the state was just extrapolated along a mode contracting at `q`
    /// ([`crate::solver::extrapolate`]): the next changes start a new trajectory. Returns the
    /// trajectory it replaces, for [`Monitor::undo_extrapolation`].
    pub fn extrapolated(&mut self, q: f64) -> (usize, Option<f64>) {
        let before = (self.epoch, self.dominant);
        self.epoch = self.changes.len();
        self.dominant = Some(q);
        before
    }

    /// Undoes an extrapolation made after the first `n` iterations: forgets the iterations
    /// since and restores the trajectory [`Monitor::extrapolated`] returned.
    pub fn undo_extrapolation(&mut self, n: usize, before: (usize, Option<f64>)) {
        self.truncate(n);
        (self.epoch, self.dominant) = before;
    }

    /// Where the changes of the current trajectory begin (after the last extrapolation).
    pub fn epoch(&self) -> usize {
        self.epoch
    }

    /// The contraction ratio over the last (up to) eight changes of the current trajectory.
    pub fn contraction(&self) -> Option<f64> {
        let n = self.changes.len();
        let w = n.checked_sub(1 + self.epoch)?.min(8);
        if w == 0 || self.changes[n - 1 - w] <= 0.0 {
            return None;
        }
        Some(
            (self.changes[n - 1] / self.changes[n - 1 - w])
                .powf(1.0 / w as f64)
                .min(0.999_999),
        )
    }

    /// Estimated distance to the fixed point relative to the solution: the last residual times
    /// q/(1−q), with q the contraction ratio of the changes over the last eight iterations (a
    /// stiff scene with q near 1 is far from converged even when each step changes little).
    ///
    /// This is the iteration error only: how far the iterate is from the *discrete* system's own
    /// fixed point, not from the true answer. The discretization (bins, elements, cluster links,
    /// τ) puts that fixed point off the true radiance by its own error, which no number of
    /// iterations removes and this estimate does not see: a closed box at ρ = 0.999 whose
    /// transport lost 2.7% per bounce once "converged" to an estimated error under 1e-4 at a
    /// mean of 36 instead of 1000.
    ///
    /// A residual below the tables' rounding is counted as that rounding: a change of zero in
    /// float32 at q = 0.9999 says that the increments fell below the format's resolution, not
    /// that the iterate is exact (the rounding, amplified by 1/(1 − q), is then the error).
    pub fn error_estimate(&self) -> Option<f64> {
        let r = self.residuals.last()?.max(self.rounding);
        // After an extrapolation, what is left in the dominant mode still contracts at its
        // measured ratio, and no mode is slower: a faster-looking window is the other modes dying
        // out, a slower-looking one rounding noise.
        // Once the trajectory since is long enough to measure and its changes are well above
        // the tables' rounding, a slower ratio seen there is real: the larger of the two.
        let since = self.changes.len() - self.epoch.min(self.changes.len());
        let q = match (self.dominant, self.contraction()) {
            (Some(d), Some(c)) if since > 8 && r > 64.0 * self.rounding => Some(d.max(c)),
            (Some(d), _) => Some(d),
            (None, c) => c,
        };
        Some(match q {
            Some(q) => r * q.max(0.0) / (1.0 - q),
            None => r,
        })
    }

    /// Records an iteration and says what to do next.
    pub fn record(&mut self, c: Change, energy: f64) -> Verdict {
        self.residuals.push(c.relative);
        self.changes.push(c.absolute);
        self.energies.push(energy);
        let k = self.residuals.len();
        if let Some(why) = self.diverging() {
            return Verdict::Diverging(why);
        }
        match self.tolerance {
            None if k >= self.limit => Verdict::Done,
            None => Verdict::Continue,
            Some(t) => {
                let e = self.error_estimate().unwrap_or(f64::INFINITY);
                if e <= t {
                    Verdict::Done
                } else if k > WARMUP && self.at_rounding() {
                    Verdict::Cap(format!(
                        "stopped at iteration {k}: the change per iteration ({:.1e}) is at the tables' rounding ({:.1e}), which leaves an estimated error of {e:.2e} above the tolerance {t:.1e}: more iterations cannot reduce it at this precision",
                        c.relative, self.rounding
                    ))
                } else if k >= self.limit {
                    Verdict::Cap(format!(
                        "stopped at the iteration cap of {k} (solver.max_iterations) with an estimated error of {e:.2e} (residual {:.2e}), above the tolerance {t:.1e}",
                        c.relative
                    ))
                } else {
                    Verdict::Continue
                }
            }
        }
    }

    /// Whether the changes are the tables' rounding: no change at all, or a relative change
    /// within 64 unit roundoffs that no longer falls over the last eight iterations (a run
    /// still contracting near the rounding goes on).
    fn at_rounding(&self) -> bool {
        let k = self.changes.len();
        let (r, u) = (self.residuals[k - 1], self.rounding);
        if r == 0.0 {
            return true;
        }
        if r > 64.0 * u || k < self.epoch + 8 {
            return false;
        }
        let best = |a: usize, b: usize| self.changes[a..b].iter().cloned().fold(f64::MAX, f64::min);
        best(k - 4, k) >= best(k - 8, k - 4)
    }

    fn diverging(&self) -> Option<String> {
        let k = self.residuals.len();
        let (r, e) = (self.residuals[k - 1], self.energies[k - 1]);
        if !r.is_finite() || !e.is_finite() {
            return Some(format!("iteration {k} produced non-finite values"));
        }
        if k <= WARMUP || r < NOISE {
            return None;
        }
        let c = &self.changes;
        if k > GROWING_RUN && (k - GROWING_RUN..k).all(|i| c[i] > c[i - 1] * 1.01) {
            return Some(format!(
                "the change per iteration grew from {:.3e} to {:.3e} over iterations {}..{k} (residual {r:.3e})",
                c[k - GROWING_RUN - 1],
                c[k - 1],
                k - GROWING_RUN
            ));
        }
        // A stall: no progress at all over 16 iterations while far from converged (|λ| ≥ 1).
        // A stiff scene (contraction 0.999) still makes some progress every iteration.
        if k >= WARMUP + STALL {
            let best =
                |a: usize, b: usize| self.changes[a..b].iter().cloned().fold(f64::MAX, f64::min);
            if best(k - STALL / 2, k) >= best(k - STALL, k - STALL / 2) {
                return Some(format!(
                    "the residual stalled at {r:.3e} over iterations {}..{k}",
                    k - STALL
                ));
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Precision;

    fn feed(m: &mut Monitor, changes: &[f64]) -> Verdict {
        let mut v = Verdict::Continue;
        for &c in changes {
            v = m.record(
                Change {
                    relative: c / 10.0,
                    absolute: c,
                },
                1.0,
            );
            if v != Verdict::Continue {
                break;
            }
        }
        v
    }

    fn settings(tolerance: Option<f64>) -> SolverSettings {
        SolverSettings {
            tolerance,
            iterations: 6,
            max_iterations: 30,
            ..Default::default()
        }
    }

    #[test]
    fn fixed_count_stops_at_the_count() {
        let mut m = Monitor::new(&settings(None));
        let geometric: Vec<f64> = (0..20).map(|k| 0.5f64.powi(k)).collect();
        assert_eq!(feed(&mut m, &geometric), Verdict::Done);
        assert_eq!(m.residuals.len(), 6);
    }

    #[test]
    fn tolerance_uses_the_contraction_ratio() {
        // q = 0.9: the error is 9× the last residual, so a plain residual test would stop early.
        let mut m = Monitor::new(&settings(Some(1e-3)));
        let slow: Vec<f64> = (0..200).map(|k| 0.9f64.powi(k)).collect();
        let v = feed(&mut m, &slow);
        assert!(
            matches!(v, Verdict::Cap(ref s) if s.contains("iteration cap of 30")),
            "{v:?}"
        );
        let mut m = Monitor {
            limit: 500,
            ..Monitor::new(&settings(Some(1e-3)))
        };
        assert_eq!(feed(&mut m, &slow), Verdict::Done);
        let est = m.error_estimate().unwrap();
        assert!(
            est <= 1e-3 && *m.residuals.last().unwrap() < 1.2e-4,
            "{est}"
        );
    }

    #[test]
    fn growth_and_stalls_are_divergence_but_early_growth_is_not() {
        let mut m = Monitor::new(&settings(Some(1e-9)));
        // Light reaching new elements: the change grows for three iterations, then decays.
        let early = [1.0, 1.5, 2.0, 2.2, 1.0, 0.5, 0.25, 0.1, 0.05];
        assert_eq!(feed(&mut m, &early), Verdict::Continue);
        let mut m = Monitor::new(&settings(Some(1e-9)));
        let growing: Vec<f64> = (0..20).map(|k| 1.2f64.powi(k)).collect();
        assert!(matches!(feed(&mut m, &growing), Verdict::Diverging(s) if s.contains("grew")));
        let mut m = Monitor::new(&settings(Some(1e-9)));
        let stalled: Vec<f64> = (0..30).map(|k| 1.0 + 0.01 * (k % 2) as f64).collect();
        assert!(matches!(feed(&mut m, &stalled), Verdict::Diverging(s) if s.contains("stalled")));
        let mut m = Monitor::new(&settings(None));
        let v = m.record(
            Change {
                relative: f64::NAN,
                absolute: 1.0,
            },
            1.0,
        );
        assert!(matches!(v, Verdict::Diverging(s) if s.contains("non-finite")));
    }

    #[test]
    fn after_an_extrapolation_the_dominant_ratio_sets_the_estimate() {
        let mut m = Monitor::new(&settings(Some(1e-9)));
        feed(
            &mut m,
            &(0..20).map(|k| 0.99f64.powi(k)).collect::<Vec<_>>(),
        );
        m.extrapolated(0.99);
        // One tiny change after the jump: a plain residual test would stop; the estimate keeps
        // the dominant mode's amplification (q/(1 − q) = 99), even when the next changes
        // look faster or (rounding) slower.
        feed(&mut m, &[1e-6, 1e-7, 1e-7]);
        let r = *m.residuals.last().unwrap();
        let e = m.error_estimate().unwrap();
        assert!((e / r - 99.0).abs() < 1e-6, "{e} vs {r}");
        // Undone, the trajectory before it is back (no dominant ratio: 20 plain changes).
        m.undo_extrapolation(20, (0, None));
        assert_eq!((m.epoch(), m.changes.len()), (0, 20));
        let plain = m.error_estimate().unwrap() / m.residuals.last().unwrap();
        assert!((plain - 99.0).abs() < 1e-6, "{plain}");
    }

    #[test]
    fn changes_at_the_tables_rounding_stop_the_run_and_say_so() {
        let mut m = Monitor::new(&settings(Some(1e-8)));
        m.rounding = Precision::F32.unit_roundoff();
        m.limit = 1000;
        // Converging at 0.999, then flat at 2e-7 relative (float32 noise): the estimate stays
        // above the tolerance, and the run stops there instead of at the cap.
        let mut changes: Vec<f64> = (0..10).map(|k| 1e-5 * 0.999f64.powi(k)).collect();
        changes.extend([2e-6; 12]);
        match feed(&mut m, &changes) {
            Verdict::Cap(s) => assert!(s.contains("rounding"), "{s}"),
            v => panic!("{v:?}"),
        }
        assert!(m.residuals.len() < changes.len());
    }
}
