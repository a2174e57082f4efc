//! Keyframes and `Scene::at` (§3.3): objects and lights as they stand at a time; what the
//! scene format promises (piecewise-linear translation, spherical rotation, light fields
//! linear, end values held, the written value a key at time 0).

use antiradiance::scene::load::parse_scene;
use antiradiance::scene::Light;
use antiradiance::Scene;
use glam::{DQuat, DVec3};
use std::path::{Path, PathBuf};

/// A scene file beside the bundled scenes (mesh paths resolve against `scenes/`).
fn scene_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/keyframes-test.toml")
}

fn parse(text: &str) -> Scene {
    parse_scene(text, &scene_path()).unwrap()
}

const BLOCK: &str = r#"
[[object]]
mesh = "cornell-box-moving/room.obj"
[[object]]
mesh = "cornell-box-moving/short-box.obj"
translate = [0.0, 0.0, 0.0]
[[object.keyframe]]
time = 1.0
translate = [0.2, 0.0, 0.0]
rotate = { axis = [0, 1, 0], angle_deg = 90 }
[[object.keyframe]]
time = 3.0
translate = [0.4, 0.2, 0.0]
[[light]]
type = "point"
position = [0.0, 1.9, 0.0]
intensity = 2.0
[[light.keyframe]]
time = 2.0
position = [0.5, 1.5, 0.0]
intensity = [4.0, 2.0, 2.0]
[[light]]
type = "spot"
position = [0.0, 1.9, 0.0]
target = [0.0, 0.0, 0.0]
intensity = 1.0
cutoff_deg = 40.0
beam_width_deg = 30.0
[[light.keyframe]]
time = 1.0
target = [1.9, 1.9, 0.0]
"#;

/// The short box's vertices at the moving scene's time `t`.
fn block(s: &Scene) -> &[DVec3] {
    &s.meshes[s.objects[1].meshes.start].positions
}

fn close(a: DVec3, b: DVec3) -> bool {
    (a - b).length() < 1e-12
}

#[test]
fn objects_move_piecewise_linearly_and_rotate_by_slerp() {
    let s = parse(BLOCK);
    assert_eq!(s.duration, Some(3.0), "the last key's time");
    assert!(s.is_animated());
    assert!(!s.objects[0].moving && s.objects[1].moving);
    let rest = block(&s).to_vec();
    // Time 0 and before: the written placement (the translate track's key at 0).
    for t in [-1.0, 0.0] {
        let at = s.at(t);
        assert!(block(&at).iter().zip(&rest).all(|(a, b)| close(*a, *b)));
    }
    // Half-way to the first key: translation halfway, rotation 45° (slerp).
    let half = DQuat::from_rotation_y(45f64.to_radians());
    let at = s.at(0.5);
    for (p, r) in block(&at).iter().zip(&rest) {
        assert!(close(*p, half * *r + DVec3::new(0.1, 0.0, 0.0)), "{p} {r}");
    }
    // Between the keys at 1 and 3 translation goes on, the rotation holds its last key.
    let quarter = DQuat::from_rotation_y(90f64.to_radians());
    let at = s.at(2.0);
    for (p, r) in block(&at).iter().zip(&rest) {
        assert!(close(*p, quarter * *r + DVec3::new(0.3, 0.1, 0.0)), "{p}");
    }
    // After the last key the end values hold; the room never moves.
    let (end, later) = (s.at(3.0), s.at(10.0));
    assert!(block(&end)
        .iter()
        .zip(block(&later))
        .all(|(a, b)| close(*a, *b)));
    assert_eq!(s.at(2.0).meshes[0].positions, s.meshes[0].positions);
    // `at` starts from the loaded scene: moving a moved scene gives the same as from rest.
    let again = s.at(2.0).at(0.5);
    assert!(block(&again)
        .iter()
        .zip(block(&s.at(0.5)))
        .all(|(a, b)| (*a - *b).length() < 1e-12));
}

#[test]
fn lights_move_linearly_from_their_written_values() {
    let s = parse(BLOCK);
    let Light::Point {
        position,
        intensity,
    } = s.at(1.0).lights[0]
    else {
        panic!("a point light")
    };
    // The written position is the key at time 0, the key at 2 the other end.
    assert!(close(position, DVec3::new(0.25, 1.7, 0.0)), "{position}");
    assert!(close(intensity, DVec3::new(3.0, 2.0, 2.0)), "{intensity}");
    let Light::Point { position, .. } = s.at(5.0).lights[0] else {
        panic!()
    };
    assert!(close(position, DVec3::new(0.5, 1.5, 0.0)));
    // The spot's axis follows its target: straight down at 0, 45° at half-way.
    let axis = |t: f64| match s.at(t).lights[1] {
        Light::Spot { axis, .. } => axis,
        _ => panic!(),
    };
    assert!(close(axis(0.0), DVec3::NEG_Y));
    assert!(close(axis(0.5), DVec3::new(0.95, -0.95, 0.0).normalize()));
    assert!(close(axis(1.0), DVec3::X));
}

#[test]
fn duration_and_moving_flag() {
    let s = parse(&format!("[animation]\nduration = 5.5\n{BLOCK}"));
    assert_eq!(s.duration(), 5.5);
    let still = parse(
        "[[object]]\nmesh = \"cornell-box-moving/room.obj\"\n[[object]]\nmesh = \"cornell-box-moving/short-box.obj\"\nmoving = true\n",
    );
    assert_eq!(still.duration, None);
    assert!(still.is_animated() && still.objects[1].moving && still.objects[1].motion.is_none());
    // A host may move a moving object, not another one.
    let mut s = still.clone();
    let m = glam::DMat4::from_translation(DVec3::new(0.1, 0.0, 0.0));
    s.set_object_transform(1, m).unwrap();
    let moved = &s.meshes[s.objects[1].meshes.start].positions;
    let rest = &still.meshes[still.objects[1].meshes.start].positions;
    assert!(moved
        .iter()
        .zip(rest)
        .all(|(a, b)| close(*a, *b + DVec3::new(0.1, 0.0, 0.0))));
    let e = s.set_object_transform(0, m).unwrap_err().to_string();
    assert!(e.contains("not marked moving"), "{e}");
    assert!(s.set_object_transform(7, m).is_err());
}

