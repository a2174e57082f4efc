//! The node traversal's gathering: a primitive's triangles placed, its material mapped and
//! overridden, a light converted, the first perspective camera kept.

use super::buffers::check_accessor;
use super::{map_material, material_name, Placement, LUMENS_PER_WATT};
use crate::error::Result;
use crate::scene::load::{color, mesh_err, scene_err, source};
use crate::scene::{Camera, Light, Material, Mesh, Scene, MAX_COORDINATE, MAX_SOURCE};
use glam::{DMat3, DMat4, DVec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// What the traversal has gathered.
pub(super) struct State<'a> {
    pub(super) path: &'a Path,
    pub(super) shown: &'a str,
    pub(super) place: &'a Placement<'a>,
    pub(super) buffers: &'a [Vec<u8>],
    /// glTF material index (None: the default) → scene material.
    pub(super) materials: BTreeMap<Option<usize>, u32>,
    pub(super) camera: Option<Camera>,
    pub(super) lights: usize,
    /// Primitive modes skipped (points, lines) and how many.
    pub(super) skipped: BTreeMap<&'static str, usize>,
    pub(super) zero_area: (usize, Option<String>),
    pub(super) bad_normals: usize,
    /// Material features ignored, for one warning per file.
    pub(super) notes: BTreeSet<&'static str>,
    pub(super) triangles: usize,
}

