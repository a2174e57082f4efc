//! `reference`: an unbiased CPU path tracer for exactly the scene format's semantics, the ground
//! truth that `study` measures antiradiance against. Deterministic for a seed (every pixel has
//! its own random stream), parallel over all cores (rayon), with a per-pixel standard error so
//! a user knows how converged the reference is.

pub mod integrator;
pub mod sampling;

use crate::error::{Error, Result};
use crate::frame::camera::View;
use crate::frame::Image;
use crate::progress::Progress;
use crate::scene::Scene;
use glam::DVec3;
use integrator::Tracer;
use rayon::prelude::*;
use sampling::Rng;
use serde::{Deserialize, Serialize};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Options of [`render_reference`].
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceOptions {
    /// Samples (camera paths) per pixel.
    pub spp: u32,
    /// Reflections per path; None: unlimited (Russian roulette ends paths without bias).
    pub max_bounces: Option<u32>,
    /// Seed of the random streams.
    pub seed: u64,
}

impl Default for ReferenceOptions {
    fn default() -> Self {
        Self {
            spp: 64,
            max_bounces: None,
            seed: 1,
        }
    }
}

/// Convergence figures of a reference render.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ReferenceStats {
    /// Samples per pixel.
    pub spp: u32,
    /// Seed.
    pub seed: u64,
    /// Reflection limit (None: unlimited).
    pub max_bounces: Option<u32>,
    /// Wall time (ms).
    pub total_ms: f64,
    /// Threads used.
    pub threads: usize,
    /// Mean over pixels of the standard error of the luminance, relative to the image's mean
    /// luminance (None at 1 spp).
    pub mean_relative_std_error: Option<f64>,
    /// Median over lit pixels of each pixel's standard error relative to its own luminance.
    pub median_pixel_relative_std_error: Option<f64>,
    /// 95th percentile of the same.
    pub p95_pixel_relative_std_error: Option<f64>,
}

/// A path-traced image with its direct part and its standard error.
#[derive(Debug, Clone)]
pub struct Reference {
    /// Radiance (mean of the samples).
    pub image: Image,
    /// The part of `image` carried by paths with at most one reflection.
    pub direct: Image,
    /// Standard error of each pixel's mean, per channel (None at 1 spp, where it is unknown).
    pub std_error: Option<Image>,
    /// Convergence figures.
    pub stats: ReferenceStats,
}

fn luminance(p: [f32; 3]) -> f64 {
    crate::metrics::luminance(p) as f64
}

fn to_f32(v: DVec3) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}

