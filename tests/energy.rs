//! Energy at cluster links (issue 17, item 4): a closed enclosure must keep all its light.
//!
//! The closed unit box with a floating block inside, every surface emitting Le with albedo ρ,
//! converges to Le/(1−ρ) everywhere. At the default solver settings (128 bins, τ = 1, the
//! relative default element size) most of the exchange goes through cluster links; before their
//! form factors were calibrated they lost 4–9% of their energy, the image below was 3.3% dark on
//! average and 7.2% at worst (1.6% and 2.9% at elements 0.25), and at ρ = 0.999 the loss
//! (amplified a thousandfold) gave 62 instead of 1000.

mod common;

use antiradiance::engine::{Options, Rendered, SolverOverrides};
use antiradiance::scene::{Material, Scene, RELATIVE_ELEMENT_SIZE};
use antiradiance::solver::{global, pull, push, LocalMode, Table};
use antiradiance::system::closed_surfaces;
use antiradiance::BackendKind as Backend;
use antiradiance::{CpuSolver, System};
use common::*;
use glam::DVec3;
use std::f64::consts::PI;

/// The element size a scene file without `solver.element_size` gets for the unit box.
fn default_element_size() -> f64 {
    RELATIVE_ELEMENT_SIZE * 3f64.sqrt()
}

/// The closed box seen from inside, looking at the block and the floor's corner.
fn closed_box(rho: f64, element_size: f64, size: u32) -> Scene {
    let mut s = uniform_enclosure(rho, 1.0, 128, element_size);
    view(
        &mut s,
        DVec3::new(0.9, 0.85, 0.95),
        DVec3::new(0.2, 0.15, 0.1),
        75.0,
        size,
    );
    s
}

/// Mean and worst relative pixel error against `want`.
fn pixel_errors(r: &Rendered, want: f64) -> (f64, f64) {
    let px: Vec<f64> = r
        .image
        .pixels
        .iter()
        .flatten()
        .map(|&v| v as f64 / want - 1.0)
        .collect();
    let mean = px.iter().sum::<f64>() / px.len() as f64;
    (mean, px.iter().fold(0.0, |a: f64, x| a.max(x.abs())))
}

/// ρ = 0.5 at the default settings (128 bins, τ = 1), converged: the image's mean within 1% of
/// Le/(1−ρ) and every pixel within 3%, on both backends (the GPU at its default float16 tables),
/// at the element size of scenes built in code (0.25, 424 elements). At the relative default a
/// scene file gets (0.072 × the diagonal, 3328 elements; CPU only, the GPU takes minutes on
/// lavapipe and measured the same to 10⁻⁴) the mean holds and the worst pixel is 3.6%: one
/// radiance pushed to every leaf of a cluster receiver, not lost energy (measured before the
/// calibration: mean −3.3%, worst 7.2%; at 0.25: −1.6%, 2.9%).
#[test]
fn closed_box_at_default_settings_keeps_its_energy_on_both_backends() {
    let (rho, want) = (0.5, 2.0);
    for (element_size, backends, worst_bound) in [
        (0.25, vec![Backend::Cpu, Backend::Gpu], 0.03),
        (default_element_size(), vec![Backend::Cpu], 0.045),
    ] {
        let s = closed_box(rho, element_size, 40);
        for backend in backends {
            let options = Options {
                backend,
                shadow_map_size: 128,
                solver: SolverOverrides {
                    tolerance: Some(1e-5),
                    ..Default::default()
                },
                ..Default::default()
            };
            let r = render_checked("closed box ρ = 0.5", &s, options);
            let (mean, worst) = pixel_errors(&r, want);
            println!(
                "closed box ρ = 0.5, elements {element_size:.4}, {backend:?}: image mean {:+.3}%, worst pixel {:.3}% from Le/(1−ρ)",
                mean * 100.0,
                worst * 100.0
            );
            // Measured: 0.25 −0.03% / 1.04% (both backends); 0.1247 −0.15% / 3.56%.
            assert!(mean.abs() < 0.005, "{backend:?}: mean {mean}");
            assert!(worst < worst_bound, "{backend:?}: worst pixel {worst}");
        }
    }
}

