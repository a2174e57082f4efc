//! A system linked for its motion (the bounded link mesh, [`crate::bound`]) following its
//! scene: elements, moving nodes, lobe factors and moving links where the objects stand now.

use super::System;
use crate::bound::{place_nodes, Bound, MIXED, STATIC};
use crate::elements::build_elements;
use crate::scene::{Scene, SolverSettings};
use glam::DVec3;

impl System {
    /// Moves a system linked for its motion ([`System::bound`]) to where `scene`'s objects
    /// stand now: the elements and moving nodes, the leaves' normals, the glossy leaves' lobe
    /// factors and the moving links ([`Bound::refresh_links`]); nothing is relinked. Returns
    /// false (and changes nothing) when there is no bound, or when `scene` is not this
    /// system's scene moved rigidly (different elements), where the caller must prepare anew.
    pub fn follow(&mut self, scene: &Scene, settings: &SolverSettings) -> crate::Result<bool> {
        let Some(bound) = self.bound.take() else {
            return Ok(false);
        };
        let result = self.follow_with(&bound, scene, settings);
        let mut bound = bound;
        if let Ok(true) = result {
            bound.transforms = bound
                .objects
                .iter()
                .map(|&o| scene.objects[o].transform)
                .collect();
        }
        self.bound = Some(bound);
        result
    }

    fn follow_with(
        &mut self,
        bound: &Bound,
        scene: &Scene,
        settings: &SolverSettings,
    ) -> crate::Result<bool> {
        let els = build_elements(scene, settings)?;
        let same = els.len() == self.elements.len()
            && els.iter().zip(&self.elements).all(|(a, b)| a.same_faces(b));
        if !same {
            return Ok(false);
        }
        self.elements = els;
        place_nodes(&mut self.hierarchy, &self.elements, &bound.node_group);
        for l in &mut self.leaves {
            let e = &self.elements[self.hierarchy.element(l.node).expect("leaf") as usize];
            l.normal = e.normal;
            l.cos_norm = self.bins.cosine_normalization(e.normal);
            l.blocks_back = e.blocks_back;
        }
        if self.lobes.iter().any(Option::is_some) {
            let (norm, slot) = super::lobe_factors(&self.leaves, &self.lobes, &self.bins);
            self.lobe_norm = norm;
            self.lobe_slot = slot;
        }
        self.refresh_moving_links(bound, self.energy_normalization);
        Ok(true)
    }

    /// [`Bound::refresh_links`] on this system's links and geometry.
    pub(crate) fn refresh_moving_links(&mut self, bound: &Bound, lambda: Option<f64>) {
        bound.refresh_links(
            &mut self.links,
            &self.hierarchy,
            &self.elements,
            &self.bins,
            &self.filters,
            lambda,
        );
    }

    /// Spheres (center, radius) around every moving object where this system has it: the top node of
    /// each group. Empty without a bound.
    pub fn moving_spheres(&self) -> Vec<(DVec3, f64)> {
        let Some(b) = &self.bound else {
            return Vec::new();
        };
        let h = &self.hierarchy;
        (0..h.len())
            .filter(|&i| {
                let g = b.node_group[i];
                let p = h.nodes[i].parent;
                g != STATIC && g != MIXED && (p == u32::MAX || b.node_group[p as usize] != g)
            })
            .map(|i| (h.nodes[i].center, h.nodes[i].radius))
            .collect()
    }
}
