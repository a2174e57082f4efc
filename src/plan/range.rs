//! The dynamic range a scene's tables need, decided before anything is allocated: which power of
//! two to scale the sources by so that float16 neither overflows (65504) nor drops the dimmest
//! source into subnormals (below 6.1e-5), and when float16 cannot hold both so the tables must be
//! float32. Tables hold intensities (radiance × area) and radiances, and interreflection
//! multiplies the sources by up to 1/(1−ρ), so areas and albedos enter as well as radiances.

use crate::scene::Precision;
use crate::system::System;
use glam::DVec3;

/// Float16's largest finite value.
pub const F16_MAX: f64 = 65504.0;

/// The brightest source × amplification is scaled to this: 32× below [`F16_MAX`], headroom for
/// unoccluded transport adding up light that antiradiance later removes, and for accumulation.
pub const SCALED_PEAK: f64 = 2048.0;

/// The dimmest source's smallest intensity must stay above this after scaling (2^-10: 16× above
/// float16's smallest normal, so its own interreflections keep full precision too).
pub const SCALED_FLOOR: f64 = 1.0 / 1024.0;

/// Interreflection gain is capped here (albedo 1 would be unbounded).
const MAX_GAIN: f64 = 1e4;

/// Largest interreflection gain 1/(1−ρ) float16 tables serve: every iteration stores I_ex with
/// a relative rounding of 2^-11, and the fixed point amplifies it by the gain (at ρ = 0.99 the
/// GPU was 12% off the exact answer in float16; float32 stays within the iteration error).
pub const F16_MAX_GAIN: f64 = 16.0;

/// Sizes that decide the tables' range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Range {
    /// Brightest source radiance (emission, environment, direct light).
    pub brightest: f64,
    /// Dimmest non-zero emission or environment radiance (`None` without any).
    pub dimmest: Option<f64>,
    /// Brightest value the tables may reach per unit source radiance: the largest leaf
    /// `area × cos_norm` (at least 1, for radiances) times the interreflection gain 1/(1−ρ_max).
    pub amplification: f64,
    /// Smallest leaf `area × cos_norm` (at most 1).
    pub smallest_intensity: f64,
    /// Interreflection gain 1/(1−ρ_max) (capped).
    pub gain: f64,
}

impl Range {
    /// The range of `sys` lit by `environment` and a direct-light table's brightest value.
    pub fn of(sys: &System, environment: DVec3, direct_max: f64) -> Self {
        let used: Vec<bool> = (0..sys.materials.len())
            .map(|m| sys.leaves.iter().any(|l| l.material as usize == m))
            .collect();
        let mats = || {
            sys.materials
                .iter()
                .zip(&used)
                .filter(|(_, u)| **u)
                .map(|(m, _)| m)
        };
        let ke: Vec<f64> = mats()
            .map(|m| m.ke.max_element())
            .chain([environment.max_element()])
            .filter(|v| *v > 0.0)
            .collect();
        let rho = mats()
            .map(|m| (m.kd + m.ks).max_element())
            .fold(0.0, f64::max);
        let gain = if rho < 1.0 {
            (1.0 / (1.0 - rho)).min(MAX_GAIN)
        } else {
            MAX_GAIN
        };
        let (lo, hi) = sys.leaves.iter().fold((f64::MAX, 0.0f64), |(lo, hi), l| {
            let a = l.area * l.cos_norm;
            (lo.min(a), hi.max(a))
        });
        Self {
            brightest: ke.iter().cloned().fold(direct_max, f64::max),
            dimmest: ke.iter().cloned().reduce(f64::min),
            // Beyond F16_MAX_GAIN the tables are float32 anyway; more headroom would only push
            // dim values toward float16's subnormals when float16 is forced.
            amplification: hi.max(1.0) * gain.min(F16_MAX_GAIN),
            smallest_intensity: lo.min(1.0),
            gain,
        }
    }

