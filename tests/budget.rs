//! A budget instead of a refusal (issue 35): a scene whose links or tables would not fit is
//! discretized coarser until it fits, and says so in its decisions; it is refused only when
//! even the coarsest settings do not fit. Face clusters keep a dense mesh's leaves near its area
//! over the element area.

mod common;

use antiradiance::engine::{fit_system, Options, Prepared};
use antiradiance::gpu::resources::ResourcePlan;
use antiradiance::scene::{load_scene, Material, Scene};
use antiradiance::BackendKind as Backend;
use common::*;
use glam::DVec3;
use std::path::Path;

fn cornell() -> Scene {
    load_scene(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.toml")).unwrap()
}

/// The Cornell box (0.70M links at τ = 1) under a budget of 200,000 links: linked at a larger τ,
/// within the budget, the step named in the decisions.
#[test]
fn a_link_budget_coarsens_the_links_until_they_fit() {
    let s = cornell();
    let options = Options {
        max_links: Some(200_000),
        ..Options::backend(Backend::Cpu)
    };
    let prep = Prepared::new(&s, &options, None, &antiradiance::progress::Silent).unwrap();
    let links = prep.system.links.len();
    println!(
        "cornell box at 200K links: τ {}, element size {}, {links} links; {:?}",
        prep.settings.oracle, prep.settings.element_size, prep.plan.decisions
    );
    assert!(links <= 200_000 && links > 20_000, "{links} links");
    assert!(prep.settings.oracle > 1.0);
    let said: Vec<&String> = prep
        .plan
        .decisions
        .iter()
        .filter(|d| d.contains("link budget"))
        .collect();
    assert_eq!(said.len(), 1, "{:?}", prep.plan.decisions);
    assert!(said[0].contains(&format!("{links} links")), "{}", said[0]);
    // At the defaults nothing is coarsened, and nothing says so.
    let prep = Prepared::new(
        &s,
        &Options::backend(Backend::Cpu),
        None,
        &antiradiance::progress::Silent,
    )
    .unwrap();
    assert_eq!(prep.settings.oracle, 1.0);
    assert!(!prep.plan.decisions.iter().any(|d| d.contains("coarsened")));
}

/// 4096 bins over a unit quad at element size 0.003 (~220K elements) need some 100 GB of
/// tables: under a 256 MB memory budget the element size grows until the tables fit.
#[test]
fn a_memory_budget_coarsens_the_elements_until_the_tables_fit() {
    let mut s = Scene::empty();
    let m = s.add_material(Material::diffuse("w", 0.5));
    quad(
        &mut s,
        "q",
        [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y],
        m,
    );
    s.solver.bins = 4096;
    s.solver.element_size = 0.003;
    let budget = 256u64 << 20;
    let mut settings = s.solver.clone();
    let (sys, said) = fit_system(&s, &mut settings, Some(budget), u64::MAX, true).unwrap();
    let tables =
        ResourcePlan::worst_table_bytes(sys.rows() as u32, 4096, settings.precision).unwrap();
    println!(
        "quad: element size {} → {}, {} elements, tables {tables} bytes; {said:?}",
        0.003,
        settings.element_size,
        sys.elements.len()
    );
    assert!(tables <= budget, "{tables} > {budget}");
    assert!(settings.element_size > 0.003);
    assert!(
        said.len() == 1 && said[0].contains("memory budget"),
        "{said:?}"
    );
}

/// Nothing fits a budget of one link: refused, saying that even the coarsest settings do not.
#[test]
fn a_scene_that_cannot_fit_is_refused_with_the_reason() {
    let s = cornell();
    let mut settings = s.solver.clone();
    let err = match fit_system(&s, &mut settings, None, 1, true) {
        Ok(_) => panic!("one link fits"),
        Err(e) => e.to_string(),
    };
    assert!(err.contains("coarsest") && err.contains("links"), "{err}");
}

/// A fine sphere (81,920 triangles) in a closed room: its triangles group into face clusters, so
/// the leaves stay near the sphere's area over the element area and the links near those of the
/// same room with a coarse sphere; without clusters every triangle is a leaf.
#[test]
fn a_dense_mesh_makes_about_its_area_in_leaves() {
    let room = |level: usize, clusters: bool| {
        let mut s = room_with_sphere(level);
        s.solver.face_clusters = clusters;
        s
    };
    let sys = |s: &Scene| antiradiance::System::build(s).unwrap();
    let coarse = sys(&room(2, true));
    let fine = sys(&room(6, true));
    let area = 4.0 * std::f64::consts::PI * 0.25;
    // The sphere is the last mesh (the room's walls come first).
    let last = |sys: &antiradiance::System| sys.elements.iter().map(|e| e.mesh).max().unwrap();
    let sphere_leaves =
        |sys: &antiradiance::System| sys.elements.iter().filter(|e| e.mesh == last(sys)).count();
    let leaves = sphere_leaves(&fine);
    println!(
        "sphere of 81920 triangles: {leaves} leaves ({} faces), {} links; 320 triangles: {} leaves, {} links",
        fine.elements.iter().filter(|e| e.mesh == last(&fine)).map(|e| e.faces.len()).sum::<usize>(),
        fine.links.len(),
        sphere_leaves(&coarse),
        coarse.links.len()
    );
    // Every triangle is in exactly one leaf.
    assert_eq!(
        fine.elements
            .iter()
            .filter(|e| e.mesh == last(&fine))
            .map(|e| e.faces.len())
            .sum::<usize>(),
        81920
    );
    // About the area over a cluster's (a disc of half the element size), within a few times.
    let disc = std::f64::consts::PI * 0.125 * 0.125;
    assert!(
        (leaves as f64) < 6.0 * area / disc && leaves >= 20,
        "{leaves} leaves for area {area}"
    );
    assert!(fine.links.len() < 3 * coarse.links.len());
    // Without clusters: one leaf per triangle at least.
    let mut s = room(4, false);
    s.solver.face_clusters = false;
    assert!(sphere_leaves(&sys(&s)) >= 5120);
}
