//! Bad scene input returns a clear error naming the file, never a panic.

use antiradiance::scene::load_scene;
use std::path::{Path, PathBuf};

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("antiradiance-bad-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn write(d: &Path, name: &str, text: &str) -> PathBuf {
    let p = d.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

const QUAD: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";

/// Loads and expects an error mentioning every `needle`.
fn expect_error(scene: &Path, needles: &[&str]) {
    let r = std::panic::catch_unwind(|| load_scene(scene));
    let e = r
        .expect("loader panicked")
        .expect_err("bad input was accepted")
        .to_string();
    assert!(!e.contains('\n'), "error is not one line: {e}");
    for n in needles {
        assert!(e.contains(n), "error `{e}` does not mention `{n}`");
    }
}

#[test]
fn missing_scene_file() {
    expect_error(
        Path::new("/nonexistent/scene.toml"),
        &["/nonexistent/scene.toml"],
    );
}

#[test]
fn malformed_toml_names_file_and_line() {
    let d = dir("toml");
    let p = write(&d, "s.toml", "[solver]\nbins = \"many\"\n");
    expect_error(&p, &["s.toml", "line 2"]);
    let p = write(
        &d,
        "u.toml",
        "[solver]\nbinz = 3\n[[object]]\nmesh = \"q.obj\"\n",
    );
    expect_error(&p, &["u.toml", "binz"]);
}

#[test]
fn missing_mesh_file() {
    let d = dir("nomesh");
    let p = write(&d, "s.toml", "[[object]]\nmesh = \"nothere.obj\"\n");
    expect_error(&p, &["s.toml", "nothere.obj"]);
}

#[test]
fn malformed_obj() {
    let d = dir("obj");
    write(&d, "m.obj", "v 0 0 0\nv 1 0 zero\nf 1 2 3\n");
    let p = write(&d, "s.toml", "[[object]]\nmesh = \"m.obj\"\n");
    expect_error(&p, &["m.obj"]);
    write(&d, "r.obj", "v 0 0 0\nv 1 0 0\nf 1 2 9\n");
    let p = write(&d, "s2.toml", "[[object]]\nmesh = \"r.obj\"\n");
    expect_error(&p, &["r.obj"]);
}

#[test]
fn nan_vertex() {
    let d = dir("nan");
    write(&d, "m.obj", "v 0 0 0\nv 1 NaN 0\nv 1 1 0\nf 1 2 3\n");
    let p = write(&d, "s.toml", "[[object]]\nmesh = \"m.obj\"\n");
    expect_error(&p, &["m.obj", "not finite"]);
}

#[test]
fn degenerate_and_duplicate_faces() {
    let d = dir("degen");
    write(&d, "m.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
    let p = write(&d, "s.toml", "[[object]]\nmesh = \"m.obj\"\n");
    expect_error(&p, &["m.obj", "degenerate"]);
    write(&d, "dup.obj", &format!("{QUAD}f 1 2 3 4\n"));
    let p = write(&d, "s2.toml", "[[object]]\nmesh = \"dup.obj\"\n");
    expect_error(&p, &["dup.obj", "duplicates"]);
}

#[test]
fn bad_settings_name_the_field() {
    let d = dir("settings");
    write(&d, "q.obj", QUAD);
    for (field, toml) in [
        ("solver.bins", "[solver]\nbins = 0\n"),
        ("bins", "[solver]\nbins = 127\n"),
        ("solver.element_size", "[solver]\nelement_size = -1.0\n"),
        ("solver.scheme", "[solver]\nscheme = \"sideways\"\n"),
        ("camera.fov_y_deg", "[camera]\neye = [0,0,1]\ntarget = [0,0,0]\nfov_y_deg = 0\n"),
        ("light[0].beam_width_deg", "[[light]]\ntype = \"spot\"\nposition = [0,1,0]\ntarget = [0,0,0]\nintensity = 1\ncutoff_deg = 30\nbeam_width_deg = 40\n"),
    ] {
        let p = write(&d, "s.toml", &format!("{toml}[[object]]\nmesh = \"q.obj\"\n"));
        expect_error(&p, &["s.toml", field]);
    }
    let p = write(&d, "e.toml", "[solver]\nbins = 64\n");
    expect_error(&p, &["e.toml", "object"]);
}
