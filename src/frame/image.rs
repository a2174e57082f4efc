//! Frames as linear RGB radiance, written as EXR (linear float, comparable pixel by pixel with a
//! Mitsuba 3 render of the same scene) or PNG (exposure, then the sRGB transfer curve).

use crate::error::{Error, Result};
use std::path::Path;

/// A linear-radiance RGB image, row-major from the top-left pixel.
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Radiance (W/(m²·sr)) per pixel.
    pub pixels: Vec<[f32; 3]>,
}

fn io_err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Output {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// sRGB transfer function of a linear value in [0, 1].
pub fn srgb_encode(v: f32) -> f32 {
    let v = v.clamp(0.0, 1.0);
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

impl Image {
    /// Pixel (x, y).
    pub fn at(&self, x: u32, y: u32) -> [f32; 3] {
        self.pixels[(y * self.width + x) as usize]
    }

    /// True when every channel of every pixel is finite.
    pub fn is_finite(&self) -> bool {
        self.pixels.iter().all(|p| p.iter().all(|c| c.is_finite()))
    }

    /// Refuses to write non-finite pixels: a NaN in an output file is never what a user wants.
    fn check_finite(&self, path: &Path) -> Result<()> {
        match self
            .pixels
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            None => Ok(()),
            Some(i) => Err(io_err(
                path,
                format!(
                    "not written: pixel ({}, {}) is {:?} (non-finite)",
                    i as u32 % self.width,
                    i as u32 / self.width,
                    self.pixels[i]
                ),
            )),
        }
    }

    /// Writes linear float RGB (32-bit channels); refuses non-finite pixels.
    pub fn write_exr(&self, path: &Path) -> Result<()> {
        self.check_finite(path)?;
        exr::prelude::write_rgb_file(path, self.width as usize, self.height as usize, |x, y| {
            let p = self.pixels[y * self.width as usize + x];
            (p[0], p[1], p[2])
        })
        .map_err(|e| io_err(path, e))
    }

    /// Reads an RGB EXR (e.g. a golden image or a Mitsuba reference).
    pub fn read_exr(path: &Path) -> Result<Self> {
        use exr::prelude::*;
        let img = read_first_rgba_layer_from_file(
            path,
            |res, _| (res.width(), vec![[0f32; 3]; res.width() * res.height()]),
            |(w, px), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                px[pos.y() * *w + pos.x()] = [r, g, b];
            },
        )
        .map_err(|e| io_err(path, e))?;
        let size = img.layer_data.size;
        Ok(Self {
            width: size.width() as u32,
            height: size.height() as u32,
            pixels: img.layer_data.channel_data.pixels.1,
        })
    }

    /// Writes 8-bit sRGB after multiplying by `2^exposure`.
    pub fn write_png(&self, path: &Path, exposure: f64) -> Result<()> {
        self.check_finite(path)?;
        let k = 2f32.powf(exposure as f32);
        let bytes: Vec<u8> = self
            .pixels
            .iter()
            .flat_map(|p| p.map(|c| (srgb_encode(c * k) * 255.0 + 0.5) as u8))
            .collect();
        image::save_buffer(
            path,
            &bytes,
            self.width,
            self.height,
            image::ColorType::Rgb8,
        )
        .map_err(|e| io_err(path, e))
    }

    /// Mean over pixels of `(a−b)² / (b² + ε)`, averaged over channels (relative MSE against
    /// reference `b`).
    pub fn rel_mse(&self, reference: &Image, eps: f32) -> f64 {
        assert_eq!(
            (self.width, self.height),
            (reference.width, reference.height)
        );
        let mut s = 0.0;
        for (a, b) in self.pixels.iter().zip(&reference.pixels) {
            for c in 0..3 {
                let d = (a[c] - b[c]) as f64;
                s += d * d / ((b[c] * b[c]) as f64 + eps as f64);
            }
        }
        s / (3 * self.pixels.len()) as f64
    }
}
