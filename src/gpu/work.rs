//! The raster work of each pass, counted from the draw records (no device): fragments, the
//! fragments that blend, primitives, and the Phong-sum terms of the local pass. lavapipe
//! rasterizes on the CPU, so these counts are the hardware-independent measure of speed that
//! `profile` reports beside the milliseconds.

use super::resources::ResourcePlan;
use crate::system::System;
use serde::Serialize;

/// What one pass draws per propagation.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct PassWork {
    /// Fragments shaded.
    pub fragments: u64,
    /// Fragments blended into their target (additive passes).
    pub blended: u64,
    /// Primitives (lines, triangles).
    pub primitives: u64,
}

/// The work of one propagation (global, push, local, pull) and of the convergence reduction.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct Work {
    /// Global: one (wide) line per rectangle of receiver bins of every link; the bins without
    /// filter weight or that the receiver does not read are discarded, not blended.
    pub global: PassWork,
    /// Push: one quad per node over its tile (nodes × bins fragments), odd depths blended.
    pub push: PassWork,
    /// Local: the irradiance texels and every leaf texel.
    pub local: PassWork,
    /// Pull: one line per cluster (clusters × bins fragments).
    pub pull: PassWork,
    /// Phong-sum terms the local pass evaluates (glossy leaves only).
    pub glossy_terms: u64,
}

impl Work {
    /// The work of the solver `plan` describes for `sys`.
    pub fn of(sys: &System, plan: &ResourcePlan) -> Self {
        let d = &plan.draw;
        let m = plan.layout.bins as u64;
        let h = &sys.hierarchy;
        let nodes = h.len() as u64;
        let odd = h.nodes.iter().filter(|n| n.depth % 2 == 1).count() as u64;
        let leaves = sys.leaves.len() as u64;
        let clusters = nodes - leaves;
        let quads = (d.leaf_quads.len() + d.diffuse_quads.len() + d.glossy_quads.len()) as u64;
        Self {
            global: PassWork {
                fragments: d.global_fragments,
                blended: d.global_blended,
                primitives: d.global_lines,
            },
            push: PassWork {
                fragments: nodes * m,
                blended: odd * m,
                primitives: 2 * nodes,
            },
            local: PassWork {
                fragments: leaves * (m + 1),
                blended: 0,
                primitives: 2 * quads,
            },
            pull: PassWork {
                fragments: clusters * m,
                blended: 0,
                primitives: clusters,
            },
            glossy_terms: if plan.lobe_bins.is_empty() {
                0
            } else {
                super::pack::glossy_terms(sys, &plan.lobe_bins)
            },
        }
    }

    /// The passes by name (`global`, `push`, `local`, `pull`).
    pub fn passes(&self) -> [(&'static str, PassWork); 4] {
        [
            ("global", self.global),
            ("push", self.push),
            ("local", self.local),
            ("pull", self.pull),
        ]
    }

    /// This work repeated `k` times (propagations per iteration).
    pub fn times(&self, k: u64) -> Self {
        let x = |p: PassWork| PassWork {
            fragments: p.fragments * k,
            blended: p.blended * k,
            primitives: p.primitives * k,
        };
        Self {
            global: x(self.global),
            push: x(self.push),
            local: x(self.local),
            pull: x(self.pull),
            glossy_terms: self.glossy_terms * k,
        }
    }

    /// Fragments of all passes.
    pub fn fragments(&self) -> u64 {
        self.passes().iter().map(|p| p.1.fragments).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::Features;
    use crate::scene::Precision;

    #[test]
    fn counts_follow_the_hierarchy_and_the_links() {
        let s = crate::scene::load_scene(std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/scenes/cornell-box-glossy.toml"
        )))
        .unwrap();
        let mut s = s;
        s.solver.bins = 32;
        s.solver.element_size = 0.5;
        let sys = System::build(&s).unwrap();
        let f = Features::for_system(&sys);
        let plan = ResourcePlan::new(
            &sys,
            &f,
            Precision::F16,
            ash::vk::Format::R16G16B16A16_SFLOAT,
            u32::MAX,
            16384,
            255,
        )
        .unwrap();
        let w = Work::of(&sys, &plan);
        let (n, l) = (sys.rows() as u64, sys.leaves.len() as u64);
        assert_eq!(w.push.fragments, n * 32);
        assert_eq!(w.pull.fragments, (n - l) * 32);
        assert_eq!(w.pull.primitives, n - l);
        // Every link blends at most its filter's support, in at least one line when it reaches
        // a bin its receiver reads; each line rasterizes its rectangle.
        let support: u64 = sys
            .links
            .links
            .iter()
            .map(|k| {
                sys.filters
                    .row(k.cone, k.receiver_bin as u32)
                    .unwrap()
                    .len() as u64
            })
            .sum();
        assert!(w.global.blended <= support && w.global.blended > 0);
        assert_eq!(w.global.primitives, plan.draw.links.len() as u64);
        assert!(w.global.primitives >= sys.links.links.len() as u64);
        assert!(w.global.fragments >= w.global.blended);
        // The glossy spheres' truncated lobes: fewer terms than every front × every incident bin.
        assert!(w.glossy_terms > 0 && w.glossy_terms < l * 32 * 16);
        assert_eq!(w.times(5).global.fragments, 5 * w.global.fragments);
    }
}
