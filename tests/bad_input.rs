//! Bad scene input returns a clear error naming the file, never a panic.

mod common;

use antiradiance::scene::load_scene;
use std::path::{Path, PathBuf};

fn dir(name: &str) -> common::Scratch {
    common::Scratch::new(&format!("bad-{name}"))
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

/// A bare OBJ or PLY given as the scene: malformed, empty, missing or a directory, one line
/// naming the file.
#[test]
fn malformed_bare_meshes() {
    let d = dir("bare");
    let p = write(&d, "m.obj", "v 0 0 0\nv 1 0 zero\nf 1 2 3\n");
    expect_error(&p, &["m.obj"]);
    let p = write(&d, "r.obj", "v 0 0 0\nv 1 0 0\nf 1 2 9\n");
    expect_error(&p, &["r.obj"]);
    let p = write(&d, "e.obj", "");
    expect_error(&p, &["e.obj", "no faces"]);
    expect_error(&d.join("missing.obj"), &["missing.obj", "not found"]);
    let p = write(&d, "h.ply", "ply\nformat ascii 1.0\nelement vertex 1\n");
    expect_error(&p, &["h.ply"]);
    let p = write(
        &d,
        "i.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n",
    );
    expect_error(&p, &["i.ply"]);
    std::fs::create_dir_all(d.join("dir.ply")).unwrap();
    expect_error(&d.join("dir.ply"), &["dir.ply", "directory"]);
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
    // Zero-area faces among others are dropped with one warning naming the file, the count and
    // the first line, as other renderers load such files (issue 35).
    write(
        &d,
        "some.obj",
        &format!("{QUAD}v 0 0 0\nv 1 0 0\nv 2 0 0\nf 5 6 7\nf 7 6 5\n"),
    );
    let p = write(&d, "s3.toml", "[[object]]\nmesh = \"some.obj\"\n");
    let s = load_scene(&p).unwrap();
    assert_eq!(s.triangle_count(), 2);
    let zero: Vec<&String> = s
        .warnings
        .iter()
        .filter(|w| w.contains("zero-area"))
        .collect();
    assert_eq!(zero.len(), 1, "{:?}", s.warnings);
    assert!(
        zero[0].contains("some.obj")
            && zero[0].contains("2 degenerate")
            && zero[0].contains("line "),
        "{}",
        zero[0]
    );
    // Duplicates are dropped with one warning per mesh (issue 18); the reversed winding is a
    // back-to-back twin and stays.
    write(&d, "dup.obj", &format!("{QUAD}f 1 2 3 4\nf 4 3 2 1\n"));
    let p = write(&d, "s2.toml", "[[object]]\nmesh = \"dup.obj\"\n");
    let s = load_scene(&p).unwrap();
    assert_eq!(s.triangle_count(), 4);
    let dup: Vec<&String> = s
        .warnings
        .iter()
        .filter(|w| w.contains("duplicate"))
        .collect();
    assert_eq!(dup.len(), 1, "{:?}", s.warnings);
    assert!(
        dup[0].contains("dup.obj") && dup[0].contains("2 duplicate triangles"),
        "{}",
        dup[0]
    );
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
        ("camera.supersample", "[camera]\neye = [0,0,1]\ntarget = [0,0,0]\nsupersample = 0\n"),
        ("camera.supersample", "[camera]\neye = [0,0,1]\ntarget = [0,0,0]\nsupersample = 9\n"),
        ("camera.passes", "[camera]\neye = [0,0,1]\ntarget = [0,0,0]\npasses = 0\n"),
        ("camera.passes", "[camera]\neye = [0,0,1]\ntarget = [0,0,0]\npasses = 17\n"),
        ("light[0].beam_width_deg", "[[light]]\ntype = \"spot\"\nposition = [0,1,0]\ntarget = [0,0,0]\nintensity = 1\ncutoff_deg = 30\nbeam_width_deg = 40\n"),
    ] {
        let p = write(&d, "s.toml", &format!("{toml}[[object]]\nmesh = \"q.obj\"\n"));
        expect_error(&p, &["s.toml", field]);
    }
    let p = write(&d, "e.toml", "[solver]\nbins = 64\n");
    expect_error(&p, &["e.toml", "object"]);
}

