//! Light through many occluders (issue 36): open-topped corridors of 1 to 4 turns with walls of
//! zero and of real thickness, lit by a sun from above or by an area emitter at one end, and a
//! stack of plates with offset openings under a sun, each against the project's path tracer.
//!
//! The frames are supersampled 4× in 4 passes (each pixel the mean of 8×8 samples per pass,
//! each pass shifted by a quarter of the samples' spacing along the pixel's diagonal: 32
//! distinct sample rows and columns, as the path tracer's pixel integrates its box): at 32² a
//! pixel holds a wall's whole top and its shadow edge, and the plain 2×2 samples alias them. Measured on the first corridor before this test: 0.32
//! relative RMSE at supersample 1, 0.075 at 4, 0.066 at 8 (the reference's noise 0.052 of it),
//! and hierarchical radiosity with ray-cast visibility on the same links 0.32 / 0.074 / 0.064:
//! what was off there was the frame's sampling, not antiradiance's cancellation.

mod common;

use antiradiance::engine::{Options, SolverOverrides};
use antiradiance::frame::Image;
use antiradiance::scene::{Light, Material, Scene};
use antiradiance::BackendKind as Backend;
use common::*;
use glam::DVec3;

const W: f64 = 0.5; // lane width
const L: f64 = 2.0; // lane length
const H: f64 = 0.5; // wall height
const T: f64 = 0.06; // a thick wall's thickness

#[derive(Clone, Copy, PartialEq, Debug)]
enum Walls {
    Thin,
    Thick,
}

#[derive(Clone, Copy, PartialEq, Debug)]
enum Lit {
    Sun,
    Emitter,
}

/// A wall standing on the floor from (x0, z0) to (x1, z1), `h` high (from `y0`): a two-sided
/// quad (zero thickness), or a box `T` thick.
#[allow(clippy::too_many_arguments)]
fn wall(
    s: &mut Scene,
    name: &str,
    a: (f64, f64),
    b: (f64, f64),
    y0: f64,
    h: f64,
    walls: Walls,
    m: u32,
) {
    let p = DVec3::new;
    match walls {
        Walls::Thin => {
            let q = [
                p(a.0, y0, a.1),
                p(b.0, y0, b.1),
                p(b.0, y0 + h, b.1),
                p(a.0, y0 + h, a.1),
            ];
            quad(s, name, q, m);
            let mut r = q;
            r.reverse();
            quad(s, &format!("{name} back"), r, m);
        }
        Walls::Thick => {
            let (lo, hi) = (
                p(a.0.min(b.0), y0, a.1.min(b.1)),
                p(a.0.max(b.0), y0 + h, a.1.max(b.1)),
            );
            let pad = |v: f64, w: f64| if v == w { T / 2.0 } else { 0.0 };
            let (dx, dz) = (pad(lo.x, hi.x), pad(lo.z, hi.z));
            add_box(s, name, lo - p(dx, 0.0, dz), hi + p(dx, 0.0, dz), m, false);
        }
    }
}

