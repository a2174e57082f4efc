//! The bounded link mesh's tests: subtrees, the bound over the motion, following it.

use super::*;
use crate::elements::build_elements;
use crate::scene::load_scene;
use crate::system::System;

/// The bundled moving Cornell box, coarse (elements 0.5, 32 bins) to keep the test short.
fn moving_box() -> Scene {
    let mut s = load_scene(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box-moving.toml"),
    )
    .unwrap();
    s.solver.element_size = 0.5;
    s.solver.bins = 32;
    s
}

#[test]
fn each_moving_object_is_one_subtree() {
    let s = moving_box();
    let sys = System::build(&s).unwrap();
    let b = sys.bound.as_ref().expect("keyframed objects are bounded");
    assert_eq!(b.objects, vec![1]);
    let h = &sys.hierarchy;
    // Exactly one node of group 1 has a parent outside it, and it holds every moving leaf.
    let tops: Vec<usize> = (0..h.len())
        .filter(|&i| b.node_group[i] == 1)
        .filter(|&i| b.node_group[h.nodes[i].parent as usize] != 1)
        .collect();
    assert_eq!(tops.len(), 1);
    let top = tops[0];
    for (e, &leaf) in h.leaf_of_element.iter().enumerate() {
        let moving = s.objects[1]
            .meshes
            .contains(&(sys.elements[e].mesh as usize));
        let inside = (top as u32..h.nodes[top].end).contains(&leaf);
        assert_eq!(moving, inside, "element {e}");
    }
    // Only the clusters above the groups mix them.
    assert!(b.node_group.iter().filter(|&&g| g == MIXED).count() <= 2);
    // A still scene has no bound and the median-split tree.
    assert!(System::build(&s.still()).unwrap().bound.is_none());
}

/// The link set is one valid for the whole motion: at every sampled time and halfway
/// between samples (covered by the travel margin), the oracle refines none of its links.
#[test]
fn no_link_is_refined_anywhere_along_the_motion() {
    let s = moving_box();
    let sys = System::build(&s).unwrap();
    let b = sys.bound.as_ref().unwrap();
    let (objects, mesh_group) = mesh_groups(&s).unwrap();
    let mut times = b.times.clone();
    times.extend(b.times.windows(2).map(|w| 0.5 * (w[0] + w[1])));
    for &t in &times {
        let els = elements_at(&s, &sys.elements, &mesh_group, &objects, &b.transforms, t);
        let mut h = sys.hierarchy.clone();
        place_nodes(&mut h, &els, &b.node_group);
        let c = Ctx::new(&h, &els, &sys.bins, s.solver.oracle);
        let split = sys
            .links
            .links
            .iter()
            .filter(|l| matches!(c.step(l.receiver, l.sender), Step::Split(_)))
            .count();
        assert_eq!(split, 0, "t = {t}: {split} links the oracle would refine");
    }
}

/// Following the motion recomputes only the links touching moving nodes; every other link
/// is what recomputing it at the new pose gives too (same pairs, same values).
#[test]
fn follow_equals_recomputing_every_link() {
    let s = moving_box();
    let mut sys = System::build(&s).unwrap();
    let pairs: Vec<(u32, u32)> = sys
        .links
        .links
        .iter()
        .map(|l| (l.receiver, l.sender))
        .collect();
    let moved = s.at(0.6);
    assert!(sys.follow(&moved, &s.solver).unwrap());
    let b = sys.bound.clone().unwrap();
    assert_ne!(b.transforms[0], s.objects[1].transform);
    let mut all = sys.clone();
    let every = Bound {
        moving_links: (0..sys.links.len() as u32).collect(),
        ..b.clone()
    };
    all.refresh_moving_links(&every, sys.energy_normalization);
    let mut changed = 0;
    for (k, (a, f)) in sys.links.links.iter().zip(&all.links.links).enumerate() {
        assert_eq!((a.receiver, a.sender), pairs[k]);
        assert_eq!(
            (a.sender_bin, a.cone, a.sides),
            (f.sender_bin, f.cone, f.sides),
            "link {k}"
        );
        let tol = 1e-12 * f.form_factor.abs().max(1e-300);
        assert!(
            (a.form_factor - f.form_factor).abs() <= tol,
            "link {k}: {a:?} vs {f:?}"
        );
        changed += (a.form_factor != 0.0) as usize;
    }
    assert!(changed > 0);
    // Elements are where preparing the moved scene puts them.
    let fresh = build_elements(&moved, &s.solver).unwrap();
    assert_eq!(sys.elements, fresh);
    // A scene whose elements differ (another subdivision) is refused, nothing changed.
    let mut finer = s.solver.clone();
    finer.element_size = 0.3;
    let before = sys.elements.clone();
    assert!(!sys.follow(&moved, &finer).unwrap());
    assert_eq!(sys.elements, before);
}