/// ρ = 0.999 and 0.9999 with `--tolerance 1e-4`, on both backends: within 5% of Le/(1−ρ)
/// (1000, 10000) in at most 300 iterations, at the element size of scenes built in code (0.25)
/// with cluster links (τ = 1). Plain iteration contracts by ρ per step and took some 8000
/// iterations at 0.999 (before the energy fix it "converged" at 62); the tail extrapolation
/// sums the rest of the series where one mode dominates.
#[test]
fn stiff_closed_box_converges_to_le_over_one_minus_rho() {
    for (rho, backend) in [
        (0.999, Backend::Cpu),
        (0.9999, Backend::Cpu),
        (0.999, Backend::Gpu),
        (0.9999, Backend::Gpu),
    ] {
        let want = 1.0 / (1.0 - rho);
        let mut s = closed_box(rho, 0.25, 32);
        s.solver.tolerance = Some(1e-4);
        s.solver.max_iterations = 300;
        let r = render_with("closed box stiff", &s, backend);
        let (mean, worst) = pixel_errors(&r, want);
        println!(
            "closed box ρ = {rho}, tolerance 1e-4, {backend:?}: {} iterations, {} extrapolations, estimated error {:.2e}, image mean {:+.3}%, worst pixel {:.3}% from {want}, warnings {:?}",
            r.stats.iterations,
            r.stats.extrapolations,
            r.stats.estimated_error.unwrap(),
            mean * 100.0,
            worst * 100.0,
            r.stats.warnings
        );
        if rho == 0.999 {
            let b = format!("stiff.{backend:?}").to_lowercase();
            // Counts: exact on the CPU (f64); another device's float32 may take an iteration more.
            let count = if backend == Backend::Gpu { 0.1 } else { 0.0 };
            record(&format!("{b}.iterations"), r.stats.iterations as f64, count);
            record(
                &format!("{b}.extrapolations"),
                r.stats.extrapolations as f64,
                count,
            );
            record(&format!("{b}.worst"), worst, 0.02);
        }
        assert!(r.stats.iterations <= 300);
        assert!(r.stats.extrapolations >= 1);
        // Measured: mean −0.1%, worst pixel 2.0%.
        assert!(mean.abs() < 0.01, "mean {mean}");
        assert!(worst < 0.05, "worst pixel {worst}");
    }
}

/// Front bins with radiance 1 and back bins with antiradiance 1 on every leaf: what a closed
/// enclosure of uniform radiance holds.
fn uniform_field(sys: &System) -> Table {
    let m = sys.bins.count;
    let mut t = Table::zeros(sys.rows(), m);
    for l in &sys.leaves {
        for (v, c) in t.row_mut(l.node as usize).iter_mut().zip(&sys.bins.centers) {
            *v = DVec3::splat(l.area * l.cos_norm * c.dot(l.normal));
        }
    }
    pull::pull(&sys.hierarchy, &mut t);
    t
}

/// Irradiance at every leaf from `l_push` (the local pass's quadrature).
fn irradiances(sys: &System, l_push: &Table) -> Vec<f64> {
    sys.leaves
        .iter()
        .map(|l| {
            let row = l_push.row(l.node as usize);
            sys.bins
                .centers
                .iter()
                .zip(row)
                .map(|(c, v)| v.x * (-c.dot(l.normal)).max(0.0))
                .sum::<f64>()
                * sys.bins.omega
                * l.cos_norm
        })
        .collect()
}

