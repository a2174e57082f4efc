//! The path tracer's light transport: exactly the scene format's semantics, sampled without
//! bias. Surfaces are one-sided (light neither leaves nor reflects off a back face), the BSDF is
//! Lambertian `kd/π` plus the normalized modified-Phong lobe ([`crate::brdf`]), `Ke` faces emit
//! uniformly from their front, analytic lights and the constant environment as in
//! [`crate::frame::lights`]. Next-event estimation samples the analytic lights and the area
//! emitters (power heuristic MIS against BSDF sampling); the environment is reached by BSDF
//! sampling; Russian roulette ends long paths. Shading normals (OBJ `vn`) as in the frame
//! ([`crate::frame::shading`]): the interpolated normal gives the BSDF's cosines and lobe, the
//! face normal the front side; light and continued paths must be above both.

use super::sampling::{power_cosine_pdf, sample_power_cosine, sample_triangle, Discrete, Rng};
use crate::brdf::mirror;
use crate::frame::lights::{brdf, incident};
use crate::frame::shading::shading_normal;
use crate::raycast::RayCaster;
use crate::scene::{Light, Material, Scene};
use glam::DVec3;
use std::f64::consts::PI;

/// Radiance carried by one camera path, split by path length.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PathRadiance {
    /// Everything.
    pub total: DVec3,
    /// Paths with at most one reflection: emitters and environment seen directly, and light
    /// that reached the visible point straight from an emitter, light or the environment.
    pub direct: DVec3,
}

/// Bounces after which Russian roulette may end a path.
const ROULETTE_AFTER: u32 = 3;

fn luminance(c: DVec3) -> f64 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// The scene prepared for tracing.
pub struct Tracer {
    caster: RayCaster,
    corners: Vec<[DVec3; 3]>,
    normals: Vec<DVec3>,
    /// Vertex normals of triangles whose mesh has `vn`.
    shading: Vec<Option<[DVec3; 3]>>,
    areas: Vec<f64>,
    material: Vec<u32>,
    materials: Vec<Material>,
    lights: Vec<Light>,
    environment: DVec3,
    /// Emitting triangles and the distribution (∝ area × luminance of Ke) to pick one.
    emitters: Vec<u32>,
    emitter_pick: Discrete,
    /// Emitter slot of each triangle (u32::MAX when it does not emit).
    emitter_slot: Vec<u32>,
    /// Ray-origin offset, relative to the scene's extent (f64 hit points are far more accurate).
    eps: f64,
    max_bounces: Option<u32>,
}

/// The power heuristic (β = 2).
fn mis(a: f64, b: f64) -> f64 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 {
        a2 / (a2 + b2)
    } else {
        0.0
    }
}

impl Tracer {
    /// Prepares `scene`; `max_bounces` limits reflections per path (None: unlimited).
    pub fn new(scene: &Scene, max_bounces: Option<u32>) -> Self {
        let mut corners = Vec::new();
        let mut material = Vec::new();
        let mut shading = Vec::new();
        for m in &scene.meshes {
            for (k, (t, &mi)) in m.triangles.iter().zip(&m.material).enumerate() {
                corners.push(t.map(|i| m.positions[i as usize]));
                material.push(mi);
                shading.push(m.normals.get(k).copied());
            }
        }
        let normals: Vec<DVec3> = corners
            .iter()
            .map(|c| (c[1] - c[0]).cross(c[2] - c[0]).normalize_or_zero())
            .collect();
        let areas: Vec<f64> = corners
            .iter()
            .map(|c| 0.5 * (c[1] - c[0]).cross(c[2] - c[0]).length())
            .collect();
        let mut emitters = Vec::new();
        let mut weights = Vec::new();
        let mut emitter_slot = vec![u32::MAX; corners.len()];
        for (i, &mi) in material.iter().enumerate() {
            let ke = scene.materials[mi as usize].ke;
            let w = areas[i] * luminance(ke).max(ke.max_element() * 1e-3);
            if w > 0.0 {
                emitter_slot[i] = emitters.len() as u32;
                emitters.push(i as u32);
                weights.push(w);
            }
        }
        let (lo, hi) = scene.bounds();
        let extent = if lo.is_finite() && hi.is_finite() {
            (hi - lo).length().max(lo.abs().max(hi.abs()).max_element())
        } else {
            1.0
        };
        Self {
            caster: RayCaster::from_triangles(corners.clone()),
            corners,
            normals,
            shading,
            areas,
            material,
            materials: scene.materials.clone(),
            lights: scene.lights.clone(),
            environment: scene.environment,
            emitters,
            emitter_pick: Discrete::new(&weights),
            emitter_slot,
            eps: 1e-9 * extent.max(f64::MIN_POSITIVE),
            max_bounces,
        }
    }

