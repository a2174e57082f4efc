//! Loaders under random input (issue 33 item 4): valid TOML, OBJ/MTL, glTF (text and binary),
//! Mitsuba XML and PLY files, mutated (bytes flipped, spans deleted or repeated, the file cut
//! short, tokens spliced in), must load to a valid scene or an error, never panic or hang.
//! Bounded cases, fixed seeds (proptest's default deterministic runner for the CI).

mod common;

use antiradiance::scene::load_scene;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Duration;

/// One edit of a file's bytes, positions as fractions of its length.
#[derive(Debug, Clone)]
enum Edit {
    Flip(f64, u8),
    Delete(f64, f64),
    Repeat(f64, f64),
    Cut(f64),
    Splice(f64, &'static str),
}

const TOKENS: [&str; 14] = [
    "-1",
    "1e300",
    "nan",
    "inf",
    "0",
    "999999999999",
    "\"",
    "]",
    "}",
    "<",
    "/>",
    "f 1 2 99999",
    "\u{0}",
    "é",
];

fn edit() -> impl Strategy<Value = Edit> {
    // A digit for a digit keeps many files loadable; the other edits mostly break them.
    prop_oneof![
        3 => (0.0..1.0f64, b'0'..=b'9').prop_map(|(p, b)| Edit::Flip(p, b)),
        2 => (0.0..1.0f64, any::<u8>()).prop_map(|(p, b)| Edit::Flip(p, b)),
        1 => (0.0..1.0f64, 0.0..0.02f64).prop_map(|(p, l)| Edit::Delete(p, l)),
        1 => (0.0..1.0f64, 0.0..0.02f64).prop_map(|(p, l)| Edit::Repeat(p, l)),
        1 => (0.0..1.0f64).prop_map(Edit::Cut),
        2 => (0.0..1.0f64, 0..TOKENS.len()).prop_map(|(p, t)| Edit::Splice(p, TOKENS[t])),
    ]
}

fn apply(mut b: Vec<u8>, edits: &[Edit]) -> Vec<u8> {
    for e in edits {
        let n = b.len();
        let at = |f: f64| ((f * n as f64) as usize).min(n);
        match *e {
            // A digit replaces a digit only (elsewhere it would mostly break the syntax).
            Edit::Flip(p, x) if n > 0 => {
                let i = at(p).min(n - 1);
                if !x.is_ascii_digit() || b[i].is_ascii_digit() {
                    b[i] = x;
                }
            }
            Edit::Delete(p, l) => {
                let (s, e) = (at(p), at(p + l).max(at(p)));
                b.drain(s..e);
            }
            Edit::Repeat(p, l) => {
                let (s, e) = (at(p), at(p + l).max(at(p)));
                let span: Vec<u8> = b[s..e].to_vec();
                b.splice(e..e, span);
            }
            Edit::Cut(p) => b.truncate(at(p)),
            Edit::Splice(p, t) => {
                let i = at(p);
                b.splice(i..i, t.bytes());
            }
            _ => {}
        }
    }
    b
}

/// Loads `path` on another thread: Ok(loaded) for a scene (true) or an error (false), Err for a
/// panic or a load that takes longer than 20 s.
fn loads_or_refuses(path: &Path) -> Result<bool, String> {
    let (tx, rx) = mpsc::channel();
    let p = path.to_path_buf();
    std::thread::spawn(move || {
        let r = std::panic::catch_unwind(|| load_scene(&p).is_ok());
        let _ = tx.send(r);
    });
    match rx.recv_timeout(Duration::from_secs(20)) {
        Ok(Ok(loaded)) => Ok(loaded),
        Ok(Err(_)) => Err("panicked".into()),
        Err(_) => Err("did not finish in 20 s".into()),
    }
}

/// Mutates `target` (a file the scene `entry` reads; `entry` itself when equal) `cases` times.
fn fuzz(name: &str, files: &[(&str, Vec<u8>)], target: usize, cases: u32) {
    let dir = common::Scratch::new(&format!("fuzz-{name}"));
    for (f, bytes) in files {
        std::fs::write(dir.join(f), bytes).unwrap();
    }
    let entry: PathBuf = dir.join(files[0].0);
    let original = files[target].1.clone();
    assert_eq!(
        loads_or_refuses(&entry),
        Ok(true),
        "{name}: the seed itself must load"
    );
    // `ANTIRADIANCE_FUZZ_SCALE=k` runs k times the listed cases (CI: 4, about 1.5 s; 40 ran 70K files clean).
    let scale: u32 = std::env::var("ANTIRADIANCE_FUZZ_SCALE")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(4);
    let cases = cases * scale.max(1);
    let config = Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    };
    let rng = TestRng::from_seed(RngAlgorithm::ChaCha, &[7; 32]);
    let mut runner = TestRunner::new_with_rng(config, rng);
    let target_path = dir.join(files[target].0);
    let (loaded, refused) = (std::cell::Cell::new(0), std::cell::Cell::new(0));
    runner
        .run(&proptest::collection::vec(edit(), 1..4), |edits| {
            std::fs::write(&target_path, apply(original.clone(), &edits)).unwrap();
            let ok = loads_or_refuses(&entry)
                .map_err(|e| TestCaseError::fail(format!("{e}: {edits:?}")))?;
            let c = if ok { &loaded } else { &refused };
            c.set(c.get() + 1);
            Ok(())
        })
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    println!(
        "{name}: {cases} mutated files: {} loaded, {} refused",
        loaded.get(),
        refused.get()
    );
    // The mutations reach both outcomes (a fuzzer whose every case loads, or fails at the
    // first byte, tests nothing).
    assert!(loaded.get() > 0 && refused.get() > 0, "{name}");
}

