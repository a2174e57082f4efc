//! Scenes: triangle meshes with Phong materials, analytic lights, environment, camera and solver
//! settings. `format` is the TOML on disk, `load` turns it into a validated [`Scene`].

pub mod animation;
mod bare;
mod files;
pub mod format;
pub mod gltf_scene;
pub mod limits;
pub mod load;
pub mod mitsuba;
mod obj;
mod object;
mod ply;
mod settings;

use glam::DVec3;
use std::path::PathBuf;

pub use crate::settings::{Precision, Scheme};
pub use limits::{
    max_elements_limit, max_links_limit, MAX_ANTIRADIANCE_STEPS, MAX_COORDINATE, MAX_ITERATIONS,
    MAX_SOURCE, RELATIVE_ELEMENT_SIZE,
};
pub use load::load_scene;

/// A material: Lambertian `kd` plus a normalized modified-Phong lobe, and optional emission.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Name from the MTL file.
    pub name: String,
    /// Diffuse albedo per channel.
    pub kd: DVec3,
    /// Specular albedo of the lobe `ks·(ns+2)/(2π)·cos^ns(α)`.
    pub ks: DVec3,
    /// Phong exponent.
    pub ns: f64,
    /// Emitted radiance of the front face.
    pub ke: DVec3,
}

impl Material {
    /// A grey Lambertian material (the default for faces without `usemtl`, as in Mitsuba).
    pub fn diffuse(name: &str, kd: f64) -> Self {
        Self {
            name: name.into(),
            kd: DVec3::splat(kd),
            ks: DVec3::ZERO,
            ns: 0.0,
            ke: DVec3::ZERO,
        }
    }

    /// True when the Phong lobe contributes.
    pub fn is_glossy(&self) -> bool {
        self.ks.max_element() > 0.0
    }

    /// True when the front face emits.
    pub fn is_emitter(&self) -> bool {
        self.ke.max_element() > 0.0
    }
}

/// A triangle mesh in world space.
#[derive(Debug, Clone)]
pub struct Mesh {
    /// Name (OBJ model name or file stem).
    pub name: String,
    /// Source file, for messages.
    pub source: PathBuf,
    /// World-space vertex positions.
    pub positions: Vec<DVec3>,
    /// Counter-clockwise triangles (front side by the OBJ convention).
    pub triangles: Vec<[u32; 3]>,
    /// Index into [`Scene::materials`] per triangle.
    pub material: Vec<u32>,
    /// Shading normals (unit, world space) at each triangle's corners, from the OBJ's `vn`:
    /// empty when the mesh has none, else one per triangle, a face without (valid) `vn` having
    /// its face normal at all three. They shade the frame only; the solver's elements stay
    /// planar.
    pub normals: Vec<[DVec3; 3]>,
}

impl Mesh {
    /// Unit front normal of triangle `t` (counter-clockwise corners).
    pub fn face_normal(&self, t: usize) -> DVec3 {
        let [a, b, c] = self.triangles[t].map(|v| self.positions[v as usize]);
        (b - a).cross(c - a).normalize_or_zero()
    }

    /// Shading normals at triangle `t`'s corners: its `vn`, or its face normal three times.
    pub fn corner_normals(&self, t: usize) -> [DVec3; 3] {
        match self.normals.get(t) {
            Some(n) => *n,
            None => [self.face_normal(t); 3],
        }
    }
}

