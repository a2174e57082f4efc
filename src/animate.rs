//! An animation rendered headless (§3.3's frame loop): the first frame solved from scratch as
//! `render` does, then every frame moves what is keyframed to its time, updates the engine,
//! runs `iterations_per_frame` warm-started iterations and draws. `antiradiance animate`
//! writes the frames and `frames.csv` from what this hands back.

use crate::engine::motion::UpdateTimes;
use crate::engine::{Engine, Options};
use crate::error::{Error, Result};
use crate::frame::Image;
use crate::progress::{Progress, Silent};
use crate::scene::Scene;
use serde::Serialize;
use std::time::Instant;

/// Frames per second when none is given.
pub const DEFAULT_FPS: f64 = 24.0;

/// How an animation is sampled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sampling {
    /// Number of frames (at least 1).
    pub frames: usize,
    /// Frames per second of scene time: frame k shows time k / fps.
    pub fps: f64,
    /// Degrees the camera turns about its target (around its up vector) from the first frame to
    /// the last: a walk around a scene, which needs no re-solve (0: the scene's camera).
    pub orbit: f64,
}

impl Sampling {
    /// `frames` (default: duration × fps, rounded, at least 1) at `fps` (default
    /// [`DEFAULT_FPS`]); a scene without keyframes needs `frames`.
    pub fn of(scene: &Scene, frames: Option<usize>, fps: Option<f64>) -> Result<Self> {
        let fps = fps.unwrap_or(DEFAULT_FPS);
        if !(fps.is_finite() && fps > 0.0) {
            return Err(Error::Invalid(format!(
                "--fps must be positive and finite, got {fps}"
            )));
        }
        let frames = match (frames, scene.duration) {
            (Some(0), _) => return Err(Error::Invalid("--frames must be at least 1".into())),
            (Some(n), _) => n,
            (None, Some(d)) => ((d * fps).round() as usize).max(1),
            (None, None) => {
                return Err(Error::Invalid(
                    "the scene has no keyframes (no [animation] duration): give --frames".into(),
                ))
            }
        };
        Ok(Self {
            frames,
            fps,
            orbit: 0.0,
        })
    }
}

/// What one frame cost and how far its solve was from settled (a row of `frames.csv`).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct FrameRecord {
    /// Frame number from 0.
    pub frame: usize,
    /// Scene time (s).
    pub time: f64,
    /// Following what moved ([`Engine::update`]); for frame 0 preparing the engine.
    pub update_ms: f64,
    /// Iterations (frame 0: the scene's full solve and its draw).
    pub solve_ms: f64,
    /// Drawing the frame into host memory.
    pub draw_ms: f64,
    /// The whole frame.
    pub total_ms: f64,
    /// Iterations run.
    pub iterations: usize,
    /// Relative change of I_ex in the frame's last iteration.
    pub residual: f64,
    /// The update's parts (zero for frame 0); not a CSV column.
    #[serde(skip)]
    pub update_parts: UpdateTimes,
}

impl FrameRecord {
    /// The CSV header, in the order of [`FrameRecord::csv`].
    pub const HEADER: &'static str =
        "frame,time,update_ms,solve_ms,draw_ms,total_ms,iterations,residual";

