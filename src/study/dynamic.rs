//! `study --animate`: error against time per frame in a moving scene (§3.3's case). Over N
//! frames at a fixed rate, every method draws each frame of the keyframed scene and is measured
//! against that frame's reference (the path tracer at high spp at that scene time, cached on
//! disk under a hash of the scene as it stands then and the reference's settings):
//! antiradiance warm-started at k iterations per frame (frame 0 its full solve); instant
//! radiosity relit per frame; the path tracer from scratch at several spp; and the path tracer
//! accumulating across frames, reset when the scene changed (an interactive path tracer).
//! Writes `frames.csv`, `error-vs-time.png` (one point per method and setting: the means over
//! the animated frames 1..N) and `error-over-frames.png`.

use super::plot::register_font;
use crate::engine::{Engine, Options};
use crate::error::{Error, Result};
use crate::frame::Image;
use crate::metrics::{compare, Metrics};
use crate::progress::{Progress, Silent};
use crate::reference::{render_reference, ReferenceOptions};
use crate::scene::Scene;
use crate::settings::Method;
use plotters::prelude::*;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What the dynamic study runs.
#[derive(Clone)]
pub struct DynamicOptions {
    /// Directory for `frames.csv`, the plots and the reference cache (`cache/`).
    pub out: PathBuf,
    /// Frames (from time 0).
    pub frames: usize,
    /// Frames per second of scene time: frame k shows time k / fps.
    pub fps: f64,
    /// Samples per pixel of each frame's reference.
    pub reference_spp: u32,
    /// Antiradiance's iterations per frame, one run each.
    pub iterations_per_frame: Vec<usize>,
    /// The path tracer from scratch: spp per frame, one run each.
    pub spp: Vec<u32>,
    /// The accumulating path tracer: spp added per frame (0: not run).
    pub accumulate_spp: u32,
    /// Instant radiosity's light paths, relit every frame (0: not run).
    pub vpls: u32,
    /// Backend, device and size of the methods' renders.
    pub render: Options,
    /// Seed of the path tracer runs (the reference uses another).
    pub seed: u64,
    /// Also write every frame's image (`images/METHOD-SETTING-FRAME.exr`) and reference
    /// (`cache/…`), for `compare`.
    pub save_images: bool,
}

impl DynamicOptions {
    /// The default sweep for `frames` frames at `fps`.
    pub fn defaults(out: PathBuf, frames: usize, fps: f64) -> Self {
        Self {
            out,
            frames,
            fps,
            reference_spp: 1024,
            iterations_per_frame: vec![1, 2, 4],
            spp: vec![1, 4, 16],
            accumulate_spp: 4,
            vpls: crate::methods::DEFAULT_VPLS,
            render: Options::default(),
            seed: 0xd1a_57d1,
            save_images: false,
        }
    }
}

/// One row of `frames.csv`.
#[derive(Debug, Clone)]
pub struct FrameRow {
    /// `antiradiance`, `instant-radiosity`, `pathtracer` or `pathtracer-accumulating`.
    pub method: &'static str,
    /// The setting (`4 iterations`, `16 spp`, …).
    pub setting: String,
    /// Frame number from 0.
    pub frame: usize,
    /// Scene time (s).
    pub time: f64,
    /// The frame's cost: update, solve and draw; a from-scratch render's whole time.
    pub frame_ms: f64,
    /// Against the frame's reference.
    pub metrics: Metrics,
    /// That reference: its file in the cache.
    pub reference: PathBuf,
    /// The image's file (`images/…`) when the study saved it.
    pub image: Option<PathBuf>,
}

/// The CSV header of [`csv`].
pub const CSV_HEADER: &str =
    "method,setting,frame,time,frame_ms,rel_rmse,mare,flip,reference,image";

/// `frames.csv`.
pub fn csv(rows: &[FrameRow]) -> String {
    let mut s = format!("{CSV_HEADER}\n");
    for r in rows {
        s += &format!(
            "{},{},{},{},{:.3},{:.6e},{:.6e},{:.6e},{},{}\n",
            r.method,
            r.setting,
            r.frame,
            r.time,
            r.frame_ms,
            r.metrics.rel_rmse,
            r.metrics.mare,
            r.metrics.flip,
            r.reference.display(),
            r.image
                .as_ref()
                .map_or(String::new(), |p| p.display().to_string())
        );
    }
    s
}

