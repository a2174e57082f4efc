//! The TOML scene file as written on disk (serde structs). `load.rs` validates and resolves it.

use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::Deserialize;
use std::collections::BTreeMap;

/// An array of exactly `N` values: serde's fixed-size arrays silently drop extra elements,
/// so a longer (or shorter) array is an error naming its length.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Exactly<T, const N: usize>(pub [T; N]);

/// Three coordinates or components.
pub type Xyz = Exactly<f64, 3>;

impl<'de, T: Deserialize<'de>, const N: usize> Deserialize<'de> for Exactly<T, N> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Vec::<T>::deserialize(d)?;
        let n = v.len();
        v.try_into()
            .map(Exactly)
            .map_err(|_| de::Error::invalid_length(n, &format!("an array of {N} values").as_str()))
    }
}

/// A number or an array of three numbers (colours, per-axis scales). Written out by hand so
/// that an array of the wrong length says so, where an untagged enum would only say that no
/// variant matched.
struct NumberOrTriple(&'static str);

/// What [`NumberOrTriple`] read.
enum OneOrThree {
    One(f64),
    Three([f64; 3]),
}

impl<'de> Visitor<'de> for NumberOrTriple {
    type Value = OneOrThree;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(f, "a number or an array of 3 numbers ({})", self.0)
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> Result<Self::Value, E> {
        Ok(OneOrThree::One(v))
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> Result<Self::Value, E> {
        Ok(OneOrThree::One(v as f64))
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<Self::Value, E> {
        Ok(OneOrThree::One(v as f64))
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
        let mut v = Vec::new();
        while let Some(x) = seq.next_element::<f64>()? {
            v.push(x);
        }
        let n = v.len();
        v.try_into()
            .map(OneOrThree::Three)
            .map_err(|_| de::Error::invalid_length(n, &self))
    }
}

/// An RGB value written either as one number (grey) or as `[r, g, b]`.
#[derive(Debug, Clone, Copy)]
pub enum Rgb {
    /// Same value in all three channels.
    Grey(f64),
    /// Per-channel value.
    Rgb([f64; 3]),
}

impl<'de> Deserialize<'de> for Rgb {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Ok(
            match d.deserialize_any(NumberOrTriple("grey or r, g, b"))? {
                OneOrThree::One(g) => Rgb::Grey(g),
                OneOrThree::Three(c) => Rgb::Rgb(c),
            },
        )
    }
}

impl Rgb {
    /// The three channels.
    pub fn channels(self) -> [f64; 3] {
        match self {
            Rgb::Grey(g) => [g; 3],
            Rgb::Rgb(c) => c,
        }
    }
}

/// A uniform or per-axis scale.
#[derive(Debug, Clone, Copy)]
pub enum Scale {
    /// Same factor on every axis.
    Uniform(f64),
    /// Per-axis factors.
    Axes([f64; 3]),
}

impl<'de> Deserialize<'de> for Scale {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Ok(
            match d.deserialize_any(NumberOrTriple("uniform or x, y, z"))? {
                OneOrThree::One(k) => Scale::Uniform(k),
                OneOrThree::Three(a) => Scale::Axes(a),
            },
        )
    }
}

/// Root of a scene file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Meshes placed in the scene.
    #[serde(default)]
    pub object: Vec<ObjectDesc>,
    /// Analytic lights.
    #[serde(default)]
    pub light: Vec<LightDesc>,
    /// Constant environment.
    pub environment: Option<EnvironmentDesc>,
    /// Pinhole camera.
    pub camera: Option<CameraDesc>,
    /// Discretization and iteration settings.
    pub solver: Option<SolverDesc>,
    /// Scene time of keyframed objects and lights.
    pub animation: Option<AnimationDesc>,
}

/// `[animation]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnimationDesc {
    /// Seconds of scene time, finite and positive (default: the last key's time).
    pub duration: Option<f64>,
}

/// One `[[object.keyframe]]`: the object's translation and/or rotation at `time`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectKeyDesc {
    /// Scene time in seconds (finite, non-negative, increasing from key to key).
    pub time: f64,
    /// Replaces the object's `translate` at this time.
    pub translate: Option<Xyz>,
    /// Replaces the object's `rotate` at this time.
    pub rotate: Option<RotateDesc>,
}

