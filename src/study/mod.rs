//! `study`: error against run time. Renders a scene over a sweep of antiradiance settings
//! (iterations 1..N for each of: bins, element sizes, the other scheme, the other precision,
//! each varied alone around the scene's own settings), the baselines as families of their own
//! (hierarchical radiosity with explicit visibility per rays-per-link setting, progressive
//! refinement per subdivision setting, iterations 1..N each, at the scene's settings; instant
//! radiosity once per VPL count) and the
//! path tracer at increasing sample counts, measures wall time (linking apart from the per-frame
//! solve) and the error against a reference, for the full image and for indirect light alone,
//! and writes `study.csv`, `error-vs-time.png` and `convergence.png`.

pub mod dynamic;
pub mod plot;

use crate::engine::{Engine, Options};
use crate::error::{Error, Result};
use crate::frame::Image;
use crate::metrics::{compare, subtract, Metrics};
use crate::progress::Progress;
use crate::reference::{render_reference, ReferenceOptions};
use crate::scene::{Precision, Scene, Scheme};
use crate::settings::{BackendKind, Method};
use std::fmt::Write as _;
use std::path::PathBuf;

/// What to sweep.
#[derive(Clone)]
pub struct StudyOptions {
    /// Directory for `study.csv` and the plots (created if missing).
    pub out: PathBuf,
    /// Antiradiance is rendered after every iteration 1..=`iterations`.
    pub iterations: usize,
    /// Bin counts (each varied alone).
    pub bins: Vec<usize>,
    /// Element sizes (each varied alone; scene units).
    pub element_sizes: Vec<f64>,
    /// Also run the scheme the scene does not use.
    pub both_schemes: bool,
    /// Also run the precision the scene does not use (GPU backend only).
    pub both_precisions: bool,
    /// Path tracer samples per pixel, one run each.
    pub spp: Vec<u32>,
    /// Seed of the path tracer runs; keep it different from the reference's, or their samples
    /// correlate and the error looks smaller than it is.
    pub seed: u64,
    /// Backend, device and any fixed overrides for antiradiance (each run varies one setting
    /// on top of these).
    pub render: Options,
    /// Methods measured (antiradiance's families, and each baseline's).
    pub methods: Vec<Method>,
    /// Visibility rays per link of the hierarchical-radiosity runs, one run each.
    pub rays_per_link: Vec<u32>,
    /// Receiver subdivision levels of the progressive-refinement runs, one run each.
    pub subdivisions: Vec<u32>,
    /// Light paths of the instant-radiosity runs, one image each (they form one curve), and
    /// of the image-based radiosity runs (one curve per cube resolution).
    pub vpls: Vec<u32>,
    /// Cube resolutions of the image-based radiosity runs, one curve each.
    pub cubes: Vec<u32>,
}

impl StudyOptions {
    /// The sweep the `study` command runs by default for `scene`.
    pub fn defaults(scene: &Scene, out: PathBuf) -> Self {
        let e = scene.solver.element_size;
        Self {
            out,
            iterations: 16,
            bins: vec![32, 64, 128, 256, 512],
            element_sizes: vec![2.0 * e, e, 0.5 * e],
            both_schemes: true,
            both_precisions: true,
            spp: vec![1, 4, 16, 64, 256],
            seed: 0x5eed_57d1,
            render: Options::default(),
            methods: Method::ALL.to_vec(),
            rays_per_link: vec![4, 16, crate::methods::DEFAULT_RAYS_PER_LINK, 141],
            subdivisions: vec![0, crate::methods::DEFAULT_SUBDIVISION],
            vpls: vec![16, 64, crate::methods::DEFAULT_VPLS, 1024],
            cubes: vec![64, crate::methods::DEFAULT_CUBE, 256],
        }
    }
}