/// A serpentine corridor of `turns` turns: `turns + 1` lanes side by side along z, each joined
/// to the next through a gap at alternate ends, open at the top. Lit by a sun slanted across
/// the lanes (their floors partly in the walls' shadows), or by an emitter on the far end wall
/// of the first lane, whose light reaches lane k only after k turns.
fn serpentine(turns: usize, walls: Walls, lit: Lit) -> Scene {
    let mut s = Scene::empty();
    let f = s.add_material(Material::diffuse("floor", 0.6));
    let w = s.add_material(Material::diffuse("wall", 0.7));
    let lanes = turns + 1;
    let x = lanes as f64 * W;
    let p = DVec3::new;
    quad(
        &mut s,
        "floor",
        [
            p(0.0, 0.0, 0.0),
            p(0.0, 0.0, L),
            p(x, 0.0, L),
            p(x, 0.0, 0.0),
        ],
        f,
    );
    wall(&mut s, "left", (0.0, 0.0), (0.0, L), 0.0, H, walls, w);
    wall(&mut s, "right", (x, 0.0), (x, L), 0.0, H, walls, w);
    wall(&mut s, "near", (0.0, L), (x, L), 0.0, H, walls, w);
    wall(&mut s, "far", (0.0, 0.0), (x, 0.0), 0.0, H, walls, w);
    for i in 1..lanes {
        let xi = i as f64 * W;
        // Lane 0 runs from the emitter at z = L to z = 0, lane 1 back, and so on.
        let (z0, z1) = if i % 2 == 1 { (W, L) } else { (0.0, L - W) };
        wall(
            &mut s,
            &format!("inner{i}"),
            (xi, z0),
            (xi, z1),
            0.0,
            H,
            walls,
            w,
        );
    }
    match lit {
        Lit::Sun => {
            s.lights = vec![Light::Directional {
                direction: DVec3::new(0.45, -1.0, 0.3).normalize(),
                irradiance: DVec3::splat(3.0),
            }];
        }
        Lit::Emitter => {
            let e = s.add_material(Material {
                ke: DVec3::splat(8.0),
                ..Material::diffuse("lamp", 0.0)
            });
            let inset = if walls == Walls::Thick { T / 2.0 } else { 0.0 };
            let z = L - inset - 1e-3;
            let (x0, x1) = (0.15 * W, 0.85 * W);
            // Facing −z, into the first lane.
            quad(
                &mut s,
                "lamp",
                [
                    p(x0, 0.05, z),
                    p(x0, H - 0.05, z),
                    p(x1, H - 0.05, z),
                    p(x1, 0.05, z),
                ],
                e,
            );
        }
    }
    default_solver(&mut s, 8);
    let c = p(x / 2.0, 0.0, L / 2.0);
    let ext = x.max(L);
    view(&mut s, c + p(0.0, 1.6 * ext, 0.9 * ext), c, 40.0, 32);
    s
}

/// Three plates stacked above a floor inside three walls (open at the top and the front), each
/// with an opening at the other end from the one above; a sun from above lights the top plate
/// and, through the openings, one patch on each layer: the floor is reached through three.
fn stack(walls: Walls) -> Scene {
    let mut s = Scene::empty();
    let g = s.add_material(Material::diffuse("grey", 0.7));
    let p = DVec3::new;
    let (x, z, top) = (2.0, 1.0, 1.5);
    quad(
        &mut s,
        "floor",
        [
            p(0.0, 0.0, 0.0),
            p(0.0, 0.0, z),
            p(x, 0.0, z),
            p(x, 0.0, 0.0),
        ],
        g,
    );
    // Walls as vertical plates: back (z = 0) and the two sides.
    wall(&mut s, "back", (0.0, 0.0), (x, 0.0), 0.0, top, walls, g);
    wall(&mut s, "left", (0.0, 0.0), (0.0, z), 0.0, top, walls, g);
    wall(&mut s, "right", (x, 0.0), (x, z), 0.0, top, walls, g);
    for (k, y) in [top, 1.0, 0.5].into_iter().enumerate() {
        // The opening: 0.4 wide, at the right end for plates 0 and 2, the left for plate 1.
        let (a, b) = if k % 2 == 0 { (1.5, 1.9) } else { (0.1, 0.5) };
        for (n, (x0, x1)) in [(0.0, a), (b, x)].into_iter().enumerate() {
            let name = format!("plate{k}.{n}");
            match walls {
                Walls::Thin => {
                    let q = [p(x0, y, 0.0), p(x0, y, z), p(x1, y, z), p(x1, y, 0.0)];
                    quad(&mut s, &name, q, g);
                    let mut r = q;
                    r.reverse();
                    quad(&mut s, &format!("{name} back"), r, g);
                }
                Walls::Thick => add_box(&mut s, &name, p(x0, y - T, 0.0), p(x1, y, z), g, false),
            }
        }
    }
    s.lights = vec![Light::Directional {
        direction: DVec3::new(0.1, -1.0, -0.2).normalize(),
        irradiance: DVec3::splat(3.0),
    }];
    default_solver(&mut s, 8);
    view(&mut s, p(1.0, 0.9, 3.4), p(1.0, 0.75, 0.4), 40.0, 32);
    s
}

