//! When and how the drive loop sums a stiff iteration's tail ([`crate::solver::extrapolate`]):
//! a snapshot of I_ex once the changes contract slowly, the extrapolation [`SPAN`] iterations
//! later where one mode dominates, and its undoing if the next change is not smaller. It works
//! through [`Solve::i_ex`] and [`Solve::warm_start`], so both backends run the same
//! arithmetic (in f64 on the host; the GPU's tables are read back and uploaded, a few times per
//! solve and only in stiff scenes).

use crate::backend::{Backend, Prepared};
use crate::error::Result;
use crate::solver::convergence::Monitor;
use crate::solver::extrapolate::{extrapolate, tail_factor, SPAN, STIFF};
use crate::solver::Table;

/// Iterations before the first snapshot: the light is still reaching new elements.
const SETTLE: usize = 8;

/// The state an extrapolation replaced, kept until the next change says whether it helped.
struct Undo {
    /// Iterations done when it was applied.
    at: usize,
    /// I_ex before it.
    before: Table,
    /// The change of the iteration before it.
    change: f64,
    /// The monitor's trajectory before it ([`Monitor::extrapolated`]).
    trajectory: (usize, Option<f64>),
}

/// The tail extrapolation's state over one run of the drive loop.
pub(crate) struct Tail {
    enabled: bool,
    snapshot: Option<(usize, Table)>,
    undo: Option<Undo>,
    /// Extrapolations applied and kept.
    pub applied: usize,
}

/// What [`Tail::check`] found after the first batch that followed an extrapolation.
pub(crate) enum Checked {
    /// Nothing to undo.
    Kept,
    /// The extrapolation was undone: the run continues from iteration `at`.
    Undone { at: usize, why: String },
}

impl Tail {
    /// A tail for one run; `enabled` is the setting and the backend's ability to resume from
    /// a table.
    pub fn new(enabled: bool) -> Self {
        Self {
            enabled,
            snapshot: None,
            undo: None,
            applied: 0,
        }
    }

    /// After a batch: undoes the last extrapolation if the first change after it is not
    /// smaller than the change before it (restoring the state and the monitor's records), and
    /// stops extrapolating in this run.
    pub fn check(
        &mut self,
        solver: &mut dyn Backend,
        prep: &Prepared,
        monitor: &mut Monitor,
    ) -> Result<Checked> {
        let Some(u) = self.undo.take() else {
            return Ok(Checked::Kept);
        };
        let Some(&after) = monitor.changes.get(u.at) else {
            self.undo = Some(u);
            return Ok(Checked::Kept);
        };
        if after < u.change {
            self.applied += 1;
            return Ok(Checked::Kept);
        }
        solver.warm_start(prep, &u.before)?;
        monitor.undo_extrapolation(u.at, u.trajectory);
        self.enabled = false;
        self.snapshot = None;
        Ok(Checked::Undone {
            at: u.at,
            why: format!(
                "the tail extrapolation at iteration {} did not reduce the change ({:.3e} after, {:.3e} before); undone, plain iteration from there",
                u.at, after, u.change
            ),
        })
    }

    /// Between batches, with `k` iterations done of `end`: takes a snapshot where the iteration
    /// is stiff, or extrapolates from the snapshot where one mode dominates since it.
    pub fn step(
        &mut self,
        solver: &mut dyn Backend,
        prep: &Prepared,
        monitor: &mut Monitor,
        k: usize,
        end: usize,
    ) -> Result<()> {
        // The extrapolated state needs iterations after it (I_total follows I_ex one late).
        if !self.enabled || self.undo.is_some() || end < k + 2 {
            return Ok(());
        }
        let stiff =
            k >= monitor.epoch() + SETTLE && monitor.contraction().is_some_and(|q| q >= STIFF);
        match self.snapshot.take() {
            None if stiff => self.snapshot = Some((k, solver.i_ex()?)),
            Some((s, x_s)) if k < s + SPAN => self.snapshot = Some((s, x_s)),
            Some((s, x_s)) => match tail_factor(&monitor.changes, &monitor.energies, s) {
                Some((q, factor)) => {
                    let x = solver.i_ex()?;
                    solver.warm_start(prep, &extrapolate(&x, &x_s, factor))?;
                    let trajectory = monitor.extrapolated(q);
                    self.undo = Some(Undo {
                        at: k,
                        before: x,
                        change: monitor.changes[k - 1],
                        trajectory,
                    });
                }
                // Not a single mode yet: a new window from here.
                None if stiff => self.snapshot = Some((k, solver.i_ex()?)),
                None => {}
            },
            None => {}
        }
        Ok(())
    }
}