/// FNV-1a, 64 bits: the cache's file names.
fn fnv(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// What a frame's image depends on: the scene as it stands (geometry, materials, lights,
/// camera and size; `Scene`'s Debug form writes every number exactly).
fn scene_key(scene: &Scene) -> u64 {
    let mut s = scene.clone();
    s.path = None;
    s.warnings.clear();
    fnv(format!(
        "{:?}|{:?}|{:?}|{:?}|{:?}",
        s.meshes, s.materials, s.lights, s.environment, s.camera
    )
    .as_bytes())
}

/// The reference of `scene` (at some time), from the cache when it holds it. Returns whether it
/// did.
fn reference(
    scene: &Scene,
    o: &DynamicOptions,
    progress: &dyn Progress,
) -> Result<(Image, PathBuf, bool)> {
    let seed = 0x07ef_5eed_u64;
    let key = fnv(format!(
        "{:x}|{}|{seed}|unlimited",
        scene_key(scene),
        o.reference_spp
    )
    .as_bytes());
    let path = o
        .out
        .join("cache")
        .join(format!("reference-{key:016x}.exr"));
    if path.is_file() {
        if let Ok(img) = Image::read_exr(&path) {
            if (img.width, img.height) == (scene.camera.width, scene.camera.height)
                && img.is_finite()
            {
                return Ok((img, path, true));
            }
        }
    }
    let r = render_reference(
        scene,
        &ReferenceOptions {
            spp: o.reference_spp,
            max_bounces: None,
            seed,
        },
        progress,
    )?;
    std::fs::create_dir_all(o.out.join("cache")).map_err(|e| Error::Io {
        path: o.out.join("cache"),
        source: e,
    })?;
    r.image.write_exr(&path)?;
    Ok((r.image, path, false))
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// What [`run`] hands back besides the rows.
pub struct DynamicRun {
    /// One per method, setting and frame.
    pub rows: Vec<FrameRow>,
    /// References read from the cache (the rest were rendered and stored).
    pub cached_references: usize,
}

/// Runs the dynamic study of `scene` (keyframed, or still: then only the camera's frames repeat).
pub fn run(scene: &Scene, o: &DynamicOptions, progress: &dyn Progress) -> Result<DynamicRun> {
    if o.frames == 0 || !(o.fps.is_finite() && o.fps > 0.0) {
        return Err(Error::Invalid(
            "study --animate: --frames must be at least 1 and --fps positive".into(),
        ));
    }
    let mut base = scene.clone();
    let (w, h) = super::study_size(scene, &o.render)?;
    base.camera.width = w;
    base.camera.height = h;
    let mut render = o.render.clone();
    render.width = Some(w);
    render.height = Some(h);
    if render.backend == crate::settings::BackendKind::Gpu && render.context.is_none() {
        render.context = Some(crate::engine::context_for(&render)?);
    }
    let times: Vec<f64> = (0..o.frames).map(|k| k as f64 / o.fps).collect();
    let scenes: Vec<Scene> = times.iter().map(|&t| base.at(t)).collect();
    let mut refs = Vec::new();
    let mut cached = 0;
    for s in &scenes {
        let (img, path, hit) = reference(s, o, progress)?;
        cached += hit as usize;
        refs.push((img, path));
    }
    let images = o.out.join("images");
    if o.save_images {
        std::fs::create_dir_all(&images).map_err(|e| Error::Io {
            path: images.clone(),
            source: e,
        })?;
    }
    let mut rows = Vec::new();
    let mut push = |method: &'static str,
                    setting: String,
                    k: usize,
                    frame_ms: f64,
                    img: &Image|
     -> Result<()> {
        let metrics = compare(img, &refs[k].0)?;
        let image = if o.save_images {
            let name = format!("{method}-{}-{k:03}.exr", setting.replace(' ', "_"));
            img.write_exr(&images.join(&name))?;
            Some(PathBuf::from("images").join(name))
        } else {
            None
        };
        let reference = refs[k]
            .1
            .strip_prefix(&o.out)
            .unwrap_or(&refs[k].1)
            .to_path_buf();
        rows.push(FrameRow {
            method,
            setting,
            frame: k,
            time: times[k],
            frame_ms,
            metrics,
            reference,
            image,
        });
        Ok(())
    };
    // Antiradiance: frame 0 solved from scratch (as `render`), then k warm-started iterations a
    // frame.
    for &n in &o.iterations_per_frame {
        let setting = format!("{n} iterations");
        let t0 = Instant::now();
        let mut engine = Engine::new(&scenes[0], &render, &Silent)?;
        let first = engine.render(&Silent)?;
        push("antiradiance", setting.clone(), 0, ms(t0), &first.image)?;
        for (k, &time) in times.iter().enumerate().skip(1) {
            let t = Instant::now();
            engine.set_time(time)?;
            engine.update()?;
            engine.iterate(n)?;
            let image = engine.draw()?;
            push("antiradiance", setting.clone(), k, ms(t), &image)?;
        }
    }
    // Instant radiosity relights every frame: its engine (virtual lights, their shadow maps) is
    // made anew for each.
    if o.vpls > 0 {
        let mut ir = render.clone();
        ir.method = Method::InstantRadiosity;
        ir.baseline.vpls = o.vpls;
        for (k, s) in scenes.iter().enumerate() {
            let t = Instant::now();
            let r = Engine::new(s, &ir, &Silent)?.render(&Silent)?;
            push(
                "instant-radiosity",
                format!("{} paths", o.vpls),
                k,
                ms(t),
                &r.image,
            )?;
        }
    }
    // The path tracer from scratch every frame.
    for &spp in &o.spp {
        for (k, s) in scenes.iter().enumerate() {
            let opts = ReferenceOptions {
                spp,
                max_bounces: None,
                seed: o.seed.wrapping_add(7919 * k as u64 + spp as u64),
            };
            let t = Instant::now();
            let r = render_reference(s, &opts, &Silent)?;
            push("pathtracer", format!("{spp} spp"), k, ms(t), &r.image)?;
        }
    }
    // The path tracer accumulating while the scene stands still, starting over when it moved.
    if o.accumulate_spp > 0 {
        let n = (w * h) as usize;
        let (mut sum, mut count, mut last) = (vec![[0f64; 3]; n], 0u64, None);
        for (k, s) in scenes.iter().enumerate() {
            let key = scene_key(s);
            if last != Some(key) {
                sum.iter_mut().for_each(|p| *p = [0.0; 3]);
                count = 0;
                last = Some(key);
            }
            let opts = ReferenceOptions {
                spp: o.accumulate_spp,
                max_bounces: None,
                seed: o.seed.wrapping_add(1_000_003 * (k as u64 + 1)),
            };
            let t = Instant::now();
            let r = render_reference(s, &opts, &Silent)?;
            let c = o.accumulate_spp as u64;
            for (acc, p) in sum.iter_mut().zip(&r.image.pixels) {
                for i in 0..3 {
                    acc[i] += p[i] as f64 * c as f64;
                }
            }
            count += c;
            let mut img = r.image.clone();
            for (out, acc) in img.pixels.iter_mut().zip(&sum) {
                *out = acc.map(|v| (v / count as f64) as f32);
            }
            push(
                "pathtracer-accumulating",
                format!("{} spp per frame", o.accumulate_spp),
                k,
                ms(t),
                &img,
            )?;
        }
    }
    Ok(DynamicRun {
        rows,
        cached_references: cached,
    })
}

/// One point per method and setting: the means of frame time and error over frames 1..N (all
/// frames when there is one).
pub fn means(rows: &[FrameRow]) -> Vec<(&'static str, String, f64, f64)> {
    let mut keys: Vec<(&'static str, String)> = Vec::new();
    for r in rows {
        if !keys.iter().any(|(m, s)| *m == r.method && *s == r.setting) {
            keys.push((r.method, r.setting.clone()));
        }
    }
    keys.into_iter()
        .map(|(m, s)| {
            let all: Vec<&FrameRow> = rows
                .iter()
                .filter(|r| r.method == m && r.setting == s)
                .collect();
            let later: Vec<&FrameRow> = all.iter().copied().filter(|r| r.frame > 0).collect();
            let pick = if later.is_empty() { &all } else { &later };
            let n = pick.len().max(1) as f64;
            let t = pick.iter().map(|r| r.frame_ms).sum::<f64>() / n;
            let e = pick.iter().map(|r| r.metrics.rel_rmse).sum::<f64>() / n;
            (m, s, t, e)
        })
        .collect()
}

fn colour(method: &str) -> RGBColor {
    match method {
        "antiradiance" => RGBColor(200, 30, 30),
        "instant-radiosity" => RGBColor(30, 120, 30),
        "image-based-radiosity" => RGBColor(200, 130, 20),
        "pathtracer" => RGBColor(30, 60, 200),
        _ => RGBColor(140, 60, 160),
    }
}

fn plot_err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Output {
        path: path.into(),
        message: format!("cannot draw the plot: {e}"),
    }
}

fn range(v: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = v
        .filter(|x| x.is_finite() && *x > 0.0)
        .fold((f64::MAX, 0.0f64), |(a, b), x| (a.min(x), b.max(x)));
    if hi <= 0.0 {
        (1e-3, 1.0)
    } else {
        (lo / 1.5, hi * 1.5)
    }
}

/// Writes `frames.csv` and the two plots into `dir`.
pub fn write(rows: &[FrameRow], dir: &Path) -> Result<()> {
    let p = dir.join("frames.csv");
    std::fs::write(&p, csv(rows)).map_err(|e| Error::Io {
        path: p.clone(),
        source: e,
    })?;
    register_font();
    let points = means(rows);
    let path = dir.join("error-vs-time.png");
    {
        let root = BitMapBackend::new(&path, (900, 600)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(&path, e))?;
        let (x0, x1) = range(points.iter().map(|p| p.2));
        let (y0, y1) = range(points.iter().map(|p| p.3));
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "per-frame error against per-frame time (means over the animated frames)",
                ("sans-serif", 18),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(|e| plot_err(&path, e))?;
        chart
            .configure_mesh()
            .x_desc("frame time (ms)")
            .y_desc("relative RMSE")
            .draw()
            .map_err(|e| plot_err(&path, e))?;
        for (m, s, t, e) in &points {
            let c = colour(m);
            chart
                .draw_series(std::iter::once(Circle::new((*t, *e), 5, c.filled())))
                .map_err(|e| plot_err(&path, e))?;
            chart
                .draw_series(std::iter::once(Text::new(
                    format!("{m}, {s}"),
                    (*t, *e),
                    ("sans-serif", 12).into_font().color(&c),
                )))
                .map_err(|e| plot_err(&path, e))?;
        }
        root.present().map_err(|e| plot_err(&path, e))?;
    }
    let path = dir.join("error-over-frames.png");
    let root = BitMapBackend::new(&path, (900, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(&path, e))?;
    let frames = rows.iter().map(|r| r.frame).max().unwrap_or(0).max(1);
    let (y0, y1) = range(rows.iter().map(|r| r.metrics.rel_rmse));
    let mut chart = ChartBuilder::on(&root)
        .caption("error over the frames", ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0f64..frames as f64, (y0..y1).log_scale())
        .map_err(|e| plot_err(&path, e))?;
    chart
        .configure_mesh()
        .x_desc("frame")
        .y_desc("relative RMSE")
        .draw()
        .map_err(|e| plot_err(&path, e))?;
    for (m, s, _, _) in &points {
        let c = colour(m);
        let line: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.method == *m && r.setting == *s)
            .map(|r| (r.frame as f64, r.metrics.rel_rmse))
            .collect();
        chart
            .draw_series(LineSeries::new(line, c.stroke_width(2)))
            .map_err(|e| plot_err(&path, e))?
            .label(format!("{m}, {s}"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], c));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(|e| plot_err(&path, e))?;
    root.present().map_err(|e| plot_err(&path, e))?;
    Ok(())
}