    fn allowed(&self, bounces: u32) -> bool {
        self.max_bounces.is_none_or(|b| bounces <= b)
    }

    /// Density (solid angle, at `p`) with which next-event estimation picks the direction to
    /// point `q` on emitting triangle `tri`.
    fn light_pdf(&self, tri: usize, p: DVec3, q: DVec3) -> f64 {
        let slot = self.emitter_slot[tri];
        if slot == u32::MAX || self.emitter_pick.is_empty() {
            return 0.0;
        }
        let d = q - p;
        let r2 = d.length_squared();
        let cos_l = (-d / r2.sqrt()).dot(self.normals[tri]);
        if cos_l <= 0.0 {
            return 0.0;
        }
        self.emitter_pick.pmf(slot as usize) / self.areas[tri] * r2 / cos_l
    }

    /// Density of [`Self::sample_bsdf`] for leaving along `wo`, light travelling along `travel`.
    fn bsdf_pdf(&self, mat: &Material, n: DVec3, travel: DVec3, wo: DVec3) -> f64 {
        let cos = -travel.dot(n);
        if cos <= 0.0 || wo.dot(n) <= 0.0 {
            return 0.0;
        }
        let p_d = Self::diffuse_probability(mat);
        let mut pdf = p_d * cos / PI;
        if p_d < 1.0 {
            // Reversibility: the lobe is symmetric in its two directions, so sample around the
            // mirror of the incoming travel direction (reversed).
            pdf += (1.0 - p_d) * power_cosine_pdf(mat.ns, mirror(-wo, n).dot(-travel));
        }
        pdf
    }

    fn diffuse_probability(mat: &Material) -> f64 {
        let (d, s) = (luminance(mat.kd).max(0.0), luminance(mat.ks).max(0.0));
        if d + s > 0.0 {
            d / (d + s)
        } else {
            1.0
        }
    }

    /// The direction `wi` (toward where light comes from) a path continues in from a point with
    /// shading normal `n` and face normal `g` that it reached travelling along `d`; None when
    /// the sample falls below either.
    fn sample_bsdf(
        &self,
        mat: &Material,
        n: DVec3,
        g: DVec3,
        d: DVec3,
        rng: &mut Rng,
    ) -> Option<DVec3> {
        let p_d = Self::diffuse_probability(mat);
        let (u0, u1, u2) = (rng.uniform(), rng.uniform(), rng.uniform());
        let wi = if u0 < p_d {
            sample_power_cosine(n, 1.0, u1, u2)
        } else {
            // Light arriving along wi and leaving toward -d peaks when wi mirrors -d.
            sample_power_cosine(mirror(d, n), mat.ns, u1, u2)
        };
        (wi.dot(n) > 0.0 && wi.dot(g) > 0.0).then_some(wi)
    }

