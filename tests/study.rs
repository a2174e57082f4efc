//! `study` on a tiny scene: the CSV has one row per run with the expected columns, and both
//! plots are written as PNG files.

mod common;

use antiradiance::engine::Options;
use antiradiance::progress::Silent;
use antiradiance::reference::{render_reference, ReferenceOptions};
use antiradiance::scene::{Material, Scene};
use antiradiance::study::{self, StudyOptions, Truth, CSV_HEADER};
use antiradiance::BackendKind;
use common::*;
use glam::DVec3;

/// A small room lit by a ceiling lamp, with a block in it (so antiradiance has work to do).
fn tiny() -> Scene {
    let mut s = Scene::empty();
    let wall = s.add_material(Material::diffuse("wall", 0.6));
    let lamp = s.add_material(Material {
        ke: DVec3::splat(8.0),
        ..Material::diffuse("lamp", 0.0)
    });
    add_box(&mut s, "room", DVec3::ZERO, DVec3::ONE, wall, true);
    add_box(
        &mut s,
        "block",
        DVec3::new(0.3, 0.0, 0.3),
        DVec3::new(0.6, 0.4, 0.6),
        wall,
        false,
    );
    quad(
        &mut s,
        "lamp",
        [
            DVec3::new(0.4, 0.99, 0.4),
            DVec3::new(0.6, 0.99, 0.4),
            DVec3::new(0.6, 0.99, 0.6),
            DVec3::new(0.4, 0.99, 0.6),
        ],
        lamp,
    );
    s.camera.eye = DVec3::new(0.5, 0.5, 0.98);
    s.camera.target = DVec3::new(0.5, 0.45, 0.0);
    s.camera.fov_y_deg = 70.0;
    s.camera.width = 24;
    s.camera.height = 24;
    s.solver.bins = 32;
    s.solver.element_size = 0.5;
    s
}