/// An analytic light.
#[derive(Debug, Clone, PartialEq)]
pub enum Light {
    /// Parallel light travelling along `direction` with `irradiance` on a facing surface.
    Directional {
        /// Unit direction of travel.
        direction: DVec3,
        /// W/m² per channel.
        irradiance: DVec3,
    },
    /// Isotropic point light.
    Point {
        /// Position.
        position: DVec3,
        /// W/sr per channel.
        intensity: DVec3,
    },
    /// Spot light: full intensity within `beam_width`, linear fall-off in angle to zero at `cutoff`.
    Spot {
        /// Position.
        position: DVec3,
        /// Unit axis direction.
        axis: DVec3,
        /// W/sr per channel on the axis.
        intensity: DVec3,
        /// Cut-off angle (radians).
        cutoff: f64,
        /// Beam width (radians).
        beam_width: f64,
    },
    /// One sample of an area emitter (`Ke` faces), made by the engine, never read from a file
    /// (`crate::frame::emitters`): a patch of `area` on the emitter at `position` with unit
    /// `normal`, radiating `radiance` from its front side, cosine-weighted.
    EmitterSample {
        /// Point on the emitter.
        position: DVec3,
        /// Unit normal of the emitter's front side.
        normal: DVec3,
        /// Emitted radiance per channel (W/(m²·sr)).
        radiance: DVec3,
        /// Emitter area the sample stands for (m²).
        area: f64,
        /// The emitter triangle's cell the sample stands for, where the samples tile the
        /// emitters: its light is then the cell's exact unoccluded irradiance
        /// ([`crate::frame::lights::irradiance_on`]), bounded and right next to the emitter.
        /// None for a point patch (a VPL, or more emitting triangles than samples).
        cell: Option<[DVec3; 3]>,
    },
}

impl Light {
    /// Short type name (`directional`, `point`, `spot`, `emitter`).
    pub fn kind(&self) -> &'static str {
        match self {
            Light::Directional { .. } => "directional",
            Light::Point { .. } => "point",
            Light::Spot { .. } => "spot",
            Light::EmitterSample { .. } => "emitter",
        }
    }
}

/// Pinhole camera. Pixel (0,0) is top-left; image right is `forward × up`.
#[derive(Debug, Clone, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: DVec3,
    /// Point looked at.
    pub target: DVec3,
    /// Up vector.
    pub up: DVec3,
    /// Vertical field of view in degrees.
    pub fov_y_deg: f64,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Each pixel is the box-filtered mean of `supersample`² frame pixels (of 2×2 samples
    /// each): 1..=[`MAX_SUPERSAMPLE`], default 1. The frame is drawn at `supersample` × the
    /// size and reduced when read back; the solve does not depend on it.
    pub supersample: u32,
    /// Where the frame's samples lie, shifted from their regular grid, in frame pixels (x
    /// right, y down): 0 but while the engine draws one of [`Camera::passes`]'s shifted frames.
    pub jitter: [f64; 2],
    /// The frame drawn this many times, each pass's samples shifted along the pixel's diagonal
    /// by `1/passes` of their spacing, and averaged (`2·supersample·passes` distinct sample rows
    /// and columns per pixel, the cost of `passes` frames): 1..=[`MAX_PASSES`], default 1.
    pub passes: u32,
    /// The axis whose field of view the scene file fixed: when `width` or `height` is
    /// overridden, [`Camera::resized`] keeps the angle along it (a Mitsuba sensor's `fov_axis`,
    /// `x` by default; TOML and glTF state the vertical angle).
    pub fov_axis: FovAxis,
}

/// The image axis a camera's field of view is measured along.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FovAxis {
    /// Vertical (`fov_y_deg` as it stands).
    #[default]
    Y,
    /// Horizontal.
    X,
    /// The image's diagonal.
    Diagonal,
    /// The shorter side.
    Smaller,
    /// The longer side.
    Larger,
}

impl FovAxis {
    /// tan(fov_y/2) from the tangent of half the angle along this axis, for a `w`×`h` image.
    pub fn tan_half_y(self, t: f64, w: f64, h: f64) -> f64 {
        match self {
            FovAxis::Y => t,
            FovAxis::X => t * h / w,
            FovAxis::Diagonal => t * h / (w * w + h * h).sqrt(),
            FovAxis::Smaller if w > h => t,
            FovAxis::Larger if w < h => t,
            FovAxis::Smaller | FovAxis::Larger => t * h / w,
        }
    }
}

