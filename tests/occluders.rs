//! Occluders in the stability suite: antiradiance must cancel what U sends through thin walls
//! and stacks of slabs, and where the discrete system grows the loop must say so and never hand
//! a non-finite image on (CPU solver; see also tests/stability.rs).

mod common;

use antiradiance::scene::{Material, Scene, Scheme};
use antiradiance::BackendKind as Backend;
use antiradiance::{CpuSolver, System};
use common::*;
use glam::DVec3;

/// Black slabs between an emitter and a floor: only antiradiance removes the light U sends
/// through them. `layers` parallel slabs, each larger than the lamp's shadow footprint.
fn layered(layers: usize, albedo: f64, thickness: f64) -> Scene {
    let mut s = Scene::empty();
    let e = s.add_material(Material {
        ke: DVec3::splat(10.0),
        ..Material::diffuse("lamp", 0.0)
    });
    let slab = s.add_material(Material::diffuse("slab", albedo));
    let f = s.add_material(Material::diffuse("floor", 0.5));
    floor(&mut s, 2.0, f);
    let p = DVec3::new;
    lamp(&mut s, 0.2, 2.0, e);
    for k in 0..layers {
        let y = 0.3 + 1.4 * k as f64 / layers.max(1) as f64;
        add_box(
            &mut s,
            &format!("slab{k}"),
            p(-0.6, y, -0.6),
            p(0.6, y + thickness, 0.6),
            slab,
            false,
        );
    }
    s.solver.bins = 64;
    s.solver.element_size = 0.3;
    s.solver.oracle = 0.5;
    // Antiradiance reaches one more layer per iteration; ten layers settle after ~40.
    s.solver.iterations = 8 + 4 * layers;
    s
}

/// Irradiance on the floor under the stack (|x|, |z| < 0.1: in every slab's umbra) relative to
/// the same spot without slabs.
fn leak(layers: usize, thickness: f64) -> f64 {
    let under = |s: &Scene| {
        let sys = System::build(s).unwrap();
        let mut solver = CpuSolver::new(&sys);
        solver.solve(Scheme::Symmetric, s.solver.iterations, 4);
        assert!(solver.i_ex.data.iter().all(|v| v.is_finite()));
        let (mut sum, mut n) = (0.0, 0);
        for (li, l) in sys.leaves.iter().enumerate() {
            let c = sys.elements[sys.hierarchy.element(l.node).unwrap() as usize].center;
            if c.y.abs() < 1e-9 && c.x.abs() < 0.6 && c.z.abs() < 0.6 && l.normal.y > 0.5 {
                sum += solver.irradiance(li).x;
                n += 1;
            }
        }
        assert!(n > 0);
        sum / n as f64
    };
    under(&layered(layers, 0.0, thickness)) / under(&layered(0, 0.0, thickness))
}

/// A thin wall (1% of the room) between a bright emitter and the floor, and ten parallel
/// occluding layers: antiradiance must still cancel the light U sends through them.
#[test]
fn thin_wall_and_ten_layers_leak_within_bounds() {
    // Measured −3.6% and −6.2%. Ten layers of cancellation amplify how cluster links are
    // weighted: eq. 17 alone gave +12.5% for ten layers, eq. 17 with the receiver-cosine
    // correction −3.7%, the calibration of cluster links (which makes a closed box exact) −6.2%.
    for (layers, thickness, bound) in [(1, 0.01, 0.05), (10, 0.02, 0.08)] {
        let l = leak(layers, thickness);
        println!("{layers} layer(s) {thickness} thick: floor under them gets {:.2}% of the unoccluded irradiance", l * 100.0);
        assert!(l.abs() < bound, "{layers} layers: leak {l}");
    }
    // Grey slabs (albedo 0.5): light bouncing between ten layers while antiradiance crosses
    // them. On this configuration the discrete system grows in both schemes (the paper's
    // warning about multiple occlusion); the loop must say so and stay finite.
    let mut s = layered(10, 0.5, 0.02);
    s.solver.element_size = 0.6;
    s.solver.oracle = 1.0;
    s.solver.iterations = 30;
    view(
        &mut s,
        DVec3::new(0.0, 1.2, 3.0),
        DVec3::new(0.0, 0.8, 0.0),
        60.0,
        16,
    );
    let c = render_with("ten grey layers", &s, Backend::Cpu);
    let converged = *c.stats.residuals.last().unwrap() < 1e-3;
    assert!(
        converged
            || c.stats
                .fallbacks
                .iter()
                .any(|f| f.contains("does not converge")),
        "neither converged nor reported: {:?}",
        c.stats.residuals
    );
}

