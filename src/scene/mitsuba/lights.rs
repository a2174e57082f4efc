//! Mitsuba emitters (besides `area`, which a shape holds) and the perspective sensor.

use super::{Reader, Value};
use crate::error::Result;
use crate::scene::{Camera, FovAxis, Light, Scene, MAX_SOURCE};
use glam::{DMat4, DVec3};
use roxmltree::Node;

/// `sunsky`'s sun irradiance (on a surface facing it) and sky radiance: set, not derived (no
/// sky model here), as the breakfast-room conversion set them.
pub const SUN_IRRADIANCE: f64 = 24.0;
/// See [`SUN_IRRADIANCE`].
pub const SKY_RADIANCE: f64 = 1.0;

impl<'a, 'i> Reader<'a, 'i> {
    pub(super) fn emitter(&mut self, scene: &mut Scene, n: Node<'a, 'i>) -> Result<()> {
        let kind = self.attr(n, "type")?;
        self.within_emitter = true;
        let p = self.props(n);
        self.within_emitter = false;
        let p = p?;
        let to_world = match p.get("toworld") {
            Some(Value::Transform(m)) => *m,
            _ => DMat4::IDENTITY,
        };
        let value = |k: &str| match p.get(k) {
            Some(Value::Color(c)) => *c,
            Some(Value::Number(x)) => DVec3::splat(*x),
            _ => DVec3::ONE,
        };
        let scale = match p.get("scale") {
            Some(Value::Number(s)) => *s,
            _ => 1.0,
        };
        let check = |v: DVec3| -> Result<DVec3> {
            if v.is_finite() && v.min_element() >= 0.0 && v.max_element() <= MAX_SOURCE {
                Ok(v)
            } else {
                Err(self.err(
                    n,
                    format!(
                        "{:?} must be non-negative and at most {MAX_SOURCE:e}",
                        v.to_array()
                    ),
                ))
            }
        };
        let axis = to_world.transform_vector3(DVec3::Z).normalize_or_zero();
        match kind.as_str() {
            "point" => {
                let position = match p.get("position") {
                    Some(Value::Vector(v)) => *v,
                    _ => to_world.transform_point3(DVec3::ZERO),
                };
                scene.lights.push(Light::Point {
                    position,
                    intensity: check(value("intensity") * scale)?,
                });
            }
            "spot" => {
                let num = |k: &str| match p.get(k) {
                    Some(Value::Number(x)) => Some(*x),
                    _ => None,
                };
                let cutoff = num("cutoffangle").unwrap_or(20.0).clamp(1e-6, 180.0);
                let beam = num("beamwidth").unwrap_or(cutoff * 0.75).clamp(0.0, cutoff);
                if axis == DVec3::ZERO {
                    return Err(self.err(n, "to_world has no direction".into()));
                }
                scene.lights.push(Light::Spot {
                    position: to_world.transform_point3(DVec3::ZERO),
                    axis,
                    intensity: check(value("intensity") * scale)?,
                    cutoff: cutoff.to_radians(),
                    beam_width: beam.to_radians(),
                });
            }
            "directional" => {
                let direction = match p.get("direction") {
                    Some(Value::Vector(v)) => v.normalize_or_zero(),
                    _ => axis,
                };
                if direction == DVec3::ZERO {
                    return Err(self.err(n, "the direction is zero".into()));
                }
                scene.lights.push(Light::Directional {
                    direction,
                    irradiance: check(value("irradiance") * scale)?,
                });
            }
            "constant" => scene.environment = check(value("radiance") * scale)?,
            "sunsky" | "sun" => {
                let Some(Value::Vector(s)) = p.get("sundirection") else {
                    self.skip(&format!("emitter {kind} without sunDirection"));
                    return Ok(());
                };
                let s = s.normalize_or_zero();
                if s == DVec3::ZERO {
                    return Err(self.err(n, "sunDirection is zero".into()));
                }
                self.note(&format!(
                    "{kind}: the sun as a directional light of irradiance {SUN_IRRADIANCE} along −sunDirection{}, magnitudes set, not derived",
                    if kind == "sunsky" { format!(", the sky as a constant radiance {SKY_RADIANCE}") } else { String::new() }
                ));
                scene.lights.push(Light::Directional {
                    direction: -s,
                    irradiance: DVec3::splat(SUN_IRRADIANCE),
                });
                if kind == "sunsky" {
                    scene.environment = DVec3::splat(SKY_RADIANCE);
                }
            }
            other => self.skip(&format!("emitter {other}")),
        }
        Ok(())
    }

    pub(super) fn sensor(&mut self, n: Node<'a, 'i>) -> Result<Option<Camera>> {
        let kind = self.attr(n, "type")?;
        if kind != "perspective" && kind != "thinlens" {
            self.skip(&format!("sensor {kind}"));
            return Ok(None);
        }
        if kind == "thinlens" {
            self.note("thinlens (as a pinhole)");
        }
        let p = self.props(n)?;
        let m = match p.get("toworld") {
            Some(Value::Transform(m)) => *m,
            _ => DMat4::IDENTITY,
        };
        let (mut width, mut height) = (768.0, 576.0);
        if let Some(film) = n.children().find(|c| c.has_tag_name("film")) {
            let fp = self.props(film)?;
            if let Some(Value::Number(w)) = fp.get("width") {
                width = *w;
            }
            if let Some(Value::Number(h)) = fp.get("height") {
                height = *h;
            }
        }
        if !((1.0..=16384.0).contains(&width) && (1.0..=16384.0).contains(&height)) {
            return Err(self.err(
                n,
                format!("film size {width} × {height} must be 1..=16384 each"),
            ));
        }
        let fov = match (p.get("fov"), p.get("focallength")) {
            (Some(Value::Number(f)), _) => *f,
            (_, Some(Value::Text(f))) => {
                // A 35 mm film's diagonal over twice the focal length.
                let mm: f64 = f
                    .trim_end_matches("mm")
                    .trim()
                    .parse()
                    .map_err(|_| self.err(n, format!("focal_length `{f}`")))?;
                2.0 * (43.266615 / (2.0 * mm)).atan().to_degrees()
            }
            _ => 2.0 * (43.266615f64 / 100.0).atan().to_degrees(),
        };
        let axis = match p.get("fovaxis") {
            Some(Value::Text(a)) => a.as_str(),
            _ if p.contains_key("focallength") || !p.contains_key("fov") => "diagonal",
            _ => "x",
        };
        let fov_axis = match axis {
            "y" => FovAxis::Y,
            "diagonal" => FovAxis::Diagonal,
            "smaller" => FovAxis::Smaller,
            "larger" => FovAxis::Larger,
            _ => FovAxis::X,
        };
        let t = (fov.to_radians() * 0.5).tan();
        let ty = fov_axis.tan_half_y(t, width, height);
        let fov_y = 2.0 * ty.atan().to_degrees();
        let eye = m.transform_point3(DVec3::ZERO);
        let forward = m.transform_vector3(DVec3::Z).normalize_or_zero();
        let up = m.transform_vector3(DVec3::Y).normalize_or_zero();
        if forward == DVec3::ZERO || up == DVec3::ZERO || !(fov_y > 0.0 && fov_y < 180.0) {
            return Err(self.err(
                n,
                "the sensor's to_world or fov does not make a camera".into(),
            ));
        }
        Ok(Some(Camera {
            eye,
            target: eye + forward,
            up,
            fov_y_deg: fov_y,
            width: width as u32,
            height: height as u32,
            supersample: 1,
            jitter: [0.0; 2],
            passes: 1,
            fov_axis,
        }))
    }
}
