//! Moving objects and lights (§3.3): keyframes read from `[[object.keyframe]]` and
//! `[[light.keyframe]]`, and [`Scene::at`], the scene as it stands at a time. Between keys
//! translation and light fields are linear, rotation is spherical; before the first and after
//! the last key the end values hold. Each channel (translate, rotate, position, …) is its own
//! track: keys that do not give it are skipped, and the value written on the `[[object]]` or
//! `[[light]]` itself is the channel's key at time 0 unless a key at time 0 gives it.

use super::format::{LightKeyDesc, ObjectDesc, Xyz};
use super::load::{scene_err, source, unit, vec3};
use super::{Light, Scene};
use crate::error::{Error, Result};
use glam::{DMat4, DQuat, DVec3};
use std::ops::Range;
use std::path::Path;

/// One `[[object]]` of a scene: its meshes, where it stands, and how it moves.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneObject {
    /// Its meshes in [`Scene::meshes`].
    pub meshes: Range<usize>,
    /// The object-to-world transform its meshes' positions are in now.
    pub transform: DMat4,
    /// Whether it may move after preparation (keyframes, `moving = true`, or a host's choice).
    pub moving: bool,
    /// Its keyframes, if any.
    pub motion: Option<ObjectMotion>,
}

/// An object's keyframes and the placement they start from.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjectMotion {
    /// Scale (not animated).
    pub scale: DVec3,
    /// Rotation written on the object (the rotate track's value at time 0 by default).
    pub rotate: DQuat,
    /// Translation written on the object (the translate track's value at time 0 by default).
    pub translate: DVec3,
    /// Keys in increasing time.
    pub keys: Vec<ObjectKey>,
}

/// One key of an object.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjectKey {
    /// Scene time (s).
    pub time: f64,
    /// Translation at this time.
    pub translate: Option<DVec3>,
    /// Rotation at this time.
    pub rotate: Option<DQuat>,
}

/// A light's keyframes and the light they start from.
#[derive(Debug, Clone, PartialEq)]
pub struct LightTrack {
    /// The light as written.
    pub base: Light,
    /// Spot lights: the target as written (the axis is target − position at every time).
    pub target: DVec3,
    /// Keys in increasing time.
    pub keys: Vec<LightKey>,
}

/// One key of a light: the fields it gives.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LightKey {
    /// Scene time (s).
    pub time: f64,
    /// Point and spot lights.
    pub position: Option<DVec3>,
    /// Spot lights.
    pub target: Option<DVec3>,
    /// Directional lights (unit).
    pub direction: Option<DVec3>,
    /// Point and spot lights.
    pub intensity: Option<DVec3>,
    /// Directional lights.
    pub irradiance: Option<DVec3>,
}

/// The value of one channel at `t`: `keys` are (time, value) of the keys that give it, `base`
/// the written value (a key at time 0 unless one is there).
fn sample<T: Copy>(base: T, keys: &[(f64, T)], t: f64, mix: impl Fn(T, T, f64) -> T) -> T {
    let mut track: Vec<(f64, T)> = Vec::with_capacity(keys.len() + 1);
    if keys.first().is_none_or(|k| k.0 > 0.0) {
        track.push((0.0, base));
    }
    track.extend_from_slice(keys);
    let (first, last) = (track[0], track[track.len() - 1]);
    if t <= first.0 {
        return first.1;
    }
    if t >= last.0 {
        return last.1;
    }
    let i = track.partition_point(|k| k.0 <= t);
    let (a, b) = (track[i - 1], track[i]);
    mix(a.1, b.1, (t - a.0) / (b.0 - a.0))
}

fn lerp(a: DVec3, b: DVec3, s: f64) -> DVec3 {
    a + (b - a) * s
}

impl ObjectMotion {
    /// The object-to-world transform at time `t`.
    pub fn transform_at(&self, t: f64) -> DMat4 {
        let tr: Vec<(f64, DVec3)> = self
            .keys
            .iter()
            .filter_map(|k| k.translate.map(|v| (k.time, v)))
            .collect();
        let rot: Vec<(f64, DQuat)> = self
            .keys
            .iter()
            .filter_map(|k| k.rotate.map(|v| (k.time, v)))
            .collect();
        let translate = sample(self.translate, &tr, t, lerp);
        let rotate = sample(self.rotate, &rot, t, |a, b, s| a.slerp(b, s));
        DMat4::from_scale_rotation_translation(self.scale, rotate, translate)
    }
}