/// Slabs spanning a closed room wall to wall (their sides lie in the walls' planes, contact
/// along every edge). Two slabs: the symmetric scheme grows (1.8× per iteration, alternating in
/// sign), the loop notices, says so and restarts it damped (ω = 0.54), which converges
/// (measured residual 2.43e-3 after its 27 iterations). Ten staggered slabs: the plain scheme
/// grows 4.9× per iteration; damped (ω = 0.25) it contracts (residual 9.65e-3 after 30
/// iterations, never growing), and the image is finite.
#[test]
fn divergence_is_detected_reported_and_never_reaches_the_image() {
    let build = |layers: usize, staggered: bool| {
        let mut s = Scene::empty();
        let m = s.add_material(Material::diffuse("m", 0.9));
        let e = s.add_material(Material {
            ke: DVec3::ONE,
            ..Material::diffuse("e", 0.5)
        });
        let p = DVec3::new;
        add_box(&mut s, "room", p(0.0, -0.1, 0.0), p(1.0, 1.2, 1.0), m, true);
        quad(
            &mut s,
            "lamp",
            [
                p(0.0, 1.19, 0.0),
                p(1.0, 1.19, 0.0),
                p(1.0, 1.19, 1.0),
                p(0.0, 1.19, 1.0),
            ],
            e,
        );
        for k in 0..layers {
            let y = 0.05 + 0.1 * k as f64;
            let (x0, w) = match (staggered, k % 2) {
                (false, _) => (0.0, 1.0),
                (true, 0) => (0.0, 0.7),
                (true, _) => (0.3, 0.7),
            };
            add_box(
                &mut s,
                &format!("l{k}"),
                p(x0, y, 0.0),
                p(x0 + w, y + 0.02, 1.0),
                m,
                false,
            );
        }
        s.solver.bins = 64;
        s.solver.element_size = 0.25;
        s.solver.iterations = 40;
        view(&mut s, p(0.5, 0.8, 0.95), p(0.5, 0.3, 0.0), 70.0, 16);
        s
    };
    let r = render_with("two wall-to-wall slabs", &build(2, false), Backend::Cpu);
    let f = r.stats.fallbacks.join(" | ");
    assert!(f.contains("symmetric scheme does not converge"), "{f}");
    assert!(
        f.contains("restarted with the symmetric scheme damped"),
        "{f}"
    );
    assert!(!f.contains("either"), "{f}");
    assert_eq!(r.stats.scheme, antiradiance::Scheme::Symmetric);
    let last = *r.stats.residuals.last().unwrap();
    assert!(
        last < 1e-2 && last < r.stats.residuals[0] / 100.0,
        "{:?}",
        r.stats.residuals
    );

    let mut s = build(10, true);
    s.solver.iterations = 30;
    let r = render_with("ten staggered wall-to-wall slabs", &s, Backend::Cpu);
    let f = r.stats.fallbacks.join(" | ");
    assert!(f.contains("symmetric scheme does not converge"), "{f}");
    assert!(f.contains("symmetric scheme damped"), "{f}");
    assert!(!f.contains("kept iteration"), "{f}");
    let last = *r.stats.residuals.last().unwrap();
    assert!(last < 2e-2, "{:?}", r.stats.residuals);
    assert!(r.stats.energies.iter().all(|e| e.is_finite()));
}