/// One row of `study.csv`.
#[derive(Debug, Clone)]
pub struct Row {
    /// `antiradiance`, `hierarchical-radiosity`, `progressive-radiosity`, `instant-radiosity`
    /// or `pathtracer`.
    pub method: &'static str,
    /// The parameter varied in this run's family: `base`, `bins`, `element_size`, `scheme`,
    /// `precision` (antiradiance), `rays_per_link` (hierarchical radiosity), `subdivision`
    /// (progressive refinement), `vpls` (instant radiosity), `cube` (image-based radiosity), or
    /// `spp`.
    pub family: String,
    /// Label of the run's curve in the plots.
    pub label: String,
    /// Bins (antiradiance).
    pub bins: Option<usize>,
    /// Element size (antiradiance).
    pub element_size: Option<f64>,
    /// Scheme (antiradiance).
    pub scheme: Option<Scheme>,
    /// Precision (antiradiance, GPU).
    pub precision: Option<Precision>,
    /// Iterations done (antiradiance).
    pub iterations: Option<usize>,
    /// Samples per pixel (path tracer).
    pub spp: Option<u32>,
    /// Leaf elements (antiradiance).
    pub elements: Option<usize>,
    /// Links (antiradiance).
    pub links: Option<usize>,
    /// Meshing + linking (ms; 0 for the path tracer, whose BVH build is in `frame_ms`).
    pub linking_ms: f64,
    /// One-time setup after linking (ms): device resources, pipelines, shadow maps, direct light,
    /// initialization (0 for the path tracer).
    pub setup_ms: f64,
    /// The per-frame part (ms): the iterations up to this one and drawing the frame; for the path
    /// tracer its whole run.
    pub frame_ms: f64,
    /// Residual of the last iteration (antiradiance).
    pub residual: Option<f64>,
    /// Errors of the full image.
    pub full: Metrics,
    /// Errors of the indirect light alone (None without the reference's direct part).
    pub indirect: Option<Metrics>,
    /// Fallbacks the run took.
    pub fallbacks: Vec<String>,
    /// Visibility rays per link (hierarchical radiosity).
    pub rays_per_link: Option<u32>,
    /// Deepest receiver subdivision (progressive refinement).
    pub subdivision: Option<u32>,
    /// Shots up to this image (progressive refinement).
    pub shots: Option<usize>,
    /// Light paths traced (instant radiosity).
    pub vpl_paths: Option<u32>,
    /// VPLs those paths left (instant radiosity).
    pub vpls: Option<usize>,
    /// Cube resolution (image-based radiosity).
    pub cube: Option<u32>,
}

impl Row {
    /// One line for a log: method, run, time and errors.
    pub fn summary(&self) -> String {
        let step = self
            .iterations
            .map(|k| format!("it {k}"))
            .or(self.spp.map(|n| format!("{n} spp")))
            .unwrap_or_default();
        let indirect = self
            .indirect
            .map(|m| format!("  indirect relRMSE {:.4}", m.rel_rmse))
            .unwrap_or_default();
        format!(
            "{:<22} {:<44} {:>8} {:>9.0} ms  relRMSE {:.4}  MARE {:.4}  FLIP {:.4}{indirect}",
            self.method,
            self.label,
            step,
            self.total_ms(),
            self.full.rel_rmse,
            self.full.mare,
            self.full.flip
        )
    }

    /// Linking, setup and frame time (ms): the time to this image from scratch.
    pub fn total_ms(&self) -> f64 {
        self.linking_ms + self.setup_ms + self.frame_ms
    }
}

/// The reference a study measures against.
pub struct Truth {
    /// Full image.
    pub image: Image,
    /// Its part carried by paths with at most one reflection (`ref.direct.exr`).
    pub direct: Option<Image>,
}

/// Indirect light below this fraction of the full image's mean counts as none: relative errors
/// of an image of (almost) zeros are not finite, so those columns stay empty.
const NO_INDIRECT: f64 = 1e-9;

impl Truth {
    /// Why the indirect-only errors are not measured, or `None` when they are.
    pub fn no_indirect_reason(&self) -> Option<String> {
        let Some(d) = &self.direct else {
            return Some("no REF.direct.exr beside the reference".into());
        };
        let mean = |img: &Image| {
            img.pixels
                .iter()
                .flatten()
                .map(|v| v.abs() as f64)
                .sum::<f64>()
                / (3 * img.pixels.len()).max(1) as f64
        };
        let full = mean(&self.image);
        let indirect = subtract(&self.image, d).map(|i| mean(&i)).unwrap_or(0.0);
        (!(indirect > NO_INDIRECT * full)).then(|| {
            format!(
                "the reference has no indirect light (mean {indirect:.3e} against {full:.3e} in all)"
            )
        })
    }

