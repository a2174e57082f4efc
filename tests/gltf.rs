//! glTF 2.0 input (issue 33): the Khronos sample models load with the counts SOURCE.txt gives,
//! mirrored nodes keep their front, light units convert by 1/683, a Cornell box written as glTF
//! renders the image of its OBJ, and every malformed-file class is one clear error.

mod common;

use antiradiance::scene::{load_scene, Light, Scene};
use antiradiance::{BackendKind, Options};
use base64::Engine as _;
use glam::DVec3;
use serde_json::{json, Value};
use std::f64::consts::FRAC_1_SQRT_2;
use std::path::{Path, PathBuf};

const SAMPLES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/gltf-samples");

fn sample(rel: &str) -> PathBuf {
    Path::new(SAMPLES).join(rel)
}

fn dir(name: &str) -> common::Scratch {
    common::Scratch::new(&format!("gltf-{name}"))
}

/// One buffer (a data URI) holding `positions`, then `normals`, then u32 `indices`, with the
/// accessors 0 (POSITION), 1 (NORMAL, if any), last (indices, if any); `extra` is merged in.
fn document(
    positions: &[[f32; 3]],
    normals: &[[f32; 3]],
    indices: &[u32],
    mode: u32,
    extra: Value,
) -> Value {
    let mut bytes = Vec::new();
    for p in positions.iter().chain(normals) {
        for x in p {
            bytes.extend_from_slice(&x.to_le_bytes());
        }
    }
    for i in indices {
        bytes.extend_from_slice(&i.to_le_bytes());
    }
    let pbytes = positions.len() * 12;
    let nbytes = normals.len() * 12;
    let (lo, hi) = positions
        .iter()
        .fold(([f32::MAX; 3], [f32::MIN; 3]), |(l, h), p| {
            (
                [l[0].min(p[0]), l[1].min(p[1]), l[2].min(p[2])],
                [h[0].max(p[0]), h[1].max(p[1]), h[2].max(p[2])],
            )
        });
    let mut views = vec![json!({"buffer": 0, "byteOffset": 0, "byteLength": pbytes})];
    let mut accessors = vec![
        json!({"bufferView": 0, "componentType": 5126, "count": positions.len(), "type": "VEC3", "min": lo, "max": hi}),
    ];
    let mut attributes = json!({"POSITION": 0});
    if !normals.is_empty() {
        views.push(json!({"buffer": 0, "byteOffset": pbytes, "byteLength": nbytes}));
        accessors.push(
            json!({"bufferView": 1, "componentType": 5126, "count": normals.len(), "type": "VEC3"}),
        );
        attributes["NORMAL"] = json!(1);
    }
    let mut primitive = json!({"attributes": attributes, "mode": mode});
    if !indices.is_empty() {
        views.push(
            json!({"buffer": 0, "byteOffset": pbytes + nbytes, "byteLength": indices.len() * 4}),
        );
        accessors.push(json!({"bufferView": views.len() - 1, "componentType": 5125, "count": indices.len(), "type": "SCALAR"}));
        primitive["indices"] = json!(accessors.len() - 1);
    }
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bytes)
    );
    let mut doc = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [primitive]}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": bytes.len(), "uri": uri}],
    });
    merge(&mut doc, extra);
    doc
}

fn merge(a: &mut Value, b: Value) {
    match (a, b) {
        (Value::Object(a), Value::Object(b)) => {
            for (k, v) in b {
                merge(a.entry(k).or_insert(Value::Null), v);
            }
        }
        (a, b) => *a = b,
    }
}

fn write(d: &Path, name: &str, doc: &Value) -> PathBuf {
    let p = d.join(name);
    std::fs::write(&p, serde_json::to_string_pretty(doc).unwrap()).unwrap();
    p
}

const TRI: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