#[test]
fn tiny_study_writes_csv_and_plots() {
    let s = tiny();
    let r = render_reference(
        &s,
        &ReferenceOptions {
            spp: 64,
            max_bounces: None,
            seed: 1,
        },
        &Silent,
    )
    .unwrap();
    let truth = Truth {
        image: r.image,
        direct: Some(r.direct),
    };
    let dir = Scratch::new("study");
    let mut o = StudyOptions::defaults(&s, dir.to_path_buf());
    o.iterations = 2;
    o.bins = vec![32, 64];
    o.element_sizes = vec![0.25];
    o.spp = vec![1, 4, 16];
    o.rays_per_link = vec![4, 16];
    o.subdivisions = vec![0, 2];
    o.vpls = vec![8, 32];
    o.cubes = vec![32];
    let ctx = context();
    o.render = Options {
        context: Some(ctx.clone()),
        backend: BackendKind::Gpu,
        shadow_map_size: 64,
        ..Default::default()
    };
    let mut logged = 0;
    let rows = study::run(&s, &truth, &o, &Silent, &mut |_| logged += 1).unwrap();
    let msgs = ctx.validation_messages();
    assert!(msgs.is_empty(), "validation errors:\n{}", msgs.join("\n"));
    let cross = study::write(&rows, &dir).unwrap();
    println!("crossover: {cross:?}");
    // base, 64 bins (32 is the base), elem 0.25, asymmetric, f32: 5 configurations × 2
    // iterations; hierarchical radiosity at 4 and 16 rays per link and progressive refinement at
    // subdivision 0 and 2, × 2 iterations; instant radiosity at 8 and 32 paths (one image
    // each); image-based radiosity at cube 32 with 8 and 32 paths (one image each); plus 3
    // path tracer runs.
    assert_eq!(rows.len(), 25);
    assert_eq!(logged, 25);
    let csv = std::fs::read_to_string(dir.join("study.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], CSV_HEADER);
    assert_eq!(lines.len(), 26);
    let cols = CSV_HEADER.split(',').count();
    let families: Vec<&str> = lines[1..]
        .iter()
        .map(|l| l.split(',').nth(1).unwrap())
        .collect();
    for f in [
        "base",
        "bins",
        "element_size",
        "scheme",
        "precision",
        "rays_per_link",
        "subdivision",
        "vpls",
        "cube",
        "spp",
    ] {
        assert!(families.contains(&f), "no {f} rows");
    }
    for l in &lines[1..] {
        assert_eq!(l.split(',').count(), cols, "row {l}");
    }
    for r in &rows {
        assert!(r.frame_ms > 0.0 && r.full.rel_rmse.is_finite() && r.full.flip >= 0.0);
        assert!(r.indirect.is_some());
        match r.method {
            "antiradiance" | "hierarchical-radiosity" => {
                assert!(r.linking_ms > 0.0 && r.residual.is_some() && r.links.unwrap() > 0)
            }
            "progressive-radiosity" => {
                assert!(r.links == Some(0) && r.shots.unwrap() > 0 && r.subdivision.is_some())
            }
            "instant-radiosity" => assert!(
                r.links == Some(0)
                    && r.iterations == Some(1)
                    && r.vpls.unwrap() >= r.vpl_paths.unwrap() as usize
            ),
            "image-based-radiosity" => assert!(
                r.links == Some(0)
                    && r.iterations == Some(1)
                    && r.cube == Some(32)
                    && r.vpls.unwrap() >= r.vpl_paths.unwrap() as usize
            ),
            _ => assert_eq!(r.method, "pathtracer"),
        }
    }
    // The path tracer's error falls as samples grow (16× the samples: about 4× less noise).
    let pt: Vec<f64> = rows
        .iter()
        .filter(|r| r.method == "pathtracer")
        .map(|r| r.full.rel_rmse)
        .collect();
    println!("path tracer relative RMSE at 1, 4, 16 spp: {pt:?}");
    assert!(pt[2] < 0.6 * pt[0], "path tracer error {pt:?}");
    for png in ["error-vs-time.png", "convergence.png"] {
        let bytes = std::fs::read(dir.join(png)).unwrap();
        assert!(
            bytes.starts_with(b"\x89PNG") && bytes.len() > 10_000,
            "{png}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The dynamic study (issue 34 item 4) on the moving Cornell box at 16×16: it writes the CSV
/// and both plots, its second run takes every per-frame reference from the cache, and every
/// error it reports is `compare`'s on the image and reference it names.
#[test]
fn dynamic_study_writes_its_rows_reuses_its_references_and_measures_as_compare() {
    use antiradiance::study::dynamic::{run, write, DynamicOptions};
    let scene = antiradiance::scene::load_scene(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box-moving.toml"),
    )
    .unwrap();
    let out = Scratch::new("dynamic");
    let mut o = DynamicOptions::defaults(out.to_path_buf(), 3, 4.0);
    o.reference_spp = 16;
    o.iterations_per_frame = vec![1, 2];
    o.spp = vec![1];
    o.accumulate_spp = 2;
    o.vpls = 8;
    o.save_images = true;
    o.render.backend = antiradiance::BackendKind::Cpu;
    o.render.width = Some(16);
    o.render.height = Some(16);
    o.render.solver.bins = Some(32);
    let first = run(&scene, &o, &antiradiance::progress::Silent).unwrap();
    assert_eq!(first.cached_references, 0);
    // 3 frames × (antiradiance at 1 and 2 iterations, instant radiosity, the path tracer from
    // scratch, accumulating).
    assert_eq!(first.rows.len(), 3 * 5);
    write(&first.rows, &out).unwrap();
    for f in ["frames.csv", "error-vs-time.png", "error-over-frames.png"] {
        assert!(std::fs::metadata(out.join(f)).unwrap().len() > 0, "{f}");
    }
    let csv = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    for col in ["method", "setting", "frame", "time", "frame_ms", "rel_rmse"] {
        assert!(header.contains(&col), "{col}");
    }
    assert_eq!(csv.lines().count(), 1 + first.rows.len());
    for r in &first.rows {
        let img =
            antiradiance::frame::Image::read_exr(&out.join(r.image.as_ref().unwrap())).unwrap();
        let reference = antiradiance::frame::Image::read_exr(&out.join(&r.reference)).unwrap();
        let m = antiradiance::metrics::compare(&img, &reference).unwrap();
        // The saved EXR is float32, as the image the study measured.
        assert!(
            (m.rel_rmse - r.metrics.rel_rmse).abs() <= 1e-9 * r.metrics.rel_rmse.max(1.0),
            "{} {} frame {}: {} vs {}",
            r.method,
            r.setting,
            r.frame,
            m.rel_rmse,
            r.metrics.rel_rmse
        );
        assert!(r.metrics.rel_rmse.is_finite() && r.frame_ms > 0.0);
    }
    // The frames differ (the block moves), so their references do.
    let refs: std::collections::BTreeSet<_> =
        first.rows.iter().map(|r| r.reference.clone()).collect();
    assert_eq!(refs.len(), 3);
    let second = run(&scene, &o, &antiradiance::progress::Silent).unwrap();
    assert_eq!(second.cached_references, 3);
    // Deterministic methods measure the same against the cached references.
    for (a, b) in first.rows.iter().zip(&second.rows) {
        if a.method == "pathtracer" || a.method == "pathtracer-accumulating" {
            assert_eq!(
                a.metrics.rel_rmse, b.metrics.rel_rmse,
                "{} {}",
                a.method, a.frame
            );
        }
    }
}