/// The mechanism: one gather of the uniform field delivers the closed hemisphere, π, to the
/// leaves — split by link kind, the links with a cluster at either end deliver their exact share
/// (the projected solid angles of their leaves) — and the transport at albedo one has spectral
/// radius exactly 1 after the closed-scene normalization.
#[test]
fn cluster_links_deliver_the_closed_hemisphere() {
    let s = closed_box(0.5, default_element_size(), 8);
    let sys = System::build(&s).unwrap();
    let h = &sys.hierarchy;
    let (n, m) = (sys.rows(), sys.bins.count);
    let field = uniform_field(&sys);
    let area: f64 = sys.leaves.iter().map(|l| l.area).sum();
    let gather = |keep: &dyn Fn(&antiradiance::linker::Link) -> bool| {
        let mut sub = sys.clone();
        sub.links.links.retain(|l| keep(l));
        let mut offsets = vec![0u32; n + 1];
        for l in &sub.links.links {
            offsets[l.receiver as usize + 1] += 1;
        }
        for i in 0..n {
            offsets[i + 1] += offsets[i];
        }
        sub.links.offsets = offsets;
        let (mut l_in, mut l_push) = (Table::zeros(n, m), Table::zeros(n, m));
        global::global(&sub, &field, &mut l_in);
        push::push(&sub, &l_in, &mut l_push);
        irradiances(&sub, &l_push)
    };
    let weighted = |e: &[f64]| {
        e.iter()
            .zip(&sys.leaves)
            .map(|(e, l)| e * l.area)
            .sum::<f64>()
            / area
    };
    // All links: the closed hemisphere on average, and at every leaf within what one radiance
    // pushed to a whole cluster of leaves allows.
    let all = gather(&|_| true);
    let mean = weighted(&all) / PI - 1.0;
    let worst = all
        .iter()
        .fold(0.0, |a: f64, e| a.max((e / PI - 1.0).abs()));
    println!(
        "uniform field, one gather: area-weighted E/π − 1 = {mean:+.2e}, worst leaf {worst:.3}"
    );
    // Measured: −0.22% and 11% (before the calibration −3.2% and 18%).
    assert!(mean.abs() < 4e-3, "{mean}");
    assert!(worst < 0.15, "{worst}");
    // Links with a cluster at either end against the exact exchange of their leaves.
    let is_leaf = |i: u32| h.element(i).is_some();
    let clustered = gather(&|l| !(is_leaf(l.receiver) && is_leaf(l.sender)));
    let mut exact = vec![0.0; sys.leaves.len()];
    let slot = |node: u32| sys.leaf_slot[node as usize] as usize;
    for l in &sys.links.links {
        if is_leaf(l.receiver) && is_leaf(l.sender) {
            continue;
        }
        let below = |a: u32| (a..h.nodes[a as usize].end).filter(|&k| is_leaf(k));
        for r in below(l.receiver) {
            let re = &sys.elements[h.element(r).unwrap() as usize];
            for s in below(l.sender) {
                let se = &sys.elements[h.element(s).unwrap() as usize];
                let phi: f64 = se
                    .faces
                    .iter()
                    .map(|f| {
                        antiradiance::linker::projected_solid_angle(
                            re.center, re.normal, &f.corners,
                        )
                    })
                    .sum();
                let sign = if se.normal.dot(re.center - se.center) > 0.0 {
                    1.0
                } else {
                    -1.0
                };
                exact[slot(r)] += sign * phi;
            }
        }
    }
    let (got, want) = (weighted(&clustered), weighted(&exact));
    println!(
        "links with a cluster at either end: {got:.4} of {want:.4} (exact), {:+.3}%",
        (got / want - 1.0) * 100.0
    );
    // Measured −0.39% (eq. 17 alone: −5.2% at element size 0.125).
    assert!((got / want - 1.0).abs() < 0.01, "{got} vs {want}");
    // The transport at albedo one: spectral radius 1 (the normalization of closed scenes).
    let lambda = sys
        .energy_normalization
        .expect("the closed box is normalized");
    println!("spectral radius before the normalization: {lambda:.7}");
    // Measured 0.99788 (before the calibration of cluster links about 0.97).
    assert!((lambda - 1.0).abs() < 5e-3, "{lambda}");
    let mut white = sys.clone();
    for mat in &mut white.materials {
        *mat = Material::diffuse("white", 1.0);
    }
    let mut solver = CpuSolver::new(&white);
    solver.state.i_ex = field.clone();
    let mut ratio = 0.0;
    for _ in 0..60 {
        let before = solver.exitant_flux();
        solver.propagate(LocalMode::Both);
        ratio = solver.exitant_flux() / before;
    }
    println!("spectral radius after: {ratio:.12}");
    assert!((ratio - 1.0).abs() < 1e-9, "{ratio}");
}

/// Closed surfaces are recognized by their edges; an open box is not normalized.
#[test]
fn only_closed_scenes_are_normalized() {
    let closed = uniform_enclosure(0.5, 1.0, 32, 0.5);
    assert!(closed_surfaces(&closed));
    let mut open = closed.clone();
    open.meshes.retain(|m| m.name != "room5");
    assert!(!closed_surfaces(&open));
    let sys = System::build(&open).unwrap();
    assert!(sys.energy_normalization.is_none());
    // A closed solid alone in the void encloses nothing that faces in: not normalized either.
    let mut solid = Scene::empty();
    let mat = solid.add_material(Material::diffuse("grey", 0.5));
    add_box(&mut solid, "solid", DVec3::ZERO, DVec3::ONE, mat, false);
    solid.solver.bins = 32;
    solid.solver.element_size = 0.5;
    assert!(closed_surfaces(&solid));
    assert!(System::build(&solid)
        .unwrap()
        .energy_normalization
        .is_none());
}
