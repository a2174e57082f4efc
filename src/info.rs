//! Scene statistics for `antiradiance info`: sizes, linking time, memory by resource, passes.

use crate::engine::{Options, Prepared};
use crate::error::Result;
use crate::gpu::frame::GpuFrame;
use crate::gpu::memory::Purpose;
use crate::gpu::resources::{table_format, ResourcePlan};
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
    /// Bytes by resource: the GPU solver's images and buffers as the plan creates them (§4.1 at
    /// the plan's precision), `frame_images` for the frame at the camera's size, `cpu_tables` for
    /// the f64 solver.
    pub memory_bytes: BTreeMap<String, u64>,
    /// The GPU passes' raster work per propagation (fragments, blended fragments, primitives;
    /// Phong-sum terms), counted from the draw records.
    pub work: crate::gpu::work::Work,
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

/// lavapipe's maxStorageBufferRange, which `info` (no device) plans against.
const LAVAPIPE_STORAGE_RANGE: u64 = 128 << 20;

impl Info {
    /// The statistics of a prepared scene: its system, plan and the memory both would take.
    /// GPU memory is the solver's images and buffers as [`ResourcePlan`] describes them, on a
    /// device that rounds float16 blending (L_in and L_push in the table format, images up to
    /// 16384 texels); a device that truncates (lavapipe) accumulates them in float32 and
    /// `profile` reports that.
    pub fn new(prep: &Prepared) -> Result<Self> {
        let (scene, sys, plan) = (&prep.scene, &prep.system, &prep.plan);
        let rows = sys.rows() as u64;
        let m = sys.bins.count as u64;
        let format = table_format(plan.precision);
        // Sized as on lavapipe (maxImageDimension2D 16384, lines up to 255 texels wide).
        let resources = ResourcePlan::new(
            sys,
            &plan.features,
            plan.precision,
            format,
            u32::MAX,
            16384,
            255,
        )?;
        let gpu = resources.memory();
        let work = crate::gpu::work::Work::of(sys, &resources);
        let mut mem = gpu.by_name();
        mem.remove("total");
        let frame = GpuFrame::planned_memory(&prep.camera, &plan.features, &prep.maps);
        mem.insert("frame_images".into(), frame.get(Purpose::FrameImages));
        mem.insert("shadow_maps".into(), frame.get(Purpose::ShadowMaps));
        mem.insert("cpu_tables".into(), crate::system::cpu_table_bytes(rows, m));
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
        let mut info = Self::new(&Prepared::new(scene, options, None, progress)?)?;
        let records = info.work.global.primitives;
        let chunks = crate::gpu::links::LinkChunks::new(records, LAVAPIPE_STORAGE_RANGE).chunks;
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
