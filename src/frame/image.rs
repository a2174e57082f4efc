//! Frames as linear RGB radiance, written as EXR (linear float, comparable pixel by pixel with a
//! Mitsuba 3 render of the same scene) or PNG (exposure, then the sRGB transfer curve).

use crate::error::{Error, Result};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

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

/// The file an output at `path` really lands in (through a symbolic link), refused when it is
/// a directory or not a regular file, or when its folder does not exist.
fn output_target(path: &Path) -> Result<PathBuf> {
    let target = match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => {
            std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf())
        }
        _ => path.to_path_buf(),
    };
    if let Ok(m) = std::fs::metadata(&target) {
        if m.is_dir() {
            return Err(io_err(path, "is a directory; give a file name"));
        }
        if !m.is_file() {
            return Err(io_err(
                path,
                "is not a regular file (outputs are written beside it and renamed over it)",
            ));
        }
    }
    if target.file_name().is_none() {
        return Err(io_err(path, "names no file"));
    }
    let folder = folder_of(&target);
    match std::fs::metadata(folder) {
        Ok(m) if m.is_dir() => Ok(target),
        Ok(_) => Err(io_err(
            path,
            format!("{} is not a folder", folder.display()),
        )),
        Err(_) => Err(io_err(
            path,
            format!("folder {} does not exist", folder.display()),
        )),
    }
}

