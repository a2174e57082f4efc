//! `antiradiance` command-line tool: parses arguments into options and calls the library.

mod cli;

use antiradiance::engine::{Engine, Options};
use antiradiance::frame::image::{check_output_path, write_atomic};
use antiradiance::frame::Image;
use antiradiance::{info::Info, scene, Scene};
use anyhow::{Context, Result};
use clap::Parser;
use cli::args::{Cli, Command};
use cli::progress::Bars;
use std::path::{Path, PathBuf};

fn default_scene() -> PathBuf {
    let bundled = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.toml");
    if bundled.is_file() {
        bundled
    } else {
        PathBuf::from("scenes/cornell-box.toml")
    }
}

/// The scene's file, to name it in errors that arise after loading (discretization, device).
fn scene_name(s: &Scene) -> String {
    s.path
        .as_ref()
        .map_or("<scene>".into(), |p| p.display().to_string())
}

fn load(path: Option<PathBuf>) -> Result<Scene> {
    let path = path.unwrap_or_else(default_scene);
    let s = scene::load_scene(&path)?;
    for w in &s.warnings {
        eprintln!("warning: {w}");
    }
    Ok(s)
}

fn write_json(path: &Option<PathBuf>, value: &impl serde::Serialize) -> Result<()> {
    if let Some(p) = path {
        let text = serde_json::to_string_pretty(value)?;
        write_atomic(p, |w| std::io::Write::write_all(w, text.as_bytes()))?;
    }
    Ok(())
}

/// Refuses, before any work, an output that could not be written (nothing is left half-done).
fn check_outputs<'a>(paths: impl IntoIterator<Item = Option<&'a PathBuf>>) -> Result<()> {
    for p in paths.into_iter().flatten() {
        check_output_path(p)?;
    }
    Ok(())
}

/// What `-o PATH` asks for, by its extension: an 8-bit PNG (`.png`), or linear EXR radiance
/// (`.exr`, as `--exr` writes); anything else is refused before any work.
enum Picture {
    Png(PathBuf),
    Exr(PathBuf),
}

fn picture(path: PathBuf) -> Result<Picture> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("png") => Ok(Picture::Png(path)),
        Some("exr") => Ok(Picture::Exr(path)),
        _ => anyhow::bail!(
            "{}: --output writes PNG (.png) or linear EXR (.exr); name the file with one of those extensions",
            path.display()
        ),
    }
}

/// Writes `image` to `-o`'s picture: PNG at `exposure`, or EXR.
fn write_picture(image: &antiradiance::frame::Image, p: &Picture, exposure: f64) -> Result<()> {
    let path = match p {
        Picture::Png(path) => {
            image.write_png(path, exposure)?;
            path
        }
        Picture::Exr(path) => {
            image.write_exr(path)?;
            path
        }
    };
    wrote(path);
    Ok(())
}

fn picture_path(p: &Option<Picture>) -> Option<&PathBuf> {
    p.as_ref().map(|p| match p {
        Picture::Png(path) | Picture::Exr(path) => path,
    })
}

fn wrote(p: &Path) {
    eprintln!("wrote {}", p.display());
}

/// Errors are one line (`Error: ...`, causes joined with `: `), whatever RUST_BACKTRACE says.
/// Keeps freed heap memory mapped for this process (glibc's trim and mmap thresholds).
/// lavapipe frees and reallocates its binned scene (64 KB blocks, tens of MB per global pass)
/// at every render pass; with glibc's default trim threshold the freed top of the heap goes back
/// to the kernel and is faulted in and zeroed again the next pass. Setting a threshold turns
/// glibc's adaptive mmap threshold off, so it is fixed at its largest (32 MB): otherwise every
/// buffer above 128 KB (shadow atlases, tables read back) would be a fresh mmap. Measured: the
/// Cornell box's system time per `profile` run 1.2 → 0.6 s, 4–7% off the iteration; Veach's
/// light setup unchanged (1.4 s with the trim threshold alone). The driver's choice, not the
/// library's: an embedding host keeps its own allocator settings.
fn keep_freed_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only changes the allocator's parameters; called before any other thread.
    unsafe {
        libc::mallopt(libc::M_TRIM_THRESHOLD, 1 << 30);
        libc::mallopt(libc::M_MMAP_THRESHOLD, 32 << 20);
    }
}