impl Camera {
    /// The camera at `width`×`height`, the angle along [`Camera::fov_axis`] kept.
    pub fn resized(&self, width: u32, height: u32) -> Camera {
        let ty = (self.fov_y_deg.to_radians() * 0.5).tan();
        let (w0, h0) = (self.width.max(1) as f64, self.height.max(1) as f64);
        // The tangent along the axis, from the vertical one at the old size.
        let t = ty / self.fov_axis.tan_half_y(1.0, w0, h0);
        let ty = self
            .fov_axis
            .tan_half_y(t, width.max(1) as f64, height.max(1) as f64);
        Camera {
            width,
            height,
            fov_y_deg: 2.0 * ty.atan().to_degrees(),
            ..self.clone()
        }
    }
}

/// Largest [`Camera::passes`].
pub const MAX_PASSES: u32 = 16;

/// Largest [`Camera::supersample`].
pub const MAX_SUPERSAMPLE: u32 = 8;

/// Solver settings (`[solver]`). The ranges below are checked when a scene file is loaded.
#[derive(Debug, Clone, PartialEq)]
pub struct SolverSettings {
    /// Directional bins `m`: [`crate::bins::MIN_BINS`]..=[`crate::bins::MAX_BINS`], a count
    /// [`crate::bins::Bins::new`] lays out as a grid.
    pub bins: usize,
    /// Iterations (outer iterations for the asymmetric scheme): 1..=[`MAX_ITERATIONS`]. Unused
    /// when `tolerance` is given. [`Default`] (a scene built in code): 4, the paper's; a scene
    /// file without `iterations` or `tolerance` gets [`DEFAULT_TOLERANCE`] instead.
    pub iterations: usize,
    /// Iteration scheme.
    pub scheme: Scheme,
    /// Longest edge of a leaf element (scene units): finite, positive, at least
    /// [`limits::MIN_RELATIVE_RESOLUTION`] × the largest coordinate magnitude, and small
    /// enough elements must number at most `max_elements` (estimated from the triangles' areas
    /// before anything is subdivided). A scene file that gives none gets
    /// [`RELATIVE_ELEMENT_SIZE`] × the scene's bounding-box diagonal (resolved at load, after
    /// the meshes are read); a value given in the file is absolute. [`Default`] (for scenes
    /// built in code): 0.25.
    pub element_size: f64,
    /// Oracle threshold τ (finite, positive): a link is refined while a node subtends more than
    /// τ·ω_bin.
    pub oracle: f64,
    /// Antiradiance steps per radiance step (asymmetric scheme): 1..=[`MAX_ANTIRADIANCE_STEPS`].
    pub antiradiance_steps: usize,
    /// GPU table precision.
    pub precision: Precision,
    /// Refuse scenes with more leaf elements than this: 1..=[`max_elements_limit`] (what this
    /// machine's memory holds).
    pub max_elements: usize,
    /// Residual target in (0, 1): iterate until the estimated error falls below it (then
    /// `iterations` is ignored and `max_iterations` caps the count). `None`: exactly
    /// `iterations`. The estimate is the distance to the discrete system's fixed point, not to
    /// the true answer ([`crate::solver::convergence::Monitor::error_estimate`]).
    pub tolerance: Option<f64>,
    /// Iteration cap when `tolerance` is given: 1..=[`MAX_ITERATIONS`].
    pub max_iterations: usize,
    /// Truncation of the cone filters (§3.1): weights below this fraction of a row's largest are
    /// dropped and the row renormalized, in [1e-9, 0.5] ([`crate::filter::CUTOFF`] by default;
    /// the README gives the error each choice costs, measured).
    pub filter_cutoff: f64,
    /// Area emitters (`Ke` faces) are sampled with this many shadow-mapped points for their
    /// direct light (per pixel and the leaves' first bounce; §3.3), 0..=[`MAX_EMITTER_SAMPLES`];
    /// 0 sends their emission through the bins instead. `None` chooses
    /// ([`crate::frame::emitters::choose`]): [`crate::frame::emitters::DEFAULT_SAMPLES`] unless
    /// the emitters cover much of the scene.
    pub emitter_samples: Option<usize>,
    /// Iterations each animated frame runs, warm-started from the previous frame's solution
    /// (§3.3; the paper's 4 by default): 1..=[`MAX_ITERATIONS`].
    pub iterations_per_frame: usize,
    /// Whether small triangles of dense meshes are grouped into face clusters, one leaf each
    /// ([`crate::clusters`]); off, every input triangle is at least one leaf.
    pub face_clusters: bool,
    /// Whether a stiff iteration's geometric tail is summed in one step where one mode
    /// dominates ([`crate::solver::extrapolate`]); off, plain iteration only.
    pub extrapolate: bool,
    /// Whether the frame evaluates the area emitters' direct light at each of a pixel's 2×2
    /// samples; off (the default), once at their mean where they lie on one flat surface
    /// (`frame::cpu::shared_direct`; on the Cornell box the compose pass 1,071 → 429 ms), which
    /// can differ at a penumbra sharper than a pixel (low resolutions).
    pub direct_per_sample: bool,
    /// Whether the splat sums (§4.3) are drawn at each of a pixel's 2×2 samples; off (the
    /// default), once per pixel at its first sample, the other samples taking their pixel's or
    /// a neighbour's on their flat surface (`frame::splat`; on the Cornell box at 512² the splat
    /// pass draws a quarter of the fragments).
    pub splat_per_sample: bool,
    /// Pixels per side of the blocks whose corner pixels evaluate the area emitters' shared
    /// direct light (1..=[`MAX_DIRECT_BLOCK`]): the other pixels interpolate it between the
    /// corners on their surface where those agree, else evaluate their own (`frame::direct`);
    /// 1 evaluates it at every pixel; `None` (the default): 2 on frames of at least
    /// `frame::direct::MIN_BLOCK_PIXELS` pixels, else 1.
    pub direct_block: Option<u32>,
    /// Whether each leaf scales the radiance pushed from its ancestors by how much more or
    /// less of their senders it sees than they do ([`crate::system::receivers`]; computed for
    /// still scenes); off, every leaf takes its cluster's radiance as it is (the paper's push).
    pub receiver_calibration: bool,
}