/// One `[[light.keyframe]]`: fields of the light at `time` (only those its type takes).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightKeyDesc {
    /// Scene time in seconds (finite, non-negative, increasing from key to key).
    pub time: f64,
    /// Point and spot: position.
    pub position: Option<Xyz>,
    /// Spot: a point on the axis.
    pub target: Option<Xyz>,
    /// Directional: direction of travel.
    pub direction: Option<Xyz>,
    /// Point and spot: intensity.
    pub intensity: Option<Rgb>,
    /// Directional: irradiance.
    pub irradiance: Option<Rgb>,
}

/// One `[[object]]`: an OBJ file, its placement and material overrides.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectDesc {
    /// OBJ path, relative to the scene file.
    pub mesh: String,
    /// Scale applied first: non-zero factors of magnitude at most
    /// [`super::MAX_COORDINATE`].
    pub scale: Option<Scale>,
    /// Rotation applied second.
    pub rotate: Option<RotateDesc>,
    /// Translation applied last (components of magnitude at most [`super::MAX_COORDINATE`]).
    pub translate: Option<Xyz>,
    /// Full 4×4 row-major object-to-world matrix; excludes scale/rotate/translate. Entries of
    /// magnitude at most [`super::MAX_COORDINATE`], invertible.
    pub matrix: Option<Exactly<Exactly<f64, 4>, 4>>,
    /// Overrides of MTL materials by name.
    #[serde(default)]
    pub materials: BTreeMap<String, MaterialOverride>,
    /// Keyframes of the object's translation and rotation (makes it moving).
    #[serde(default)]
    pub keyframe: Vec<ObjectKeyDesc>,
    /// Moved by the host between frames (`Engine::set_object_transform`) without keyframes
    /// (keyframes imply it; `false` with keyframes is refused).
    pub moving: Option<bool>,
    /// Every face also gets its back-to-back twin, so both sides reflect (a Mitsuba
    /// `twosided` BSDF; [`super::add_twins`]). Emission stays on the front.
    pub two_sided: Option<bool>,
}

/// Rotation by `angle_deg` degrees about `axis` (right-handed).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotateDesc {
    /// Rotation axis (non-zero, normalized on load).
    pub axis: Xyz,
    /// Angle in degrees.
    pub angle_deg: f64,
}

/// Replaces fields of a named MTL material.
#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct MaterialOverride {
    /// Diffuse albedo.
    pub kd: Option<Rgb>,
    /// Phong specular albedo.
    pub ks: Option<Rgb>,
    /// Phong exponent.
    pub ns: Option<f64>,
    /// Emitted radiance (one-sided, front face), at most [`super::MAX_SOURCE`].
    pub ke: Option<Rgb>,
}

/// One `[[light]]`: `type` says which of the optional fields it needs. One flat struct rather
/// than an internally tagged enum, because serde lets unknown keys through such an enum's
/// variants; `load` checks that exactly the fields of the light's type are given.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightDesc {
    /// `"directional"`, `"point"` or `"spot"`.
    #[serde(rename = "type")]
    pub kind: String,
    /// Directional: direction in which light travels (non-zero).
    pub direction: Option<Xyz>,
    /// Directional: irradiance (W/m²) on a surface facing the light, in
    /// [0, [`super::MAX_SOURCE`]].
    pub irradiance: Option<Rgb>,
    /// Point and spot: position.
    pub position: Option<Xyz>,
    /// Point and spot: radiant intensity (W/sr; on the axis for a spot), in
    /// [0, [`super::MAX_SOURCE`]].
    pub intensity: Option<Rgb>,
    /// Spot: a point on the axis (not the position).
    pub target: Option<Xyz>,
    /// Spot: angle from the axis at which intensity reaches zero, in (0, 180].
    pub cutoff_deg: Option<f64>,
    /// Spot: angle from the axis inside which intensity is full, in [0, cutoff_deg].
    pub beam_width_deg: Option<f64>,
    /// Keyframes of the light's position, target, direction, intensity or irradiance.
    #[serde(default)]
    pub keyframe: Vec<LightKeyDesc>,
}