impl LightTrack {
    /// The light at time `t` (a spot whose target meets its position keeps the written axis).
    pub fn light_at(&self, t: f64) -> Light {
        let chan = |f: fn(&LightKey) -> Option<DVec3>, base: DVec3| {
            let keys: Vec<(f64, DVec3)> = self
                .keys
                .iter()
                .filter_map(|k| f(k).map(|v| (k.time, v)))
                .collect();
            sample(base, &keys, t, lerp)
        };
        match self.base.clone() {
            Light::Directional {
                direction,
                irradiance,
            } => Light::Directional {
                direction: chan(|k| k.direction, direction)
                    .try_normalize()
                    .unwrap_or(direction),
                irradiance: chan(|k| k.irradiance, irradiance),
            },
            Light::Point {
                position,
                intensity,
            } => Light::Point {
                position: chan(|k| k.position, position),
                intensity: chan(|k| k.intensity, intensity),
            },
            Light::Spot {
                position,
                axis,
                intensity,
                cutoff,
                beam_width,
            } => {
                let p = chan(|k| k.position, position);
                let target = chan(|k| k.target, self.target);
                Light::Spot {
                    position: p,
                    axis: (target - p).try_normalize().unwrap_or(axis),
                    intensity: chan(|k| k.intensity, intensity),
                    cutoff,
                    beam_width,
                }
            }
            other => other,
        }
    }
}

impl Scene {
    /// Registers meshes `meshes` (already in world space at `transform`) as one object and
    /// returns its index; `moving` objects may be moved after preparation
    /// ([`Scene::set_object_transform`]). For scenes built in code.
    pub fn add_object(&mut self, meshes: Range<usize>, transform: DMat4, moving: bool) -> usize {
        self.objects.push(SceneObject {
            meshes,
            transform,
            moving,
            motion: None,
        });
        self.objects.len() - 1
    }

    /// Gives object `object` keyframes (for scenes built in code, as `[[object.keyframe]]`
    /// does in a file): `keys` in increasing time, each translation and rotation replacing the
    /// object's at that time, the object's current transform supplying the scale and the
    /// values of channels no key gives. The object becomes moving, is placed where the keys
    /// put it at time 0, and the scene's duration covers the last key. The links made for
    /// such a scene are bounded for the whole motion, so [`crate::engine::Engine::set_time`]
    /// updates follow it without relinking.
    pub fn set_object_keyframes(&mut self, object: usize, keys: Vec<ObjectKey>) -> Result<()> {
        let n = self.objects.len();
        let o = self.objects.get(object).ok_or_else(|| {
            Error::Invalid(format!("object {object} does not exist ({n} objects)"))
        })?;
        let bad = |what: String| Error::Invalid(format!("object {object} keyframes: {what}"));
        if keys.is_empty() {
            return Err(bad("no keys".into()));
        }
        let mut prev: Option<f64> = None;
        for (i, k) in keys.iter().enumerate() {
            if !(k.time.is_finite() && k.time >= 0.0) || prev.is_some_and(|p| k.time <= p) {
                return Err(bad(format!(
                    "key {i}: times must be finite, non-negative and increasing, got {}",
                    k.time
                )));
            }
            if k.translate.is_some_and(|v| !v.is_finite())
                || k.rotate
                    .is_some_and(|q| !q.is_finite() || !q.is_normalized())
            {
                return Err(bad(format!(
                    "key {i}: translations must be finite and rotations unit quaternions"
                )));
            }
            prev = Some(k.time);
        }
        let (scale, rotate, translate) = o.transform.to_scale_rotation_translation();
        let last = prev.expect("keys is not empty");
        let motion = ObjectMotion {
            scale,
            rotate,
            translate,
            keys,
        };
        let start = motion.transform_at(0.0);
        let o = &mut self.objects[object];
        o.motion = Some(motion);
        o.moving = true;
        self.duration = Some(self.duration.map_or(last, |d| d.max(last)));
        self.place(object, start);
        Ok(())
    }

    /// Whether anything moves: a keyframed or `moving` object, or a keyframed light.
    pub fn is_animated(&self) -> bool {
        self.objects.iter().any(|o| o.moving)
            || self.light_tracks.iter().any(|l| !l.keys.is_empty())
    }

    /// Seconds of scene time the keyframes span (`[animation] duration`, else the last key's
    /// time); 0 for a scene without keyframes.
    pub fn duration(&self) -> f64 {
        self.duration.unwrap_or(0.0)
    }

