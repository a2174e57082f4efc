//! Link structure: every (receiver leaf, sender leaf) pair with the sender (partly) in front of
//! the receiver is covered by exactly one link between ancestors-or-selves; none twice.

mod common;

use antiradiance::linker::partly_in_front;
use antiradiance::scene::{Material, Scene};
use antiradiance::System;
use common::*;
use glam::DVec3;

fn check_coverage(scene: &Scene) {
    let sys = System::build(scene).unwrap();
    let h = &sys.hierarchy;
    let n = sys.elements.len();
    let mut count = vec![0u8; n * n];
    for l in &sys.links.links {
        assert_ne!(l.receiver, l.sender, "self link survived");
        // Zero where the two ends are coplanar (they exchange nothing; see `calibrate_form_factors`).
        assert!(l.form_factor.is_finite() && l.form_factor >= 0.0);
        assert!((l.sender_bin as usize) < sys.bins.count && l.sender_bin == l.receiver_bin);
        for r in l.receiver..h.nodes[l.receiver as usize].end {
            let Some(re) = h.element(r) else { continue };
            for s in l.sender..h.nodes[l.sender as usize].end {
                let Some(se) = h.element(s) else { continue };
                let c = &mut count[re as usize * n + se as usize];
                *c += 1;
                assert!(*c == 1, "pair ({re}, {se}) covered twice");
            }
        }
    }
    let mut front = 0;
    for r in 0..n {
        for s in 0..n {
            let c = count[r * n + s];
            if r == s {
                assert_eq!(c, 0, "element {r} linked to itself");
            } else if partly_in_front(&sys.elements[r], &sys.elements[s]) {
                // Senders straddling the receiver's plane too: their front part sends light.
                front += 1;
                assert_eq!(c, 1, "front pair ({r}, {s}) not covered");
            }
        }
    }
    assert!(front > 0);
    println!(
        "{n} elements, {} links, {front} front pairs",
        sys.links.len()
    );
}

#[test]
fn every_front_pair_is_linked_exactly_once() {
    for oracle in [1.0, 0.3] {
        let mut s = uniform_enclosure(0.5, 1.0, 64, 0.35);
        s.solver.oracle = oracle;
        check_coverage(&s);
    }
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.toml");
    let mut cb = antiradiance::scene::load_scene(&path).unwrap();
    cb.solver.element_size = 0.4;
    cb.solver.bins = 32;
    check_coverage(&cb);
}

#[test]
fn linking_reports_count_and_rate() {
    let mut s = Scene::empty();
    let m = s.add_material(Material::diffuse("w", 0.5));
    add_box(&mut s, "room", DVec3::ZERO, DVec3::ONE, m, true);
    s.solver.element_size = 0.25;
    let sys = System::build(&s).unwrap();
    assert!(!sys.links.is_empty());
    assert!(sys.links.linking_ms > 0.0 && sys.links.links_per_second() > 0.0);
    assert_eq!(*sys.links.offsets.last().unwrap() as usize, sys.links.len());
}
