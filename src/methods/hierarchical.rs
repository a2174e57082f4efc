//! Hierarchical radiosity with clustering and explicit visibility on the same links (the
//! paper's Fig. 14f): the links antiradiance uses, each form factor multiplied by its visibility
//! fraction ([`super::visibility`]), solved by the same CPU or GPU iterations with antiradiance
//! off. Only the preparation differs, so the comparison isolates what implicit visibility costs
//! and saves. Links no ray gets through are dropped (they would carry nothing).
//!
//! Glossy materials keep their Phong lobes in the directional bins, exactly as antiradiance does
//! (the solver is the same). The environment is refused: the solver adds it to every element's
//! front bins, and only antiradiance removes it where something blocks the sky.

use super::visibility::link_visibility;
use super::{MethodReport, MethodSettings};
use crate::backend::{Backend, Draw, Prepared, Solve};
use crate::error::{Error, Result};
use crate::frame::Image;
use crate::gpu::memory::MemoryReport;
use crate::raycast::RayCaster;
use crate::scene::{Precision, Scheme};
use crate::settings::BackendKind;
use crate::solver::convergence::Figures;
use crate::solver::Table;
use glam::DVec3;

/// Turns `prep` into the hierarchical-radiosity system: visibility on every link (form factors
/// scaled, fully occluded links dropped) and antiradiance off. Returns what it cost.
pub fn prepare(prep: &mut Prepared, settings: &MethodSettings) -> Result<MethodReport> {
    if prep.scene.environment != DVec3::ZERO {
        return Err(Error::Invalid(
            "hierarchical-radiosity does not support an [environment]: the solver adds it to \
             every element unoccluded, and only antiradiance removes the blocked part"
                .into(),
        ));
    }
    // Links reaching only a leaf's back carry light to be blocked, which antiradiance off
    // never uses: drop them before tracing their visibility.
    prep.system
        .links
        .links
        .retain(|l| l.sides != crate::linker::BACK);
    let caster = RayCaster::new(&prep.system);
    let n = settings.rays_per_link;
    let (vis, stats) = link_visibility(&prep.system, &caster, n);
    let links = &mut prep.system.links;
    let before = links.links.len();
    let kept: Vec<_> = links
        .links
        .iter()
        .zip(&vis)
        .filter(|(_, &v)| v > 0.0)
        .map(|(l, &v)| crate::linker::Link {
            form_factor: l.form_factor * v,
            ..*l
        })
        .collect();
    // Links stay sorted by receiver; rebuild the per-receiver offsets.
    links.offsets.iter_mut().for_each(|o| *o = 0);
    for l in &kept {
        links.offsets[l.receiver as usize + 1] += 1;
    }
    for i in 1..links.offsets.len() {
        links.offsets[i] += links.offsets[i - 1];
    }
    links.links = kept;
    let plan = &mut prep.plan;
    plan.features.antiradiance = false;
    plan.decisions.push(format!(
        "hierarchical radiosity: visibility of {before} links from {n} rays each ({} rays, {:.0} ms; {} links fully occluded and dropped, {} partly occluded); antiradiance off",
        stats.rays, stats.ms, stats.occluded, stats.partial
    ));
    let mut report = MethodReport {
        setup_ms: stats.ms,
        rays: stats.rays,
        ..Default::default()
    };
    for (k, v) in [
        ("rays_per_link", n as f64),
        ("links_before_visibility", before as f64),
        ("occluded_links", stats.occluded as f64),
        ("partly_occluded_links", stats.partial as f64),
    ] {
        report.figures.insert(k.into(), v);
    }
    Ok(report)
}

/// The solver backend of the prepared hierarchical-radiosity system, with the method's report.
pub struct HierarchicalBackend {
    inner: Box<dyn Backend>,
    report: MethodReport,
}

impl HierarchicalBackend {
    /// Wraps the CPU or GPU backend made for the prepared system.
    pub fn new(inner: Box<dyn Backend>, report: MethodReport) -> Self {
        Self { inner, report }
    }
}

impl Solve for HierarchicalBackend {
    fn prepare_lights(&mut self, prep: &mut Prepared) -> Result<()> {
        self.inner.prepare_lights(prep)
    }
    fn initialize(&mut self, prep: &Prepared) -> Result<()> {
        self.inner.initialize(prep)
    }
    fn iterate_batch(
        &mut self,
        prep: &Prepared,
        scheme: Scheme,
        antiradiance_steps: usize,
        n: usize,
    ) -> Result<Vec<Figures>> {
        self.inner
            .iterate_batch(prep, scheme, antiradiance_steps, n)
    }
    fn damp(&mut self, weight: f64) -> bool {
        self.inner.damp(weight)
    }
    fn i_ex(&mut self) -> Result<Table> {
        self.inner.i_ex()
    }
    fn i_total(&mut self) -> Result<Table> {
        self.inner.i_total()
    }
    fn overflow_limit(&self) -> f64 {
        self.inner.overflow_limit()
    }
    fn widen(&mut self, prep: &Prepared) -> Result<Option<String>> {
        self.inner.widen(prep)
    }
    fn precision(&self) -> Precision {
        self.inner.precision()
    }
    fn method_report(&self) -> Option<MethodReport> {
        Some(self.report.clone())
    }
}

impl Draw for HierarchicalBackend {
    fn draw(&mut self, prep: &Prepared) -> Result<Image> {
        self.inner.draw(prep)
    }
    fn set_camera(&mut self, prep: &Prepared) -> Result<()> {
        self.inner.set_camera(prep)
    }
}

impl Backend for HierarchicalBackend {
    fn kind(&self) -> BackendKind {
        self.inner.kind()
    }
    fn device(&self) -> String {
        self.inner.device()
    }
    fn take_timings(&mut self) -> Vec<(String, f64)> {
        self.inner.take_timings()
    }
    fn fallbacks(&self) -> Vec<String> {
        self.inner.fallbacks()
    }
    fn recorder(&mut self) -> &mut dyn std::any::Any {
        self.inner.recorder()
    }
    fn memory(&self) -> MemoryReport {
        self.inner.memory()
    }
}