#[test]
fn khronos_samples_load_with_their_counts() {
    // (file, triangles drawn, lights) from gltf-samples/SOURCE.txt.
    let cases = [
        ("Box/glTF-Binary/Box.glb", 12, 0),
        ("BoxInterleaved/glTF-Binary/BoxInterleaved.glb", 12, 0),
        (
            "NegativeScaleTest/glTF-Binary/NegativeScaleTest.glb",
            7724,
            0,
        ),
        ("OrientationTest/glTF-Binary/OrientationTest.glb", 524, 0),
        ("SimpleSparseAccessor/glTF/SimpleSparseAccessor.gltf", 12, 0),
        ("SimpleMeshes/glTF/SimpleMeshes.gltf", 2, 0),
        ("Cameras/glTF/Cameras.gltf", 2, 0),
        ("LightsPunctualLamp/glTF/LightsPunctualLamp.gltf", 6000, 5),
        (
            "EmissiveStrengthTest/glTF-Binary/EmissiveStrengthTest.glb",
            90,
            0,
        ),
        ("Triangle/glTF/Triangle.gltf", 1, 0),
        (
            "TriangleWithoutIndices/glTF/TriangleWithoutIndices.gltf",
            1,
            0,
        ),
    ];
    for (file, triangles, lights) in cases {
        let s = load_scene(&sample(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        // doubleSided materials' faces get back-to-back twins; the file's own are counted.
        let own: usize = s
            .meshes
            .iter()
            .filter(|m| !m.name.ends_with(antiradiance::scene::BACK_SUFFIX))
            .map(|m| m.triangles.len())
            .sum();
        assert_eq!(own, triangles, "{file}");
        assert_eq!(s.lights.len(), lights, "{file}");
        println!(
            "{file}: {} meshes, warnings {:?}",
            s.meshes.len(),
            s.warnings
        );
    }
    // Bounds: the accessors' own min/max where the nodes have no transform; the box is ±0.5
    // about the origin after its root's −90° turn about x.
    let bounds = |f: &str| load_scene(&sample(f)).unwrap().bounds();
    let (lo, hi) = bounds("SimpleSparseAccessor/glTF/SimpleSparseAccessor.gltf");
    assert_eq!((lo, hi), (DVec3::ZERO, DVec3::new(6.0, 4.0, 0.0)));
    let (lo, hi) = bounds("Triangle/glTF/Triangle.gltf");
    assert_eq!((lo, hi), (DVec3::ZERO, DVec3::new(1.0, 1.0, 0.0)));
    for f in [
        "Box/glTF-Binary/Box.glb",
        "BoxInterleaved/glTF-Binary/BoxInterleaved.glb",
    ] {
        let (lo, hi) = bounds(f);
        assert!(
            (lo + DVec3::splat(0.5)).abs().max_element() < 1e-6,
            "{f} {lo}"
        );
        assert!(
            (hi - DVec3::splat(0.5)).abs().max_element() < 1e-6,
            "{f} {hi}"
        );
    }
    // Interleaved and separate accessors give the same box.
    let a = load_scene(&sample("Box/glTF-Binary/Box.glb")).unwrap();
    let b = load_scene(&sample("BoxInterleaved/glTF-Binary/BoxInterleaved.glb")).unwrap();
    assert_eq!(a.meshes[0].positions, b.meshes[0].positions);
    assert_eq!(a.meshes[0].normals, b.meshes[0].normals);
    // SimpleMeshes: one mesh drawn twice, the second 1 to the right.
    let s = load_scene(&sample("SimpleMeshes/glTF/SimpleMeshes.gltf")).unwrap();
    assert_eq!(s.meshes.len(), 2);
    for (p, q) in s.meshes[0].positions.iter().zip(&s.meshes[1].positions) {
        assert!((*q - *p - DVec3::X).length() < 1e-6);
    }
    // Cameras: the perspective camera (yfov 0.7, aspect 1) at (0.5, 0.5, 3) looking down −z.
    let c = load_scene(&sample("Cameras/glTF/Cameras.gltf"))
        .unwrap()
        .camera;
    assert!((c.eye - DVec3::new(0.5, 0.5, 3.0)).length() < 1e-6);
    assert!(((c.target - c.eye).normalize() - DVec3::NEG_Z).length() < 1e-6);
    assert!((c.fov_y_deg - 0.7f64.to_degrees()).abs() < 1e-4);
    assert_eq!((c.width, c.height), (512, 512));
    // The square is turned −45° about x: its normal is (0, sin 45°, cos 45°)... from (0, 0, 1).
    let m = &load_scene(&sample("Cameras/glTF/Cameras.gltf"))
        .unwrap()
        .meshes[0];
    let n = m.face_normal(0);
    assert!(
        (n - DVec3::new(0.0, 1.0, 1.0).normalize()).length() < 2e-3,
        "{n}"
    );
    // Emissive strength: the five emitters are (0.1, 0.5, 0.9) × 1, 2, 4, 8, 16.
    let s = load_scene(&sample(
        "EmissiveStrengthTest/glTF-Binary/EmissiveStrengthTest.glb",
    ))
    .unwrap();
    for k in [1.0, 2.0, 4.0, 8.0, 16.0] {
        let want = DVec3::new(0.1, 0.5, 0.9) * k;
        assert!(
            s.materials.iter().any(|m| (m.ke - want).length() < 1e-5),
            "no emitter of {want}: {:?}",
            s.materials.iter().map(|m| m.ke).collect::<Vec<_>>()
        );
    }
}

#[test]
fn mirrored_nodes_keep_their_front() {
    // NegativeScaleTest: six nodes scaled by −1 (two of them twice). Its NORMALs are the file's;
    // a winding not turned round under a mirror would face every mirrored triangle against its
    // normals, which the loader reports ("unusable NORMALs").
    let s = load_scene(&sample(
        "NegativeScaleTest/glTF-Binary/NegativeScaleTest.glb",
    ))
    .unwrap();
    assert!(
        !s.warnings.iter().any(|w| w.contains("unusable NORMAL")),
        "{:?}",
        s.warnings
    );
    let agreeing = s
        .meshes
        .iter()
        .flat_map(|m| (0..m.triangles.len()).map(move |t| (m, t)))
        .filter(|(m, t)| {
            let n = m.corner_normals(*t);
            (n[0] + n[1] + n[2]).dot(m.face_normal(*t)) > 0.0
        })
        .count();
    assert_eq!(agreeing, s.triangle_count());
    // Three of its materials are doubleSided: their faces have twins.
    assert!(s.triangle_count() > 7724, "{}", s.triangle_count());
    // One triangle facing +z under x ↦ −x still faces +z.
    let d = dir("mirror");
    let normals = [[0.0, 0.0, 1.0f32]; 3];
    let doc = document(
        &TRI,
        &normals,
        &[0, 1, 2],
        4,
        json!({"nodes": [{"mesh": 0, "scale": [-1.0, 1.0, 1.0]}]}),
    );
    let s = load_scene(&write(&d, "mirror.gltf", &doc)).unwrap();
    assert!((s.meshes[0].face_normal(0) - DVec3::Z).length() < 1e-9);
    assert!((s.meshes[0].positions[1] + DVec3::X).length() < 1e-9);
    assert!(s.meshes[0].normals[0]
        .iter()
        .all(|n| (*n - DVec3::Z).length() < 1e-9));
}

#[test]
fn punctual_lights_convert_candela_and_lux_to_watts() {
    let s = load_scene(&sample("LightsPunctualLamp/glTF/LightsPunctualLamp.gltf")).unwrap();
    // lights[0]: color (1, 0.6318749785, 0.2390997559), 15 cd.
    let want = DVec3::new(1.0, 0.6318749785423279, 0.23909975588321689) * 15.0 / 683.0;
    assert!(
        s.lights.iter().any(
            |l| matches!(l, Light::Point { intensity, .. } if (*intensity - want).length() < 1e-6)
        ),
        "{:?}",
        s.lights
    );
    let d = dir("lights");
    let lights = json!({
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "directional", "intensity": 683.0},
            {"type": "point", "intensity": 2732.0, "color": [1.0, 0.5, 0.0]},
            {"type": "spot", "intensity": 68.3, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.5}}
        ]}},
        "scenes": [{"nodes": [0, 1, 2, 3]}],
        "nodes": [
            {"mesh": 0},
            // A quarter turn about x: −z becomes −y (straight down).
            {"rotation": [-FRAC_1_SQRT_2, 0.0, 0.0, FRAC_1_SQRT_2], "extensions": {"KHR_lights_punctual": {"light": 0}}},
            {"translation": [1.0, 2.0, 3.0], "extensions": {"KHR_lights_punctual": {"light": 1}}},
            {"translation": [0.0, 5.0, 0.0], "rotation": [-FRAC_1_SQRT_2, 0.0, 0.0, FRAC_1_SQRT_2], "extensions": {"KHR_lights_punctual": {"light": 2}}}
        ]
    });
    let s = load_scene(&write(
        &d,
        "lights.gltf",
        &document(&TRI, &[], &[0, 1, 2], 4, lights),
    ))
    .unwrap();
    assert_eq!(s.lights.len(), 3);
    match &s.lights[0] {
        Light::Directional {
            direction,
            irradiance,
        } => {
            assert!((*direction - DVec3::NEG_Y).length() < 1e-6, "{direction}");
            assert!((*irradiance - DVec3::ONE).length() < 1e-9);
        }
        l => panic!("{l:?}"),
    }
    match &s.lights[1] {
        Light::Point {
            position,
            intensity,
        } => {
            assert_eq!(*position, DVec3::new(1.0, 2.0, 3.0));
            assert!((*intensity - DVec3::new(4.0, 2.0, 0.0)).length() < 1e-6);
        }
        l => panic!("{l:?}"),
    }
    match &s.lights[2] {
        Light::Spot {
            position,
            axis,
            intensity,
            cutoff,
            beam_width,
        } => {
            assert_eq!(*position, DVec3::new(0.0, 5.0, 0.0));
            assert!((*axis - DVec3::NEG_Y).length() < 1e-6);
            assert!((*intensity - DVec3::splat(0.1)).length() < 1e-6);
            assert!((cutoff - 0.5).abs() < 1e-6 && (beam_width - 0.2).abs() < 1e-6);
        }
        l => panic!("{l:?}"),
    }
}

