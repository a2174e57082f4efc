//! Image error metrics against a reference (`study`, tests): relative RMSE, mean absolute
//! relative error and FLIP (NVIDIA's perceptual difference, through the `nv-flip` crate).
//!
//! Relative errors divide by `|r| + ε` per channel, with `ε` = 1% of the reference's mean value,
//! so dark pixels do not dominate and the metrics do not depend on the radiance unit. FLIP
//! compares low-dynamic-range images: both are multiplied by one exposure (the reference's
//! 99th-percentile luminance maps to 1), clamped and sRGB-encoded, then compared at FLIP's
//! default 67 pixels per degree; the score is the mean of FLIP's error map (0 = identical).

use crate::error::{Error, Result};
use crate::frame::image::{srgb_encode, Image};
use serde::Serialize;

/// Errors of one image against a reference.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Metrics {
    /// `sqrt(mean(((x−r)/(|r|+ε))²))` over pixels and channels.
    pub rel_rmse: f64,
    /// `mean(|x−r|/(|r|+ε))` over pixels and channels.
    pub mare: f64,
    /// Mean FLIP error (0..1).
    pub flip: f64,
}

/// Rec. 709 luminance of a linear RGB pixel.
pub fn luminance(p: [f32; 3]) -> f32 {
    0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]
}

fn same_size(a: &Image, b: &Image) -> Result<()> {
    if (a.width, a.height) != (b.width, b.height) {
        return Err(Error::Invalid(format!(
            "image sizes differ: {}x{} vs reference {}x{}",
            a.width, a.height, b.width, b.height
        )));
    }
    Ok(())
}

/// Exposure that maps the 99th-percentile luminance of `reference` to 1 (1 for a black image).
pub fn flip_exposure(reference: &Image) -> f32 {
    let mut l: Vec<f32> = reference.pixels.iter().map(|&p| luminance(p)).collect();
    l.sort_by(f32::total_cmp);
    let p99 = l
        .get(((l.len().max(1) - 1) as f64 * 0.99) as usize)
        .copied()
        .unwrap_or(0.0);
    if p99 > 0.0 && p99.is_finite() {
        1.0 / p99
    } else {
        1.0
    }
}

fn ldr(img: &Image, exposure: f32) -> nv_flip::FlipImageRgb8 {
    let bytes: Vec<u8> = img
        .pixels
        .iter()
        .flat_map(|p| p.map(|c| (srgb_encode(c * exposure) * 255.0 + 0.5) as u8))
        .collect();
    nv_flip::FlipImageRgb8::with_data(img.width, img.height, &bytes)
}

