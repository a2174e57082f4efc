//! Scene statistics for `antiradiance info`: sizes, linking time, memory by resource, passes.

use crate::scene::{Precision, Scene};
use crate::system::System;
use serde::Serialize;
use std::collections::BTreeMap;

/// Summary of a discretized scene.
#[derive(Debug, Clone, Serialize)]
pub struct Info {
    /// Scene file.
    pub scene: String,
    /// Input triangles.
    pub triangles: usize,
    /// Leaf elements.
    pub elements: usize,
    /// Hierarchy nodes (table rows).
    pub nodes: usize,
    /// Hierarchy depth.
    pub depth: u32,
    /// Links.
    pub links: usize,
    /// Directional bins.
    pub bins: usize,
    /// Cone classes with a spreading table.
    pub cone_classes: usize,
    /// Element subdivision and hierarchy time.
    pub meshing_ms: f64,
    /// Link construction time.
    pub linking_ms: f64,
    /// Links built per second.
    pub links_per_second: f64,
    /// Bytes by resource (GPU layout of §4.1 at the scene's precision; `cpu_tables` for the solver).
    pub memory_bytes: BTreeMap<String, u64>,
    /// Passes a render of this scene runs, in order.
    pub passes: Vec<String>,
    /// Loader warnings.
    pub warnings: Vec<String>,
}

/// Bytes of one GPU link vertex (receiver, sender, packed bins, form factor, cone).
pub const LINK_BYTES: u64 = 20;

/// The passes a render of `scene` runs, in execution order.
pub fn passes(scene: &Scene) -> Vec<String> {
    let mut p = Vec::new();
    for kind in ["directional", "spot", "point"] {
        if scene.lights.iter().any(|l| l.kind() == kind) {
            p.push(format!("shadow_{kind}"));
        }
    }
    if !scene.lights.is_empty() {
        p.push("direct_init".into());
    }
    if scene.environment.max_element() > 0.0 {
        p.push("environment_init".into());
    }
    p.extend(["global", "push"].map(String::from));
    let glossy = scene.materials.iter().any(|m| m.is_glossy());
    let diffuse = scene.materials.iter().any(|m| !m.is_glossy());
    if diffuse {
        p.push("local_diffuse".into());
    }
    if glossy {
        p.push("local_glossy".into());
    }
    p.push("pull".into());
    p
}

impl Info {
    /// Gathers the statistics of a built system.
    pub fn new(scene: &Scene, sys: &System) -> Self {
        let rows = sys.rows() as u64;
        let m = sys.bins.count as u64;
        let texel = match scene.solver.precision {
            Precision::F16 => 8,
            Precision::F32 => 16,
        };
        let mut mem = BTreeMap::new();
        // I_ex ping-pong pair, L_in, pushed L_in, I_total.
        mem.insert("tables".into(), 5 * rows * m * texel);
        mem.insert("links".into(), sys.links.len() as u64 * LINK_BYTES);
        mem.insert("filter_tables".into(), sys.filters.dense_bytes());
        mem.insert(
            "element_attributes".into(),
            sys.leaves.len() as u64 * 3 * 16,
        );
        let pull_lines: u64 = sys
            .hierarchy
            .leaves
            .iter()
            .map(|&l| sys.hierarchy.nodes[l as usize].depth as u64)
            .sum();
        mem.insert("push_pull_primitives".into(), (pull_lines + rows) * 8);
        mem.insert("cpu_tables".into(), 4 * rows * m * 24);
        Self {
            scene: scene
                .path
                .as_ref()
                .map_or("<memory>".into(), |p| p.display().to_string()),
            triangles: scene.triangle_count(),
            elements: sys.elements.len(),
            nodes: sys.rows(),
            depth: sys.hierarchy.max_depth(),
            links: sys.links.len(),
            bins: sys.bins.count,
            cone_classes: sys.filters.used_classes().len(),
            meshing_ms: sys.meshing_ms,
            linking_ms: sys.links.linking_ms,
            links_per_second: sys.links.links_per_second(),
            memory_bytes: mem,
            passes: passes(scene),
            warnings: scene.warnings.clone(),
        }
    }

    /// Human-readable multi-line summary.
    pub fn text(&self) -> String {
        let mut s = format!(
            "scene      {}\ntriangles  {}\nelements   {} ({} nodes, depth {})\nbins       {} ({} cone classes)\nlinks      {}\nmeshing    {:.1} ms\nlinking    {:.1} ms ({:.0} links/s)\nmemory\n",
            self.scene, self.triangles, self.elements, self.nodes, self.depth, self.bins, self.cone_classes,
            self.links, self.meshing_ms, self.linking_ms, self.links_per_second
        );
        for (k, v) in &self.memory_bytes {
            s += &format!("  {k:<22}{:>10.2} MB\n", *v as f64 / 1e6);
        }
        s += &format!("passes     {}\n", self.passes.join(", "));
        s
    }
}
