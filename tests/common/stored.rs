//! Path-traced references stored with the tests (`tests/data/references/`), so the suite does not
//! path-trace thousands of samples per pixel on every run: the largest part of its time.
//!
//! A stored reference is named by a fingerprint of everything the path tracer reads: the scene
//! (geometry, materials, lights, environment, camera; not file paths or solver settings) and
//! the options (spp, bounces, seed). The tracer is deterministic for a seed, so a stored
//! reference is the very image the test would render. Each use still checks it: a fresh trace
//! at 1/32 of the samples (another seed) must agree with it within the two images' noise, so a
//! changed path tracer fails the test instead of being measured against an old answer.
//! A missing one is rendered in full (and written when `ANTIRADIANCE_RECORD_REFERENCES=1`):
//! `ANTIRADIANCE_RECORD_REFERENCES=1 cargo test --release` refreshes them all; it does not remove
//! the files of scenes no test renders any more (empty the folder first to prune them).

use antiradiance::frame::Image;
use antiradiance::reference::{render_reference, Reference, ReferenceOptions, ReferenceStats};
use antiradiance::scene::Scene;
use std::io::{Read, Write};
use std::path::PathBuf;

const MAGIC: &[u8; 8] = b"ARREF001";

/// What a stored reference is named by: FNV-1a over the Debug text of the scene as the path
/// tracer sees it and of the options.
pub fn fingerprint(scene: &Scene, opts: &ReferenceOptions) -> u64 {
    let mut s = scene.clone();
    s.path = None;
    s.warnings.clear();
    s.objects.clear();
    s.light_tracks.clear();
    s.duration = None;
    s.solver = Default::default();
    for m in &mut s.meshes {
        m.source = PathBuf::new();
    }
    let text = format!("{s:?}|{}|{:?}|{}", opts.spp, opts.max_bounces, opts.seed);
    text.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

fn path(fp: u64) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/references")
        .join(format!("{fp:016x}.bin"))
}

fn recording() -> bool {
    std::env::var_os("ANTIRADIANCE_RECORD_REFERENCES").is_some_and(|v| v == "1")
}

/// The path tracer's answer for `scene` at `opts`: the stored one, checked against a short fresh
/// trace, or a full render where none is stored.
pub fn reference(scene: &Scene, opts: &ReferenceOptions) -> Reference {
    let silent = &antiradiance::progress::Silent;
    let fp = fingerprint(scene, opts);
    let file = path(fp);
    if !recording() {
        if let Some(stored) = load(&file) {
            check(scene, opts, &stored, &file);
            return stored;
        }
        eprintln!(
            "no stored reference {} ({} spp): rendering it; \
             ANTIRADIANCE_RECORD_REFERENCES=1 stores it",
            file.display(),
            opts.spp
        );
    }
    let r = render_reference(scene, opts, silent).unwrap();
    if recording() {
        save(&file, &r);
    }
    r
}

