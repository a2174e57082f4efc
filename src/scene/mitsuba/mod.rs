//! Mitsuba scenes (`.xml`, versions 0.5–3, a documented subset) with `roxmltree`: `obj`,
//! `ply`, `rectangle`, `cube` and `sphere` shapes with `to_world`; `diffuse`, `plastic`,
//! `roughplastic`, `conductor`, `roughconductor`, `principled` and `twosided` BSDFs mapped
//! onto Lambert + Phong; `area`, `point`, `spot`, `directional`, `constant` and `sunsky`
//! emitters; the `perspective` sensor and its film; `default` parameters and `$var`
//! substitution. Whatever else a file holds is named in one warning and skipped. The mapping is
//! `scripts/convert-breakfast-room.py`'s and the Veach converter's, so a scene read here equals
//! its hand-made TOML (tests/mitsuba.rs); the README states it.

mod lights;
mod materials;
mod shapes;
mod spectrum;

use super::load::{framing, scene_err};
use super::settings::resolve_element_size;
use super::Scene;
use crate::error::{Error, Result};
use glam::{DMat3, DMat4, DQuat, DVec3, DVec4};
use roxmltree::Node;
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::Path;

pub use crate::scene::BACK_SUFFIX;
pub use lights::{SKY_RADIANCE, SUN_IRRADIANCE};
pub use materials::GLASS_EXPONENT;

/// Reads a Mitsuba XML scene.
pub fn load_mitsuba_scene(path: &Path) -> Result<Scene> {
    let text = super::files::read_text(path, "Mitsuba XML")
        .map_err(|p| scene_err(path, format!("scene file {p}")))?;
    parse_mitsuba_scene(&text, path)
}

/// Parses Mitsuba XML text as if it had been read from `path` (messages, relative paths).
pub fn parse_mitsuba_scene(text: &str, path: &Path) -> Result<Scene> {
    let doc = roxmltree::Document::parse(text)
        .map_err(|e| scene_err(path, format!("not well-formed XML: {e}")))?;
    let root = doc.root_element();
    if root.tag_name().name() != "scene" {
        return Err(scene_err(
            path,
            format!(
                "the root element is <{}>, not <scene>",
                root.tag_name().name()
            ),
        ));
    }
    let mut r = Reader {
        path,
        doc: &doc,
        vars: HashMap::new(),
        named: HashMap::new(),
        warned: BTreeSet::new(),
        skipped: BTreeMap::new(),
        notes: BTreeSet::new(),
        materials: HashMap::new(),
        within_emitter: false,
    };
    let mut scene = Scene::empty();
    scene.path = Some(path.to_path_buf());
    scene.solver = crate::scene::SolverSettings::for_file();
    let mut camera = None;
    for node in root.children().filter(Node::is_element) {
        match node.tag_name().name() {
            "default" => {
                let name = r.attr(node, "name")?;
                let value = r.attr(node, "value")?;
                r.vars.entry(name).or_insert(value);
            }
            "bsdf" | "texture" => {
                if let Some(id) = node.attribute("id") {
                    r.named.insert(id.to_string(), node);
                } else {
                    r.skip("a <bsdf> without an id at the top level");
                }
            }
            "shape" => r.shape(&mut scene, node)?,
            "emitter" => r.emitter(&mut scene, node)?,
            "sensor" => camera = r.sensor(node)?.or(camera),
            "integrator" => r.note("the integrator (the project's own solver renders)"),
            other => r.skip(&format!("<{other}>")),
        }
    }
    if scene.meshes.is_empty() {
        return Err(scene_err(
            path,
            "no shapes: a scene needs at least one mesh".into(),
        ));
    }
    scene.camera = camera.unwrap_or_else(|| framing(&scene));
    let mut warned = std::mem::take(&mut r.warned);
    if !r.skipped.is_empty() {
        let list: Vec<String> = r
            .skipped
            .iter()
            .map(|(k, n)| {
                if *n == 1 {
                    k.clone()
                } else {
                    format!("{k} ×{n}")
                }
            })
            .collect();
        warned.insert(format!(
            "{}: skipped (not supported): {}",
            path.display(),
            list.join(", ")
        ));
    }
    if !r.notes.is_empty() {
        warned.insert(format!(
            "{}: approximated or ignored: {}",
            path.display(),
            r.notes.iter().cloned().collect::<Vec<_>>().join("; ")
        ));
    }
    resolve_element_size(&mut scene, false, path)?;
    scene.warnings = warned.into_iter().collect();
    Ok(scene)
}

/// A property child (`<float name=… value=…/>` and the like).
#[derive(Clone)]
pub(super) enum Value {
    Number(f64),
    Text(String),
    Color(DVec3),
    Vector(DVec3),
    Transform(DMat4),
    /// A `<texture>` where a colour was wanted.
    Texture,
}