fn main() -> std::process::ExitCode {
    keep_freed_memory();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if !e.use_stderr() => e.exit(), // --help, --version
        Err(e) => {
            // clap's first line names the flag and the value; usage hints are dropped.
            let text = e.to_string();
            let line = text.lines().next().unwrap_or("invalid arguments");
            eprintln!("Error: {}", line.trim_start_matches("error: "));
            return std::process::ExitCode::from(2);
        }
    };
    match run(cli) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("Error: {}", format!("{e:#}").replace('\n', " "));
            std::process::ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Animate {
            scene,
            out,
            frames,
            fps,
            exr,
            iterations_per_frame,
            solver,
            size,
            exposure,
            backend,
            shadow_map_size,
            device,
        } => {
            let s = load(Some(scene))?;
            let name = scene_name(&s);
            let args = cli::animate::AnimateArgs {
                out,
                frames,
                fps,
                exr,
                iterations_per_frame,
                solver,
                size,
                exposure,
                backend,
                shadow_map_size,
                device,
            };
            cli::animate::run(&s, args, &name)?;
        }
        Command::Compare {
            test,
            reference,
            diff,
        } => {
            check_outputs([diff.as_ref()])?;
            let (t, r) = (Image::read_exr(&test)?, Image::read_exr(&reference)?);
            t.check_finite(&test)?;
            r.check_finite(&reference)?;
            let m = antiradiance::metrics::compare(&t, &r)?;
            println!("{}", serde_json::to_string_pretty(&m)?);
            if let Some(p) = diff {
                antiradiance::metrics::difference_map(&t, &r, 0.5)?.write_png(&p, 0.0)?;
                wrote(&p);
            }
        }
        Command::Study {
            scene,
            reference,
            out,
            iterations,
            bins,
            element_sizes,
            spp,
            methods,
            rays_per_link,
            subdivisions,
            vpls,
            one_scheme,
            one_precision,
            backend,
            device,
        } => {
            let s = load(scene)?;
            std::fs::create_dir_all(&out).with_context(|| format!("{}", out.display()))?;
            check_outputs([Some(&out.join("study.csv"))])?;
            let truth = antiradiance::study::Truth::load(&reference)?;
            if let Some(why) = truth.no_indirect_reason() {
                eprintln!("note: {why}; the indirect-only columns stay empty");
            }
            let mut o = antiradiance::study::StudyOptions::defaults(&s, out.clone());
            o.iterations = iterations as usize;
            o.bins = bins.unwrap_or(o.bins);
            o.element_sizes = element_sizes.unwrap_or(o.element_sizes);
            o.spp = spp.unwrap_or(o.spp);
            o.methods = methods.unwrap_or(o.methods);
            o.rays_per_link = rays_per_link.unwrap_or(o.rays_per_link);
            o.subdivisions = subdivisions.unwrap_or(o.subdivisions);
            o.vpls = vpls.unwrap_or(o.vpls);
            o.both_schemes = !one_scheme;
            o.both_precisions = !one_precision;
            o.render.backend = backend;
            o.render.device = device;
            let rows = antiradiance::study::run(&s, &truth, &o, &Bars::default(), &mut |r| {
                eprintln!("{}", r.summary());
            })?;
            let cross = antiradiance::study::write(&rows, &out)?;
            eprintln!("full image, relative RMSE: {cross}");
            eprintln!(
                "wrote {}/study.csv, error-vs-time.png, convergence.png",
                out.display()
            );
        }
        Command::Reference {
            scene,
            spp,
            exr,
            max_bounces,
            seed,
            size,
            output,
            exposure,
            json,
        } => {
            let (direct, stderr) = antiradiance::reference::sibling_paths(&exr);
            let output = output.map(picture).transpose()?;
            check_outputs([
                Some(&exr),
                Some(&direct),
                Some(&stderr),
                picture_path(&output),
                json.as_ref(),
            ])?;
            let mut s = load(scene)?;
            // The path tracer renders the scene's camera at the requested size.
            let camera = Options {
                width: size.width,
                height: size.height,
                ..Options::default()
            }
            .resolve(&s)?
            .camera;
            s.camera = camera;
            let opts = antiradiance::reference::ReferenceOptions {
                spp,
                max_bounces,
                seed,
            };
            let r = antiradiance::reference::render_reference(&s, &opts, &Bars::default())?;
            eprintln!("{}", r.stats.summary());
            for p in r.write(&exr)? {
                wrote(&p);
            }
            if let Some(p) = &output {
                write_picture(&r.image, p, exposure)?;
            }
            write_json(&json, &r.stats)?;
        }
        Command::Profile {
            scene,
            frames,
            warmup,
            bins,
            precision,
            json,
            device,
            plan,
        } => {
            check_outputs([json.as_ref()])?;
            let s = load(scene)?;
            let mut o = plan.options();
            o.solver.bins = bins;
            o.solver.precision = precision;
            o.device = device;
            if let Some(c) = o.resolve(&s)?.target {
                eprintln!("{}", c.summary());
            }
            let report = antiradiance::profile::profile(&s, &o, frames as usize, warmup as usize)
                .with_context(|| scene_name(&s))?;
            print!("{}", report.text());
            write_json(&json, &report)?;
        }
        Command::View {
            scene,
            solver,
            size,
            frames,
            screenshot,
            resize,
            step,
            shadow_map_size,
            exposure,
            device,
            plan,
        } => {
            if let Some(p) = &screenshot {
                // The presented image is 8-bit sRGB: a PNG.
                if !matches!(picture(p.clone())?, Picture::Png(_)) {
                    anyhow::bail!(
                        "{}: --screenshot writes the presented 8-bit image as PNG (.png)",
                        p.display()
                    );
                }
            }
            check_outputs([screenshot.as_ref()])?;
            let s = load(scene)?;
            let mut o = plan.options();
            o.solver = solver.overrides();
            o.width = size.width;
            o.height = size.height;
            o.shadow_map_size = shadow_map_size;
            o.device = device;
            let name = scene_name(&s);
            cli::view::run(cli::view::ViewRequest {
                scene: s,
                options: o,
                frames,
                screenshot,
                resize,
                step,
                exposure,
            })
            .with_context(|| name)?;
        }
        Command::Info { scene, json, plan } => {
            let s = load(scene)?;
            let o = plan.options();
            if let Some(c) = o.resolve(&s)?.target {
                eprintln!("{}", c.summary());
            }
            let info = Info::of(&s, &o, &antiradiance::progress::Silent)
                .with_context(|| scene_name(&s))?;
            if json {
                println!("{}", serde_json::to_string_pretty(&info)?);
            } else {
                print!("{}", info.text());
            }
        }
        Command::Render {
            scene,
            output,
            exr,
            json,
            time,
            solver,
            tolerance,
            max_iterations,
            size,
            exposure,
            backend,
            method,
            baseline,
            shadow_map_size,
            device,
            plan,
        } => {
            let picture = match output.clone() {
                Some(p) => Some(picture(p)?),
                None => exr
                    .is_none()
                    .then(|| Picture::Png(PathBuf::from("out.png"))),
            };
            check_outputs([picture_path(&picture), exr.as_ref(), json.as_ref()])?;
            let mut s = load(scene)?;
            if let Some(t) = time {
                s.move_to(t);
            }
            // One frame: linked for where things stand, not for the keyframes' motion.
            let s = s.still();
            let mut o = plan.options();
            o.solver = solver.overrides();
            o.solver.tolerance = tolerance;
            o.solver.max_iterations = max_iterations;
            o.width = size.width;
            o.height = size.height;
            o.backend = backend;
            o.method = method;
            o.baseline = baseline.settings();
            o.shadow_map_size = shadow_map_size;
            o.device = device;
            let bars = Bars::default();
            let r = Engine::new(&s, &o, &bars)
                .and_then(|mut e| e.render(&bars))
                .with_context(|| scene_name(&s))?;
            report(&r.stats);
            if let Some(p) = &exr {
                r.image.write_exr(p)?;
                wrote(p);
            }
            if let Some(p) = &picture {
                write_picture(&r.image, p, exposure)?;
            }
            write_json(&json, &r.stats)?;
        }
    }
    Ok(())
}

