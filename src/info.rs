//! Scene statistics for `antiradiance info`: sizes, linking time, memory by resource, passes.

use crate::engine::planned::{DeviceLimits, Planned, Work};
use crate::engine::{Options, Prepared};
use crate::error::Result;
use crate::plan::Shading;
use crate::progress::Progress;
use crate::scene::{Precision, Scene};
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
    /// Bytes by resource on lavapipe's limits: the GPU solver's images and buffers as the plan
    /// creates them (§4.1 at the plan's precision), `frame_images` for the frame at the
    /// camera's size, `cpu_tables` for the f64 solver.
    pub memory_bytes: BTreeMap<String, u64>,
    /// The GPU passes' raster work per propagation on lavapipe's limits (fragments, blended
    /// fragments, primitives; Phong-sum terms), counted from the draw records.
    pub work: Work,
    /// The same plan on a discrete GPU's limits ([`DeviceLimits::discrete`]): wider images
    /// hold more rows per column, narrower lines cut the global pass's footprints finer.
    pub discrete_gpu: Planned,
    /// Descriptor ranges the link records are read through on lavapipe (128 MiB each).
    pub link_ranges: u32,
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
    /// The statistics of a prepared scene: its system, plan and the memory both would take.
    /// GPU memory and work are [`Prepared::planned`] on lavapipe's limits and on a discrete
    /// GPU's.
    pub fn new(prep: &Prepared) -> Result<Self> {
        let (scene, sys, plan) = (&prep.scene, &prep.system, &prep.plan);
        let lavapipe = prep.planned(&DeviceLimits::lavapipe())?;
        let mut discrete_gpu = prep.planned(&DeviceLimits::discrete())?;
        let cpu = crate::system::cpu_table_bytes(sys.rows() as u64, sys.bins.count as u64);
        let mut mem = lavapipe.memory_bytes;
        mem.insert("cpu_tables".into(), cpu);
        discrete_gpu.memory_bytes.insert("cpu_tables".into(), cpu);
        let (work, link_ranges) = (lavapipe.work, lavapipe.link_chunks);
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
            work,
            discrete_gpu,
            link_ranges,
            passes: plan.passes(),
            decisions: plan.decisions.clone(),
            shading: plan.shading.clone(),
            precision: plan.precision,
            all_passes: plan.all_passes,
            warnings: scene.warnings.clone(),
        })
    }

    /// Prepares `scene` with `options` (no device) and gathers its statistics.
    pub fn of(scene: &Scene, options: &Options, progress: &dyn Progress) -> Result<Self> {
        let prep = Prepared::new(scene, options, None, progress)?;
        let mut info = Self::new(&prep)?;
        let records = info.work.global.primitives;
        let chunks = info.link_ranges;
        info.decisions.push(format!(
            "checked against a link budget of {} (--max-links) and {}; info opens no device and assumes lavapipe's limits: maxImageDimension2D 16384, line width 255, maxStorageBufferRange 128 MiB (the {records} link records read in {chunks} range{}); on the GPU backend the tables must also fit the device's memory, which `render` checks",
            options
                .max_links
                .unwrap_or(crate::engine::DEFAULT_MAX_LINKS),
            options.memory_budget.map_or("no memory budget (--memory-budget)".to_string(), |b| {
                format!("a memory budget of {b} bytes (--memory-budget)")
            }),
            if chunks == 1 { "" } else { "s" }
        ));
        Ok(info)
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
        let total = |m: &BTreeMap<String, u64>| m.values().sum::<u64>() as f64 / 1e6;
        s += &format!(
            "  (on a {} with {}-texel images and {}-texel lines: {:.2} MB in all, against {:.2} MB)\n",
            self.discrete_gpu.limits.name,
            self.discrete_gpu.limits.max_image_dimension,
            self.discrete_gpu.limits.max_line_width,
            total(&self.discrete_gpu.memory_bytes),
            total(&self.memory_bytes)
        );
        s += "work per propagation (fragments, blended, primitives)\n";
        for (k, w) in self.work.passes() {
            s += &format!(
                "  {k:<8}{:>14}{:>14}{:>12}\n",
                w.fragments, w.blended, w.primitives
            );
        }
        if self.work.glossy_terms > 0 {
            s += &format!("  glossy terms {}\n", self.work.glossy_terms);
        }
        s += &format!("passes     {}\n", self.passes.join(", "));
        for d in &self.decisions {
            s += &format!("  - {d}\n");
        }
        s
    }
}