/// The bundled Cornell box's meshes and materials written as one glTF file (one node and
/// primitive per mesh, world-space positions), its materials by name.
fn cornell_as_gltf(s: &Scene) -> Value {
    let mut bytes: Vec<u8> = Vec::new();
    let (mut views, mut accessors, mut meshes, mut nodes) = (vec![], vec![], vec![], vec![]);
    for (k, m) in s.meshes.iter().enumerate() {
        let p0 = bytes.len();
        for p in &m.positions {
            for x in p.to_array() {
                bytes.extend_from_slice(&(x as f32).to_le_bytes());
            }
        }
        let i0 = bytes.len();
        for t in &m.triangles {
            for v in t {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
        }
        views.push(json!({"buffer": 0, "byteOffset": p0, "byteLength": i0 - p0}));
        views.push(json!({"buffer": 0, "byteOffset": i0, "byteLength": bytes.len() - i0}));
        accessors.push(json!({"bufferView": 2 * k, "componentType": 5126, "count": m.positions.len(), "type": "VEC3"}));
        accessors.push(json!({"bufferView": 2 * k + 1, "componentType": 5125, "count": m.triangles.len() * 3, "type": "SCALAR"}));
        assert!(m.material.iter().all(|&x| x == m.material[0]));
        meshes.push(json!({"primitives": [{"attributes": {"POSITION": 2 * k}, "indices": 2 * k + 1, "material": m.material[0]}]}));
        nodes.push(json!({"mesh": k, "name": m.name}));
    }
    let materials: Vec<Value> = s
        .materials
        .iter()
        .map(|m| {
            let strength = m.ke.max_element().max(1.0);
            json!({
                "name": m.name,
                "pbrMetallicRoughness": {"baseColorFactor": [m.kd.x, m.kd.y, m.kd.z, 1.0], "metallicFactor": 0.0},
                "emissiveFactor": (m.ke / strength).to_array(),
                "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": strength}}
            })
        })
        .collect();
    json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{"nodes": (0..nodes.len()).collect::<Vec<_>>()}],
        "nodes": nodes, "meshes": meshes, "materials": materials,
        "accessors": accessors, "bufferViews": views,
        "buffers": [{"byteLength": bytes.len(), "uri": format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&bytes))}],
    })
}