/// Path-traces `scene` from its camera.
pub fn render_reference(
    scene: &Scene,
    opts: &ReferenceOptions,
    progress: &dyn Progress,
) -> Result<Reference> {
    if opts.spp == 0 {
        return Err(Error::Invalid("reference: --spp must be at least 1".into()));
    }
    let t0 = Instant::now();
    let tracer = Tracer::new(scene, opts.max_bounces);
    let view = View::new(&scene.camera);
    let (w, h) = (view.width as usize, view.height as usize);
    let mut mean = vec![[0f32; 3]; w * h];
    let mut direct = vec![[0f32; 3]; w * h];
    let mut err = vec![[0f32; 3]; w * h];
    let rows_done = AtomicU64::new(0);
    let n = opts.spp as f64;
    progress.begin("path tracing", h as u64);
    // Rayon works on a scoped thread while this one reports progress (Progress need not be Sync).
    std::thread::scope(|s| {
        let work = s.spawn(|| {
            mean.par_chunks_mut(w)
                .zip(direct.par_chunks_mut(w))
                .zip(err.par_chunks_mut(w))
                .enumerate()
                .for_each(|(y, ((m_row, d_row), e_row))| {
                    for x in 0..w {
                        let mut rng = Rng::new(opts.seed, (y * w + x) as u64);
                        let (mut sum, mut sum2, mut dsum) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
                        for _ in 0..opts.spp {
                            let px = x as f64 + rng.uniform();
                            let py = y as f64 + rng.uniform();
                            let r = tracer.radiance(view.eye, view.ray(px, py), &mut rng);
                            sum += r.total;
                            sum2 += r.total * r.total;
                            dsum += r.direct;
                        }
                        let m = sum / n;
                        // Unbiased sample variance of the mean: (Σx² − n·m²) / (n(n−1)).
                        let var = if opts.spp > 1 {
                            ((sum2 - m * m * n) / (n * (n - 1.0))).max(DVec3::ZERO)
                        } else {
                            DVec3::ZERO
                        };
                        m_row[x] = to_f32(m);
                        d_row[x] = to_f32(dsum / n);
                        e_row[x] = to_f32(var.map(f64::sqrt));
                    }
                    rows_done.fetch_add(1, Ordering::Relaxed);
                });
        });
        let mut reported = 0;
        // Poll often (the wall time is measured, and short runs must not wait for a tick).
        while !work.is_finished() {
            std::thread::sleep(Duration::from_millis(2));
            let d = rows_done.load(Ordering::Relaxed);
            progress.advance(d - reported);
            reported = d;
        }
        progress.advance(rows_done.load(Ordering::Relaxed) - reported);
        work.join().expect("path tracing thread panicked");
    });
    progress.end();
    let image = Image {
        width: view.width,
        height: view.height,
        pixels: mean,
    };
    let std_error = Image {
        width: view.width,
        height: view.height,
        pixels: err,
    };
    let mean_lum = image.pixels.iter().map(|&p| luminance(p)).sum::<f64>() / (w * h) as f64;
    let mean_err = std_error.pixels.iter().map(|&p| luminance(p)).sum::<f64>() / (w * h) as f64;
    let mut rel: Vec<f64> = image
        .pixels
        .iter()
        .zip(&std_error.pixels)
        .filter(|(p, _)| luminance(**p) > 1e-3 * mean_lum)
        .map(|(p, e)| luminance(*e) / luminance(*p))
        .collect();
    rel.sort_by(f64::total_cmp);
    let pct = |q: f64| {
        if rel.is_empty() {
            0.0
        } else {
            rel[((rel.len() - 1) as f64 * q).round() as usize]
        }
    };
    let known = opts.spp > 1;
    let stats = ReferenceStats {
        spp: opts.spp,
        seed: opts.seed,
        max_bounces: opts.max_bounces,
        total_ms: t0.elapsed().as_secs_f64() * 1e3,
        threads: rayon::current_num_threads(),
        mean_relative_std_error: known.then_some(if mean_lum > 0.0 {
            mean_err / mean_lum
        } else {
            0.0
        }),
        median_pixel_relative_std_error: known.then(|| pct(0.5)),
        p95_pixel_relative_std_error: known.then(|| pct(0.95)),
    };

    Ok(Reference {
        image,
        direct: Image {
            width: view.width,
            height: view.height,
            pixels: direct,
        },
        std_error: known.then_some(std_error),
        stats,
    })
}

impl Reference {
    /// Writes `exr`, its `.direct.exr` and (above 1 spp) its `.stderr.exr`; returns the paths.
    pub fn write(&self, exr: &std::path::Path) -> Result<Vec<std::path::PathBuf>> {
        let (direct, stderr) = sibling_paths(exr);
        self.image.write_exr(exr)?;
        self.direct.write_exr(&direct)?;
        let mut out = vec![exr.to_path_buf(), direct];
        if let Some(e) = &self.std_error {
            e.write_exr(&stderr)?;
            out.push(stderr);
        }
        Ok(out)
    }
}

impl ReferenceStats {
    /// A summary for a log: time, threads and how converged the image is.
    pub fn summary(&self) -> String {
        let conv = match (
            self.mean_relative_std_error,
            self.median_pixel_relative_std_error,
            self.p95_pixel_relative_std_error,
        ) {
            (Some(m), Some(med), Some(p95)) => format!(
                "standard error {:.3}% of the image mean; per lit pixel median {:.3}%, 95th \
                 percentile {:.3}%",
                m * 100.0,
                med * 100.0,
                p95 * 100.0
            ),
            _ => "standard error unknown at 1 spp".to_string(),
        };
        format!(
            "{} spp on {} threads in {:.1} s; {conv}",
            self.spp,
            self.threads,
            self.total_ms / 1e3
        )
    }
}

/// The file names written beside a reference `ref.exr`: `ref.direct.exr` (paths with at most one
/// reflection, for the indirect-only error) and `ref.stderr.exr` (per-pixel standard error).
pub fn sibling_paths(exr: &std::path::Path) -> (std::path::PathBuf, std::path::PathBuf) {
    let stem = exr.with_extension("");
    (
        stem.with_extension("direct.exr"),
        stem.with_extension("stderr.exr"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sibling_names() {
        let (d, e) = sibling_paths(std::path::Path::new("out/ref.exr"));
        assert_eq!(d, std::path::PathBuf::from("out/ref.direct.exr"));
        assert_eq!(e, std::path::PathBuf::from("out/ref.stderr.exr"));
    }
}
