//! The command line's edge cases (issue 18): flags are checked before any work, errors are one
//! line with an exact exit status, and a failed run leaves no output behind. GPU runs have the
//! validation layer on (`ANTIRADIANCE_VALIDATION=1`), so a validation message is visible here.

mod common;

use antiradiance::frame::Image;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_antiradiance"));
    c.env("ANTIRADIANCE_VALIDATION", "1");
    c
}

fn scratch(name: &str) -> common::Scratch {
    common::Scratch::new(&format!("cli-{name}"))
}

fn scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/accept/one-triangle.toml")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs and expects exit status `code` with one `Error:` line mentioning every needle, and no
/// validation message.
fn refused(args: &[&str], code: i32, needles: &[&str]) {
    let o = bin().args(args).output().unwrap();
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(code), "{args:?}: {e}");
    let errors: Vec<&str> = e.lines().filter(|l| l.starts_with("Error:")).collect();
    assert_eq!(errors.len(), 1, "{args:?}: {e}");
    for n in needles {
        assert!(
            errors[0].contains(n),
            "{args:?}: `{}` lacks `{n}`",
            errors[0]
        );
    }
    assert!(!e.contains("validation"), "{args:?}: {e}");
}

#[test]
fn non_finite_and_out_of_range_flags_are_refused_naming_the_flag() {
    let s = scene();
    let s = s.to_str().unwrap();
    refused(&["render", s, "--exposure", "nan"], 2, &["--exposure"]);
    refused(&["render", s, "--exposure", "inf"], 2, &["--exposure"]);
    refused(&["render", s, "--tolerance", "nan"], 2, &["--tolerance"]);
    refused(
        &["render", s, "--target-error", "-1"],
        2,
        &["--target-error"],
    );
    refused(&["profile", s, "--frames", "0"], 2, &["--frames"]);
    refused(
        &["render", s, "--iterations", "1000000"],
        1,
        &["--iterations"],
    );
    refused(
        &["render", s, "--max-iterations", "0"],
        1,
        &["--max-iterations"],
    );
    refused(&["render", s, "--width", "0"], 1, &["--width"]);
    refused(&["render", s, "--bins", "7"], 1, &["--bins"]);
    refused(&["render", s, "--passes", "0"], 2, &["--passes"]);
    refused(
        &["render", s, "--emitter-map-size", "8"],
        1,
        &["--emitter-map-size"],
    );
    refused(
        &["animate", s, "--out", "o", "--passes", "17"],
        2,
        &["--passes"],
    );
    refused(
        &[
            "render",
            s,
            "--method",
            "image-based-radiosity",
            "--near-rays",
            "5000",
        ],
        1,
        &["--near-rays"],
    );
    // A negative number after a list flag is its value, refused by name.
    refused(
        &[
            "study",
            s,
            "--reference",
            "r.exr",
            "--out",
            "o",
            "--element-sizes",
            "-0.5",
        ],
        2,
        &["--element-sizes", "-0.5"],
    );
    refused(
        &["render", s, "--device", "no such device"],
        1,
        &["no such device"],
    );
}