    /// One CSV line (no newline).
    pub fn csv(&self) -> String {
        format!(
            "{},{},{:.3},{:.3},{:.3},{:.3},{},{:.6e}",
            self.frame,
            self.time,
            self.update_ms,
            self.solve_ms,
            self.draw_ms,
            self.total_ms,
            self.iterations,
            self.residual
        )
    }
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Renders `sampling.frames` frames of `scene` with `options`, handing each image and record
/// to `each` as it is drawn; `progress` counts frames. Returns the records.
pub fn animate(
    scene: &Scene,
    options: &Options,
    sampling: Sampling,
    progress: &dyn Progress,
    each: &mut dyn FnMut(&FrameRecord, &Image) -> Result<()>,
) -> Result<Vec<FrameRecord>> {
    if scene.duration.is_some() && options.method != crate::settings::Method::Antiradiance {
        // Before any frame is written: moving objects and lights need the warm-started solve.
        return Err(Error::Invalid(format!(
            "--method {}: the scene has keyframes, and moving objects and lights need the \
             antiradiance method (a still scene can be walked with --orbit by any method)",
            options.method
        )));
    }
    let mut records = Vec::with_capacity(sampling.frames);
    progress.begin("frames", sampling.frames as u64);
    let t0 = Instant::now();
    let mut engine = Engine::new(&scene.at(0.0), options, &Silent)?;
    let update_ms = ms(t0);
    let t = Instant::now();
    let rendered = engine.render(&Silent)?;
    // The first frame is `render`'s solve and draw in one: both are in `solve_ms`.
    let first = FrameRecord {
        frame: 0,
        time: 0.0,
        update_ms,
        solve_ms: ms(t),
        draw_ms: 0.0,
        total_ms: ms(t0),
        iterations: rendered.stats.iterations,
        residual: rendered.stats.residuals.last().copied().unwrap_or(0.0),
        update_parts: UpdateTimes::default(),
    };
    each(&first, &rendered.image)?;
    records.push(first);
    progress.advance(1);
    let n = engine.prepared().settings.iterations_per_frame;
    // Without keyframes nothing moves: no update (every method can walk a still scene).
    let moves = scene.duration.is_some();
    // The camera as the engine drew frame 0 (its size in output pixels, as set_camera wants).
    let mut base = engine.prepared().camera.clone();
    let k = base.supersample.max(1);
    (base.width, base.height) = (base.width / k, base.height / k);
    for k in 1..sampling.frames {
        let time = k as f64 / sampling.fps;
        let start = Instant::now();
        if moves {
            engine.set_time(time)?;
            engine.update()?;
        }
        if sampling.orbit != 0.0 {
            let turn = sampling.orbit.to_radians() * k as f64 / (sampling.frames - 1) as f64;
            engine.set_camera(orbited(&base, turn))?;
        }
        let update_ms = ms(start);
        let t = Instant::now();
        engine.iterate(n)?;
        let solve_ms = ms(t);
        let t = Instant::now();
        let image = engine.draw()?;
        let draw_ms = ms(t);
        if !image.is_finite() {
            return Err(Error::Numerical(format!(
                "frame {k} (time {time}) has non-finite pixels"
            )));
        }
        let r = FrameRecord {
            frame: k,
            time,
            update_ms,
            solve_ms,
            draw_ms,
            total_ms: ms(start),
            iterations: n,
            residual: engine.last_residual().unwrap_or(0.0),
            update_parts: engine.update_times(),
        };
        each(&r, &image)?;
        records.push(r);
        progress.advance(1);
    }
    progress.end();
    Ok(records)
}

/// `camera` turned by `angle` (radians) about its target, around its up vector.
pub fn orbited(camera: &crate::scene::Camera, angle: f64) -> crate::scene::Camera {
    let axis = camera.up.normalize();
    let q = glam::DQuat::from_axis_angle(axis, angle);
    crate::scene::Camera {
        eye: camera.target + q * (camera.eye - camera.target),
        ..camera.clone()
    }
}

/// A one-line summary of the frame rate: all frames, and the animated ones (after the first,
/// which is solved from scratch).
pub fn summary(records: &[FrameRecord]) -> String {
    let total: f64 = records.iter().map(|r| r.total_ms).sum();
    let rest = &records[1.min(records.len())..];
    let mean = |f: fn(&FrameRecord) -> f64| rest.iter().map(f).sum::<f64>() / rest.len() as f64;
    let mut s = format!("{} frames in {:.1} s", records.len(), total / 1e3);
    if !rest.is_empty() {
        let frame = mean(|r| r.total_ms);
        let iteration = mean(|r| r.solve_ms / r.iterations.max(1) as f64);
        let update = mean(|r| r.update_ms);
        s += &format!(
            "; animated frames {:.1} ms each ({:.2} fps): update {:.1} ms (follow or relink {:.1}, backend {:.1}, shadow maps and direct light {:.1}, carry-over {:.1}; {:.1} iterations' worth), solve {:.1} ms ({:.1} ms per iteration), draw {:.1} ms",
            frame,
            1e3 / frame,
            update,
            mean(|r| r.update_parts.prepare_ms),
            mean(|r| r.update_parts.backend_ms),
            mean(|r| r.update_parts.lights_ms),
            mean(|r| r.update_parts.carry_ms),
            update / iteration,
            mean(|r| r.solve_ms),
            iteration,
            mean(|r| r.draw_ms)
        );
    }
    s
}