/// `[environment]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentDesc {
    /// Constant radiance arriving from every direction not blocked by geometry, in
    /// [0, [`super::MAX_SOURCE`]].
    pub radiance: Rgb,
}

/// `[camera]`. Positions have components of magnitude at most [`super::MAX_COORDINATE`].
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    /// Eye position.
    pub eye: Xyz,
    /// Point looked at (not the eye).
    pub target: Xyz,
    /// Up vector (default +y; not parallel to the view direction).
    pub up: Option<Xyz>,
    /// Vertical field of view in degrees, in (0, 180) (default 40).
    pub fov_y_deg: Option<f64>,
    /// Image width in pixels, 1..=16384 (default 512).
    pub width: Option<i64>,
    /// Image height in pixels, 1..=16384 (default 512).
    pub height: Option<i64>,
    /// Frame pixels per image pixel along each axis, box-filtered, 1..=8 (default 1).
    pub supersample: Option<i64>,
    /// Shifted passes of the frame, averaged ([`super::Camera::passes`]).
    pub passes: Option<i64>,
}

/// `[solver]`; [`super::SolverSettings`] has the defaults and the ranges.
#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct SolverDesc {
    /// Number of directional bins `m` (a count that lays out as a grid).
    pub bins: Option<i64>,
    /// Number of iterations, 1..=[`super::MAX_ITERATIONS`].
    pub iterations: Option<i64>,
    /// `"symmetric"` or `"asymmetric"`.
    pub scheme: Option<String>,
    /// Longest edge of a leaf element, absolute (scene units); finite, positive, and giving at
    /// most `max_elements` elements. Absent: [`super::RELATIVE_ELEMENT_SIZE`] × the scene's
    /// bounding-box diagonal.
    pub element_size: Option<f64>,
    /// Link oracle threshold τ (finite, positive): refine while a node subtends more than
    /// τ·ω_bin.
    pub oracle: Option<f64>,
    /// Antiradiance steps per radiance step in the asymmetric scheme,
    /// 1..=[`super::MAX_ANTIRADIANCE_STEPS`].
    pub antiradiance_steps: Option<i64>,
    /// `"f16"` or `"f32"` GPU tables.
    pub precision: Option<String>,
    /// Upper bound on leaf elements (refuses scenes that would exceed it),
    /// 1..=[`super::max_elements_limit`].
    pub max_elements: Option<i64>,
    /// Residual target in (0, 1) (iterate until the estimated error is below it: the distance to
    /// the discrete fixed point, not to the true answer).
    pub tolerance: Option<f64>,
    /// Iteration cap when a tolerance is given, 1..=[`super::MAX_ITERATIONS`].
    pub max_iterations: Option<i64>,
    /// Cone-filter weights below this fraction of a row's largest are dropped, in
    /// [1e-9, 0.5].
    pub filter_cutoff: Option<f64>,
    /// Iterations per animated frame, warm-started from the previous frame,
    /// 1..=[`super::MAX_ITERATIONS`] (default 4, the paper's).
    pub iterations_per_frame: Option<i64>,
    /// Shadow-mapped samples of the area emitters, 0..=[`super::MAX_EMITTER_SAMPLES`] (0: their
    /// emission goes through the bins).
    pub emitter_samples: Option<i64>,
    /// Group the small triangles of dense meshes into face clusters (default true).
    pub face_clusters: Option<bool>,
    /// Sum the geometric tail of a stiff iteration in one step (default true).
    pub extrapolate: Option<bool>,
    /// The area emitters' direct light at each of a pixel's 2×2 samples (default false: once
    /// per pixel where its samples lie on one flat surface).
    pub direct_per_sample: Option<bool>,
    /// The splatted indirect light's kernel sum at each of a pixel's 2×2 samples (default
    /// false: once per pixel, at its first sample).
    pub splat_per_sample: Option<bool>,
    /// Pixels per side of the blocks sharing the area emitters' direct light (default 2; 1:
    /// per pixel).
    pub direct_block: Option<i64>,
    /// Scale each leaf's pushed radiance by its own view of its ancestors' senders (default true).
    pub receiver_calibration: Option<bool>,
}