/// The folder a file path lies in (`.` for a bare name).
fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Creates a new, empty temporary file beside `target`.
fn temporary_beside(target: &Path) -> std::io::Result<(PathBuf, File)> {
    use std::sync::atomic::{AtomicU64, Ordering};
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let name = target.file_name().unwrap_or_default().to_string_lossy();
    loop {
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let tmp = folder_of(target).join(format!(".{name}.{}.{n}.tmp", std::process::id()));
        match std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)
        {
            Ok(f) => return Ok((tmp, f)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
}

/// Refuses, with one line naming `path`, an output path that could not be written: a
/// directory, something other than a regular file, a folder that does not exist or cannot be
/// written. Meant to run before any work whose result would go there.
pub fn check_output_path(path: &Path) -> Result<()> {
    let target = output_target(path)?;
    let folder = folder_of(&target);
    let (tmp, file) = temporary_beside(&target).map_err(|e| {
        io_err(
            path,
            format!("cannot write in folder {}: {e}", folder.display()),
        )
    })?;
    drop(file);
    let _ = std::fs::remove_file(tmp);
    Ok(())
}

/// Writes `path` completely or not at all: `write` fills a temporary file in the same folder,
/// which replaces `path` (by a rename) only once `write` succeeded and the data is on disk. On
/// any failure the temporary file is removed and `path` is left as it was.
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>,
) -> Result<()> {
    let target = output_target(path)?;
    let (tmp, file) = temporary_beside(&target).map_err(|e| {
        io_err(
            path,
            format!(
                "cannot write in folder {}: {e}",
                folder_of(&target).display()
            ),
        )
    })?;
    let mut w = BufWriter::new(file);
    let written = write(&mut w)
        .and_then(|()| w.flush())
        .and_then(|()| w.into_inner().map_err(|e| e.into_error()))
        .and_then(|f| f.sync_all())
        .and_then(|()| std::fs::rename(&tmp, &target));
    written.map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io_err(path, format!("not written: {e}"))
    })
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
    /// Each k×k block of pixels replaced by its mean (a supersampled frame reduced to the
    /// image: the box filter over the pixel the path tracer integrates). `k` divides both sides.
    pub fn box_reduced(self, k: u32) -> Image {
        if k <= 1 {
            return self;
        }
        let (w, h) = (self.width / k, self.height / k);
        debug_assert_eq!((w * k, h * k), (self.width, self.height));
        let mut pixels = vec![[0.0f32; 3]; (w * h) as usize];
        let scale = 1.0 / (k * k) as f64;
        for y in 0..h {
            for x in 0..w {
                let mut sum = [0.0f64; 3];
                for dy in 0..k {
                    for dx in 0..k {
                        let p = self.at(x * k + dx, y * k + dy);
                        for c in 0..3 {
                            sum[c] += p[c] as f64;
                        }
                    }
                }
                pixels[(y * w + x) as usize] = sum.map(|v| (v * scale) as f32);
            }
        }
        Image {
            width: w,
            height: h,
            pixels,
        }
    }

    /// Pixel (x, y).
    pub fn at(&self, x: u32, y: u32) -> [f32; 3] {
        self.pixels[(y * self.width + x) as usize]
    }

    /// True when every channel of every pixel is finite.
    pub fn is_finite(&self) -> bool {
        self.pixels.iter().all(|p| p.iter().all(|c| c.is_finite()))
    }

    /// The first non-finite pixel (x, y, value) and how many there are.
    fn non_finite(&self) -> Option<(u32, u32, [f32; 3], usize)> {
        let bad = |p: &&[f32; 3]| !p.iter().all(|c| c.is_finite());
        let i = self.pixels.iter().position(|p| bad(&p))?;
        let count = self.pixels.iter().filter(bad).count();
        Some((
            i as u32 % self.width,
            i as u32 / self.width,
            self.pixels[i],
            count,
        ))
    }

    /// An error naming `path` (the file this image came from or goes to) when a pixel is not
    /// finite: metrics of such an image mean nothing, and a NaN in an output file is never what
    /// a user wants.
    pub fn check_finite(&self, path: &Path) -> Result<()> {
        match self.non_finite() {
            None => Ok(()),
            Some((x, y, p, n)) => Err(io_err(
                path,
                format!("pixel ({x}, {y}) is {p:?}, not finite ({n} non-finite pixels)"),
            )),
        }
    }

    /// [`Image::check_finite`] before writing `path`.
    fn check_writable(&self, path: &Path) -> Result<()> {
        self.check_finite(path).map_err(|e| match e {
            Error::Output { path, message } => Error::Output {
                path,
                message: format!("not written: {message}"),
            },
            e => e,
        })
    }

    /// Writes linear float RGB (32-bit channels), atomically ([`write_atomic`]); refuses
    /// non-finite pixels.
    pub fn write_exr(&self, path: &Path) -> Result<()> {
        use exr::prelude::*;
        self.check_writable(path)?;
        write_atomic(path, |w| {
            let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
                let p = self.pixels[y * self.width as usize + x];
                (p[0], p[1], p[2])
            });
            Image::from_channels((self.width as usize, self.height as usize), channels)
                .write()
                .to_buffered(w)
                .map_err(std::io::Error::other)
        })
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

    /// Writes 8-bit sRGB after multiplying by `2^exposure`, atomically ([`write_atomic`]), in
    /// the format the extension names; refuses non-finite pixels.
    pub fn write_png(&self, path: &Path, exposure: f64) -> Result<()> {
        self.check_writable(path)?;
        let format = image::ImageFormat::from_path(path).map_err(|e| io_err(path, e))?;
        let k = 2f32.powf(exposure as f32);
        let bytes: Vec<u8> = self
            .pixels
            .iter()
            .flat_map(|p| p.map(|c| (srgb_encode(c * k) * 255.0 + 0.5) as u8))
            .collect();
        write_atomic(path, |w| {
            image::write_buffer_with_format(
                w,
                &bytes,
                self.width,
                self.height,
                image::ColorType::Rgb8,
                format,
            )
            .map_err(std::io::Error::other)
        })
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

#[cfg(test)]
mod tests {
    use super::*;

    fn folder(name: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("antiradiance-image-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn entries(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    fn image(v: f32) -> Image {
        Image {
            width: 3,
            height: 2,
            pixels: vec![[v, 0.5, 0.25]; 6],
        }
    }

    #[test]
    fn box_reduction_averages_each_block() {
        let pixels = (0..24).map(|i| [i as f32, 1.0, -(i as f32)]).collect();
        let big = Image {
            width: 6,
            height: 4,
            pixels,
        };
        let small = big.clone().box_reduced(2);
        assert_eq!((small.width, small.height), (3, 2));
        // Block (1, 1) holds pixels 14, 15, 20, 21 of the 6-wide image.
        assert_eq!(small.at(1, 1), [17.5, 1.0, -17.5]);
        assert_eq!(small.at(0, 0), [3.5, 1.0, -3.5]);
        assert_eq!(big.clone().box_reduced(1).pixels, big.pixels);
    }

    #[test]
    fn writes_are_whole_or_absent() {
        let d = folder("atomic");
        let exr = d.join("a.exr");
        image(1.0).write_exr(&exr).unwrap();
        image(1.0).write_png(&d.join("a.png"), 0.0).unwrap();
        assert_eq!(Image::read_exr(&exr).unwrap(), image(1.0));
        assert_eq!(entries(&d), ["a.exr", "a.png"]);
        // A failure half-way leaves the old file as it was and no temporary file behind.
        let e = write_atomic(&exr, |w| {
            w.write_all(b"partial")?;
            Err(std::io::Error::other("disk full"))
        })
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("a.exr") && e.contains("not written: disk full"),
            "{e}"
        );
        assert_eq!(Image::read_exr(&exr).unwrap(), image(1.0));
        let e = image(f32::NAN)
            .write_exr(&d.join("nan.exr"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("nan.exr") && e.contains("not written: pixel (0, 0)"),
            "{e}"
        );
        let e = image(1.0)
            .write_png(&d.join("a.unknown"), 0.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("a.unknown"), "{e}");
        assert_eq!(entries(&d), ["a.exr", "a.png"]);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn output_paths_are_checked_before_any_work() {
        let d = folder("paths");
        check_output_path(&d.join("fine.png")).unwrap();
        assert!(
            entries(&d).is_empty(),
            "the probe is removed: {:?}",
            entries(&d)
        );
        let e = |p: &Path| check_output_path(p).unwrap_err().to_string();
        assert!(e(&d).contains("is a directory"), "{}", e(&d));
        let missing = d.join("no/such/folder/x.png");
        assert!(e(&missing).contains("does not exist"), "{}", e(&missing));
        std::fs::write(d.join("file"), "").unwrap();
        let under_file = d.join("file/x.png");
        assert!(
            e(&under_file).contains("is not a folder"),
            "{}",
            e(&under_file)
        );
        #[cfg(unix)]
        assert!(e(Path::new("/dev/null")).contains("not a regular file"));
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn non_finite_images_read_but_fail_the_check_naming_the_file() {
        let d = folder("finite");
        let p = d.join("ok.exr");
        image(2.0).write_exr(&p).unwrap();
        let mut img = Image::read_exr(&p).unwrap();
        img.check_finite(&p).unwrap();
        img.pixels[4][1] = f32::INFINITY;
        img.pixels[5][0] = f32::NAN;
        let e = img
            .check_finite(Path::new("test.exr"))
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "test.exr: pixel (1, 1) is [2.0, inf, 0.25], not finite (2 non-finite pixels)"
        );
        std::fs::remove_dir_all(&d).unwrap();
    }
}