#[test]
fn zero_iterations_render_direct_light_only_and_say_so() {
    let d = scratch("zero");
    let exr = d.join("z.exr");
    let o = bin()
        .args([
            "render",
            scene().to_str().unwrap(),
            "--backend",
            "cpu",
            "--width",
            "8",
        ])
        .args([
            "--height",
            "8",
            "--iterations",
            "0",
            "--exr",
            exr.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stderr(&o).contains("0 iterations"), "{}", stderr(&o));
    assert!(Image::read_exr(&exr).unwrap().is_finite());
}

#[test]
fn a_bad_output_path_is_refused_before_rendering_and_leaves_nothing() {
    let d = scratch("outputs");
    let png = d.join("out.png");
    let s = scene();
    let args = |json: &str| {
        let mut a = vec!["render", s.to_str().unwrap(), "--backend", "cpu"];
        a.extend(["--width", "8", "--height", "8", "--iterations", "1"]);
        a.extend(["-o", png.to_str().unwrap(), "--json"]);
        a.push(json);
        a.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let bad = d.join("missing/stats.json");
    let o = bin().args(args(bad.to_str().unwrap())).output().unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("missing"), "{}", stderr(&o));
    assert!(!stderr(&o).contains("elements"), "rendered before refusing");
    assert!(!png.exists(), "a PNG was left behind");
    // A directory as an output is refused by name too.
    let o = bin().args(args(d.to_str().unwrap())).output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("directory"), "{}", stderr(&o));
    assert!(!png.exists());
    // Nothing but the outputs in the folder: no temporary files left either.
    let good = d.join("stats.json");
    let o = bin().args(args(good.to_str().unwrap())).output().unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let mut names: Vec<String> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["out.png", "stats.json"]);
}