/// Most emitter samples (each has six shadow-map faces).
pub const MAX_EMITTER_SAMPLES: usize = 4096;

/// Largest `solver.direct_block` (beyond, a penumbra is interpolated over more pixels than the
/// shadow filter blurs it).
pub const MAX_DIRECT_BLOCK: u32 = 8;

/// `solver.tolerance` of a scene file that gives neither `iterations` nor `tolerance`: the
/// iteration runs until the monitor's estimated error is 1%. Measured (32², CPU): the Cornell
/// box 8 iterations, MNRoom 52 (its file's 6 leave an estimate of 0.12, the image 3.4% RMS from
/// a solve to 1e-3; 36 iterations to 5e-2 leave 0.2%), Veach's indirectly lit room 16 (its
/// file's 8: estimate 1.2e-2, image 8.2% from converged). The breakfast room's damped iteration stays near 1.5e-2 to the cap, for an
/// image no nearer the path tracer's than at 4 (its file states 4).
pub const DEFAULT_TOLERANCE: f64 = 1e-2;

/// `solver.max_iterations` with [`DEFAULT_TOLERANCE`] unless the file gives one: a scene whose
/// error falls slowly stops here with a warning that states its estimated error, instead of
/// running the thousand iterations an explicit tolerance may.
pub const DEFAULT_ITERATION_CAP: usize = 100;

impl SolverSettings {
    /// The settings of a scene file that states none (a TOML scene without `iterations` or
    /// `tolerance`, a Mitsuba or glTF file): [`Default`] iterating to [`DEFAULT_TOLERANCE`],
    /// at most [`DEFAULT_ITERATION_CAP`] times.
    pub fn for_file() -> Self {
        Self {
            tolerance: Some(DEFAULT_TOLERANCE),
            max_iterations: DEFAULT_ITERATION_CAP,
            ..Self::default()
        }
    }
}