/// Relative RMSE of `direct` against the reference's direct light (its one-bounce paths), over
/// the measured pixels.
fn direct_error(direct: &Image, one_bounce: &Image, measured: &[bool]) -> f64 {
    let (mut sq, mut sum, mut n) = (0.0, 0.0, 0usize);
    for (i, &m) in measured.iter().enumerate() {
        if m {
            for c in 0..3 {
                let (a, b) = (direct.pixels[i][c] as f64, one_bounce.pixels[i][c] as f64);
                sq += (a - b).powi(2);
                sum += b;
                n += 1;
            }
        }
    }
    (sq / n as f64).sqrt() / (sum / n as f64).max(1e-12)
}

/// Per pixel of a `w`×`h` image of `scene`: whether 33×33 rays over its box, borders
/// included, all meet one plane, so the pixel holds no silhouette, crease or sliver of another
/// surface. Over these pixels the direct light's error is the shading's (emitter samples,
/// shadow lookups at contacts) without the frame's regular sub-pixel grid missing a sliver of
/// lit floor behind a wall's top, which a box-filtered reference integrates.
fn one_surface(scene: &Scene, w: u32, h: u32) -> Vec<bool> {
    const N: u32 = 32;
    let mut tris = Vec::new();
    for m in &scene.meshes {
        for t in &m.triangles {
            tris.push(t.map(|i| m.positions[i as usize]));
        }
    }
    let caster = antiradiance::raycast::RayCaster::from_triangles(tris.clone());
    let mut camera = scene.camera.clone();
    (camera.width, camera.height) = (w, h);
    let view = antiradiance::frame::camera::View::new(&camera);
    let plane = |k: u32| {
        let c = &tris[k as usize];
        let n = (c[1] - c[0]).cross(c[2] - c[0]).normalize();
        ((n * 1e5).round(), (n.dot(c[0]) * 1e5).round())
    };
    let mut out = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let mut first = None;
            let one = (0..=N).all(|j| {
                (0..=N).all(|i| {
                    let (px, py) = (
                        x as f64 + i as f64 / N as f64,
                        y as f64 + j as f64 / N as f64,
                    );
                    caster
                        .closest(view.eye, view.ray(px, py), 0.0, f64::INFINITY)
                        .is_some_and(|hit| {
                            *first.get_or_insert(plane(hit.shape)) == plane(hit.shape)
                        })
                })
            });
            out.push(one);
        }
    }
    out
}

struct Bound {
    rel_rmse: f64,
    median: f64,
    p90: f64,
    direct: f64,
    direct_inside: f64,
}