#[test]
fn cornell_box_as_gltf_renders_as_its_obj() {
    let toml = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.toml");
    let obj = load_scene(&toml).unwrap();
    let d = dir("cornell");
    write(&d, "cornell.gltf", &cornell_as_gltf(&obj));
    // The TOML's materials exactly (kd, no lobe) by name, as an object's overrides; emission
    // from emissiveFactor × KHR_materials_emissive_strength.
    let mut text = std::fs::read_to_string(&toml)
        .unwrap()
        .replace("cornell-box/CornellBox-Original.obj", "cornell.gltf");
    for m in &obj.materials {
        text += &format!(
            "materials.{} = {{ kd = [{}, {}, {}], ks = 0.0, ns = 0.0 }}\n",
            m.name, m.kd.x, m.kd.y, m.kd.z
        );
    }
    let gl = load_scene(&write_text(&d, "cornell.toml", &text)).unwrap();
    assert_eq!(gl.triangle_count(), obj.triangle_count());
    for a in &obj.materials {
        let b = gl.materials.iter().find(|b| b.name == a.name).unwrap();
        assert!(
            (a.ke - b.ke).length() < 1e-4 * a.ke.length().max(1.0),
            "{a:?} {b:?}"
        );
        assert_eq!((a.kd, a.ks), (b.kd, b.ks), "{}", a.name);
    }
    let render = |s: &Scene| {
        let mut s = s.clone();
        s.camera.width = 48;
        s.camera.height = 48;
        s.solver.bins = 32;
        s.solver.iterations = 3;
        let o = Options {
            backend: BackendKind::Cpu,
            shadow_map_size: 128,
            ..Default::default()
        };
        antiradiance::engine::render(&s, &o, &antiradiance::progress::Silent).unwrap()
    };
    let (a, b) = (render(&obj), render(&gl));
    let m = antiradiance::metrics::compare(&b.image, &a.image).unwrap();
    println!("glTF vs OBJ Cornell box: relative RMSE {:.2e}", m.rel_rmse);
    // The issue asks ≤ 1e-3; the geometry is the same float32 values in the same order, so the
    // images agree to rounding (2.7e-8 measured): held at 1e-6.
    assert!(m.rel_rmse <= 1e-6, "{}", m.rel_rmse);
}