/// Mean FLIP error of `test` against `reference` at a shared `exposure`.
pub fn flip(test: &Image, reference: &Image, exposure: f32) -> Result<f64> {
    same_size(test, reference)?;
    let map = nv_flip::flip(
        ldr(reference, exposure),
        ldr(test, exposure),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    let pool = nv_flip::FlipPool::from_image(&map);
    Ok(pool.mean() as f64)
}

/// Relative RMSE and mean absolute relative error (see the module documentation for ε).
pub fn relative_errors(test: &Image, reference: &Image) -> Result<(f64, f64)> {
    same_size(test, reference)?;
    let n = (3 * reference.pixels.len()).max(1) as f64;
    let mean = reference
        .pixels
        .iter()
        .flatten()
        .map(|&v| v.abs() as f64)
        .sum::<f64>()
        / n;
    let eps = (0.01 * mean).max(f64::MIN_POSITIVE);
    let (mut sq, mut abs) = (0.0, 0.0);
    for (a, b) in test.pixels.iter().zip(&reference.pixels) {
        for c in 0..3 {
            let r = (a[c] as f64 - b[c] as f64) / (b[c].abs() as f64 + eps);
            if r.is_finite() {
                sq += r * r;
                abs += r.abs();
            } else {
                // A NaN or infinite pixel is as wrong as an error can be, not something to skip.
                return Ok((f64::INFINITY, f64::INFINITY));
            }
        }
    }
    Ok(((sq / n).sqrt(), abs / n))
}

/// All metrics of `test` against `reference`.
pub fn compare(test: &Image, reference: &Image) -> Result<Metrics> {
    let (rel_rmse, mare) = relative_errors(test, reference)?;
    let flip = flip(test, reference, flip_exposure(reference))?;
    Ok(Metrics {
        rel_rmse,
        mare,
        flip,
    })
}

/// A picture of where `test` departs from `reference`: red where it is brighter, blue where it is
/// darker, full intensity at a relative luminance error of `scale` (e.g. 0.5 = 50%).
pub fn difference_map(test: &Image, reference: &Image, scale: f32) -> Result<Image> {
    same_size(test, reference)?;
    let mean = reference.pixels.iter().map(|&p| luminance(p)).sum::<f32>()
        / reference.pixels.len().max(1) as f32;
    let eps = (0.01 * mean).max(f32::MIN_POSITIVE);
    Ok(Image {
        width: test.width,
        height: test.height,
        pixels: test
            .pixels
            .iter()
            .zip(&reference.pixels)
            .map(|(a, b)| {
                let (la, lb) = (luminance(*a), luminance(*b));
                let r = ((la - lb) / (lb.abs() + eps) / scale).clamp(-1.0, 1.0);
                if r.is_nan() {
                    [1.0, 0.0, 1.0]
                } else if r >= 0.0 {
                    [r, 0.0, 0.0]
                } else {
                    [0.0, 0.0, -r]
                }
            })
            .collect(),
    })
}

/// `a − b` per pixel (e.g. an image minus the reference's direct part: its indirect light).
pub fn subtract(a: &Image, b: &Image) -> Result<Image> {
    same_size(a, b)?;
    Ok(Image {
        width: a.width,
        height: a.height,
        pixels: a
            .pixels
            .iter()
            .zip(&b.pixels)
            .map(|(x, y)| [x[0] - y[0], x[1] - y[1], x[2] - y[2]])
            .collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img(w: u32, h: u32, f: impl Fn(u32, u32) -> [f32; 3]) -> Image {
        Image {
            width: w,
            height: h,
            pixels: (0..h)
                .flat_map(|y| (0..w).map(move |x| (x, y)))
                .map(|(x, y)| f(x, y))
                .collect(),
        }
    }

    #[test]
    fn identical_images_have_zero_error() {
        let a = img(32, 32, |x, y| [x as f32 * 0.1, y as f32 * 0.05, 0.5]);
        let m = compare(&a, &a).unwrap();
        assert_eq!((m.rel_rmse, m.mare, m.flip), (0.0, 0.0, 0.0));
    }

    #[test]
    fn known_relative_errors() {
        // Reference 1 everywhere (ε = 0.01), test 1.1 on half the pixels.
        let r = img(16, 16, |_, _| [1.0; 3]);
        let t = img(16, 16, |x, _| if x < 8 { [1.1; 3] } else { [1.0; 3] });
        let (rmse, mare) = relative_errors(&t, &r).unwrap();
        let e = 0.1 / 1.01;
        assert!((mare - e / 2.0).abs() < 1e-6, "{mare}");
        assert!((rmse - (e * e / 2.0).sqrt()).abs() < 1e-6, "{rmse}");
        // Scale invariance: both images ×1e4 give the same numbers.
        let k = |i: &Image| Image {
            pixels: i.pixels.iter().map(|p| p.map(|c| c * 1e4)).collect(),
            ..i.clone()
        };
        let (rmse2, mare2) = relative_errors(&k(&t), &k(&r)).unwrap();
        assert!((rmse2 - rmse).abs() < 1e-6 && (mare2 - mare).abs() < 1e-6);
        let nan = img(2, 2, |_, _| [f32::NAN; 3]);
        let (a, b) = relative_errors(&nan, &img(2, 2, |_, _| [1.0; 3])).unwrap();
        assert!(
            a.is_infinite() && b.is_infinite(),
            "NaN pixels count as infinitely wrong"
        );
    }

    #[test]
    fn flip_grows_with_the_difference_and_sizes_must_match() {
        let r = img(64, 64, |x, y| [((x / 8 + y / 8) % 2) as f32 * 0.8 + 0.1; 3]);
        let slight = img(64, 64, |x, y| r.at(x, y).map(|c| c * 1.02));
        let strong = img(64, 64, |x, y| r.at(x, y).map(|c| 0.9 - c));
        let e = flip_exposure(&r);
        let (a, b) = (flip(&slight, &r, e).unwrap(), flip(&strong, &r, e).unwrap());
        assert!(a > 0.0 && a < 0.05 && b > 0.3, "slight {a}, strong {b}");
        assert!(compare(&img(8, 8, |_, _| [0.0; 3]), &r).is_err());
    }
}