/// Renders `scene` on both backends (the GPU only where `gpu`) supersampled 4× in 4 passes, against the
/// path tracer: prints the figures, records the CPU's, checks `bound`.
fn check(key: &str, scene: &Scene, gpu: bool, bound: &Bound) {
    let truth = path_traced(scene, 8192);
    let options = |backend, iterations| Options {
        supersample: Some(4),
        passes: Some(4),
        solver: SolverOverrides {
            iterations,
            ..Default::default()
        },
        ..Options::backend(backend)
    };
    let backends: &[Backend] = if gpu {
        &[Backend::Cpu, Backend::Gpu]
    } else {
        &[Backend::Cpu]
    };
    let (w, h) = (scene.camera.width, scene.camera.height);
    let inside: Vec<bool> = one_surface(scene, w, h)
        .into_iter()
        .zip(&truth.measured)
        .map(|(a, b)| a && *b)
        .collect();
    let mut cpu: Option<(Image, Image)> = None;
    for &b in backends {
        let r = render_checked(key, scene, options(b, None));
        let d = render_checked(key, scene, options(b, Some(0))).image;
        // The GPU draws what the CPU draws: the direct light (the same G-buffer, lights and
        // shadow lookups) and the whole frame (metrics::relative_errors). Measured, direct /
        // frame: thin-sun-2 0.0113 / 0.0006 (0.0059 / 0.0008 in one pass; 0.047 / 0.045 before
        // the G-buffer's twin faces broke their depth tie by their slope: the walls' black backs
        // in a third of their pixels), thick-lamp-3 0.0049 / 0.0036 (float32 cells beside the
        // lamp), the plates 0.0001 / 0.0002. Bounds 1.3× and 2.8×.
        if let Some((ci, cd)) = &cpu {
            let rel = |a, b| antiradiance::metrics::relative_errors(a, b).unwrap().0;
            let (e_direct, e_all) = (rel(&d, cd), rel(&r.image, ci));
            println!(
                "corridors {key}: GPU against CPU, direct light {e_direct:.4}, frame {e_all:.4}"
            );
            assert!(
                e_direct < 1.5e-2,
                "{key}: GPU direct light {e_direct:.4} from the CPU's"
            );
            assert!(e_all < 1e-2, "{key}: GPU frame {e_all:.4} from the CPU's");
        }
        let m = measure(&r.image, &d, &truth);
        let de = direct_error(&d, &truth.reference.direct, &truth.measured);
        let di = direct_error(&d, &truth.reference.direct, &inside);
        let n = inside.iter().filter(|&&b| b).count();
        println!("corridors {key} {b}: {m}; direct light against the one-bounce image {de:.4}, over the {n} pixels that hold one surface {di:.4}");
        if b == Backend::Cpu {
            record(&format!("corridors.{key}.rmse"), m.rel_rmse, 0.02);
            record(&format!("corridors.{key}.median"), m.indirect_median, 0.02);
            record(&format!("corridors.{key}.p90"), m.indirect_p90, 0.02);
            record(&format!("corridors.{key}.direct"), de, 0.02);
            record(&format!("corridors.{key}.direct-inside"), di, 0.02);
        }
        assert!(
            di < bound.direct_inside,
            "{key} {b}: direct light over the pixels that hold one surface {di:.4} ≥ {}",
            bound.direct_inside
        );
        assert!(
            m.rel_rmse < bound.rel_rmse,
            "{key} {b}: relative RMSE {:.4} ≥ {}",
            m.rel_rmse,
            bound.rel_rmse
        );
        assert!(
            m.indirect_median < bound.median,
            "{key} {b}: median {:.4} ≥ {}",
            m.indirect_median,
            bound.median
        );
        assert!(
            m.indirect_p90 < bound.p90,
            "{key} {b}: 90th percentile {:.4} ≥ {}",
            m.indirect_p90,
            bound.p90
        );
        assert!(
            de < bound.direct,
            "{key} {b}: direct light {de:.4} ≥ {}",
            bound.direct
        );
        if b == Backend::Cpu {
            cpu = Some((r.image, d));
        }
    }
}

// Bounds about 1.5× the worst of each family as measured (CPU and GPU alike; the figures of
// every scene are in docs/measurements.json, held within 2% by `record`). Against issue 36's
// targets (relative RMSE 0.15, median 10%, 90th percentile 30%, direct light 2%): the
// corridors under the sun meet all four (and the direct light also against a converged
// reference, `direct_light_against_a_converged_reference`); the lamp-lit corridors meet the
// relative RMSE after the first turn and the plates meet it, but not the medians of their dark
// lanes nor the direct light. References at 8192 spp: at 2048 their noise was a third to a half
// of the lamp-lit corridors' measured error.