fn write_text(d: &Path, name: &str, text: &str) -> PathBuf {
    let p = d.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn malformed_files_are_one_clear_error() {
    let d = dir("bad");
    let err = |p: &Path| {
        let e = load_scene(p)
            .expect_err(&p.display().to_string())
            .to_string();
        assert!(e.contains(&p.display().to_string()), "{e}");
        e
    };
    // Truncated .glb.
    let glb = std::fs::read(sample("Box/glTF-Binary/Box.glb")).unwrap();
    let cut = d.join("truncated.glb");
    std::fs::write(&cut, &glb[..1000]).unwrap();
    let e = err(&cut);
    assert!(e.contains("not a valid glTF"), "{e}");
    // An accessor that reaches past its buffer view.
    let mut doc = document(&TRI, &[], &[0, 1, 2], 4, json!({}));
    doc["accessors"][0]["count"] = json!(30);
    let e = err(&write(&d, "accessor.gltf", &doc));
    assert!(e.contains("accessors[0] (POSITION) reaches past"), "{e}");
    // POSITION of the wrong type.
    let mut doc = document(&TRI, &[], &[0, 1, 2], 4, json!({}));
    doc["accessors"][0]["componentType"] = json!(5123);
    let e = err(&write(&d, "type.gltf", &doc));
    assert!(e.contains("POSITION must be"), "{e}");
    // A missing buffer file.
    let mut doc = document(&TRI, &[], &[0, 1, 2], 4, json!({}));
    doc["buffers"][0]["uri"] = json!("absent.bin");
    let e = err(&write(&d, "buffer.gltf", &doc));
    assert!(
        e.contains("buffers[0]") && e.contains("absent.bin") && e.contains("not found"),
        "{e}"
    );
    // A short buffer.
    let mut doc = document(&TRI, &[], &[0, 1, 2], 4, json!({}));
    doc["buffers"][0]["byteLength"] = json!(4000);
    let e = err(&write(&d, "short.gltf", &doc));
    assert!(e.contains("fewer than its byteLength"), "{e}");
    // An index out of range.
    let e = err(&write(
        &d,
        "index.gltf",
        &document(&TRI, &[], &[0, 1, 7], 4, json!({})),
    ));
    assert!(e.contains("index 7 is out of range"), "{e}");
    // Lines only.
    let e = err(&write(
        &d,
        "lines.gltf",
        &document(&TRI, &[], &[0, 1, 1, 2], 1, json!({})),
    ));
    assert!(e.contains("points or lines only"), "{e}");
    // A reference to an accessor that does not exist (the crate's validation).
    let mut doc = document(&TRI, &[], &[0, 1, 2], 4, json!({}));
    doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(9);
    let e = err(&write(&d, "reference.gltf", &doc));
    assert!(e.contains("not a valid glTF"), "{e}");
    // A node that is its own child.
    let mut doc = document(&TRI, &[], &[0, 1, 2], 4, json!({}));
    doc["nodes"] = json!([{"mesh": 0, "children": [1]}, {"children": [0]}]);
    let _ = err(&write(&d, "cycle.gltf", &doc));
    // Not JSON at all, and an empty file.
    let _ = err(&write_text(&d, "text.gltf", "{ this is not json"));
    let _ = err(&write_text(&d, "empty.glb", ""));
    // The command line: one line, non-zero exit, no panic.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_antiradiance"))
        .args(["info", cut.to_str().unwrap()])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    // Lines beside triangles are skipped with a warning, not an error.
    let mut doc = document(&TRI, &[], &[0, 1, 2], 4, json!({}));
    let p = doc["meshes"][0]["primitives"][0].clone();
    let mut line = p.clone();
    line["mode"] = json!(1);
    line.as_object_mut().unwrap().remove("indices");
    doc["meshes"][0]["primitives"] = json!([p, line]);
    let s = load_scene(&write(&d, "mixed.gltf", &doc)).unwrap();
    assert_eq!(s.triangle_count(), 1);
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("1 lines primitive skipped")),
        "{:?}",
        s.warnings
    );
}

#[test]
fn a_gltf_camera_stands_in_for_a_missing_toml_camera() {
    let d = dir("camera");
    let cams = std::fs::read(sample("Cameras/glTF/Cameras.gltf")).unwrap();
    std::fs::write(d.join("c.gltf"), cams).unwrap();
    std::fs::copy(
        sample("Cameras/glTF/simpleSquare.bin"),
        d.join("simpleSquare.bin"),
    )
    .unwrap();
    let without = write_text(
        &d,
        "a.toml",
        "[[object]]\nmesh = \"c.gltf\"\ntranslate = [1.0, 0.0, 0.0]\n",
    );
    let c = load_scene(&without).unwrap().camera;
    // The object's translation moves the glTF's camera with it.
    assert!(
        (c.eye - DVec3::new(1.5, 0.5, 3.0)).length() < 1e-6,
        "{}",
        c.eye
    );
    let with = write_text(
        &d,
        "b.toml",
        "[camera]\neye = [0.0, 0.0, 9.0]\ntarget = [0.0, 0.0, 0.0]\n[[object]]\nmesh = \"c.gltf\"\n",
    );
    assert_eq!(
        load_scene(&with).unwrap().camera.eye,
        DVec3::new(0.0, 0.0, 9.0)
    );
}
