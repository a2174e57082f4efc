//! `[solver]` settings: each checked against its range ([`SolverSettings`] documents them), and
//! the element size resolved and checked once the meshes are read.

use super::format::SolverDesc;
use super::limits::{max_elements_limit, MIN_RELATIVE_RESOLUTION};
use super::load::scene_err;
use super::{
    Precision, Scene, Scheme, SolverSettings, MAX_ANTIRADIANCE_STEPS, MAX_ITERATIONS,
    RELATIVE_ELEMENT_SIZE,
};
use crate::error::Result;
use std::path::Path;

/// An integer setting in `1..=max`; `why` says what the cap is.
fn count(
    v: Option<i64>,
    default: usize,
    max: usize,
    why: &str,
    field: &str,
    path: &Path,
) -> Result<usize> {
    match v {
        None => Ok(default),
        Some(x) if x >= 1 && x as u64 <= max as u64 => Ok(x as usize),
        Some(x) => Err(scene_err(
            path,
            format!("`{field}` must be in 1..={max} ({why}), got {x}"),
        )),
    }
}

fn positive(v: Option<f64>, default: f64, field: &str, path: &Path) -> Result<f64> {
    match v {
        None => Ok(default),
        Some(x) if x.is_finite() && x > 0.0 => Ok(x),
        Some(x) => Err(scene_err(
            path,
            format!("`{field}` must be a positive finite number, got {x:?}"),
        )),
    }
}

const ITERATION_CAP: &str = "a cap: the iteration converges in tens of steps, and more than this is a typo that would run for hours";

/// The `[solver]` table, checked. `element_size` keeps the default until
/// [`resolve_element_size`] knows the scene's size.
pub fn solver_settings(s: &SolverDesc, path: &Path) -> Result<SolverSettings> {
    // A file that states neither a count nor a tolerance gets the monitor's (issue 36).
    let d = if s.iterations.is_none() && s.tolerance.is_none() {
        SolverSettings::for_file()
    } else {
        SolverSettings::default()
    };
    let bins = match s.bins {
        None => d.bins,
        Some(x) if x >= 1 => x as usize,
        Some(x) => {
            return Err(scene_err(
                path,
                format!("`solver.bins` must be at least 1, got {x}"),
            ))
        }
    };
    crate::bins::Bins::new(bins).map_err(|e| scene_err(path, format!("`solver.bins`: {e}")))?;
    let scheme = match s.scheme.as_deref() {
        None => Scheme::default(),
        Some(x) => x
            .parse::<Scheme>()
            .map_err(|e| scene_err(path, format!("`solver.scheme`: {e}")))?,
    };
    // The CPU's f64 is reported, not requested: a scene asks for a GPU table format.
    let precision = match s.precision.as_deref() {
        None => Precision::default(),
        Some(x) => match x.parse::<Precision>() {
            Ok(p @ (Precision::F16 | Precision::F32)) => p,
            _ => {
                return Err(scene_err(
                    path,
                    format!("`solver.precision` must be \"f16\" or \"f32\", got {x:?}"),
                ))
            }
        },
    };
    let machine = max_elements_limit();
    Ok(SolverSettings {
        bins,
        iterations: count(
            s.iterations,
            d.iterations,
            MAX_ITERATIONS,
            ITERATION_CAP,
            "solver.iterations",
            path,
        )?,
        scheme,
        element_size: positive(s.element_size, d.element_size, "solver.element_size", path)?,
        oracle: positive(s.oracle, d.oracle, "solver.oracle", path)?,
        antiradiance_steps: count(
            s.antiradiance_steps,
            d.antiradiance_steps,
            MAX_ANTIRADIANCE_STEPS,
            "a cap: each step is a full global pass, and more never change the fixed point",
            "solver.antiradiance_steps",
            path,
        )?,
        precision,
        max_elements: count(
            s.max_elements,
            d.max_elements,
            machine,
            &format!(
                "what this machine's memory holds at {} bytes per element before links and tables",
                super::limits::BYTES_PER_ELEMENT
            ),
            "solver.max_elements",
            path,
        )?,
        tolerance: match s.tolerance {
            None => d.tolerance,
            Some(t) if t.is_finite() && t > 0.0 && t < 1.0 => Some(t),
            Some(t) => {
                return Err(scene_err(
                    path,
                    format!("`solver.tolerance` must be in (0, 1), got {t}"),
                ))
            }
        },
        max_iterations: count(
            s.max_iterations,
            d.max_iterations,
            MAX_ITERATIONS,
            ITERATION_CAP,
            "solver.max_iterations",
            path,
        )?,
        iterations_per_frame: count(
            s.iterations_per_frame,
            d.iterations_per_frame,
            MAX_ITERATIONS,
            ITERATION_CAP,
            "solver.iterations_per_frame",
            path,
        )?,
        face_clusters: s.face_clusters.unwrap_or(d.face_clusters),
        extrapolate: s.extrapolate.unwrap_or(d.extrapolate),
        direct_per_sample: s.direct_per_sample.unwrap_or(d.direct_per_sample),
        splat_per_sample: s.splat_per_sample.unwrap_or(d.splat_per_sample),
        receiver_calibration: s.receiver_calibration.unwrap_or(d.receiver_calibration),
        direct_block: match s.direct_block {
            None => d.direct_block,
            Some(n) if (1..=super::MAX_DIRECT_BLOCK as i64).contains(&n) => Some(n as u32),
            Some(n) => {
                return Err(scene_err(
                    path,
                    format!(
                        "`solver.direct_block` must be 1..={}, got {n}",
                        super::MAX_DIRECT_BLOCK
                    ),
                ))
            }
        },
        emitter_samples: match s.emitter_samples {
            None => d.emitter_samples,
            Some(n) if (0..=super::MAX_EMITTER_SAMPLES as i64).contains(&n) => Some(n as usize),
            Some(n) => {
                return Err(scene_err(
                    path,
                    format!(
                        "`solver.emitter_samples` must be 0..={}, got {n}",
                        super::MAX_EMITTER_SAMPLES
                    ),
                ))
            }
        },
        filter_cutoff: match s.filter_cutoff {
            None => d.filter_cutoff,
            Some(c) if (1e-9..=0.5).contains(&c) => c,
            Some(c) => {
                return Err(scene_err(
                    path,
                    format!("`solver.filter_cutoff` must be in [1e-9, 0.5], got {c}"),
                ))
            }
        },
    })
}