    /// Places object `object` at `m` (object-to-world, replacing where it stood), moving its
    /// meshes' vertices. Refuses objects not marked moving, and non-invertible or non-finite
    /// transforms.
    pub fn set_object_transform(&mut self, object: usize, m: DMat4) -> Result<()> {
        let n = self.objects.len();
        let o = self.objects.get(object).ok_or_else(|| {
            Error::Invalid(format!("object {object} does not exist ({n} objects)"))
        })?;
        if !o.moving {
            return Err(Error::Invalid(format!(
                "object {object} was not marked moving (give it keyframes or `moving = true`): its links were made for where it stands"
            )));
        }
        let det = m.determinant();
        if !m.is_finite() || !(det.abs() > 0.0) || !det.is_finite() {
            return Err(Error::Invalid(format!(
                "object {object}: the transform must be finite and invertible"
            )));
        }
        self.place(object, m);
        Ok(())
    }

    /// Moves object `object`'s vertices from its current transform to `m`.
    fn place(&mut self, object: usize, m: DMat4) {
        let o = &mut self.objects[object];
        let step = m * o.transform.inverse();
        o.transform = m;
        // Shading normals by the inverse transpose (turned with the winding by a mirror).
        let linear = glam::DMat3::from_mat4(step);
        let normal_matrix = linear.inverse().transpose() * linear.determinant().signum();
        for mesh in &mut self.meshes[o.meshes.clone()] {
            for p in &mut mesh.positions {
                *p = step.transform_point3(*p);
            }
            for n in mesh.normals.iter_mut().flatten() {
                *n = (normal_matrix * *n).normalize();
            }
        }
    }

    /// The scene as it stands at time `t` (seconds; clamped to the keys): keyframed objects
    /// moved, keyframed lights changed. Everything else is as loaded.
    pub fn at(&self, t: f64) -> Scene {
        let mut s = self.clone();
        s.move_to(t);
        s
    }

    /// The scene as it stands with no object keyframed (their keys dropped, nothing else
    /// changed): what `render` and `render --time` prepare, linked for this pose alone rather
    /// than for a motion ([`crate::bound`]).
    pub fn still(&self) -> Scene {
        let mut s = self.clone();
        for o in &mut s.objects {
            o.motion = None;
        }
        s
    }

    /// [`Scene::at`] in place.
    pub fn move_to(&mut self, t: f64) {
        for i in 0..self.objects.len() {
            if let Some(m) = &self.objects[i].motion {
                let target = m.transform_at(t);
                self.place(i, target);
            }
        }
        for (i, track) in self.light_tracks.iter().enumerate() {
            if !track.keys.is_empty() {
                self.lights[i] = track.light_at(t);
            }
        }
    }
}

/// Checks a key's time: finite, non-negative, after the previous key's.
fn key_time(t: f64, prev: Option<f64>, field: &str, path: &Path) -> Result<f64> {
    if !(t.is_finite() && t >= 0.0) {
        return Err(scene_err(
            path,
            format!("`{field}` must be finite and non-negative, got {t:?}"),
        ));
    }
    if let Some(p) = prev.filter(|&p| t <= p) {
        return Err(scene_err(
            path,
            format!("`{field}` must be greater than the previous key's time {p}, got {t}"),
        ));
    }
    Ok(t)
}

/// The object's keyframes, checked (`None` without keys); `scale`, `rotate`, `translate` as
/// the object gives them.
pub(super) fn object_motion(
    o: &ObjectDesc,
    i: usize,
    (scale, rotate, translate): (DVec3, DQuat, DVec3),
    path: &Path,
) -> Result<Option<ObjectMotion>> {
    if o.keyframe.is_empty() {
        return Ok(None);
    }
    if o.matrix.is_some() {
        return Err(scene_err(
            path,
            format!("`object[{i}].keyframe` needs the object placed by scale, rotate and translate, not `matrix`"),
        ));
    }
    if o.moving == Some(false) {
        return Err(scene_err(
            path,
            format!("`object[{i}].moving` is false but the object has keyframes"),
        ));
    }
    let mut keys = Vec::new();
    let mut prev = None;
    for (k, d) in o.keyframe.iter().enumerate() {
        let f = |name: &str| format!("object[{i}].keyframe[{k}].{name}");
        let time = key_time(d.time, prev, &f("time"), path)?;
        prev = Some(time);
        let rotate = match d.rotate {
            None => None,
            Some(r) => {
                if !r.angle_deg.is_finite() {
                    return Err(scene_err(
                        path,
                        format!("`{}` must be finite", f("rotate.angle_deg")),
                    ));
                }
                Some(DQuat::from_axis_angle(
                    unit(r.axis, &f("rotate.axis"), path)?,
                    r.angle_deg.to_radians(),
                ))
            }
        };
        let translate = d
            .translate
            .map(|v| vec3(v, &f("translate"), path))
            .transpose()?;
        if rotate.is_none() && translate.is_none() {
            return Err(scene_err(
                path,
                format!("`object[{i}].keyframe[{k}]` gives neither translate nor rotate"),
            ));
        }
        keys.push(ObjectKey {
            time,
            translate,
            rotate,
        });
    }
    Ok(Some(ObjectMotion {
        scale,
        rotate,
        translate,
        keys,
    }))
}