    /// Reads a reference EXR and, when present, its `REF.direct.exr` beside it. Images with a
    /// non-finite pixel are refused (naming the file): no metric of them would be finite.
    pub fn load(path: &std::path::Path) -> Result<Self> {
        let image = Image::read_exr(path)?;
        image.check_finite(path)?;
        let (direct_path, _) = crate::reference::sibling_paths(path);
        let direct = if direct_path.is_file() {
            let d = Image::read_exr(&direct_path)?;
            d.check_finite(&direct_path)?;
            if (d.width, d.height) != (image.width, image.height) {
                return Err(Error::Output {
                    path: direct_path,
                    message: "size differs from the reference beside it".into(),
                });
            }
            Some(d)
        } else {
            None
        };
        Ok(Self { image, direct })
    }
}

struct Config {
    family: &'static str,
    label: String,
    options: Options,
}

fn configs(scene: &Scene, o: &StudyOptions) -> Result<Vec<Config>> {
    let base = o.render.resolve(scene)?.settings;
    let mut out = Vec::new();
    let with = |method: Method, f: &dyn Fn(&mut Options)| {
        let mut options = o.render.clone();
        options.method = method;
        f(&mut options);
        options
    };
    if o.methods.contains(&Method::HierarchicalRadiosity) {
        for &n in &o.rays_per_link {
            out.push(Config {
                family: "rays_per_link",
                label: format!("hierarchical radiosity, {n} rays/link"),
                options: with(Method::HierarchicalRadiosity, &|r| {
                    r.baseline.rays_per_link = n
                }),
            });
        }
    }
    if o.methods.contains(&Method::ProgressiveRadiosity) {
        for &l in &o.subdivisions {
            out.push(Config {
                family: "subdivision",
                label: format!("progressive refinement, subdivision {l}"),
                options: with(Method::ProgressiveRadiosity, &|r| {
                    r.baseline.subdivision = l
                }),
            });
        }
    }
    if o.methods.contains(&Method::InstantRadiosity) {
        // One image per VPL count, all on one curve: nothing iterates.
        for &v in &o.vpls {
            out.push(Config {
                family: "vpls",
                label: "instant radiosity".into(),
                options: with(Method::InstantRadiosity, &|r| {
                    r.baseline.vpls = v;
                    r.solver.iterations = Some(1);
                }),
            });
        }
    }
    if o.methods.contains(&Method::ImageBasedRadiosity) {
        // Per cube resolution a curve of one image per VPL count: the cube is built once.
        for &c in &o.cubes {
            for &v in &o.vpls {
                out.push(Config {
                    family: "cube",
                    label: format!("image-based radiosity, cube {c}"),
                    options: with(Method::ImageBasedRadiosity, &|r| {
                        r.baseline.vpls = v;
                        r.baseline.cube = c;
                        r.solver.iterations = Some(1);
                    }),
                });
            }
        }
    }
    if !o.methods.contains(&Method::Antiradiance) {
        return Ok(out);
    }
    out.push(Config {
        family: "base",
        label: format!(
            "base ({} bins, elem {}, {}, {})",
            base.bins, base.element_size, base.scheme, base.precision
        ),
        options: with(Method::Antiradiance, &|_| {}),
    });
    let mut vary = |family: &'static str, label: String, f: &dyn Fn(&mut Options)| {
        let options = with(Method::Antiradiance, f);
        if options.solver.apply(&base) != base {
            out.push(Config {
                family,
                label,
                options,
            });
        }
    };
    for &b in &o.bins {
        vary("bins", format!("{b} bins"), &|r| r.solver.bins = Some(b));
    }
    for &e in &o.element_sizes {
        vary("element_size", format!("elem {e}"), &|r| {
            r.solver.element_size = Some(e)
        });
    }
    if o.both_schemes {
        let other = base.scheme.other();
        vary("scheme", other.to_string(), &|r| {
            r.solver.scheme = Some(other)
        });
    }
    if o.both_precisions && o.render.backend == BackendKind::Gpu {
        let other = base.precision.other();
        vary("precision", other.to_string(), &|r| {
            r.solver.precision = Some(other)
        });
    }
    Ok(out)
}

fn measure(image: &Image, truth: &Truth) -> Result<(Metrics, Option<Metrics>)> {
    let full = compare(image, &truth.image)?;
    let indirect = match &truth.direct {
        Some(d) if truth.no_indirect_reason().is_none() => {
            Some(compare(&subtract(image, d)?, &subtract(&truth.image, d)?)?)
        }
        _ => None,
    };
    Ok((full, indirect))
}