fn read(rel: &str) -> Vec<u8> {
    std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)).unwrap()
}

const OBJ: &str = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nusemtl a\nf 1//1 2//1 3//1 4//1\nusemtl b\nf 1 3 2\n";
const MTL: &str = "newmtl a\nKd 0.5 0.4 0.3\nKs 0.1 0.1 0.1\nNs 20\nnewmtl b\nKe 1 1 1\n";

fn toml() -> Vec<u8> {
    br#"[camera]
eye = [0.5, 0.5, 3.0]
target = [0.5, 0.5, 0.0]
width = 32
height = 32
[solver]
bins = 32
iterations = 2
element_size = 0.5
[[light]]
type = "spot"
position = [0.5, 0.5, 2.0]
target = [0.5, 0.5, 0.0]
intensity = 3.0
cutoff_deg = 40.0
beam_width_deg = 20.0
[[object]]
mesh = "m.obj"
scale = 1.0
materials.a = { kd = 0.5 }
[[object]]
mesh = "t.gltf"
translate = [0.0, 0.0, -1.0]
"#
    .to_vec()
}

#[test]
fn toml_obj_and_mtl_never_panic() {
    let gltf = read("tests/data/gltf-samples/Triangle/glTF/Triangle.gltf");
    let bin = read("tests/data/gltf-samples/Triangle/glTF/simpleTriangle.bin");
    let files = [
        ("scene.toml", toml()),
        ("m.obj", OBJ.as_bytes().to_vec()),
        ("m.mtl", MTL.as_bytes().to_vec()),
        ("t.gltf", gltf),
        ("simpleTriangle.bin", bin),
    ];
    fuzz("toml", &files, 0, 192);
    fuzz("obj", &files, 1, 192);
    fuzz("mtl", &files, 2, 96);
}

#[test]
fn gltf_never_panics() {
    let box_glb = read("tests/data/gltf-samples/Box/glTF-Binary/Box.glb");
    fuzz("glb", &[("box.glb", box_glb)], 0, 256);
    let sparse =
        read("tests/data/gltf-samples/SimpleSparseAccessor/glTF/SimpleSparseAccessor.gltf");
    let sparse_bin =
        read("tests/data/gltf-samples/SimpleSparseAccessor/glTF/SimpleSparseAccessor.bin");
    let files = [("s.gltf", sparse), ("SimpleSparseAccessor.bin", sparse_bin)];
    fuzz("gltf", &files, 0, 256);
    fuzz("gltf-bin", &files, 1, 128);
    let cams = read("tests/data/gltf-samples/Cameras/glTF/Cameras.gltf");
    let square = read("tests/data/gltf-samples/Cameras/glTF/simpleSquare.bin");
    fuzz(
        "cameras",
        &[("c.gltf", cams), ("simpleSquare.bin", square)],
        0,
        128,
    );
}

#[test]
fn mitsuba_xml_and_ply_never_panic() {
    let xml = br#"<scene version="3.0.0">
  <default name="r" value="0.5"/>
  <sensor type="perspective"><float name="fov" value="45"/>
    <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="24"/></film></sensor>
  <bsdf type="twosided" id="w"><bsdf type="roughplastic"><float name="alpha" value="0.2"/><rgb name="diffuse_reflectance" value="$r"/></bsdf></bsdf>
  <shape type="obj"><string name="filename" value="m.obj"/><ref id="w"/>
    <transform name="to_world"><rotate y="1" angle="30"/><translate x="1"/></transform></shape>
  <shape type="ply"><string name="filename" value="q.ply"/><emitter type="area"><rgb name="radiance" value="2"/></emitter></shape>
  <shape type="sphere"><float name="radius" value="0.3"/><bsdf type="conductor"/></shape>
  <emitter type="spot"><transform name="to_world"><matrix value="1 0 0 0 0 1 0 2 0 0 1 0 0 0 0 1"/></transform><rgb name="intensity" value="5"/></emitter>
</scene>"#
        .to_vec();
    let ply = b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n".to_vec();
    let mut bin = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n".to_vec();
    for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for x in v {
            bin.extend_from_slice(&x.to_le_bytes());
        }
    }
    bin.push(3);
    for i in [0i32, 1, 2] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let files = [
        ("scene.xml", xml),
        ("m.obj", OBJ.as_bytes().to_vec()),
        ("q.ply", ply),
    ];
    fuzz("xml", &files, 0, 256);
    fuzz("ply", &files, 2, 128);
    let files = [
        ("scene.xml", files[0].1.clone()),
        ("m.obj", OBJ.as_bytes().to_vec()),
        ("q.ply", bin),
    ];
    fuzz("ply-binary", &files, 2, 128);
}
