//! What the commands share: loading the scene, refusing unwritable outputs before any work,
//! writing pictures and JSON, and the render report on stderr.

use antiradiance::frame::image::{check_output_path, write_atomic};
use antiradiance::{scene, Scene};
use anyhow::Result;
use std::path::{Path, PathBuf};

pub fn default_scene() -> PathBuf {
    let bundled = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.toml");
    if bundled.is_file() {
        bundled
    } else {
        PathBuf::from("scenes/cornell-box.toml")
    }
}

/// The scene's file, to name it in errors that arise after loading (discretization, device).
pub fn scene_name(s: &Scene) -> String {
    s.path
        .as_ref()
        .map_or("<scene>".into(), |p| p.display().to_string())
}

pub fn load(path: Option<PathBuf>) -> Result<Scene> {
    let path = path.unwrap_or_else(default_scene);
    let s = scene::load_scene(&path)?;
    for w in &s.warnings {
        eprintln!("warning: {w}");
    }
    Ok(s)
}

pub fn write_json(path: &Option<PathBuf>, value: &impl serde::Serialize) -> Result<()> {
    if let Some(p) = path {
        let text = serde_json::to_string_pretty(value)?;
        write_atomic(p, |w| std::io::Write::write_all(w, text.as_bytes()))?;
    }
    Ok(())
}

/// Refuses, before any work, an output that could not be written (nothing is left half-done).
pub fn check_outputs<'a>(paths: impl IntoIterator<Item = Option<&'a PathBuf>>) -> Result<()> {
    for p in paths.into_iter().flatten() {
        check_output_path(p)?;
    }
    Ok(())
}

/// What `-o PATH` asks for, by its extension: an 8-bit PNG (`.png`), or linear EXR radiance
/// (`.exr`, as `--exr` writes); anything else is refused before any work.
pub enum Picture {
    /// An 8-bit PNG.
    Png(PathBuf),
    /// Linear EXR radiance.
    Exr(PathBuf),
}

pub fn picture(path: PathBuf) -> Result<Picture> {
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
pub fn write_picture(image: &antiradiance::frame::Image, p: &Picture, exposure: f64) -> Result<()> {
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

pub fn picture_path(p: &Option<Picture>) -> Option<&PathBuf> {
    p.as_ref().map(|p| match p {
        Picture::Png(path) | Picture::Exr(path) => path,
    })
}

pub fn wrote(p: &Path) {
    eprintln!("wrote {}", p.display());
}

/// What a render did, on stderr: the target choice, fallbacks, residual per iteration,
/// warnings, the estimated error and the sizes.
pub fn report(st: &antiradiance::engine::RenderStats) {
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