/// The size a study of `scene` with `render`'s options renders at: the scene camera's, or the
/// options' width and height where given.
pub fn study_size(scene: &Scene, render: &Options) -> Result<(u32, u32)> {
    let c = render.resolve(scene)?.camera;
    Ok((c.width, c.height))
}

/// Runs the sweep on `scene` at [`study_size`] against `truth`, which must be that size, and
/// returns one row per image; `log` receives one line per row as it is measured.
pub fn run(
    scene: &Scene,
    truth: &Truth,
    o: &StudyOptions,
    progress: &dyn Progress,
    log: &mut dyn FnMut(&Row),
) -> Result<Vec<Row>> {
    if o.iterations == 0 {
        return Err(Error::Invalid(
            "study: --iterations must be at least 1".into(),
        ));
    }
    let mut o = o.clone();
    // The study renders at the scene's own size (or `render.width`/`height`), where the path
    // tracer's cost per pixel weighs as it does for a user; the reference must match it.
    let (w, h) = study_size(scene, &o.render)?;
    if (truth.image.width, truth.image.height) != (w, h) {
        return Err(Error::Invalid(format!(
            "the reference is {}×{} but the study renders at {w}×{h} (the scene camera's size, or --width/--height): render the reference with `reference --width {w} --height {h}`, or pass the reference's size to the study",
            truth.image.width, truth.image.height
        )));
    }
    o.render.width = Some(w);
    o.render.height = Some(h);
    o.render.solver.iterations = Some(o.iterations);
    if o.render.backend == BackendKind::Gpu {
        o.render.context = Some(crate::engine::context_for(&o.render)?);
    }
    let mut rows = Vec::new();
    for c in configs(scene, &o)? {
        let mut frames = Vec::new();
        let mut engine = Engine::new(scene, &c.options, progress)?;
        let s = engine.prepared().settings.clone();
        let (stats, _) = engine.render_each_iteration(progress, &mut |f| {
            let (full, indirect) = measure(&f.image, truth)?;
            frames.push((
                f.iteration,
                f.setup_ms,
                f.solve_ms + f.frame_ms,
                full,
                indirect,
            ));
            Ok(())
        })?;
        let method = c.options.method;
        let report = stats.method_report.clone().unwrap_or_default();
        let per_iteration = report.figures.get("shots_per_iteration").copied();
        for (k, setup_ms, ms, full, indirect) in frames {
            let row = Row {
                method: method.as_str(),
                family: c.family.into(),
                label: c.label.clone(),
                bins: Some(stats.bins),
                element_size: Some(s.element_size),
                // Progressive refinement and instant radiosity have no scheme; a baseline
                // reports its own precision.
                scheme: (method.uses_links()).then_some(s.scheme),
                precision: (o.render.backend == BackendKind::Gpu).then_some(
                    if method == Method::Antiradiance {
                        s.precision
                    } else {
                        stats.precision
                    },
                ),
                iterations: Some(k),
                spp: None,
                elements: Some(stats.elements),
                links: Some(stats.links),
                linking_ms: stats.linking_ms,
                setup_ms,
                frame_ms: ms,
                residual: k
                    .checked_sub(1)
                    .and_then(|i| stats.residuals.get(i).copied()),
                full,
                indirect,
                fallbacks: stats.fallbacks.clone(),
                rays_per_link: (method == Method::HierarchicalRadiosity)
                    .then_some(c.options.baseline.rays_per_link),
                subdivision: (method == Method::ProgressiveRadiosity)
                    .then_some(c.options.baseline.subdivision),
                shots: per_iteration.map(|n| (k * n as usize).min(report.shots.len())),
                vpl_paths: matches!(
                    method,
                    Method::InstantRadiosity | Method::ImageBasedRadiosity
                )
                .then_some(c.options.baseline.vpls),
                vpls: report.figures.get("vpls").map(|&v| v as usize),
                cube: (method == Method::ImageBasedRadiosity).then_some(c.options.baseline.cube),
            };
            log(&row);
            rows.push(row);
        }
    }
    let mut scene = scene.clone();
    scene.camera.width = truth.image.width;
    scene.camera.height = truth.image.height;
    for &spp in &o.spp {
        let r = render_reference(
            &scene,
            &ReferenceOptions {
                spp,
                max_bounces: None,
                seed: o.seed,
            },
            progress,
        )?;
        let (full, indirect) = measure(&r.image, truth)?;
        let row = Row {
            method: "pathtracer",
            family: "spp".into(),
            label: "path tracer".into(),
            bins: None,
            element_size: None,
            scheme: None,
            precision: None,
            iterations: None,
            spp: Some(spp),
            elements: None,
            links: None,
            linking_ms: 0.0,
            setup_ms: 0.0,
            frame_ms: r.stats.total_ms,
            residual: None,
            full,
            indirect,
            fallbacks: Vec::new(),
            rays_per_link: None,
            subdivision: None,
            shots: None,
            vpl_paths: None,
            vpls: None,
            cube: None,
        };
        log(&row);
        rows.push(row);
    }
    Ok(rows)
}