/// The corpus in `tests/bad-input/`: every scene fails through the command-line tool with a
/// non-zero status and a one-line error naming the file and the field (`# expect:` on its first
/// line), never a panic. `# command: render` runs a GPU render instead of `info` (the device
/// memory estimate refuses before anything is allocated).
#[test]
fn corpus_gives_one_line_errors_naming_file_and_field() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad-input");
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 30, "only {} bad scenes", scenes.len());
    let out_png = std::env::temp_dir().join(format!("bad-input-{}.png", std::process::id()));
    for scene in &scenes {
        let text = std::fs::read_to_string(scene).unwrap();
        let header = |key: &str| {
            text.lines()
                .find_map(|l| l.strip_prefix(&format!("# {key}: ")))
                .map(str::to_string)
        };
        let expect = header("expect").expect("`# expect:` line");
        let command = header("command").unwrap_or_else(|| "info".into());
        let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_antiradiance"));
        // GPU renders with the validation layer on: a refused scene must not leave a validation
        // message behind either.
        cmd.env("ANTIRADIANCE_VALIDATION", "1");
        cmd.arg(&command).arg(scene);
        if command == "render" {
            cmd.args(["--width", "8", "--height", "8", "-o"])
                .arg(&out_png);
        }
        let out = cmd.output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        let name = scene.file_name().unwrap().to_string_lossy();
        assert_eq!(out.status.code(), Some(1), "{name}: {stderr}");
        assert!(!stderr.contains("vulkan validation"), "{name}: {stderr}");
        assert!(!stderr.contains("panicked"), "{name}: panicked: {stderr}");
        let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("Error")).collect();
        assert_eq!(errors.len(), 1, "{name}: not one error line: {stderr}");
        let line = errors[0];
        let lines: Vec<&str> = stderr
            .lines()
            .filter(|l| !l.trim().is_empty() && !l.starts_with("warning"))
            .collect();
        assert_eq!(lines.len(), 1, "{name}: more than one line: {stderr}");
        let file_named = expect_file(&text).map_or(name.to_string(), |m| m);
        assert!(
            line.contains(&file_named) || line.contains(&*name),
            "{name}: error does not name the file: {line}"
        );
        assert!(
            line.contains(&expect),
            "{name}: error does not mention `{expect}`: {line}"
        );
        println!("{name}: {line}");
    }
}

/// The mesh a scene names, when the error is about that file.
fn expect_file(text: &str) -> Option<String> {
    text.lines()
        .find_map(|l| l.strip_prefix("mesh = \""))
        .map(|m| m.trim_end_matches('"').to_string())
}

/// Loads on another thread: a loader that opened a FIFO would block forever, and this fails
/// instead of hanging the suite. A liveness guard, not a speed bound: the refusal is a
/// metadata check that reads nothing, so 60 s on any machine means it blocked.
fn load_within_seconds(scene: &Path) -> Result<antiradiance::Scene, String> {
    let (tx, rx) = std::sync::mpsc::channel();
    let p = scene.to_path_buf();
    std::thread::spawn(move || {
        let _ = tx.send(load_scene(&p).map_err(|e| e.to_string()));
    });
    rx.recv_timeout(std::time::Duration::from_secs(60))
        .expect("loading blocked (opened a pipe or a device?)")
}