    /// Direct light at `p` (face normal `g`, shading normal `n`, material `mat`, seen from
    /// direction `wo`) from the analytic lights and one sampled area-emitter point, with the MIS
    /// weight for the latter.
    fn next_event(
        &self,
        p: DVec3,
        g: DVec3,
        n: DVec3,
        mat: &Material,
        wo: DVec3,
        rng: &mut Rng,
    ) -> DVec3 {
        let origin = p + g * self.eps;
        let mut l = DVec3::ZERO;
        for light in &self.lights {
            let Some(inc) = incident(light, p) else {
                continue;
            };
            let cos = -inc.travel.dot(n);
            if cos <= 0.0 || inc.travel.dot(g) >= 0.0 {
                continue;
            }
            let dist = match light {
                Light::Directional { .. } => f64::INFINITY,
                Light::Point { position, .. }
                | Light::Spot { position, .. }
                | Light::EmitterSample { position, .. } => (*position - origin).length(),
            };
            if !self.caster.occluded(origin, -inc.travel, 0.0, dist) {
                l += brdf(mat, n, inc.travel, wo) * inc.irradiance * cos;
            }
        }
        if !self.emitter_pick.is_empty() {
            let slot = self.emitter_pick.sample(rng.uniform());
            let tri = self.emitters[slot] as usize;
            let q = sample_triangle(&self.corners[tri], rng.uniform(), rng.uniform());
            let to = q - origin;
            let r = to.length();
            let wi = to / r;
            let cos = wi.dot(n);
            let pdf_light = self.light_pdf(tri, origin, q);
            if cos > 0.0
                && wi.dot(g) > 0.0
                && pdf_light > 0.0
                && !self.caster.occluded(origin, wi, 0.0, r * (1.0 - 1e-9))
            {
                let ke = self.materials[self.material[tri] as usize].ke;
                let f = brdf(mat, n, -wi, wo);
                let w = mis(pdf_light, self.bsdf_pdf(mat, n, -wi, wo));
                l += f * ke * (cos * w / pdf_light);
            }
        }
        l
    }

    /// Radiance arriving at `o` from direction `-d` (d: unit travel direction of the camera ray).
    pub fn radiance(&self, o: DVec3, d: DVec3, rng: &mut Rng) -> PathRadiance {
        let mut out = PathRadiance::default();
        let mut add = |bounces: u32, v: DVec3| {
            out.total += v;
            if bounces <= 1 {
                out.direct += v;
            }
        };
        let (mut o, mut d) = (o, d);
        let mut beta = DVec3::ONE;
        // Density of the BSDF sample that produced `d` (None for the camera ray), and where.
        let mut prev: Option<(f64, DVec3)> = None;
        let mut bounces = 0u32;
        loop {
            let Some(hit) = self.caster.closest(o, d, 0.0, f64::INFINITY) else {
                add(bounces, beta * self.environment);
                break;
            };
            let tri = hit.leaf as usize;
            let g = self.normals[tri];
            let wo = -d;
            if wo.dot(g) <= 0.0 {
                break; // back faces are black
            }
            let n = match &self.shading[tri] {
                Some(c) => shading_normal(
                    c[0] * (1.0 - hit.u - hit.v) + c[1] * hit.u + c[2] * hit.v,
                    g,
                    wo,
                ),
                None => g,
            };
            let mat = &self.materials[self.material[tri] as usize];
            let c = &self.corners[tri];
            let p = c[0] * (1.0 - hit.u - hit.v) + c[1] * hit.u + c[2] * hit.v;
            if mat.is_emitter() {
                let w = match prev {
                    None => 1.0,
                    Some((pdf_bsdf, from)) => mis(pdf_bsdf, self.light_pdf(tri, from, p)),
                };
                add(bounces, beta * mat.ke * w);
            }
            bounces += 1;
            if !self.allowed(bounces) {
                break;
            }
            add(bounces, beta * self.next_event(p, g, n, mat, wo, rng));
            // The path goes on even at the bounce limit: emitters and the environment it reaches
            // next still count `bounces` reflections.
            let Some(wi) = self.sample_bsdf(mat, n, g, d, rng) else {
                break;
            };
            let pdf = self.bsdf_pdf(mat, n, -wi, wo);
            if pdf <= 0.0 {
                break;
            }
            beta *= brdf(mat, n, -wi, wo) * (wi.dot(n) / pdf);
            if bounces >= ROULETTE_AFTER {
                let q = beta.max_element().min(0.95);
                if q <= 0.0 || rng.uniform() >= q {
                    break;
                }
                beta /= q;
            }
            if beta.max_element() <= 0.0 {
                break;
            }
            prev = Some((pdf, p + g * self.eps));
            o = p + g * self.eps;
            d = wi;
        }
        out
    }
}