/// The CSV header of [`csv`].
pub const CSV_HEADER: &str = "method,family,bins,element_size,scheme,precision,iterations,spp,\
elements,links,linking_ms,setup_ms,frame_ms,total_ms,residual,rel_rmse,mare,flip,indirect_rel_rmse,\
indirect_mare,indirect_flip,fallbacks,rays_per_link,subdivision,shots,vpl_paths,vpls,cube";

/// `study.csv`: one row per run, empty fields where a column does not apply.
pub fn csv(rows: &[Row]) -> String {
    fn opt<T: std::fmt::Display>(v: Option<T>) -> String {
        v.map(|v| v.to_string()).unwrap_or_default()
    }
    let mut s = String::from(CSV_HEADER);
    s.push('\n');
    for r in rows {
        let ind = |f: fn(&Metrics) -> f64| opt(r.indirect.as_ref().map(f));
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{:.3},{:.3},{:.3},{:.3},{},{:.6e},{:.6e},{:.6e},{},{},{},\"{}\",{},{},{},{},{},{}",
            r.method,
            r.family,
            opt(r.bins),
            opt(r.element_size),
            opt(r.scheme),
            opt(r.precision),
            opt(r.iterations),
            opt(r.spp),
            opt(r.elements),
            opt(r.links),
            r.linking_ms,
            r.setup_ms,
            r.frame_ms,
            r.total_ms(),
            opt(r.residual.map(|v| format!("{v:.6e}"))),
            r.full.rel_rmse,
            r.full.mare,
            r.full.flip,
            ind(|m| m.rel_rmse),
            ind(|m| m.mare),
            ind(|m| m.flip),
            r.fallbacks.join("; ").replace('"', "'").replace(',', ";"),
            opt(r.rays_per_link),
            opt(r.subdivision),
            opt(r.shots),
            opt(r.vpl_paths),
            opt(r.vpls),
            opt(r.cube),
        );
    }
    s
}

/// Writes `study.csv`, `error-vs-time.png` and `convergence.png` into `dir`; returns the
/// equal-time comparison (see [`plot::crossover`]) for the full image.
pub fn write(rows: &[Row], dir: &std::path::Path) -> Result<plot::Crossover> {
    std::fs::create_dir_all(dir).map_err(|e| Error::Output {
        path: dir.to_path_buf(),
        message: e.to_string(),
    })?;
    let text = csv(rows);
    crate::frame::image::write_atomic(&dir.join("study.csv"), |w| {
        std::io::Write::write_all(w, text.as_bytes())
    })?;
    // Plots go to a temporary file renamed when complete, like every other output.
    fn whole<T>(
        dir: &std::path::Path,
        name: &str,
        draw: impl FnOnce(&std::path::Path) -> Result<T>,
    ) -> Result<T> {
        let (tmp, path) = (dir.join(format!(".{name}.partial.png")), dir.join(name));
        let out = draw(&tmp).and_then(|v| {
            std::fs::rename(&tmp, &path)
                .map(|_| v)
                .map_err(|e| Error::Output {
                    path: path.clone(),
                    message: e.to_string(),
                })
        });
        if out.is_err() {
            let _ = std::fs::remove_file(&tmp);
        }
        out
    }
    let cross = whole(dir, "error-vs-time.png", |p| plot::error_vs_time(rows, p))?;
    whole(dir, "convergence.png", |p| plot::convergence(rows, p))?;
    Ok(cross)
}