impl Default for SolverSettings {
    fn default() -> Self {
        Self {
            bins: 128,
            iterations: 4,
            scheme: Scheme::Symmetric,
            element_size: 0.25,
            oracle: 1.0,
            antiradiance_steps: 4,
            precision: Precision::F16,
            max_elements: 2_000_000,
            tolerance: None,
            max_iterations: 1000,
            filter_cutoff: crate::filter::CUTOFF,
            emitter_samples: None,
            iterations_per_frame: 4,
            face_clusters: true,
            extrapolate: true,
            direct_per_sample: false,
            splat_per_sample: false,
            direct_block: None,
            receiver_calibration: true,
        }
    }
}

/// Appended to the name of a two-sided mesh's back-facing twin ([`add_twins`]).
pub const BACK_SUFFIX: &str = " (back)";

/// Gives every mesh in `meshes` its back-to-back twin (reversed winding and normals), so that
/// both sides of the surface reflect: surfaces here have one front. The twin reflects as its
/// original does but emits nothing (Mitsuba's area emitters emit from the front only).
pub fn add_twins(scene: &mut Scene, meshes: std::ops::Range<usize>) {
    let mut dark: std::collections::HashMap<u32, u32> = std::collections::HashMap::new();
    for k in meshes {
        let m = &scene.meshes[k];
        let (triangles, normals) = (
            m.triangles.iter().map(|t| [t[0], t[2], t[1]]).collect(),
            m.normals.iter().map(|n| [-n[0], -n[2], -n[1]]).collect(),
        );
        let (name, source, positions) = (
            format!("{}{BACK_SUFFIX}", m.name),
            m.source.clone(),
            m.positions.clone(),
        );
        let original = m.material.clone();
        let material = original
            .iter()
            .map(|&id| {
                if !scene.materials[id as usize].is_emitter() {
                    return id;
                }
                *dark.entry(id).or_insert_with(|| {
                    let mut d = scene.materials[id as usize].clone();
                    d.ke = DVec3::ZERO;
                    scene.materials.push(d);
                    (scene.materials.len() - 1) as u32
                })
            })
            .collect();
        scene.meshes.push(Mesh {
            name,
            source,
            positions,
            triangles,
            material,
            normals,
        });
    }
}

/// A validated scene.
#[derive(Debug, Clone)]
pub struct Scene {
    /// Scene file, if loaded from one.
    pub path: Option<PathBuf>,
    /// Meshes in world space.
    pub meshes: Vec<Mesh>,
    /// All materials; meshes index into this.
    pub materials: Vec<Material>,
    /// Analytic lights.
    pub lights: Vec<Light>,
    /// Constant environment radiance.
    pub environment: DVec3,
    /// Camera.
    pub camera: Camera,
    /// Solver settings.
    pub solver: SolverSettings,
    /// Approximations made while loading (unsupported MTL features), one line each, no repeats.
    pub warnings: Vec<String>,
    /// The `[[object]]`s: which meshes each placed, where, and how it moves (empty for scenes
    /// built in code unless [`Scene::add_object`] registers some).
    pub objects: Vec<animation::SceneObject>,
    /// Keyframes of the lights, by index into `lights` (may be shorter: lights without).
    pub light_tracks: Vec<animation::LightTrack>,
    /// Seconds of scene time the animation spans (`None`: no keyframes).
    pub duration: Option<f64>,
}

impl Scene {
    /// A scene with no geometry, lights or environment and default camera and settings,
    /// to be filled programmatically (tests, engines).
    pub fn empty() -> Self {
        Self {
            path: None,
            meshes: Vec::new(),
            materials: Vec::new(),
            lights: Vec::new(),
            environment: DVec3::ZERO,
            camera: Camera {
                eye: DVec3::new(0.0, 1.0, 3.5),
                target: DVec3::new(0.0, 1.0, 0.0),
                up: DVec3::Y,
                fov_y_deg: 40.0,
                width: 512,
                height: 512,
                supersample: 1,
                jitter: [0.0; 2],
                passes: 1,
                fov_axis: Default::default(),
            },
            solver: SolverSettings::default(),
            warnings: Vec::new(),
            objects: Vec::new(),
            light_tracks: Vec::new(),
            duration: None,
        }
    }