#[test]
fn keyframe_errors_name_the_field() {
    let cases = [
        (
            "[[object]]\nmesh = \"cornell-box-moving/room.obj\"\nmoving = false\n[[object.keyframe]]\ntime = 0.0\ntranslate = [0, 0, 0]\n",
            "object[0].moving",
        ),
        (
            "[[object]]\nmesh = \"cornell-box-moving/room.obj\"\n[[object.keyframe]]\ntime = 1.0\n",
            "object[0].keyframe[0]",
        ),
        (
            "[[object]]\nmesh = \"cornell-box-moving/room.obj\"\n[[object.keyframe]]\ntime = 1.0\ntranslate = [0, 0, 0]\n[[object.keyframe]]\ntime = 1.0\ntranslate = [0, 1, 0]\n",
            "object[0].keyframe[1].time",
        ),
        (
            "[[light]]\ntype = \"spot\"\nposition = [0, 1, 0]\ntarget = [0, 0, 0]\nintensity = 1\ncutoff_deg = 40\nbeam_width_deg = 30\n[[light.keyframe]]\ntime = 1.0\ntarget = [0, 1, 0]\n[[object]]\nmesh = \"cornell-box-moving/room.obj\"\n",
            "light[0].keyframe[0]",
        ),
        (
            "[[light]]\ntype = \"directional\"\ndirection = [0, -1, 0]\nirradiance = 1\n[[light.keyframe]]\ntime = 1.0\nposition = [0, 1, 0]\n[[object]]\nmesh = \"cornell-box-moving/room.obj\"\n",
            "light[0].keyframe[0].position",
        ),
    ];
    for (text, field) in cases {
        let e = parse_scene(text, &scene_path()).unwrap_err().to_string();
        assert!(e.contains(field), "`{e}` does not name `{field}`");
        assert!(
            e.contains("keyframes-test.toml"),
            "`{e}` does not name the file"
        );
    }
}

#[test]
fn bundled_moving_scene_is_the_cornell_box() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let moving =
        antiradiance::scene::load_scene(&root.join("scenes/cornell-box-moving.toml")).unwrap();
    let still = antiradiance::scene::load_scene(&root.join("scenes/cornell-box.toml")).unwrap();
    // At time 0 the same triangles as the static box (less its dropped duplicate face).
    let tris = |s: &Scene| {
        let mut v: Vec<[i64; 9]> = s
            .meshes
            .iter()
            .flat_map(|m| {
                m.triangles.iter().map(move |t| {
                    let p = t.map(|i| m.positions[i as usize]);
                    let q = |x: f64| (x * 1e6).round() as i64;
                    [
                        q(p[0].x),
                        q(p[0].y),
                        q(p[0].z),
                        q(p[1].x),
                        q(p[1].y),
                        q(p[1].z),
                        q(p[2].x),
                        q(p[2].y),
                        q(p[2].z),
                    ]
                })
            })
            .collect();
        v.sort();
        v
    };
    assert_eq!(tris(&moving.at(0.0)), tris(&still));
    assert_eq!(tris(&moving.at(2.0)), tris(&still), "the animation loops");
    assert_ne!(tris(&moving.at(1.0)), tris(&still));
    assert_eq!(moving.duration(), 2.0);
}

/// Keys given in code (`Scene::set_object_keyframes`, for hosts building scenes) move an object
/// exactly as the same keys read from a file; bad keys are refused with the object named.
#[test]
fn keyframes_given_in_code_equal_the_file_format() {
    let file = parse(BLOCK);
    let mut code = parse(
        r#"
[[object]]
mesh = "cornell-box-moving/room.obj"
[[object]]
mesh = "cornell-box-moving/short-box.obj"
moving = true
"#,
    );
    use antiradiance::scene::animation::ObjectKey;
    let key = |time: f64, t: [f64; 3], deg: Option<f64>| ObjectKey {
        time,
        translate: Some(DVec3::from_array(t)),
        rotate: deg.map(|d| DQuat::from_rotation_y(d.to_radians())),
    };
    let keys = vec![
        key(1.0, [0.2, 0.0, 0.0], Some(90.0)),
        key(3.0, [0.4, 0.2, 0.0], None),
    ];
    code.set_object_keyframes(1, keys.clone()).unwrap();
    assert_eq!(code.duration, Some(3.0));
    assert!(code.objects[1].moving);
    for t in [0.0, 0.5, 2.0, 4.0] {
        let (a, b) = (file.at(t), code.at(t));
        assert!(
            block(&a)
                .iter()
                .zip(block(&b))
                .all(|(p, q)| (*p - *q).length() < 1e-12),
            "t = {t}"
        );
    }
    let mut bad = keys.clone();
    bad[1].time = 1.0;
    let e = code.set_object_keyframes(1, bad).unwrap_err().to_string();
    assert!(e.contains("object 1") && e.contains("increasing"), "{e}");
    let mut bad = keys;
    bad[0].translate = Some(DVec3::new(f64::NAN, 0.0, 0.0));
    assert!(code.set_object_keyframes(1, bad).is_err());
    assert!(code.set_object_keyframes(1, Vec::new()).is_err());
    assert!(code.set_object_keyframes(7, Vec::new()).is_err());
}