/// A fresh trace at 1/32 of the samples (at least 32, another seed) must agree with `stored`:
/// their RMSE over the pixels within 1.6× of what the two images' standard errors predict
/// (measured 0.77–1.22 on the 42 stored ones) and their means within 10 standard errors of the
/// difference (measured up to 4.9: the short trace underestimates its fireflies' spread; on a
/// 32² image at 32 spp that is a bias of about 3%).
fn check(scene: &Scene, opts: &ReferenceOptions, stored: &Reference, file: &std::path::Path) {
    let fresh = render_reference(
        scene,
        &ReferenceOptions {
            spp: (opts.spp / 32).max(32),
            max_bounces: opts.max_bounces,
            seed: opts.seed ^ 0x5eed,
        },
        &antiradiance::progress::Silent,
    )
    .unwrap();
    let (a, sa) = (&stored.image, stored.std_error.as_ref().unwrap());
    let (b, sb) = (&fresh.image, fresh.std_error.as_ref().unwrap());
    assert_eq!(
        (a.width, a.height),
        (b.width, b.height),
        "{}",
        file.display()
    );
    let (mut sq, mut var, mut diff, mut n) = (0.0f64, 0.0f64, 0.0f64, 0usize);
    for i in 0..a.pixels.len() {
        for c in 0..3 {
            let d = a.pixels[i][c] as f64 - b.pixels[i][c] as f64;
            sq += d * d;
            var += (sa.pixels[i][c] as f64).powi(2) + (sb.pixels[i][c] as f64).powi(2);
            diff += d;
            n += 1;
        }
    }
    // Two noiseless images (e.g. all black) must be equal.
    let ratio = if var > 0.0 {
        (sq / var).sqrt()
    } else if sq > 0.0 {
        f64::INFINITY
    } else {
        0.0
    };
    // The standard error of the mean difference, from the per-pixel ones (pixels independent).
    let mean_se = var.sqrt() / n as f64;
    let mean_z = if mean_se > 0.0 {
        (diff / n as f64).abs() / mean_se
    } else {
        0.0
    };
    println!(
        "stored reference {}: a fresh {} spp trace is {ratio:.2}× the expected RMSE from it, \
         mean {mean_z:.1} standard errors",
        file.file_name().unwrap().to_string_lossy(),
        fresh.stats.spp
    );
    assert!(
        ratio < 1.6 && mean_z < 10.0,
        "the path tracer no longer gives the stored reference {} ({ratio:.2}× the expected RMSE, \
         mean off by {mean_z:.1} standard errors): if the change is meant, refresh with \
         ANTIRADIANCE_RECORD_REFERENCES=1",
        file.display()
    );
}

fn put_image(out: &mut Vec<u8>, im: &Image) {
    for p in &im.pixels {
        for v in p {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
}

fn save(file: &std::path::Path, r: &Reference) {
    std::fs::create_dir_all(file.parent().unwrap()).unwrap();
    let stats = serde_json::to_vec(&r.stats).unwrap();
    let mut out = Vec::new();
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&r.image.width.to_le_bytes());
    out.extend_from_slice(&r.image.height.to_le_bytes());
    out.extend_from_slice(&(stats.len() as u32).to_le_bytes());
    out.extend_from_slice(&stats);
    put_image(&mut out, &r.image);
    put_image(&mut out, &r.direct);
    put_image(
        &mut out,
        r.std_error
            .as_ref()
            .expect("a reference of more than 1 spp"),
    );
    std::fs::File::create(file)
        .and_then(|mut f| f.write_all(&out))
        .unwrap_or_else(|e| panic!("{}: {e}", file.display()));
}

fn load(file: &std::path::Path) -> Option<Reference> {
    let mut bytes = Vec::new();
    std::fs::File::open(file)
        .ok()?
        .read_to_end(&mut bytes)
        .ok()?;
    assert!(
        bytes.starts_with(MAGIC),
        "{}: not a stored reference",
        file.display()
    );
    let mut at = MAGIC.len();
    let u32_at = |at: &mut usize| {
        let v = u32::from_le_bytes(bytes[*at..*at + 4].try_into().unwrap());
        *at += 4;
        v
    };
    let (w, h, len) = (u32_at(&mut at), u32_at(&mut at), u32_at(&mut at) as usize);
    let stats: ReferenceStats = serde_json::from_slice(&bytes[at..at + len]).unwrap();
    at += len;
    let n = (w * h) as usize;
    assert_eq!(
        bytes.len(),
        at + 3 * n * 12,
        "{}: truncated",
        file.display()
    );
    let mut image = || {
        let pixels = (0..n)
            .map(|_| {
                std::array::from_fn(|_| {
                    let v = f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
                    at += 4;
                    v
                })
            })
            .collect();
        Image {
            width: w,
            height: h,
            pixels,
        }
    };
    let (image, direct, std_error) = (image(), image(), image());
    Some(Reference {
        image,
        direct,
        std_error: Some(std_error),
        stats,
    })
}