    /// Adds a material and returns its index.
    pub fn add_material(&mut self, m: Material) -> u32 {
        self.materials.push(m);
        (self.materials.len() - 1) as u32
    }

    /// Adds a mesh of counter-clockwise triangles with one material.
    pub fn add_mesh(
        &mut self,
        name: &str,
        positions: Vec<DVec3>,
        triangles: Vec<[u32; 3]>,
        material: u32,
    ) {
        let n = triangles.len();
        self.meshes.push(Mesh {
            name: name.into(),
            source: PathBuf::from(format!("<{name}>")),
            positions,
            triangles,
            material: vec![material; n],
            normals: Vec::new(),
        });
    }

    /// Total number of input triangles.
    pub fn triangle_count(&self) -> usize {
        self.meshes.iter().map(|m| m.triangles.len()).sum()
    }

    /// Every triangle's corners (world space), mesh by mesh.
    pub fn triangle_corners(&self) -> impl Iterator<Item = [DVec3; 3]> + '_ {
        self.meshes.iter().flat_map(|m| {
            m.triangles
                .iter()
                .map(|t| t.map(|v| m.positions[v as usize]))
        })
    }

    /// Axis-aligned bounds of all vertices.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for p in self.meshes.iter().flat_map(|m| m.positions.iter()) {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        (lo, hi)
    }
}

/// A unit square in the y = 0 plane facing +y (kd 0.5, `ks`, exponent 20) at 32 bins and
/// element size 0.6: the small scene unit tests discretize.
#[cfg(test)]
pub(crate) fn test_plane(ks: f64) -> Scene {
    let mut s = Scene::empty();
    let m = s.add_material(Material {
        ks: DVec3::splat(ks),
        ns: 20.0,
        ..Material::diffuse("plane", 0.5)
    });
    s.add_mesh(
        "plane",
        vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, -1.0),
            DVec3::new(0.0, 0.0, -1.0),
        ],
        vec![[0, 1, 2], [0, 2, 3]],
        m,
    );
    s.solver.bins = 32;
    s.solver.element_size = 0.6;
    s
}

#[cfg(test)]
mod fov_tests {
    use super::*;

    fn tan_x(c: &Camera) -> f64 {
        (c.fov_y_deg.to_radians() * 0.5).tan() * c.width as f64 / c.height as f64
    }

    #[test]
    fn a_resized_camera_keeps_the_angle_along_its_axis() {
        let mut c = Scene::empty().camera;
        (c.width, c.height, c.fov_y_deg) = (1024, 1024, 35.0);
        // Vertical: the angle as stated.
        assert_eq!(c.resized(128, 72).fov_y_deg, 35.0);
        // Mitsuba's default axis x: 35° across at 1024² and at 128×72 (20.11° vertically).
        c.fov_axis = FovAxis::X;
        let r = c.resized(128, 72);
        assert!((tan_x(&r) - (17.5f64).to_radians().tan()).abs() < 1e-12);
        assert!((r.fov_y_deg - 20.1135).abs() < 1e-3, "{}", r.fov_y_deg);
        // The diagonal kept: tan along it is the same at both sizes.
        c.fov_axis = FovAxis::Diagonal;
        let r = c.resized(300, 100);
        let diag = |c: &Camera| {
            let (w, h) = (c.width as f64, c.height as f64);
            (c.fov_y_deg.to_radians() * 0.5).tan() * (w * w + h * h).sqrt() / h
        };
        assert!((diag(&r) - diag(&c)).abs() < 1e-12);
        // The same size changes nothing.
        assert_eq!(c.resized(1024, 1024), c);
    }
}
