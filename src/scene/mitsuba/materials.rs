//! Mitsuba BSDFs as Lambert + Phong (the mapping the README states).

use super::Reader;
use super::Value;
use crate::error::Result;
use crate::scene::gltf_scene::{map_material, phong_exponent};
use crate::scene::Material;
use glam::DVec3;
use roxmltree::Node;
use std::collections::HashMap;

/// Phong exponent standing in for a smooth dielectric (glass), opaque here: the Veach
/// conversion's `Ns 10000`.
pub const GLASS_EXPONENT: f64 = 10000.0;

impl<'a, 'i> Reader<'a, 'i> {
    /// The BSDF a shape refers to or holds, as a material.
    pub(super) fn bsdf(&mut self, n: Node<'a, 'i>, name: &str) -> Result<Material> {
        let p = self.props(n)?;
        let kind = self.attr(n, "type")?;
        // Err: a texture (what stands in for it is the caller's).
        let rgb = |k: &str, default: f64| match p.get(k) {
            Some(Value::Color(c)) => Ok(*c),
            Some(Value::Number(x)) => Ok(DVec3::splat(*x)),
            Some(Value::Texture) => Err(()),
            _ => Ok(DVec3::splat(default)),
        };
        let alpha = |p: &HashMap<String, Value>, default: f64| match (
            p.get("alpha"),
            p.get("alphau"),
            p.get("alphav"),
        ) {
            (Some(Value::Number(a)), _, _) => *a,
            (_, Some(Value::Number(u)), Some(Value::Number(v))) => (u * v).sqrt(),
            _ => default,
        };
        let mut m = Material::diffuse(name, 0.5);
        match kind.as_str() {
            "twosided" | "mask" | "bumpmap" | "normalmap" => {
                if kind == "twosided" {
                    self.note("twosided (each face gets a back-to-back twin that reflects and does not emit)");
                } else {
                    self.note(&format!("{kind} (its inner BSDF is used)"));
                }
                return match n
                    .children()
                    .find(|c| c.has_tag_name("bsdf") || c.has_tag_name("ref"))
                {
                    Some(c) => self.bsdf_of(c, name),
                    None => Ok(m),
                };
            }
            "diffuse" | "roughdiffuse" => {
                if kind == "roughdiffuse" {
                    self.note("roughdiffuse (as diffuse)");
                }
                m.kd = rgb("reflectance", 0.5).unwrap_or_else(|_| {
                    self.notes.insert(
                        "textures (a diffuse texture is grey 0.5, a plastic's base 0.8)".into(),
                    );
                    DVec3::splat(0.5)
                });
            }
            "plastic" | "roughplastic" => {
                // What the dielectric coat's Fresnel leaves the base (≈ 10% at IOR 1.5) and the
                // coat's normal-incidence reflectance.
                let base = rgb("diffusereflectance", 0.5).unwrap_or_else(|_| {
                    self.notes.insert(
                        "textures (a diffuse texture is grey 0.5, a plastic's base 0.8)".into(),
                    );
                    DVec3::splat(0.8)
                });
                m.kd = base * 0.9;
                m.ks = DVec3::splat(0.04) * rgb("specularreflectance", 1.0).unwrap_or(DVec3::ONE);
                m.ns = if kind == "plastic" {
                    phong_exponent(0.0)
                } else {
                    phong_exponent(alpha(&p, 0.1))
                };
            }
            "conductor" | "roughconductor" => {
                let scale = rgb("specularreflectance", 1.0).unwrap_or(DVec3::ONE);
                let f0 = match (p.get("eta"), p.get("k")) {
                    (Some(Value::Color(eta)), Some(Value::Color(k))) => {
                        let f = |n: f64, k: f64| {
                            ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k)
                        };
                        DVec3::new(f(eta.x, k.x), f(eta.y, k.y), f(eta.z, k.z))
                    }
                    _ => {
                        if p.contains_key("material") {
                            self.note(
                                "named conductor materials (no tables here: reflectance 0.9)",
                            );
                            DVec3::splat(0.9)
                        } else {
                            DVec3::ONE
                        }
                    }
                };
                m.kd = DVec3::ZERO;
                m.ks = scale * f0;
                m.ns = if kind == "conductor" {
                    phong_exponent(0.0)
                } else {
                    phong_exponent(alpha(&p, 0.1))
                };
            }
            "dielectric" | "thindielectric" | "roughdielectric" => {
                self.note("dielectrics (glass as an opaque sharp lobe: no transmission)");
                m.kd = DVec3::ZERO;
                m.ks = DVec3::ONE;
                m.ns = GLASS_EXPONENT;
            }
            "principled" => {
                let base = rgb("basecolor", 0.5).unwrap_or(DVec3::splat(0.5));
                let num = |k: &str, d: f64| match p.get(k) {
                    Some(Value::Number(x)) => *x,
                    _ => d,
                };
                m = map_material(
                    name,
                    [base.x as f32, base.y as f32, base.z as f32, 1.0],
                    num("metallic", 0.0) as f32,
                    num("roughness", 0.5) as f32,
                    [0.0; 3],
                    0.0,
                );
            }
            other => self.skip(&format!("bsdf {other} (grey diffuse 0.5 instead)")),
        }
        Ok(m)
    }

    /// A `<bsdf>` or a `<ref>` to one.
    pub(super) fn bsdf_of(&mut self, c: Node<'a, 'i>, name: &str) -> Result<Material> {
        if c.has_tag_name("ref") {
            let id = self.attr(c, "id")?;
            let target = *self
                .named
                .get(&id)
                .ok_or_else(|| self.err(c, format!("no <bsdf id=\"{id}\"> before it")))?;
            return self.bsdf(target, name);
        }
        self.bsdf(c, name)
    }
}
