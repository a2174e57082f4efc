//! Link records read in several descriptor ranges (issue 35, item 4): the global pass draws the
//! links chunk by chunk with a set per chunk, in the same order as from one range, so the
//! solution is the same; after a move the chunks follow the new record count. Here the range
//! is capped far below maxStorageBufferRange so that a small scene needs many chunks.

mod common;

use antiradiance::engine::{Engine, GpuTuning, Options};
use antiradiance::progress::Silent;
use antiradiance::scene::load_scene;
use antiradiance::BackendKind;
use std::path::Path;

fn scene(name: &str) -> antiradiance::Scene {
    load_scene(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scenes")
            .join(name),
    )
    .unwrap()
}

fn options(link_range: Option<u64>) -> Options {
    let mut o = Options {
        backend: BackendKind::Gpu,
        width: Some(32),
        height: Some(32),
        shadow_map_size: 256,
        context: Some(common::context()),
        gpu: GpuTuning {
            link_range,
            force_table_accumulation: common::force_f16_accumulation(),
            ..GpuTuning::default()
        },
        ..Options::default()
    };
    o.solver.bins = Some(32);
    o.solver.element_size = Some(0.5);
    o
}

/// Largest absolute difference of two tables, over their largest value.
fn table_diff(a: &antiradiance::solver::Table, b: &antiradiance::solver::Table) -> f64 {
    assert_eq!(a.data.len(), b.data.len());
    let peak = b.data.iter().fold(0.0f64, |m, v| m.max(v.max_element()));
    let worst = a
        .data
        .iter()
        .zip(&b.data)
        .fold(0.0f64, |m, (p, q)| m.max((*p - *q).abs().max_element()));
    worst / peak
}

/// 3,072-byte ranges (256 records): the Cornell box's links take dozens of chunks, and the
/// exitant table equals the one-range solve's. The draws keep their order, so additive blending
/// sums in the same order: measured equal to the last bit (0.0).
#[test]
fn chunked_links_solve_as_one_range() {
    let s = scene("cornell-box.toml");
    let mut one = Engine::new(&s, &options(None), &Silent).unwrap();
    let mut chunked = Engine::new(&s, &options(Some(3072)), &Silent).unwrap();
    for e in [&mut one, &mut chunked] {
        e.initialize().unwrap();
        e.iterate(4).unwrap();
    }
    let records = chunked.work().unwrap().global.primitives;
    assert!(
        records > 20 * 256,
        "{records} records: too few for many chunks"
    );
    let d = table_diff(&chunked.i_ex().unwrap(), &one.i_ex().unwrap());
    println!("{records} line records in chunks of 256: I_ex differs by {d:e} of its peak");
    assert!(d <= 1e-6, "{d}");
    let img = (chunked.draw().unwrap(), one.draw().unwrap());
    assert_eq!(img.0.pixels, img.1.pixels);
    common::assert_clean(&common::context());
}

/// After keyframed moves the follow re-packs the records in place: the chunks are rewritten
/// for the new records, and the warm-started solution equals the one-range engine's.
#[test]
fn chunked_links_follow_moves() {
    let s = scene("cornell-box-moving.toml");
    let mut one = Engine::new(&s, &options(None), &Silent).unwrap();
    let mut chunked = Engine::new(&s, &options(Some(3072 * 3)), &Silent).unwrap();
    let n = one.prepared().settings.iterations_per_frame;
    for e in [&mut one, &mut chunked] {
        e.initialize().unwrap();
        e.iterate(n).unwrap();
    }
    for t in [0.2, 0.4] {
        for e in [&mut one, &mut chunked] {
            e.set_time(t).unwrap();
            e.update().unwrap();
            assert!(!e.relinked() && e.warm_started(), "t = {t}");
            e.iterate(n).unwrap();
        }
        let d = table_diff(&chunked.i_ex().unwrap(), &one.i_ex().unwrap());
        println!("t = {t}: I_ex differs by {d:e} of its peak");
        assert!(d <= 1e-6, "t = {t}: {d}");
    }
    common::assert_clean(&common::context());
}