    /// Power-of-two source scale for float16 tables (exact in binary floats, so it changes no
    /// rounding; the system is linear in its sources).
    pub fn scale(&self) -> f64 {
        let peak = self.brightest * self.amplification;
        if !peak.is_finite() || peak <= 0.0 {
            return 1.0;
        }
        2f64.powi((SCALED_PEAK / peak).log2().floor().clamp(-120.0, 120.0) as i32)
    }

    /// Why float16 tables cannot hold this scene (then the tables must be float32), or `None`.
    pub fn float16_shortfall(&self) -> Option<String> {
        if self.gain > F16_MAX_GAIN {
            return Some(format!(
                "albedo up to {:.4} amplifies float16's rounding (4.9e-4 per iteration) by 1/(1−ρ) = {:.0}",
                1.0 - 1.0 / self.gain,
                self.gain
            ));
        }
        let dim = self.dimmest? * self.smallest_intensity;
        let peak = self.brightest * self.amplification;
        let span = peak / dim;
        (span > SCALED_PEAK / SCALED_FLOOR).then(|| {
            format!(
                "the scene's dynamic range ({span:.1e}: brightest source {:.3e} × amplification {:.1e}, dimmest {:.3e} × smallest element intensity {:.1e}) exceeds float16's usable {:.1e}",
                self.brightest,
                self.amplification,
                self.dimmest.unwrap_or(0.0),
                self.smallest_intensity,
                SCALED_PEAK / SCALED_FLOOR
            )
        })
    }

    /// The precision to use when `requested` is asked for, with the reason for any change.
    pub fn precision(&self, requested: Precision) -> (Precision, Option<String>) {
        match (requested, self.float16_shortfall()) {
            (Precision::F16, Some(why)) => (
                Precision::F32,
                Some(format!("{why}; tables in float32 instead of float16")),
            ),
            (p, _) => (p, None),
        }
    }

    /// The largest |value| (unscaled) a table of `precision` may reach at `scale` before
    /// float16 overflow is near (half of 65504); unbounded for float32.
    pub fn overflow_limit(precision: Precision, scale: f64) -> f64 {
        match precision {
            Precision::F16 => 0.5 * F16_MAX / scale,
            Precision::F32 | Precision::F64 => f64::MAX,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn range(brightest: f64, dimmest: Option<f64>, amplification: f64, small: f64) -> Range {
        Range {
            brightest,
            dimmest,
            amplification,
            smallest_intensity: small,
            gain: 1.0,
        }
    }

    #[test]
    fn scale_keeps_the_peak_in_float16() {
        for (b, a) in [
            (1e-4, 1.0),
            (1.0, 100.0),
            (1e6, 1.0),
            (17.0, 4.0),
            (1.0, 1e4 * 6e6),
        ] {
            let r = range(b, Some(b), a, 1.0);
            let peak = b * a * r.scale();
            assert!(
                peak <= SCALED_PEAK && peak > SCALED_PEAK / 2.0,
                "{b} {a}: {peak}"
            );
            assert_eq!(r.scale().log2().fract(), 0.0);
        }
    }

    #[test]
    fn wide_ranges_need_float32() {
        assert!(range(1e6, Some(1e-4), 1.0, 1.0)
            .float16_shortfall()
            .is_some());
        assert!(range(10.0, Some(1.0), 4.0, 0.01)
            .float16_shortfall()
            .is_none());
        // Albedo 0.999 with tiny elements: the gain and the areas count too.
        let r = range(1.0, Some(1.0), 10.0, 1e-8);
        let (p, why) = r.precision(Precision::F16);
        assert_eq!(p, Precision::F32);
        assert!(why.unwrap().contains("float32"));
        assert_eq!(r.precision(Precision::F32), (Precision::F32, None));
        let stiff = Range {
            gain: 100.0,
            ..range(1.0, Some(1.0), 100.0, 1.0)
        };
        assert!(stiff.float16_shortfall().unwrap().contains("1/(1−ρ) = 100"));
    }
}
