//! Tail extrapolation for stiff enclosures. Where one eigenmode of the iteration dominates, the
//! error after iteration k is that mode times q^k (q its eigenvalue), so the rest of the
//! Neumann series is a geometric tail that can be summed in one step: with X_s the state m
//! iterations earlier, X* ≈ X_k + (X_k − X_s)·q^m/(1 − q^m). A closed room of albedo 0.999 needs
//! ~3,000 plain iterations for 5%; with this, a few dozen (the radiosity literature's "ambient
//! term" serves the same purpose; this is its linear-algebra form, valid for any single dominant
//! mode). Pure functions here; the drive loop ([`crate::engine`]) decides when, on either backend.

use super::Table;

/// Contraction ratio from which plain iteration is slow enough to extrapolate: below it, 40
/// iterations reduce the error 10⁻² without help.
pub const STIFF: f64 = 0.9;

/// Iterations between the snapshot and the extrapolation: the window over which the single-mode
/// behaviour is checked. Long enough for faster modes (eigenvalues ≤ 0.5·q) to have died out by
/// 2⁻¹⁶ relative to the dominant one.
pub const SPAN: usize = 16;

/// The two halves of the window must measure the same q within this fraction of 1 − q: the
/// extrapolated tail is then right within about this fraction × m/(1 − q^m)·(1 − q) (a tenth of
/// the tail for q = 0.999, m = 16), and a mode mixture or an oscillation fails the test.
pub const AGREEMENT: f64 = 0.05;

/// Geometric-mean ratio of `values[b]` over `values[a]` per step, when both are positive.
fn ratio(values: &[f64], a: usize, b: usize) -> Option<f64> {
    let (x, y) = (*values.get(a)?, *values.get(b)?);
    (b > a && x > 0.0 && y > 0.0 && x.is_finite() && y.is_finite())
        .then(|| (y / x).powf(1.0 / (b - a) as f64))
}

/// Whether `values[from..]` decrease geometrically at one ratio: the ratio over the whole run, when
/// its halves agree within [`AGREEMENT`] × (1 − q).
fn single_mode(values: &[f64], from: usize) -> Option<f64> {
    let last = values.len().checked_sub(1)?;
    if last < from + 4 {
        return None;
    }
    let mid = (from + last) / 2;
    let q = ratio(values, from, last)?;
    let (qa, qb) = (ratio(values, from, mid)?, ratio(values, mid, last)?);
    ((qa - qb).abs() <= AGREEMENT * (1.0 - q)).then_some(q)
}

/// The dominant contraction ratio q and the tail factor q^m/(1 − q^m) for extrapolating from the
/// state after iteration `s` to the state after iteration k = `changes.len()` (m = k − s), or
/// `None` where extrapolating would not be safe. `changes[i]` is ‖X_{i+1} − X_i‖ and
/// `energies[i]` the exitant flux after iteration i + 1 (the monitor's records).
///
/// Safe means: q in [[`STIFF`], 1), the change norms contracting at one ratio over the window,
/// and the flux rising or falling monotonically at the same ratio (an oscillating mode, a
/// mixture of modes, or a mode that carries no flux fails one of these).
pub fn tail_factor(changes: &[f64], energies: &[f64], s: usize) -> Option<(f64, f64)> {
    let k = changes.len();
    if energies.len() != k || k < s + 8 {
        return None;
    }
    // The changes of iterations s+1..=k.
    let q = single_mode(changes, s)?;
    if !(STIFF..1.0).contains(&q) {
        return None;
    }
    // Flux increments of the same iterations (the first needs the flux before iteration s+1).
    if s == 0 {
        return None;
    }
    let steps: Vec<f64> = (s..k).map(|i| energies[i] - energies[i - 1]).collect();
    // signum(0) is 1: a flat step is refused explicitly.
    let sign = steps[0].signum();
    if steps.iter().any(|&d| d == 0.0 || d.signum() != sign) {
        return None;
    }
    let magnitudes: Vec<f64> = steps.iter().map(|d| d.abs()).collect();
    let qe = single_mode(&magnitudes, 0)?;
    if (qe - q).abs() > AGREEMENT * (1.0 - q) {
        return None;
    }
    let qm = q.powi((k - s) as i32);
    Some((q, qm / (1.0 - qm)))
}

/// `x + factor·(x − before)`, value by value (all rows: the clusters' rows are the pull of the
/// leaves', a linear map, so they extrapolate alike).
pub fn extrapolate(x: &Table, before: &Table, factor: f64) -> Table {
    debug_assert_eq!(x.data.len(), before.data.len());
    let mut out = x.clone();
    for (o, b) in out.data.iter_mut().zip(&before.data) {
        *o += (*o - *b) * factor;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// The records of a scalar iteration x ← a·x + 1 from 0 (fixed point 1/(1 − a)), plus a
    /// faster mode of amplitude `fast` and ratio `mu`.
    fn records(a: f64, fast: f64, mu: f64, n: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let x: Vec<f64> = (0..=n)
            .map(|k| (1.0 - a.powi(k as i32)) / (1.0 - a) + fast * mu.powi(k as i32))
            .collect();
        let changes = (1..=n).map(|k| (x[k] - x[k - 1]).abs()).collect();
        let energies = x[1..].to_vec();
        (x, changes, energies)
    }

    #[test]
    fn a_single_stiff_mode_is_summed_to_its_fixed_point() {
        let a = 0.999;
        let (x, changes, energies) = records(a, 0.0, 0.0, 40);
        let (s, k) = (20, 40);
        let (q, f) = tail_factor(&changes, &energies, s).expect("one stiff mode");
        assert!((q - a).abs() < 1e-9, "{q}");
        let y = x[k] + (x[k] - x[s]) * f;
        // After 40 iterations the plain iterate is 96% short; the extrapolation is exact.
        assert!((x[k] * (1.0 - a) - 1.0).abs() > 0.9);
        assert!((y * (1.0 - a) - 1.0).abs() < 1e-9, "{y}");
        let t = |v: f64| Table {
            data: vec![DVec3::splat(v)],
            bins: 1,
        };
        let e = extrapolate(&t(x[k]), &t(x[s]), f);
        assert!((e.data[0].x - y).abs() < 1e-9);
    }

    #[test]
    fn fast_mixed_oscillating_or_short_runs_are_left_alone() {
        // Not stiff: plain iteration is quick.
        let (_, c, e) = records(0.5, 0.0, 0.0, 40);
        assert_eq!(tail_factor(&c, &e, 20), None);
        // Two modes of comparable size (0.95 and 0.99) over the window: the halves disagree.
        let (_, c, e) = records(0.99, -30.0, 0.95, 40);
        assert_eq!(tail_factor(&c, &e, 20), None);
        // An oscillating dominant mode: the change norms contract, the flux alternates.
        let x: Vec<f64> = (0..=40).map(|k| 1.0 + (-0.99f64).powi(k)).collect();
        let c: Vec<f64> = (1..=40).map(|k| (x[k] - x[k - 1]).abs()).collect();
        assert_eq!(tail_factor(&c, &x[1..], 20), None);
        // Too few iterations since the snapshot.
        let (_, c, e) = records(0.999, 0.0, 0.0, 24);
        assert_eq!(tail_factor(&c, &e, 20), None);
        // A faster mode that has died out by the window is no obstacle.
        let (_, c, e) = records(0.999, -5.0, 0.3, 60);
        assert!(tail_factor(&c, &e, 40).is_some());
    }
}