pub(super) struct Reader<'a, 'i> {
    path: &'a Path,
    doc: &'a roxmltree::Document<'i>,
    vars: HashMap<String, String>,
    named: HashMap<String, Node<'a, 'i>>,
    warned: BTreeSet<String>,
    skipped: BTreeMap<String, usize>,
    notes: BTreeSet<String>,
    /// Reading an emitter's properties (a spectrum is converted without D65, unbounded).
    within_emitter: bool,
    /// Scene material per (BSDF id or inline position, emitted radiance bits).
    materials: HashMap<(String, [u64; 3]), u32>,
}

/// Parameter names compared as Mitsuba 0.5 and 3 spell them (`toWorld`, `to_world`).
fn key(name: &str) -> String {
    name.chars()
        .filter(|c| *c != '_')
        .flat_map(char::to_lowercase)
        .collect()
}

fn numbers(s: &str) -> Option<Vec<f64>> {
    s.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
        .map(|t| t.parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect()
}

impl<'a, 'i> Reader<'a, 'i> {
    pub(super) fn line(&self, n: Node) -> u32 {
        self.doc.text_pos_at(n.range().start).row
    }

    pub(super) fn err(&self, n: Node, m: String) -> Error {
        scene_err(
            self.path,
            format!("line {}: <{}>: {m}", self.line(n), n.tag_name().name()),
        )
    }

    pub(super) fn skip(&mut self, what: &str) {
        *self.skipped.entry(what.to_string()).or_default() += 1;
    }

    pub(super) fn note(&mut self, what: &str) {
        self.notes.insert(what.to_string());
    }

    /// An attribute with `$name` replaced by the `<default>`s.
    pub(super) fn attr(&self, n: Node, name: &str) -> Result<String> {
        let v = n
            .attribute(name)
            .ok_or_else(|| self.err(n, format!("no `{name}` attribute")))?;
        self.substitute(n, v)
    }

    pub(super) fn substitute(&self, n: Node, v: &str) -> Result<String> {
        let mut out = String::new();
        let mut rest = v;
        while let Some(i) = rest.find('$') {
            out.push_str(&rest[..i]);
            let tail = &rest[i + 1..];
            let len = tail
                .find(|c: char| !(c.is_alphanumeric() || c == '_'))
                .unwrap_or(tail.len());
            let var = &tail[..len];
            let value = self
                .vars
                .get(var)
                .ok_or_else(|| self.err(n, format!("`${var}` has no <default name=\"{var}\">")))?;
            out.push_str(value);
            rest = &tail[len..];
        }
        out.push_str(rest);
        Ok(out)
    }

    /// The `name`d property children of `n`.
    pub(super) fn props(&mut self, n: Node<'a, 'i>) -> Result<HashMap<String, Value>> {
        let mut out = HashMap::new();
        for c in n.children().filter(Node::is_element) {
            let Some(name) = c.attribute("name") else {
                continue;
            };
            let tag = c.tag_name().name();
            let v = match tag {
                "float" | "integer" => {
                    let s = self.attr(c, "value")?;
                    Value::Number(
                        s.trim()
                            .parse::<f64>()
                            .ok()
                            .filter(|x| x.is_finite())
                            .ok_or_else(|| self.err(c, format!("`{s}` is not a finite number")))?,
                    )
                }
                "boolean" | "string" => Value::Text(self.attr(c, "value")?),
                "rgb" | "srgb" | "spectrum" => Value::Color(self.color(c)?),
                "point" | "vector" => Value::Vector(self.point(c)?),
                "transform" => Value::Transform(self.transform(c)?),
                // A checkerboard is its colours' mean (as the Veach conversion took it); any
                // other texture stands for whatever the BSDF puts in its place.
                "texture" if c.attribute("type") == Some("checkerboard") => {
                    let p = self.props(c)?;
                    let col = |k: &str, d: f64| match p.get(k) {
                        Some(Value::Color(x)) => *x,
                        Some(Value::Number(x)) => DVec3::splat(*x),
                        _ => DVec3::splat(d),
                    };
                    self.note("checkerboard textures (the mean of their two colours)");
                    Value::Color((col("color0", 0.4) + col("color1", 0.2)) * 0.5)
                }
                "texture" => Value::Texture,
                _ => continue,
            };
            out.insert(key(name), v);
        }
        Ok(out)
    }

    pub(super) fn color(&mut self, c: Node) -> Result<DVec3> {
        let s = self.attr(c, "value")?;
        let tag = c.tag_name().name();
        if tag == "spectrum" && s.contains(':') {
            // Wavelength:value pairs, converted as Mitsuba 3's RGB modes convert them.
            let pairs: Option<Vec<(f64, f64)>> = s
                .split(',')
                .map(|p| {
                    let (l, v) = p.split_once(':')?;
                    let (l, v) = (l.trim().parse::<f64>().ok()?, v.trim().parse::<f64>().ok()?);
                    (l.is_finite() && v.is_finite()).then_some((l, v))
                })
                .collect();
            let pairs = pairs
                .filter(|p| p.len() >= 2 && p.windows(2).all(|w| w[0].0 < w[1].0))
                .ok_or_else(|| {
                    self.err(
                        c,
                        format!("`{s}`: a spectrum is increasing wavelength:value pairs"),
                    )
                })?;
            return Ok(spectrum::to_srgb(&pairs, self.within_emitter));
        }
        let v = numbers(&s).ok_or_else(|| self.err(c, format!("`{s}` is not a colour")))?;
        let rgb = match v.as_slice() {
            [x] => DVec3::splat(*x),
            [r, g, b] => DVec3::new(*r, *g, *b),
            _ => return Err(self.err(c, format!("`{s}`: a colour is one or three numbers"))),
        };
        if tag == "srgb" {
            let lin = |x: f64| {
                if x <= 0.04045 {
                    x / 12.92
                } else {
                    ((x + 0.055) / 1.055).powf(2.4)
                }
            };
            return Ok(DVec3::new(lin(rgb.x), lin(rgb.y), lin(rgb.z)));
        }
        Ok(rgb)
    }

    /// A point or vector: `value="x y z"` or `x`, `y`, `z` attributes (missing ones 0).
    pub(super) fn point(&self, c: Node) -> Result<DVec3> {
        self.xyz(c, 0.0)
    }

    pub(super) fn xyz(&self, c: Node, missing: f64) -> Result<DVec3> {
        if c.attribute("value").is_some() {
            let s = self.attr(c, "value")?;
            return match numbers(&s).as_deref() {
                Some([x]) => Ok(DVec3::splat(*x)),
                Some([x, y, z]) => Ok(DVec3::new(*x, *y, *z)),
                _ => Err(self.err(c, format!("`{s}` is not three numbers"))),
            };
        }
        let mut v = [missing; 3];
        for (k, a) in ["x", "y", "z"].iter().enumerate() {
            if c.attribute(*a).is_some() {
                let s = self.attr(c, a)?;
                v[k] = s
                    .trim()
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| self.err(c, format!("`{a}` = `{s}` is not a finite number")))?;
            }
        }
        Ok(DVec3::from_array(v))
    }

    /// `<transform>`: its operations applied in order (each after the ones before).
    pub(super) fn transform(&self, t: Node) -> Result<DMat4> {
        let mut m = DMat4::IDENTITY;
        for op in t.children().filter(Node::is_element) {
            let step = match op.tag_name().name() {
                "matrix" => {
                    let s = self.attr(op, "value")?;
                    let v = numbers(&s).filter(|v| v.len() == 16 || v.len() == 9);
                    let v =
                        v.ok_or_else(|| self.err(op, "16 (or 9) finite numbers wanted".into()))?;
                    if v.len() == 9 {
                        DMat4::from_mat3(
                            DMat3::from_cols_array(&v.try_into().unwrap_or([0.0; 9])).transpose(),
                        )
                    } else {
                        let mut a = [0.0; 16];
                        a.copy_from_slice(&v);
                        DMat4::from_cols_array(&a).transpose()
                    }
                }
                "translate" => DMat4::from_translation(self.xyz(op, 0.0)?),
                "scale" => DMat4::from_scale(self.xyz(op, 1.0)?),
                "rotate" => {
                    let axis = self.xyz(op, 0.0)?;
                    let angle = self.attr(op, "angle")?;
                    let angle: f64 = angle
                        .trim()
                        .parse()
                        .map_err(|_| self.err(op, format!("angle `{angle}` is not a number")))?;
                    if axis.length() == 0.0 {
                        return Err(self.err(op, "the rotation axis is zero".into()));
                    }
                    DMat4::from_quat(DQuat::from_axis_angle(axis.normalize(), angle.to_radians()))
                }
                "lookat" => {
                    let get = |a: &str| -> Result<DVec3> {
                        let s = self.attr(op, a)?;
                        match numbers(&s).as_deref() {
                            Some([x, y, z]) => Ok(DVec3::new(*x, *y, *z)),
                            _ => Err(self.err(op, format!("`{a}` = `{s}` is not three numbers"))),
                        }
                    };
                    let origin = get("origin")?;
                    let target = get("target")?;
                    let up = if op.attribute("up").is_some() {
                        get("up")?
                    } else {
                        DVec3::Y
                    };
                    let dir = (target - origin).normalize_or_zero();
                    let left = up.cross(dir).normalize_or_zero();
                    if dir == DVec3::ZERO || left == DVec3::ZERO {
                        return Err(
                            self.err(op, "origin, target and up do not make a frame".into())
                        );
                    }
                    let new_up = dir.cross(left);
                    DMat4::from_cols(
                        left.extend(0.0),
                        new_up.extend(0.0),
                        dir.extend(0.0),
                        origin.extend(1.0),
                    )
                }
                other => return Err(self.err(op, format!("unknown transform operation <{other}>"))),
            };
            m = step * m;
        }
        if !m.is_finite() || m.row(3) != DVec4::new(0.0, 0.0, 0.0, 1.0) {
            return Err(self.err(t, "the transform must be finite and affine".into()));
        }
        Ok(m)
    }
}