/// `-o` writes by the extension it is given: `.exr` linear EXR radiance (the same image as
/// `--exr`), `.png` 8-bit sRGB; any other extension is refused before rendering.
#[test]
fn output_format_follows_the_extension() {
    let d = scratch("formats");
    let s = scene();
    let run = |extra: &[&str]| {
        let mut a = vec!["render", s.to_str().unwrap(), "--backend", "cpu"];
        a.extend(["--width", "8", "--height", "8", "--iterations", "1"]);
        a.extend(extra);
        bin().args(a).output().unwrap()
    };
    let (o_exr, exr) = (d.join("o.EXR"), d.join("exr.exr"));
    let o = run(&[
        "-o",
        o_exr.to_str().unwrap(),
        "--exr",
        exr.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let (a, b) = (
        Image::read_exr(&o_exr).unwrap(),
        Image::read_exr(&exr).unwrap(),
    );
    assert_eq!(a.pixels, b.pixels);
    let jpg = d.join("o.jpg");
    refused(
        &["render", s.to_str().unwrap(), "-o", jpg.to_str().unwrap()],
        1,
        &["o.jpg", ".png", ".exr"],
    );
    assert!(!jpg.exists());
}

#[test]
fn compare_refuses_a_non_finite_image_naming_it() {
    let d = scratch("compare");
    let good = Image {
        width: 2,
        height: 2,
        pixels: vec![[1.0; 3]; 4],
    };
    let mut bad = good.clone();
    bad.pixels[3] = [f32::NAN, 1.0, 1.0];
    let (g, b) = (d.join("good.exr"), d.join("bad.exr"));
    good.write_exr(&g).unwrap();
    // The writers refuse non-finite images, so write the bad one's bytes through exr directly.
    exr::prelude::write_rgb_file(&b, 2, 2, |x, y| {
        let p = bad.pixels[y * 2 + x];
        (p[0], p[1], p[2])
    })
    .unwrap();
    refused(
        &["compare", b.to_str().unwrap(), g.to_str().unwrap()],
        1,
        &["bad.exr", "not finite"],
    );
    let o = bin()
        .args(["compare", g.to_str().unwrap(), g.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("\"rel_rmse\": 0.0"));
}

#[test]
fn study_without_indirect_light_leaves_those_columns_empty_and_says_why() {
    let d = scratch("study");
    // A lone triangle under a directional light: the reference has no indirect light at all.
    let reference = d.join("ref.exr");
    let o = bin()
        .args([
            "reference",
            scene().to_str().unwrap(),
            "--spp",
            "4",
            "--width",
            "8",
        ])
        .args(["--height", "8", "--exr", reference.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let out = d.join("study");
    let o = bin()
        .args(["study", scene().to_str().unwrap(), "--reference"])
        .arg(&reference)
        .args([
            "--out",
            out.to_str().unwrap(),
            "--backend",
            "cpu",
            "--iterations",
            "1",
            "--width",
            "8",
            "--height",
            "8",
        ])
        .args([
            "--bins",
            "32",
            "--element-sizes",
            "0.5",
            "--spp",
            "1",
            "--one-scheme",
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stderr(&o).contains("no indirect light"), "{}", stderr(&o));
    let csv = std::fs::read_to_string(out.join("study.csv")).unwrap();
    assert!(!csv.contains("inf") && !csv.contains("NaN"), "{csv}");
    for line in csv.lines().skip(1) {
        let cols: Vec<&str> = line.split(',').collect();
        assert!(cols[18..21].iter().all(|c| c.is_empty()), "{line}");
        assert!(cols[15].parse::<f64>().unwrap().is_finite(), "{line}");
    }
    // The study renders at the scene camera's size unless told: an 8×8 reference is refused,
    // naming the file and the flags, before any work.
    let (r, o2) = (reference.to_str().unwrap(), d.join("study2"));
    refused(
        &[
            "study",
            scene().to_str().unwrap(),
            "--reference",
            r,
            "--out",
            o2.to_str().unwrap(),
        ],
        1,
        &["ref.exr", "8×8", "--width"],
    );
    assert!(!o2.exists());
}

/// A floor and a small plate above it moving on keyframes, under a moving point light.
fn moving_scene(dir: &Path) -> PathBuf {
    let quad = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad-input/quad.obj");
    let text = format!(
        r#"[camera]
eye = [0.5, 1.5, 1.5]
target = [0.5, 0.0, -0.5]
width = 16
height = 16
[solver]
bins = 32
element_size = 0.25
[[light]]
type = "point"
position = [0.5, 1.0, -0.5]
intensity = 1.0
[[light.keyframe]]
time = 0.2
position = [0.3, 1.0, -0.3]
[[object]]
mesh = "{q}"
rotate = {{ axis = [1, 0, 0], angle_deg = -90 }}
[[object]]
mesh = "{q}"
scale = 0.3
rotate = {{ axis = [1, 0, 0], angle_deg = -90 }}
translate = [0.3, 0.5, -0.3]
[[object.keyframe]]
time = 0.2
translate = [0.4, 0.5, -0.4]
"#,
        q = quad.display()
    );
    let p = dir.join("moving.toml");
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn animate_writes_frames_csv_and_a_summary() {
    let d = scratch("animate");
    let s = moving_scene(&d);
    let out = d.join("frames");
    let o = bin()
        .args([
            "animate",
            s.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .args(["--fps", "10", "--exr", "--backend", "cpu"])
        .output()
        .unwrap();
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{e}");
    // Duration 0.2 s (the last key) × 10 fps: 2 frames.
    let csv = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(
        lines[0],
        "frame,time,update_ms,solve_ms,draw_ms,total_ms,iterations,residual"
    );
    assert_eq!(lines.len(), 3, "{csv}");
    assert!(lines[2].starts_with("1,0.1,"), "{csv}");
    for k in 0..2 {
        for ext in ["png", "exr"] {
            let f = out.join(format!("frame-{k:04}.{ext}"));
            assert!(f.is_file(), "{} missing", f.display());
        }
    }
    let a = Image::read_exr(&out.join("frame-0000.exr")).unwrap();
    let b = Image::read_exr(&out.join("frame-0001.exr")).unwrap();
    assert!(a.is_finite() && b.is_finite());
    assert_ne!(a.pixels, b.pixels, "the plate and the light moved");
    assert!(e.contains("fps"), "no frame-rate summary: {e}");
}

#[test]
fn animate_flags_are_checked() {
    let d = scratch("animate-flags");
    let s = moving_scene(&d);
    let (s, out) = (s.to_str().unwrap(), d.join("o"));
    let out = out.to_str().unwrap();
    refused(&["animate", s, "--out", out, "--fps", "0"], 2, &["--fps"]);
    refused(&["animate", s, "--out", out, "--fps", "nan"], 2, &["--fps"]);
    refused(
        &["animate", s, "--out", out, "--frames", "0"],
        2,
        &["--frames"],
    );
    refused(
        &["animate", s, "--out", out, "--iterations-per-frame", "0"],
        2,
        &["--iterations-per-frame"],
    );
    let still = scene();
    refused(
        &["animate", still.to_str().unwrap(), "--out", out],
        1,
        &["--frames"],
    );
    refused(&["render", s, "--time", "nan"], 2, &["--time"]);
    refused(
        &["animate", s, "--out", out, "--orbit", "nan"],
        2,
        &["--orbit"],
    );
    // Keyframes need antiradiance: refused before any frame is written.
    let o2 = d.join("o2");
    refused(
        &[
            "animate",
            s,
            "--out",
            o2.to_str().unwrap(),
            "--method",
            "image-based-radiosity",
        ],
        1,
        &["--method image-based-radiosity", "keyframes"],
    );
    assert!(!o2.join("frame-0000.png").exists());
    let still = scene();
    refused(
        &[
            "render",
            still.to_str().unwrap(),
            "--method",
            "image-based-radiosity",
            "--cube",
            "3",
        ],
        1,
        &["--cube"],
    );
}

/// The CLI reports the plan: `info --json` and `render --json` list `passes`; `--all-passes`
/// forces everything; `--target-error` picks a measured setting and says which.
/// (The scene-adaptive pipeline's library side is tests/adaptive.rs.)
#[test]
fn cli_reports_passes_and_target_error() {
    let exe = env!("CARGO_BIN_EXE_antiradiance");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/adaptive/spot-floor.toml");
    // Every run with the validation layer on: exit status 0 and no validation message.
    let run = |args: &[&str]| {
        let out = std::process::Command::new(exe)
            .env("ANTIRADIANCE_VALIDATION", "1")
            .args(args)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        assert_eq!(out.status.code(), Some(0), "{args:?}: {stderr}");
        assert!(!stderr.contains("vulkan validation"), "{args:?}: {stderr}");
        (out.stdout, stderr)
    };
    let json =
        |args: &[&str]| -> serde_json::Value { serde_json::from_slice(&run(args).0).unwrap() };
    let s = scene.to_str().unwrap();
    let info = json(&["info", s, "--json"]);
    let passes: Vec<&str> = info["passes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert!(passes.contains(&"shadow_spot") && !passes.contains(&"antiradiance"));
    let all = json(&["info", s, "--json", "--all-passes"]);
    assert!(all["passes"]
        .as_array()
        .unwrap()
        .iter()
        .any(|v| v == "antiradiance"));
    assert!(all["memory_bytes"]["tables"].as_u64() > info["memory_bytes"]["tables"].as_u64());
    let dir = scratch("adaptive");
    let stats = dir.join("stats.json");
    let (stats_path, exr) = (stats.to_str().unwrap(), dir.join("out.exr"));
    let (_, stderr) = run(&[
        "render",
        s,
        "--backend",
        "cpu",
        "--target-error",
        "0.6",
        "--width",
        "16",
        "--height",
        "16",
        "--json",
        stats_path,
        "--exr",
        exr.to_str().unwrap(),
    ]);
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
    assert_eq!(r["passes"], info["passes"]);
    let t = &r["target"];
    assert!(t["measured_error"].as_f64().unwrap() <= 0.6, "{t}");
    assert_eq!(r["bins"], t["bins"]);
    assert!(stderr.contains("target error 0.6"), "{stderr}");
    // The GPU backend (the default) reports the same plan, validation on.
    run(&[
        "render",
        s,
        "--width",
        "16",
        "--height",
        "16",
        "--json",
        stats_path,
        "--exr",
        exr.to_str().unwrap(),
    ]);
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
    assert_eq!(r["backend"], "gpu");
    assert_eq!(r["passes"], info["passes"]);
    std::fs::remove_dir_all(&dir).ok();
}