impl State<'_> {
    pub(super) fn err(&self, m: String) -> crate::error::Error {
        mesh_err(self.path, m)
    }

    /// The scene material of a primitive's material, made on first use.
    pub(super) fn material(&mut self, scene: &mut Scene, m: gltf::Material) -> Result<u32> {
        if let Some(&k) = self.materials.get(&m.index()) {
            return Ok(k);
        }
        let name = material_name(&m);
        let mut mat = match m.index() {
            None => {
                self.notes.insert("primitives without a material get the grey diffuse material (Kd 0.5), as OBJ faces without usemtl");
                Material::diffuse(&name, 0.5)
            }
            Some(_) => {
                let pbr = m.pbr_metallic_roughness();
                if pbr.base_color_texture().is_some()
                    || pbr.metallic_roughness_texture().is_some()
                    || m.normal_texture().is_some()
                    || m.occlusion_texture().is_some()
                    || m.emissive_texture().is_some()
                {
                    self.notes.insert("textures (their factors are used)");
                }
                if m.alpha_mode() != gltf::material::AlphaMode::Opaque {
                    self.notes.insert("alpha (treated as opaque)");
                }
                map_material(
                    &name,
                    pbr.base_color_factor(),
                    pbr.metallic_factor(),
                    pbr.roughness_factor(),
                    m.emissive_factor(),
                    m.emissive_strength().unwrap_or(1.0),
                )
            }
        };
        if let Some(ov) = self.place.overrides.get(&name) {
            let f = |k: &str| format!("{}.{name}.{k}", self.place.field);
            let sp = self.place.scene_path;
            if let Some(c) = ov.kd {
                mat.kd = color(c, &f("kd"), sp)?;
            }
            if let Some(c) = ov.ks {
                mat.ks = color(c, &f("ks"), sp)?;
            }
            if let Some(c) = ov.ke {
                mat.ke = source(c, &f("ke"), sp)?;
            }
            if let Some(n) = ov.ns {
                if !(n.is_finite() && n >= 0.0) {
                    return Err(scene_err(
                        sp,
                        format!("`{}` must be finite and >= 0", f("ns")),
                    ));
                }
                mat.ns = n;
            }
        }
        for (v, what) in [
            (mat.kd, "baseColorFactor"),
            (mat.ks, "baseColorFactor"),
            (mat.ke, "emissive"),
        ] {
            if !(v.is_finite() && v.min_element() >= 0.0) {
                return Err(self.err(format!(
                    "material {name}: {what} must be finite and non-negative"
                )));
            }
        }
        if mat.ke.max_element() > MAX_SOURCE {
            return Err(self.err(format!(
                "material {name}: emission {:?} exceeds {MAX_SOURCE:e}: {}",
                mat.ke.max_element(),
                crate::scene::load::SOURCE_LIMIT_REASON
            )));
        }
        scene.materials.push(mat);
        let k = (scene.materials.len() - 1) as u32;
        self.materials.insert(m.index(), k);
        Ok(k)
    }

    /// Appends one scene mesh per primitive of `mesh` placed by `world` (then the placement).
    pub(super) fn mesh(
        &mut self,
        scene: &mut Scene,
        node: &gltf::Node,
        mesh: &gltf::Mesh,
        world: DMat4,
        _warned: &mut BTreeSet<String>,
    ) -> Result<()> {
        let m = self.place.transform * world;
        let outer = DMat3::from_mat4(self.place.transform).determinant();
        let lin = DMat3::from_mat4(m);
        let det_node = DMat3::from_mat4(world).determinant();
        if !(lin.determinant().abs() > 0.0) {
            return Err(self.err(format!(
                "nodes[{}]: its transform is singular (a zero scale)",
                node.index()
            )));
        }
        // glTF turns the winding round under a mirroring node; the scene's own transform turns
        // the front round as an OBJ object's does (object.rs), so the normals go with it.
        let flip = det_node < 0.0;
        let normal_matrix = lin.inverse().transpose() * outer.signum();
        let buffers = self.buffers;
        for prim in mesh.primitives() {
            let at = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
            let mode = prim.mode();
            let kind = match mode {
                Mode::Points => Some("points"),
                Mode::Lines | Mode::LineLoop | Mode::LineStrip => Some("lines"),
                _ => None,
            };
            if let Some(k) = kind {
                *self.skipped.entry(k).or_default() += 1;
                continue;
            }
            let pos = prim
                .get(&gltf::Semantic::Positions)
                .ok_or_else(|| self.err(format!("{at}: no POSITION attribute")))?;
            check_accessor(
                &pos,
                "POSITION",
                Dimensions::Vec3,
                &[DataType::F32],
                buffers,
            )
            .map_err(|e| self.err(format!("{at}: {e}")))?;
            let normals_acc = prim.get(&gltf::Semantic::Normals);
            if let Some(n) = &normals_acc {
                check_accessor(n, "NORMAL", Dimensions::Vec3, &[DataType::F32], buffers)
                    .map_err(|e| self.err(format!("{at}: {e}")))?;
                if n.count() != pos.count() {
                    return Err(self.err(format!(
                        "{at}: NORMAL has {} entries, POSITION {}",
                        n.count(),
                        pos.count()
                    )));
                }
            }
            if let Some(ind) = prim.indices() {
                check_accessor(
                    &ind,
                    "indices",
                    Dimensions::Scalar,
                    &[DataType::U8, DataType::U16, DataType::U32],
                    buffers,
                )
                .map_err(|e| self.err(format!("{at}: {e}")))?;
            }
            let reader = prim.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
            let unreadable = |what: &str| self.err(format!("{at}: its {what} cannot be read"));
            let local: Vec<[f32; 3]> = reader
                .read_positions()
                .ok_or_else(|| unreadable("POSITION"))?
                .collect();
            let n = local.len();
            let indices: Vec<u32> = match reader.read_indices() {
                Some(i) => i.into_u32().collect(),
                None if prim.indices().is_some() => return Err(unreadable("indices")),
                None => (0..n as u32).collect(),
            };
            if let Some(&bad) = indices.iter().find(|&&i| i as usize >= n) {
                return Err(self.err(format!(
                    "{at}: index {bad} is out of range (POSITION has {n} vertices)"
                )));
            }
            let vn: Option<Vec<[f32; 3]>> = match normals_acc {
                Some(_) => Some(
                    reader
                        .read_normals()
                        .ok_or_else(|| unreadable("NORMAL"))?
                        .collect(),
                ),
                None => None,
            };
            let corners = triangulate(mode, &indices);
            let positions: Vec<DVec3> = local
                .iter()
                .map(|p| m.transform_point3(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)))
                .collect();
            if let Some(p) = positions
                .iter()
                .find(|p| !(p.is_finite() && p.abs().max_element() <= MAX_COORDINATE))
            {
                return Err(self.err(format!(
                    "{at}: a vertex is placed at {:?}, beyond ±{MAX_COORDINATE:e} (the largest coordinate magnitude float32 tables handle)",
                    p.to_array()
                )));
            }
            let material = self.material(scene, prim.material())?;
            let mut triangles = Vec::with_capacity(corners.len());
            let mut normals = Vec::new();
            for (t, tri) in corners.into_iter().enumerate() {
                let tri = if flip { [tri[0], tri[2], tri[1]] } else { tri };
                let [a, b, c] = tri.map(|v| positions[v as usize]);
                let longest = (b - a).length().max((c - b).length()).max((a - c).length());
                let cross = (b - a).cross(c - a);
                if !(cross.length() > 1e-9 * longest * longest) {
                    self.zero_area.0 += 1;
                    self.zero_area
                        .1
                        .get_or_insert_with(|| format!("{at} triangle {t}"));
                    continue;
                }
                triangles.push(tri);
                if let Some(vn) = &vn {
                    let face = cross.normalize();
                    let placed = tri.map(|v| {
                        let [x, y, z] = vn[v as usize];
                        normal_matrix * DVec3::new(x as f64, y as f64, z as f64)
                    });
                    let usable = |n: &DVec3| {
                        let len = n.length();
                        len.is_finite() && len > 0.0 && n.dot(face) >= 0.0
                    };
                    normals.push(if placed.iter().all(usable) {
                        placed.map(DVec3::normalize)
                    } else {
                        self.bad_normals += 1;
                        [face; 3]
                    });
                }
            }
            if triangles.is_empty() {
                continue;
            }
            self.triangles += triangles.len();
            let count = triangles.len();
            scene.meshes.push(Mesh {
                name: node
                    .name()
                    .or(mesh.name())
                    .map_or_else(|| format!("mesh{}", mesh.index()), str::to_string),
                source: self.path.to_path_buf(),
                positions,
                triangles,
                material: vec![material; count],
                normals,
            });
            // A doubleSided material is lit from both sides: its back-to-back twin.
            if prim.material().double_sided() {
                let k = scene.meshes.len();
                crate::scene::add_twins(scene, k - 1..k);
            }
        }
        Ok(())
    }

    /// A `KHR_lights_punctual` light placed by `m`, its photometric units in watts.
    pub(super) fn light(&self, l: &gltf::khr_lights_punctual::Light, m: DMat4) -> Result<Light> {
        use gltf::khr_lights_punctual::Kind;
        let at = format!("KHR_lights_punctual light {}", l.index());
        let c = l.color();
        let value = DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) * l.intensity() as f64
            / LUMENS_PER_WATT;
        if !(value.is_finite() && value.min_element() >= 0.0 && value.max_element() <= MAX_SOURCE) {
            return Err(self.err(format!(
                "{at}: color × intensity / {LUMENS_PER_WATT} = {:?} must be finite, non-negative and at most {MAX_SOURCE:e}",
                value.to_array()
            )));
        }
        let position = m.transform_point3(DVec3::ZERO);
        let axis = m.transform_vector3(DVec3::NEG_Z).normalize_or_zero();
        if axis == DVec3::ZERO && !matches!(l.kind(), Kind::Point) {
            return Err(self.err(format!("{at}: its node's transform has no direction")));
        }
        Ok(match l.kind() {
            Kind::Directional => Light::Directional {
                direction: axis,
                irradiance: value,
            },
            Kind::Point => Light::Point {
                position,
                intensity: value,
            },
            Kind::Spot {
                inner_cone_angle,
                outer_cone_angle,
            } => {
                let outer = (outer_cone_angle as f64).clamp(1e-6, std::f64::consts::FRAC_PI_2);
                Light::Spot {
                    position,
                    axis,
                    intensity: value,
                    cutoff: outer,
                    beam_width: (inner_cone_angle as f64).clamp(0.0, outer),
                }
            }
        })
    }

    /// Keeps the first perspective camera (looking down its node's −Z, up +Y).
    pub(super) fn camera(&mut self, cam: &gltf::Camera, m: DMat4) {
        if self.camera.is_some() {
            return;
        }
        let gltf::camera::Projection::Perspective(p) = cam.projection() else {
            self.notes.insert("orthographic cameras");
            return;
        };
        let eye = m.transform_point3(DVec3::ZERO);
        let forward = m.transform_vector3(DVec3::NEG_Z).normalize_or_zero();
        let up = m.transform_vector3(DVec3::Y).normalize_or_zero();
        let fov = (p.yfov() as f64).to_degrees();
        if forward == DVec3::ZERO || up == DVec3::ZERO || !(fov > 0.0 && fov < 180.0) {
            return;
        }
        let aspect = p.aspect_ratio().map_or(1.0, |a| a as f64);
        let width = 512u32;
        let height = if aspect.is_finite() && aspect > 0.0 {
            ((width as f64 / aspect).round() as u32).clamp(1, 16384)
        } else {
            width
        };
        self.camera = Some(Camera {
            eye,
            target: eye + forward,
            up,
            fov_y_deg: fov,
            width,
            height,
            supersample: 1,
            jitter: [0.0; 2],
            passes: 1,
            fov_axis: Default::default(),
        });
    }

    /// The file's warnings, one line each; refuses a file with no triangles.
    pub(super) fn finish(&self, warned: &mut BTreeSet<String>) -> Result<()> {
        let shown = self.shown;
        if !self.skipped.is_empty() {
            let what: Vec<String> = self
                .skipped
                .iter()
                .map(|(k, n)| format!("{n} {k} primitive{}", if *n == 1 { "" } else { "s" }))
                .collect();
            warned.insert(format!(
                "{shown}: {} skipped: they are not surfaces",
                what.join(" and ")
            ));
        }
        if self.triangles == 0 {
            return Err(self.err(if self.skipped.is_empty() {
                "no triangles: the file has no mesh with a triangle primitive in its scene".into()
            } else {
                "no triangles: its primitives are points or lines only".into()
            }));
        }
        if let (n, Some(first)) = (self.zero_area.0, &self.zero_area.1) {
            warned.insert(format!(
                "{shown}: {n} degenerate (zero-area) {} dropped (first: {first})",
                if n == 1 { "triangle" } else { "triangles" }
            ));
        }
        if self.bad_normals > 0 {
            warned.insert(format!(
                "{shown}: {} unusable NORMALs (zero, not finite, or facing away from the face): shaded with the face normal",
                match self.bad_normals {
                    1 => "1 triangle has".to_string(),
                    n => format!("{n} triangles have"),
                }
            ));
        }
        if !self.notes.is_empty() {
            warned.insert(format!(
                "{shown}: ignored: {}",
                self.notes.iter().copied().collect::<Vec<_>>().join("; ")
            ));
        }
        Ok(())
    }
}

/// Triangles of a triangle list, strip or fan (the glTF spec's orders).
pub(super) fn triangulate(mode: Mode, idx: &[u32]) -> Vec<[u32; 3]> {
    match mode {
        Mode::TriangleStrip => (2..idx.len())
            .map(|i| {
                if i % 2 == 0 {
                    [idx[i - 2], idx[i - 1], idx[i]]
                } else {
                    [idx[i - 1], idx[i - 2], idx[i]]
                }
            })
            .collect(),
        Mode::TriangleFan => (2..idx.len())
            .map(|i| [idx[i - 1], idx[i], idx[0]])
            .collect(),
        _ => idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
    }
}