/// Zero-thickness walls (two quads back to back) under the sun, against 8192 spp: relative
/// RMSE 0.058 / 0.055 / 0.051 / 0.059 at 1–4 turns, the indirect-only pixels 4–8% off at the
/// median, 13–19% at the 90th percentile; direct light 1.2–1.5% from the reference's one-bounce
/// image (3–4% in one pass against 2048 spp), 0.4–0.6% over the pixels that hold one surface
/// (the GPU's the same; 0.076 / 0.027 / 0.100 while its G-buffer showed the walls' backs).
const THIN_SUN: Bound = Bound {
    rel_rmse: 0.15,
    median: 0.125,
    p90: 0.3,
    direct: 0.022,
    direct_inside: 0.009,
};

/// Walls 0.06 thick under the sun: 0.079 / 0.031 / 0.024 / 0.072, medians 3–9%, p90 9–27%,
/// direct light 1.2–1.6% (5–7% in one pass against 2048 spp; 0.5–0.7% over the pixels that
/// hold one surface).
const THICK_SUN: Bound = Bound {
    rel_rmse: 0.14,
    median: 0.125,
    p90: 0.4,
    direct: 0.025,
    direct_inside: 0.01,
};

/// Lit by the emitter at one end, zero-thickness walls: 0.19 / 0.089 / 0.106 / 0.101 (0.21 /
/// 0.13 / 0.14 / 0.16 in one pass against 2048 spp). The indirect-only pixels lie in the lanes
/// after a turn, whose light in the reference is a few thousandths of the first lane's: about
/// half of them are exactly zero in the frame (which clamps a negative sum of light and
/// antiradiance to zero: median 100%) and others get light the reference does not have (90th
/// percentile up to 138×; at 2048 spp, whose noise lifted those lanes, 25×). The emitter's
/// direct light is 3.5–6.5% from the reference's (11–13% in one pass: 60–90% of its squared
/// error was one pixel row whose top 3% sees the lit floor over the near wall's top, a sliver a
/// regular sub-pixel grid misses, its first row 1/16 or 1/32 into the pixel; the passes' first
/// row lies 1/64 into it). Over the pixels that hold one surface: 1.4–2.5% (the emitter's cells
/// give each point its exact unshadowed irradiance; thin-lamp-3's is the floor pixels beside
/// the lamp, where a pixel's samples average a steep near field).
const THIN_LAMP: Bound = Bound {
    rel_rmse: 0.29,
    median: 1.5,
    p90: 200.0,
    direct: 0.1,
    direct_inside: 0.038,
};

/// As [`THIN_LAMP`] with thick walls: 0.21 / 0.099 / 0.084 / 0.091 (0.30 / 0.21 / 0.18 / 0.24
/// in one pass against 2048 spp), p90 up to 65×, direct 3.5–7.1% (21–33% in one pass: the
/// walls' tops over the lit lane, which a regular grid samples in steps of its rows). Over the
/// pixels that hold one surface 0.9–2.3% (the GPU's 1.6% on thick-lamp-3).
const THICK_LAMP: Bound = Bound {
    rel_rmse: 0.31,
    median: 1.5,
    p90: 100.0,
    direct: 0.106,
    direct_inside: 0.035,
};

/// The plates: thin 0.144 (median 11%, p90 33%, direct 0.071), thick 0.117 (15%, 50%, 0.052);
/// in one pass against 2048 spp 0.205 / 0.166, direct 0.28 / 0.23. Over the pixels that hold
/// one surface the direct light is 0.044 / 0.039 off (0.17 / 0.19 in one pass): rows of the
/// back wall crossed by the plates' horizontal shadow edges, where every pixel of a row takes
/// the same share of the samples' rows.
const STACK: Bound = Bound {
    rel_rmse: 0.22,
    median: 0.23,
    p90: 0.76,
    direct: 0.106,
    direct_inside: 0.066,
};

