//! A frame drawn in passes (`camera.passes`): each pass draws the whole frame with its samples
//! shifted along the pixel's diagonal by a fraction of the sample spacing, and the passes are
//! averaged. A regular grid of `m` samples per side integrates a hard edge parallel to the
//! image rows in steps of `1/m` of a pixel, every pixel of the row alike (a wall's top over a
//! lit floor, a sun's shadow edge); `P` shifted passes make that `1/(m·P)`, as a box-filtered
//! pixel integrates it (issue 36; docs/measurements.md "Frames in passes").

use crate::backend::{Backend, Prepared};
use crate::error::Result;
use crate::frame::camera::SUPERSAMPLE;
use crate::frame::Image;

/// The shift of pass `p` of `passes`, in frame pixels along both axes: the passes' sample
/// positions split each sample's cell (`1/SUPERSAMPLE` of a frame pixel) evenly, centred on
/// the unshifted sample (one pass: no shift).
pub fn pass_jitter(p: u32, passes: u32) -> f64 {
    let passes = passes.max(1) as f64;
    ((p as f64 + 0.5) / passes - 0.5) / SUPERSAMPLE as f64
}

/// Draws `prep`'s camera on `backend`: its `passes` shifted frames averaged, each pixel the
/// mean of its `supersample`² frame pixels. The camera is left unshifted.
pub(crate) fn draw_frame(backend: &mut dyn Backend, prep: &mut Prepared) -> Result<Image> {
    let (k, passes) = (prep.camera.supersample, prep.camera.passes.max(1));
    if passes == 1 {
        return Ok(backend.draw(prep)?.box_reduced(k));
    }
    let drawn = draw_passes(backend, prep, passes);
    prep.camera.jitter = [0.0; 2];
    backend.set_camera(prep)?;
    Ok(drawn?.box_reduced(k))
}

fn draw_passes(backend: &mut dyn Backend, prep: &mut Prepared, passes: u32) -> Result<Image> {
    let mut sum: Option<Image> = None;
    for p in 0..passes {
        let d = pass_jitter(p, passes);
        prep.camera.jitter = [d, d];
        backend.set_camera(prep)?;
        let image = backend.draw(prep)?;
        match &mut sum {
            None => sum = Some(image),
            Some(s) => {
                for (a, b) in s.pixels.iter_mut().zip(&image.pixels) {
                    for c in 0..3 {
                        a[c] += b[c];
                    }
                }
            }
        }
    }
    let mut image = sum.expect("at least one pass");
    for a in &mut image.pixels {
        for v in a.iter_mut() {
            *v /= passes as f32;
        }
    }
    Ok(image)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn passes_split_a_sample_cell_evenly() {
        assert_eq!(pass_jitter(0, 1), 0.0);
        // Four passes: the samples at 0.25 of a frame pixel lie at 0.0625, 0.1875, 0.3125,
        // 0.4375: the cell 0..0.5 in quarters, at their centres.
        let at: Vec<f64> = (0..4).map(|p| 0.25 + pass_jitter(p, 4)).collect();
        for (a, b) in at.iter().zip([0.0625, 0.1875, 0.3125, 0.4375]) {
            assert!((a - b).abs() < 1e-15, "{at:?}");
        }
    }
}
