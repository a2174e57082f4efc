//! The image-based radiosity representation (`../shared/papers/image-based-radiosity-representation.txt`):
//! Keller's instant radiosity, whose virtual point lights light every frame for the camera it has,
//! accumulated instead in a view-independent layered depth cube ([`cube`]).
//!
//! **Construction** (the paper's §4): the VPLs are traced as instant radiosity traces them
//! ([`super::instant::trace`]); each renders its hemicube ([`hemicube`]: five faces, `H×H` in
//! front, `H×H/2` on the sides, `H` = `--hemicube`), every texel that sees a surface's front
//! shaded with the VPL's irradiance there (the same clamped disc as instant radiosity's, so the
//! fall-off is computed during warping, as the paper allows); the samples are warped into the
//! cube: each into the LDI of its normal, merging with a layer on its plane or opening one; a
//! light's samples in one layer are averaged, and a sample whose footprint is wider than a cell
//! is copied into the neighbouring cells the light's own samples missed (§4.3's splatting).
//! Visibility is the hemicube's: nothing else tests it.
//!
//! **Reconstruction** (§5): every frame sample warps into the cube (the LDI of its face normal,
//! the 2×2 nearest cells weighted bilinearly, each where it has a layer on the sample's plane)
//! and takes `kd/π` of the irradiance found (the paper's `ρ·r`, ρ applied at reconstruction).
//! The direct light is every other method's (shadow-mapped lights and emitter samples, per
//! pixel); the cube holds the indirect light only, as the VPLs do. Diffuse only: a glossy
//! material's lobe reflects no indirect light here.
//!
//! **The clamp's near field** ([`near`]): the VPLs' clamp takes a tenth of the indirect light
//! along a room's edges and in its corners; once the cube is built, each layer gathers it back
//! from the surfaces near it, with the light the cube holds there (bias compensation, once per
//! layer rather than per pixel and frame). `--near-rays 0` leaves the paper's clamped cube.
//!
//! **View independence**: the cube is built when the lights are prepared, not per frame: a
//! camera that moves only reconstructs.

pub mod backend;
pub mod cube;
pub mod gpu;
pub mod hemicube;
pub mod near;

use super::{instant, MethodReport, MethodSettings};
use crate::frame::cpu::SampleIndirect;
use crate::frame::surfaces::Surfaces;
use crate::raycast::RayCaster;
use crate::scene::{Material, Scene};
use crate::system::System;
use cube::Cube;
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;
use std::time::Instant;

/// VPLs whose hemicubes are cast together before they are warped (bounds the samples held;
/// the GPU's item buffer holds this many side by side, up to 4096 texels wide).
pub fn chunk(hemicube: u32) -> usize {
    (4096 / hemicube.max(1) as usize).clamp(1, 32)
}

/// Casts a chunk of VPLs' hemicubes: ray cast ([`hemicube::cast`]) or rasterized ([`gpu`]).
pub type CastChunk<'a> =
    dyn FnMut(&[crate::scene::Light]) -> crate::error::Result<Vec<Vec<hemicube::Sample>>> + 'a;

/// The CPU's hemicubes: rays through `caster`, lifted `lift` off the VPLs' surfaces.
pub fn ray_cast<'a>(
    caster: &'a RayCaster,
    surf: &'a Surfaces,
    hemicube: u32,
    lift: f64,
) -> impl FnMut(&[crate::scene::Light]) -> crate::error::Result<Vec<Vec<hemicube::Sample>>> + 'a {
    move |lights| {
        Ok(lights
            .par_iter()
            .map(|l| hemicube::cast(l, hemicube, caster, surf, lift))
            .collect())
    }
}

/// The built cube and what building it cost.
pub struct Built {
    /// The cube.
    pub cube: Cube,
    /// The VPLs, the cube's size and the time each step took (`figures`).
    pub report: MethodReport,
    /// The VPLs' clamp disc (m²), whose near field [`near::restore`] gives back.
    pub clamp_area: f64,
}

/// The cube's bounds: the scene's.
pub fn bounds(surf: &Surfaces) -> (DVec3, DVec3) {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for corners in &surf.corners {
        for &c in corners {
            lo = lo.min(c);
            hi = hi.max(c);
        }
    }
    (lo, hi)
}

/// Traces the VPLs of `scene` and builds the cube from their hemicubes (`settings.cube` cells
/// along the bounds' longest side, `settings.hemicube` texels per face side), each chunk of
/// VPLs cast by `cast` (rays lifted [`lift`] off their surfaces).
pub fn build(
    scene: &Scene,
    sys: &System,
    surf: &Surfaces,
    settings: &MethodSettings,
    cast: &mut CastChunk<'_>,
) -> crate::error::Result<Built> {
    let vpls = instant::trace(scene, sys, settings)?;
    let (lo, hi) = bounds(surf);
    let mut cube = Cube::new(lo, hi, settings.cube as usize);
    let t = Instant::now();
    let (mut cast_ms, mut samples) = (0.0, 0u64);
    for chunk in vpls.lights.chunks(chunk(settings.hemicube)) {
        let t0 = Instant::now();
        let cast = cast(chunk)?;
        cast_ms += t0.elapsed().as_secs_f64() * 1e3;
        for s in &cast {
            samples += s.len() as u64;
            hemicube::warp(&mut cube, s);
        }
    }
    let total_ms = t.elapsed().as_secs_f64() * 1e3;
    let mut report = MethodReport {
        setup_ms: vpls.ms + total_ms,
        rays: vpls.lights.len() as u64 * hemicube::texels(DVec3::Z, settings.hemicube).len() as u64,
        ..Default::default()
    };
    for (k, v) in [
        ("vpl_paths", vpls.paths as f64),
        ("vpls", vpls.lights.len() as f64),
        ("vpl_flux", (vpls.flux.x + vpls.flux.y + vpls.flux.z) / 3.0),
        ("cube_resolution", settings.cube as f64),
        ("hemicube", settings.hemicube as f64),
        ("cube_cells", cube.cells() as f64),
        ("cube_layers", cube.layers() as f64),
        ("cube_bytes", cube.bytes() as f64),
        ("cube_dropped", cube.dropped() as f64),
        ("hemicube_samples", samples as f64),
        ("trace_ms", vpls.ms),
        ("hemicube_ms", cast_ms),
        ("warp_ms", total_ms - cast_ms),
    ] {
        report.figures.insert(k.into(), v);
    }
    Ok(Built {
        cube,
        report,
        clamp_area: vpls.clamp_area,
    })
}

/// How far a VPL's hemicube rays leave its surface (progressive refinement's shooter offset).
pub fn lift(sys: &System) -> f64 {
    super::progressive::surface_offset(sys)
}

/// The frame's indirect light from the cube: `kd/π` times the irradiance it holds.
pub struct CubeIndirect<'a>(pub &'a Cube);

impl SampleIndirect for CubeIndirect<'_> {
    fn radiance(&self, p: DVec3, n: DVec3, m: &Material) -> DVec3 {
        m.kd / PI * self.0.irradiance(p, n)
    }
}