#[test]
fn thin_walls_under_the_sun() {
    for turns in 1..=4 {
        let s = serpentine(turns, Walls::Thin, Lit::Sun);
        check(&format!("thin-sun-{turns}"), &s, turns == 2, &THIN_SUN);
    }
}

#[test]
fn thick_walls_under_the_sun() {
    for turns in 1..=4 {
        let s = serpentine(turns, Walls::Thick, Lit::Sun);
        check(&format!("thick-sun-{turns}"), &s, false, &THICK_SUN);
    }
}

#[test]
fn thin_walls_lit_from_one_end() {
    for turns in 1..=4 {
        let s = serpentine(turns, Walls::Thin, Lit::Emitter);
        check(&format!("thin-lamp-{turns}"), &s, false, &THIN_LAMP);
    }
}

#[test]
fn thick_walls_lit_from_one_end() {
    for turns in 1..=4 {
        let s = serpentine(turns, Walls::Thick, Lit::Emitter);
        check(&format!("thick-lamp-{turns}"), &s, turns == 3, &THICK_LAMP);
    }
}

#[test]
fn a_stack_of_plates_with_offset_openings() {
    check("stack-thin", &stack(Walls::Thin), false, &STACK);
    check("stack-thick", &stack(Walls::Thick), true, &STACK);
}

