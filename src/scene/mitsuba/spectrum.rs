//! Sampled spectra (`<spectrum value="λ:v, …">`) to linear sRGB as Mitsuba 3's RGB modes
//! convert them (`spectrum_list_to_srgb`): the piecewise-linear spectrum, zero outside its
//! wavelengths, integrated over 360–830 nm against the CIE 1931 observer, weighted by the D65
//! illuminant for a reflectance (so that a flat 1 is white) and not for an emitter, then XYZ to
//! linear sRGB; reflectances clamped to [0, 1], emission to ≥ 0. The observer is Wyman, Sloan
//! and Shirley's multi-lobe fit (JCGT 2013, within about 1% of the tables).

use glam::{DMat3, DVec3};

/// CIE D65, 360–830 nm every 10 nm (relative, 100 at 560 nm).
const D65: [f64; 48] = [
    46.6383, 52.0891, 49.9755, 54.6482, 82.7549, 91.486, 93.4318, 86.6823, 104.865, 117.008,
    117.812, 114.861, 115.923, 108.811, 109.354, 107.802, 104.79, 107.689, 104.405, 104.046, 100.0,
    96.3342, 95.788, 88.6856, 90.0062, 89.5991, 87.6987, 83.2886, 83.6992, 80.0268, 80.2146,
    82.2778, 78.2842, 69.7213, 71.6091, 74.349, 61.604, 69.8856, 75.087, 63.5927, 46.4182, 66.8054,
    63.3828, 64.304, 59.4519, 51.959, 57.4406, 60.3125,
];

fn d65(l: f64) -> f64 {
    let x = ((l - 360.0) / 10.0).clamp(0.0, 47.0);
    let i = (x.floor() as usize).min(46);
    let f = x - i as f64;
    D65[i] * (1.0 - f) + D65[i + 1] * f
}

/// A lobe of the fit: a Gaussian of width `a` below `mu` and `b` above.
fn g(l: f64, mu: f64, a: f64, b: f64) -> f64 {
    let t = (l - mu) / if l < mu { a } else { b };
    (-0.5 * t * t).exp()
}

/// The CIE 1931 2° observer x̄, ȳ, z̄ at `l` nm.
fn observer(l: f64) -> DVec3 {
    DVec3::new(
        1.056 * g(l, 599.8, 37.9, 31.0) + 0.362 * g(l, 442.0, 16.0, 26.7)
            - 0.065 * g(l, 501.1, 20.4, 26.2),
        0.821 * g(l, 568.8, 46.9, 40.5) + 0.286 * g(l, 530.9, 16.3, 31.1),
        1.217 * g(l, 437.0, 11.8, 36.0) + 0.681 * g(l, 459.0, 26.0, 13.8),
    )
}

/// XYZ to linear sRGB (D65 white).
fn xyz_to_srgb(xyz: DVec3) -> DVec3 {
    DMat3::from_cols_array(&[
        3.240479, -0.969256, 0.055648, -1.537150, 1.875991, -0.204043, -0.498535, 0.041556,
        1.057311,
    ]) * xyz
}

/// Linear sRGB of the spectrum given as (wavelength nm, value) pairs in increasing order.
pub fn to_srgb(pairs: &[(f64, f64)], emitter: bool) -> DVec3 {
    let steps = 1000;
    let (mut xyz, mut norm) = (DVec3::ZERO, 0.0);
    for i in 0..steps {
        let l = 360.0 + 470.0 * i as f64 / (steps - 1) as f64;
        let w = if emitter { 1.0 } else { d65(l) };
        let o = observer(l);
        norm += o.y * w;
        let Some(k) = pairs.windows(2).position(|p| p[0].0 <= l && l <= p[1].0) else {
            continue;
        };
        let ((l0, v0), (l1, v1)) = (pairs[k], pairs[k + 1]);
        let v = if l1 > l0 {
            v0 + (v1 - v0) * (l - l0) / (l1 - l0)
        } else {
            v0
        };
        xyz += o * v * w;
    }
    let rgb = xyz_to_srgb(xyz / norm);
    if emitter {
        rgb.max(DVec3::ZERO)
    } else {
        rgb.clamp(DVec3::ZERO, DVec3::ONE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flat_spectra_are_grey_and_white_is_white() {
        let flat = [(360.0, 1.0), (830.0, 1.0)];
        let w = to_srgb(&flat, false);
        assert!((w - DVec3::ONE).abs().max_element() < 0.02, "{w}");
        let half = to_srgb(&[(360.0, 0.5), (830.0, 0.5)], false);
        assert!(
            (half - DVec3::splat(0.5)).abs().max_element() < 0.01,
            "{half}"
        );
        // An equal-energy emitter is white with Y = its value, a little pink in sRGB.
        let e = to_srgb(&[(360.0, 2.0), (830.0, 2.0)], true);
        let y = 0.2126 * e.x + 0.7152 * e.y + 0.0722 * e.z;
        assert!(e.x > e.z && (y - 2.0).abs() < 0.01, "{e}");
    }
}