/// Paths that are not regular files say what they are, and are never read (a FIFO would
/// block the open, `/dev/zero` would never end): these cannot live in the corpus.
#[cfg(unix)]
#[test]
fn mesh_paths_that_are_not_files_say_what_they_are() {
    let d = dir("paths");
    let mesh = |name: &str| {
        let p = write(
            &d,
            &format!("{name}.toml"),
            &format!("[[object]]\nmesh = \"{name}\"\n"),
        );
        let e = load_within_seconds(&p).expect_err("accepted");
        assert!(!e.contains('\n'), "{e}");
        assert!(e.contains("`object[0].mesh`: ") && e.contains(name), "{e}");
        e
    };
    let fifo = d.join("fifo.obj");
    let _ = std::fs::remove_file(&fifo);
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    if made.is_ok_and(|s| s.success()) {
        assert!(mesh("fifo.obj").contains("is a named pipe (FIFO), not a regular file"));
    }
    for (link, to) in [("loop-a.obj", "loop-b.obj"), ("loop-b.obj", "loop-a.obj")] {
        let _ = std::fs::remove_file(d.join(link));
        std::os::unix::fs::symlink(d.join(to), d.join(link)).unwrap();
    }
    assert!(mesh("loop-a.obj").contains("is a symbolic link loop"));
    let _ = std::fs::remove_file(d.join("dangling.obj"));
    std::os::unix::fs::symlink(d.join("gone.obj"), d.join("dangling.obj")).unwrap();
    assert!(mesh("dangling.obj").contains("gone.obj, which does not exist"));
    std::fs::create_dir_all(d.join("folder.obj")).unwrap();
    assert!(mesh("folder.obj").contains("is a directory, not a file"));
    assert!(mesh("/dev/zero").contains("is a character device, not a regular file"));
    // The scene file itself too.
    let e = load_within_seconds(Path::new("/dev/zero")).unwrap_err();
    assert!(
        e.contains("/dev/zero: scene file is a character device"),
        "{e}"
    );
    let e = load_within_seconds(&d).unwrap_err();
    assert!(e.contains("scene file is a directory"), "{e}");
}

#[test]
fn scene_files_that_are_not_utf8_text_say_so() {
    let d = dir("encoding");
    let latin1 = d.join("latin1.toml");
    std::fs::write(&latin1, b"# sc\xe8ne\n[[object]]\nmesh = \"q.obj\"\n").unwrap();
    expect_error(&latin1, &["latin1.toml", "not UTF-8", "line 1"]);
    let binary = d.join("binary.toml");
    std::fs::write(&binary, b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR").unwrap();
    expect_error(&binary, &["binary.toml", "binary file"]);
}

/// Sizes that would recurse or allocate without bound are refused at load, quickly, whatever
/// `max_elements` allows.
#[test]
fn absurd_sizes_are_refused_quickly() {
    let d = dir("sizes");
    write(&d, "q.obj", QUAD);
    let machine = antiradiance::scene::max_elements_limit();
    for (toml, field) in [
        (
            format!("[solver]\nelement_size = 1e-6\nmax_elements = {machine}\n"),
            "max_elements",
        ),
        (
            "[solver]\nelement_size = 5e-324\n".to_string(),
            "solver.element_size",
        ),
        (
            "[solver]\niterations = 1000000000000\n".to_string(),
            "solver.iterations",
        ),
        (
            "[solver]\nantiradiance_steps = 1000000000000\n".to_string(),
            "solver.antiradiance_steps",
        ),
    ] {
        let p = write(
            &d,
            "s.toml",
            &format!("{toml}[[object]]\nmesh = \"q.obj\"\n"),
        );
        // Refused when the settings are read, before any mesh is loaded or element made.
        expect_error(&p, &["s.toml", field]);
    }
    for (obj, object) in [
        ("v 0 0 0\nv 1e30 0 0\nv 0 1e30 0\nf 1 2 3\n", ""),
        (QUAD, "scale = 1e30\n"),
        (
            QUAD,
            "matrix = [[1e30, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]\n",
        ),
    ] {
        write(&d, "m.obj", obj);
        let p = write(
            &d,
            "s.toml",
            &format!("[[object]]\nmesh = \"m.obj\"\n{object}"),
        );
        // Refused when the mesh is placed, before anything is subdivided.
        expect_error(&p, &["1e15"]);
    }
}