/// The direct light against a nearly converged one-bounce image (the path tracer at 32,768 spp,
/// `reference --max-bounces 1`), at 4× supersampling in 4 passes, on the CPU (the GPU's direct
/// light is the CPU's within 1.1%, `check`): the eight corridors under the sun and the 1- and
/// 4-turn ones lit from one end. A 2048-spp reference is itself 1.4–2.1%
/// from a 65,536-spp one under the sun (its jittered pixel samples at the walls' edges), and
/// lit by the small emitter its one-bounce image is noisier still: most of the lamp-lit
/// corridors' 6–14% against 2048 spp was that reference's. Measured: under the sun 1.29 / 1.15 / 1.05 /
/// 1.17% with thin walls at 1–4 turns, 1.35 / 1.07 / 0.97 / 1.19% with thick ones, 0.30–0.46%
/// over the pixels that hold one surface: within issue 36's 2%. In one pass at 8× (as many
/// samples, on a regular 16×16 grid) the worst was 2.22% / 0.86%. Lit from one end: thin 2.10
/// / 7.66%, thick 2.05 / 6.71% (1 / 4 turns), 0.6–1.2% over the pixels that hold one surface;
/// the rest is the rows of a wall's top over the lit lane (one pass: 7.7–25.8%). The same four
/// at 8× in 16 passes with 256² emitter-sample maps: 1.45 / 1.68%, 1.44 / 2.03%, where the
/// reference's own noise (its per-pixel standard errors, as a relative RMSE) is 1.48 / 2.29%
/// and 1.97 / 2.61%: there the measurement no longer resolves the frame's error from the
/// reference's. Bounds about 1.5×.
#[test]
fn direct_light_against_a_converged_reference() {
    use antiradiance::reference::ReferenceOptions;
    // Worst over all pixels and over one-surface pixels, under the sun and from the lamp.
    let (mut sun, mut lamp): ((f64, f64), (f64, f64)) = ((0.0, 0.0), (0.0, 0.0));
    // The lamp at 8× in 16 passes with 256² maps: the worst error and the worst noise of the
    // reference it is measured against.
    let (mut fine_lamp, mut lamp_noise) = (0.0f64, 0.0f64);
    let mut cases = Vec::new();
    for walls in [Walls::Thin, Walls::Thick] {
        for turns in 1..=4 {
            cases.push((walls, turns, Lit::Sun));
        }
        for turns in [1, 4] {
            cases.push((walls, turns, Lit::Emitter));
        }
    }
    for (walls, turns, lit) in cases {
        let scene = serpentine(turns, walls, lit);
        let key = format!("{walls:?}-{lit:?}-{turns}");
        let fine = reference(
            &scene,
            &ReferenceOptions {
                spp: 32768,
                max_bounces: Some(1),
                seed: 79,
            },
        );
        let (w, h) = (scene.camera.width, scene.camera.height);
        let all = vec![true; (w * h) as usize];
        let inside = one_surface(&scene, w, h);
        let d = render_checked(
            &key,
            &scene,
            direct_only(4, 4, antiradiance::frame::emitters::SAMPLE_MAP_SIZE),
        )
        .image;
        let (e, ei) = (
            direct_error(&d, &fine.direct, &all),
            direct_error(&d, &fine.direct, &inside),
        );
        println!(
            "{key}: direct light at 4x in 4 passes against 32,768 spp {e:.4}, one surface {ei:.4}"
        );
        let worst = if lit == Lit::Sun { &mut sun } else { &mut lamp };
        *worst = (worst.0.max(e), worst.1.max(ei));
        if lit == Lit::Emitter {
            let d = render_checked(&key, &scene, direct_only(8, 16, 256)).image;
            let (e, noise) = (direct_error(&d, &fine.direct, &all), noise(&fine));
            println!(
                "{key}: at 8x in 16 passes, 256² maps {e:.4}; the reference's own noise {noise:.4}"
            );
            fine_lamp = fine_lamp.max(e);
            lamp_noise = lamp_noise.max(noise);
        }
    }
    println!(
        "worst under the sun {:.4} / {:.4}, from the lamp {:.4} / {:.4}",
        sun.0, sun.1, lamp.0, lamp.1
    );
    record("corridors.sun-direct", sun.0, 0.02);
    record("corridors.sun-direct.inside", sun.1, 0.02);
    record("corridors.lamp-direct", lamp.0, 0.02);
    record("corridors.lamp-direct.inside", lamp.1, 0.02);
    record("corridors.lamp-direct.fine", fine_lamp, 0.02);
    record("corridors.lamp-direct.noise", lamp_noise, 0.001);
    assert!(sun.0 < 0.02, "direct light under the sun {:.4}", sun.0);
    assert!(
        sun.1 < 0.007,
        "direct light under the sun where a pixel holds one surface {:.4}",
        sun.1
    );
    assert!(lamp.0 < 0.115, "direct light from the lamp {:.4}", lamp.0);
    assert!(
        lamp.1 < 0.018,
        "direct light from the lamp where a pixel holds one surface {:.4}",
        lamp.1
    );
    assert!(
        fine_lamp < 0.03,
        "direct light from the lamp at 8x in 16 passes {fine_lamp:.4}"
    );
}

/// The CPU frame's emission and direct light alone (`--iterations 0`) at `supersample`× in
/// `passes` passes, the emitter samples' maps `map`².
fn direct_only(supersample: u32, passes: u32, map: u32) -> Options {
    let mut o = Options {
        supersample: Some(supersample),
        passes: Some(passes),
        solver: SolverOverrides {
            iterations: Some(0),
            ..Default::default()
        },
        ..Options::backend(Backend::Cpu)
    };
    o.emitter_map_size = map;
    o
}

/// A path-traced image's own noise as a relative RMSE: the root mean square of its pixels'
/// standard errors over its mean (with `max_bounces: Some(1)` the image is the one-bounce
/// image). Its samples are independent, so the standard errors estimate each pixel's noise.
fn noise(r: &antiradiance::reference::Reference) -> f64 {
    let se = r.std_error.as_ref().expect("standard errors");
    let (mut var, mut sum, mut n) = (0.0, 0.0, 0usize);
    for (s, p) in se.pixels.iter().zip(&r.image.pixels) {
        for c in 0..3 {
            var += (s[c] as f64).powi(2);
            sum += p[c] as f64;
            n += 1;
        }
    }
    (var / n as f64).sqrt() / (sum / n as f64).max(1e-12)
}