/// The fields a light's keyframes may give, by type.
const KEY_FIELDS: [(&str, &[&str]); 3] = [
    ("directional", &["direction", "irradiance"]),
    ("point", &["position", "intensity"]),
    ("spot", &["position", "target", "intensity"]),
];

/// Light `i`'s keyframes, checked; `base` is the light as written, `target` a spot's target.
pub(super) fn light_track(
    keys: &[LightKeyDesc],
    i: usize,
    base: &Light,
    target: DVec3,
    path: &Path,
) -> Result<LightTrack> {
    let kind = base.kind();
    let allowed = KEY_FIELDS
        .iter()
        .find(|(k, _)| *k == kind)
        .map_or(&[][..], |(_, f)| *f);
    let mut out = Vec::new();
    let mut prev = None;
    for (k, d) in keys.iter().enumerate() {
        let f = |name: &str| format!("light[{i}].keyframe[{k}].{name}");
        let time = key_time(d.time, prev, &f("time"), path)?;
        prev = Some(time);
        let given = [
            ("position", d.position.is_some()),
            ("target", d.target.is_some()),
            ("direction", d.direction.is_some()),
            ("intensity", d.intensity.is_some()),
            ("irradiance", d.irradiance.is_some()),
        ];
        for (name, present) in given {
            if present && !allowed.contains(&name) {
                return Err(scene_err(
                    path,
                    format!(
                        "`{}` does not apply: a {kind} light's keyframes take {}",
                        f(name),
                        allowed.join(", ")
                    ),
                ));
            }
        }
        if !given.iter().any(|(_, p)| *p) {
            return Err(scene_err(
                path,
                format!(
                    "`light[{i}].keyframe[{k}]` gives none of {}",
                    allowed.join(", ")
                ),
            ));
        }
        let v = |x: Option<Xyz>, name: &str| x.map(|x| vec3(x, &f(name), path)).transpose();
        let c = |x: Option<super::format::Rgb>, name: &str| {
            x.map(|x| source(x, &f(name), path)).transpose()
        };
        out.push(LightKey {
            time,
            position: v(d.position, "position")?,
            target: v(d.target, "target")?,
            direction: d
                .direction
                .map(|x| unit(x, &f("direction"), path))
                .transpose()?,
            intensity: c(d.intensity, "intensity")?,
            irradiance: c(d.irradiance, "irradiance")?,
        });
    }
    let track = LightTrack {
        base: base.clone(),
        target,
        keys: out,
    };
    // A spot needs its target apart from its position at every key.
    if let Light::Spot { .. } = base {
        for (k, key) in track.keys.iter().enumerate() {
            let chan = |f: fn(&LightKey) -> Option<DVec3>, b: DVec3| {
                let ks: Vec<(f64, DVec3)> = track
                    .keys
                    .iter()
                    .filter_map(|k| f(k).map(|v| (k.time, v)))
                    .collect();
                sample(b, &ks, key.time, lerp)
            };
            let p = chan(|k| k.position, light_position(base));
            let t = chan(|k| k.target, target);
            if !((t - p).length() > 1e-12 * p.abs().max(t.abs()).max_element()) {
                return Err(scene_err(
                    path,
                    format!(
                        "`light[{i}].keyframe[{k}]`: the spot's target meets its position at time {}",
                        key.time
                    ),
                ));
            }
        }
    }
    Ok(track)
}

fn light_position(l: &Light) -> DVec3 {
    match l {
        Light::Point { position, .. } | Light::Spot { position, .. } => *position,
        _ => DVec3::ZERO,
    }
}

/// `[animation] duration`, checked, else the last key's time (`None` without any key).
pub(super) fn duration(given: Option<f64>, scene: &Scene, path: &Path) -> Result<Option<f64>> {
    if let Some(d) = given {
        if !(d.is_finite() && d > 0.0) {
            return Err(scene_err(
                path,
                format!("`animation.duration` must be positive and finite, got {d:?}"),
            ));
        }
        return Ok(Some(d));
    }
    let last = scene
        .objects
        .iter()
        .filter_map(|o| o.motion.as_ref())
        .flat_map(|m| m.keys.iter().map(|k| k.time))
        .chain(
            scene
                .light_tracks
                .iter()
                .flat_map(|l| l.keys.iter().map(|k| k.time)),
        )
        .fold(None, |a: Option<f64>, t| Some(a.map_or(t, |a| a.max(t))));
    Ok(last)
}