/// Sets `scene.solver.element_size` to [`RELATIVE_ELEMENT_SIZE`] × the bounding-box diagonal
/// unless the file gave one, then refuses a size float64 cannot bisect to or one whose
/// elements (a lower bound from the triangles' areas and edges, before anything is
/// subdivided) would exceed `solver.max_elements`.
pub fn resolve_element_size(scene: &mut Scene, given: bool, path: &Path) -> Result<()> {
    let (lo, hi) = scene.bounds();
    let diagonal = (hi - lo).length();
    if !given {
        scene.solver.element_size = RELATIVE_ELEMENT_SIZE * diagonal;
    }
    let size = scene.solver.element_size;
    let origin = if given {
        String::new()
    } else {
        format!(
            " (no element_size in the file: {RELATIVE_ELEMENT_SIZE} × the scene's diagonal {diagonal:.4e})"
        )
    };
    let magnitude = lo.abs().max(hi.abs()).max_element();
    if !(size.is_finite() && size > 0.0 && size >= MIN_RELATIVE_RESOLUTION * magnitude) {
        return Err(scene_err(
            path,
            format!(
                "`solver.element_size` {size:?}{origin} is finer than float64 coordinates of magnitude {magnitude:e} can bisect to (at least {:e})",
                MIN_RELATIVE_RESOLUTION * magnitude
            ),
        ));
    }
    let limit = scene.solver.max_elements;
    let estimate = crate::elements::estimate_elements(scene, size);
    if !(estimate <= limit as f64) {
        return Err(scene_err(
            path,
            format!(
                "`solver.element_size` {size:?}{origin} would create at least {estimate:.3e} elements, more than `solver.max_elements` ({limit}); use a larger element size"
            ),
        ));
    }
    Ok(())
}
