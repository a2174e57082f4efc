//! Scene statistics for `antiradiance info`: sizes, linking time, memory by resource, passes.

use crate::error::Result;
use crate::frame::surfaces::Surfaces;
use crate::plan::{Plan, Shading};
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
    /// Bytes by resource: the GPU solver's images and buffers as the plan creates them (§4.1 at
    /// the plan's precision), `frame_images` for the frame at the camera's size, `cpu_tables` for
    /// the f64 solver.
    pub memory_bytes: BTreeMap<String, u64>,
    /// Passes a render of this scene runs, in order (the scene analysis, [`Plan::passes`]).
    pub passes: Vec<String>,
    /// What the analysis decided and why.
    pub decisions: Vec<String>,
    /// Indirect-light shading per object.
    pub shading: BTreeMap<String, Shading>,
    /// Table precision of a GPU render.
    pub precision: Precision,
    /// True when `--all-passes` forced everything on.
    pub all_passes: bool,
    /// Loader warnings.
    pub warnings: Vec<String>,
}

impl Info {
    /// Gathers the statistics of a built system and its plan (see [`Plan::new`]).
    pub fn new(scene: &Scene, sys: &System, plan: &Plan) -> Result<Self> {
        let rows = sys.rows() as u64;
        let m = sys.bins.count as u64;
        let gpu = crate::gpu::resources::Resources::planned_memory(
            sys,
            &plan.features,
            plan.precision,
            16384,
        )?;
        let mut mem = gpu.by_name();
        mem.remove("total");
        mem.insert("frame_images".into(), frame_bytes(scene, plan));
        mem.insert("cpu_tables".into(), 4 * rows * m * 24);
        Ok(Self {
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
            passes: plan.passes(),
            decisions: plan.decisions.clone(),
            shading: plan.shading.clone(),
            precision: plan.precision,
            all_passes: plan.all_passes,
            warnings: scene.warnings.clone(),
        })
    }

    /// [`Info::new`] with the plan of a render (`all_passes` as `--all-passes`).
    pub fn of(scene: &Scene, sys: &System, all_passes: bool) -> Result<Self> {
        let surf = Surfaces::new(scene, sys);
        Self::new(scene, sys, &Plan::new(scene, sys, &surf, all_passes))
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
        for d in &self.decisions {
            s += &format!("  - {d}\n");
        }
        s
    }
}

/// Bytes of the frame's images at the camera's size (G-buffer at 2×2 samples, the vertex-radiance
/// and splat targets only where the plan draws them, the output; shadow maps not included).
fn frame_bytes(scene: &Scene, plan: &Plan) -> u64 {
    let ss = crate::frame::camera::SUPERSAMPLE as u64;
    let (w, h) = (scene.camera.width as u64, scene.camera.height as u64);
    let samples = w * h * ss * ss;
    let f = &plan.features;
    // Position (RGBA32F) + depth (D32), vertex radiance and splat sums (RGBA32F), output.
    samples * (16 + 4)
        + if f.vertex { samples * 16 } else { 16 }
        + if f.splat { samples * 16 } else { 16 }
        + w * h * 16
}