/// What a render did, on stderr: the target choice, fallbacks, residual per iteration,
/// warnings, the estimated error and the sizes.
fn report(st: &antiradiance::engine::RenderStats) {
    if let Some(c) = &st.target {
        eprintln!("{}", c.summary());
    }
    for f in &st.fallbacks {
        eprintln!("fallback: {f}");
    }
    for (i, (res, e)) in st.residuals.iter().zip(&st.energies).enumerate() {
        eprintln!(
            "iteration {:>3}: residual {res:.3e}, exitant flux {e:.4e} W",
            i + 1
        );
    }
    for w in &st.warnings {
        eprintln!("warning: {w}");
    }
    if st.iterations == 0 {
        eprintln!("note: 0 iterations: the image shows emission and direct light only, no interreflection");
    }
    if let Some(e) = st.estimated_error {
        let tail = match st.extrapolations {
            0 => String::new(),
            n => format!(", {n} tail extrapolation{}", if n == 1 { "" } else { "s" }),
        };
        eprintln!(
            "estimated error {e:.2e} ({} scheme, {} tables{tail})",
            st.scheme, st.precision
        );
    }
    eprintln!(
        "{} elements, {} links, {} bins on {}; {:.0} ms in all",
        st.elements, st.links, st.bins, st.device, st.total_ms
    );
}
