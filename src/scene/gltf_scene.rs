//! glTF 2.0 (`.gltf`, `.glb`) with the `gltf` crate: triangle meshes under the node hierarchy,
//! metallic-roughness materials mapped onto the Lambert + Phong model, emission,
//! `KHR_lights_punctual` and the first perspective camera. Every accessor is checked against its
//! buffer before it is read, so a malformed file is an error naming the file and the part, not a
//! panic. The mappings are stated in the README ("glTF 2.0").

use super::format::MaterialOverride;
use super::load::{color, mesh_err, scene_err, source};
use super::{Camera, Light, Material, Mesh, Scene, MAX_COORDINATE, MAX_SOURCE};
use crate::error::Result;
use base64::Engine as _;
use glam::{DMat3, DMat4, DVec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Lumens per watt (the photopic peak, 555 nm): `KHR_lights_punctual`'s candela and lux over
/// this are the project's W/sr and W/m² (the factor Blender's exporter uses).
pub const LUMENS_PER_WATT: f64 = 683.0;

/// Normal-incidence reflectance of glTF's dielectric (IOR 1.5), the Phong lobe's `ks` of a
/// non-metal.
pub const DIELECTRIC_F0: f64 = 0.04;

/// Largest Phong exponent a roughness maps to: a narrower lobe than 128–256 bins resolve
/// (the same cap as the Mitsuba mapping's).
pub const MAX_PHONG_EXPONENT: f64 = 200.0;

/// The extensions read; any other a file uses is named in one warning.
const SUPPORTED: [&str; 2] = ["KHR_lights_punctual", "KHR_materials_emissive_strength"];

/// The Phong exponent of a microfacet roughness α (Beckmann/GGX width): `2/α² − 2`, at most
/// [`MAX_PHONG_EXPONENT`] (Walter et al.'s correspondence, as in the Mitsuba mapping).
pub fn phong_exponent(alpha: f64) -> f64 {
    if alpha > 0.0 {
        (2.0 / (alpha * alpha) - 2.0).clamp(0.0, MAX_PHONG_EXPONENT)
    } else {
        MAX_PHONG_EXPONENT
    }
}

/// A glTF material as Lambert + Phong: `kd = (1 − metallic)(1 − 0.04)·baseColor`,
/// `ks = (1 − metallic)·0.04 + metallic·baseColor`, `ns` from α = roughness²
/// ([`phong_exponent`]), `ke = emissiveFactor × emissiveStrength`.
pub fn map_material(
    name: &str,
    base: [f32; 4],
    metallic: f32,
    roughness: f32,
    emissive: [f32; 3],
    strength: f32,
) -> Material {
    let b = DVec3::new(base[0] as f64, base[1] as f64, base[2] as f64);
    let m = (metallic as f64).clamp(0.0, 1.0);
    let r = (roughness as f64).clamp(0.0, 1.0);
    Material {
        name: name.into(),
        kd: b * (1.0 - m) * (1.0 - DIELECTRIC_F0),
        ks: DVec3::splat(DIELECTRIC_F0 * (1.0 - m)) + b * m,
        ns: phong_exponent(r * r),
        ke: DVec3::new(emissive[0] as f64, emissive[1] as f64, emissive[2] as f64)
            * strength as f64,
    }
}

/// Where a glTF file goes: as an `[[object]]`'s mesh (its transform and material overrides) or
/// as a whole scene (identity, none).
pub struct Placement<'a> {
    /// The scene file, for messages about overrides.
    pub scene_path: &'a Path,
    /// The field the overrides are under (`object[3].materials`).
    pub field: String,
    /// Applied after the node hierarchy.
    pub transform: DMat4,
    /// Material overrides by name.
    pub overrides: &'a BTreeMap<String, MaterialOverride>,
}

/// What a glTF file brought besides its meshes and materials.
pub struct Loaded {
    /// The first perspective camera in node order, placed.
    pub camera: Option<Camera>,
    /// How many lights it added.
    pub lights: usize,
}

/// Reads the glTF file `path` (its bytes given) into `scene`: meshes, materials, lights.
pub fn load_gltf(
    scene: &mut Scene,
    path: &Path,
    bytes: &[u8],
    place: &Placement,
    warned: &mut BTreeSet<String>,
) -> Result<Loaded> {
    let shown = path.display().to_string();
    let g = parse(bytes).map_err(|e| mesh_err(path, format!("not a valid glTF 2.0 file: {e}")))?;
    let ignored: Vec<&str> = g
        .extensions_used()
        .filter(|e| !SUPPORTED.contains(e))
        .collect();
    if !ignored.is_empty() {
        warned.insert(format!(
            "{shown}: extensions ignored: {}",
            ignored.join(", ")
        ));
    }
    let buffers = read_buffers(&g, path)?;
    for name in place.overrides.keys() {
        if !g.materials().any(|m| material_name(&m) == *name) {
            return Err(scene_err(
                place.scene_path,
                format!(
                    "`{}.{name}`: no material of that name in {shown}",
                    place.field
                ),
            ));
        }
    }
    // The spec's nodes form trees: a node shared by two parents would be walked once per path
    // (exponentially many in a crafted file).
    let mut parents = vec![0usize; g.nodes().count()];
    for c in g.nodes().flat_map(|n| n.children()) {
        parents[c.index()] += 1;
        if parents[c.index()] > 1 {
            return Err(mesh_err(
                path,
                format!("nodes[{}] is the child of more than one node", c.index()),
            ));
        }
    }
    let roots: Vec<gltf::Node> = match g.default_scene().or_else(|| g.scenes().next()) {
        Some(s) => s.nodes().collect(),
        None => {
            let children: BTreeSet<usize> = g
                .nodes()
                .flat_map(|n| n.children().map(|c| c.index()))
                .collect();
            g.nodes().filter(|n| !children.contains(&n.index())).collect()
        }
    };
    let mut st = State {
        path,
        shown: &shown,
        place,
        buffers: &buffers,
        materials: BTreeMap::new(),
        camera: None,
        lights: 0,
        skipped: BTreeMap::new(),
        zero_area: (0, None),
        bad_normals: 0,
        notes: BTreeSet::new(),
        triangles: 0,
    };
    let node_count = g.nodes().count();
    let mut stack: Vec<(gltf::Node, DMat4, usize)> =
        roots.into_iter().rev().map(|n| (n, DMat4::IDENTITY, 0)).collect();
    while let Some((node, parent, depth)) = stack.pop() {
        if depth > node_count {
            return Err(mesh_err(
                path,
                format!("nodes[{}]: the node hierarchy has a cycle", node.index()),
            ));
        }
        let local = DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
        let world = parent * local;
        if !world.is_finite() {
            return Err(mesh_err(
                path,
                format!("nodes[{}]: its transform is not finite", node.index()),
            ));
        }
        if let Some(mesh) = node.mesh() {
            st.mesh(scene, &node, &mesh, world, warned)?;
        }
        if let Some(light) = node.light() {
            let l = st.light(&light, place.transform * world)?;
            scene.lights.push(l);
            st.lights += 1;
        }
        if let Some(cam) = node.camera() {
            st.camera(&cam, place.transform * world);
        }
        for c in node.children().collect::<Vec<_>>().into_iter().rev() {
            stack.push((c, world, depth + 1));
        }
    }
    st.finish(warned)?;
    Ok(Loaded {
        camera: st.camera,
        lights: st.lights,
    })
}

/// The document and its binary chunk, validated by the crate's rules but for POSITION's
/// `min`/`max`, which other loaders do not require either. The crate's validation indexes the
/// POSITION accessor without a check, so that index is checked first.
fn parse(bytes: &[u8]) -> std::result::Result<gltf::Gltf, String> {
    use gltf::json::validation::{Checked, Validate};
    let g = gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| e.to_string())?;
    let root = g.document.as_json();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let pos = prim
                .attributes
                .get(&Checked::Valid(gltf::json::mesh::Semantic::Positions));
            if let Some(i) = pos.filter(|i| i.value() >= root.accessors.len()) {
                return Err(format!(
                    "meshes[{m}].primitives[{p}].attributes.POSITION: accessor {} does not exist ({} accessors)",
                    i.value(),
                    root.accessors.len()
                ));
            }
        }
    }
    let mut errors = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, error| {
        let path = path().as_str().to_string();
        let optional = matches!(error, gltf::json::validation::Error::Missing)
            && path.contains("\"POSITION\"]")
            && (path.ends_with(".min") || path.ends_with(".max"));
        if !optional {
            errors.push(format!("{path}: {error}"));
        }
    });
    if errors.is_empty() {
        Ok(g)
    } else {
        let more = errors.len().saturating_sub(3);
        errors.truncate(3);
        Err(format!(
            "{}{}",
            errors.join("; "),
            if more > 0 { format!(" (and {more} more)") } else { String::new() }
        ))
    }
}

/// The name a material goes by (for overrides and in the scene).
fn material_name(m: &gltf::Material) -> String {
    match (m.name(), m.index()) {
        (Some(n), _) if !n.trim().is_empty() => n.trim().to_string(),
        (_, Some(i)) => format!("material{i}"),
        _ => super::object::DEFAULT_MATERIAL.to_string(),
    }
}

/// Every buffer's bytes: the GLB's binary chunk, a `data:` URI or a file beside `path`.
fn read_buffers(g: &gltf::Gltf, path: &Path) -> Result<Vec<Vec<u8>>> {
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut out = Vec::new();
    for b in g.buffers() {
        let i = b.index();
        let data = match b.source() {
            gltf::buffer::Source::Bin => g.blob.clone().ok_or_else(|| {
                mesh_err(
                    path,
                    format!("buffers[{i}] is the binary chunk, which the file does not have"),
                )
            })?,
            gltf::buffer::Source::Uri(uri) => {
                if let Some(rest) = uri.strip_prefix("data:") {
                    let (_, data) = rest.split_once(";base64,").ok_or_else(|| {
                        mesh_err(path, format!("buffers[{i}]: a data URI that is not base64"))
                    })?;
                    base64::engine::general_purpose::STANDARD
                        .decode(data)
                        .map_err(|e| mesh_err(path, format!("buffers[{i}]: bad base64: {e}")))?
                } else {
                    let file = dir.join(percent_decode(uri));
                    super::files::read_bytes(&file).map_err(|p| {
                        mesh_err(
                            path,
                            format!("buffers[{i}]: its file {} {p}", file.display()),
                        )
                    })?
                }
            }
        };
        if data.len() < b.length() {
            return Err(mesh_err(
                path,
                format!(
                    "buffers[{i}] holds {} bytes, fewer than its byteLength {} (truncated?)",
                    data.len(),
                    b.length()
                ),
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// `%20` and the like in a relative URI.
fn percent_decode(uri: &str) -> String {
    let b = uri.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Checks that `acc` has the type asked for and lies inside its buffer view and buffer (and so
/// its sparse parts), so that the reader cannot fail halfway or overrun.
fn check_accessor(
    acc: &gltf::Accessor,
    what: &str,
    dims: Dimensions,
    types: &[DataType],
    buffers: &[Vec<u8>],
) -> std::result::Result<(), String> {
    let i = acc.index();
    if acc.dimensions() != dims || !types.contains(&acc.data_type()) {
        return Err(format!(
            "accessors[{i}] ({what}) is {:?} {:?}; {what} must be {dims:?} of {types:?}",
            acc.dimensions(),
            acc.data_type()
        ));
    }
    if acc.count() == 0 {
        return Err(format!("accessors[{i}] ({what}) has count 0"));
    }
    let size = acc.size();
    let in_view = |view: &gltf::buffer::View, offset: usize, count: usize, size: usize| {
        let stride = view.stride().unwrap_or(size);
        let buffer_len = buffers.get(view.buffer().index()).map_or(0, Vec::len);
        let view_end = view.offset().checked_add(view.length());
        let end = stride
            .checked_mul(count - 1)
            .and_then(|s| s.checked_add(offset))
            .and_then(|s| s.checked_add(size));
        match (view_end, end) {
            (Some(ve), Some(e)) if stride >= size && ve <= buffer_len && e <= view.length() => {
                Ok(())
            }
            _ => Err(format!(
                "accessors[{i}] ({what}) reaches past bufferViews[{}] or its buffer",
                view.index()
            )),
        }
    };
    match acc.view() {
        Some(v) => in_view(&v, acc.offset(), acc.count(), size)?,
        None if acc.sparse().is_none() => {
            return Err(format!("accessors[{i}] ({what}) has no bufferView"))
        }
        None => {}
    }
    if let Some(s) = acc.sparse() {
        if s.count() == 0 || s.count() > acc.count() {
            return Err(format!("accessors[{i}] ({what}): sparse count {}", s.count()));
        }
        let idx = s.indices();
        in_view(&idx.view(), idx.offset(), s.count(), idx.index_type().size())?;
        let val = s.values();
        in_view(&val.view(), val.offset(), s.count(), size)?;
    }
    Ok(())
}

/// What the traversal has gathered.
struct State<'a> {
    path: &'a Path,
    shown: &'a str,
    place: &'a Placement<'a>,
    buffers: &'a [Vec<u8>],
    /// glTF material index (None: the default) → scene material.
    materials: BTreeMap<Option<usize>, u32>,
    camera: Option<Camera>,
    lights: usize,
    /// Primitive modes skipped (points, lines) and how many.
    skipped: BTreeMap<&'static str, usize>,
    zero_area: (usize, Option<String>),
    bad_normals: usize,
    /// Material features ignored, for one warning per file.
    notes: BTreeSet<&'static str>,
    triangles: usize,
}

impl State<'_> {
    fn err(&self, m: String) -> crate::error::Error {
        mesh_err(self.path, m)
    }

    /// The scene material of a primitive's material, made on first use.
    fn material(&mut self, scene: &mut Scene, m: gltf::Material) -> Result<u32> {
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
                if m.double_sided() {
                    self.notes.insert("doubleSided (surfaces are one-sided: the counter-clockwise front)");
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
                    return Err(scene_err(sp, format!("`{}` must be finite and >= 0", f("ns"))));
                }
                mat.ns = n;
            }
        }
        for (v, what) in [(mat.kd, "baseColorFactor"), (mat.ks, "baseColorFactor"), (mat.ke, "emissive")] {
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
                super::load::SOURCE_LIMIT_REASON
            )));
        }
        scene.materials.push(mat);
        let k = (scene.materials.len() - 1) as u32;
        self.materials.insert(m.index(), k);
        Ok(k)
    }

    /// Appends one scene mesh per primitive of `mesh` placed by `world` (then the placement).
    fn mesh(
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
            check_accessor(&pos, "POSITION", Dimensions::Vec3, &[DataType::F32], buffers)
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
                    self.zero_area.1.get_or_insert_with(|| format!("{at} triangle {t}"));
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
        }
        Ok(())
    }

    /// A `KHR_lights_punctual` light placed by `m`, its photometric units in watts.
    fn light(&self, l: &gltf::khr_lights_punctual::Light, m: DMat4) -> Result<Light> {
        use gltf::khr_lights_punctual::Kind;
        let at = format!("KHR_lights_punctual light {}", l.index());
        let c = l.color();
        let value =
            DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) * l.intensity() as f64 / LUMENS_PER_WATT;
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
    fn camera(&mut self, cam: &gltf::Camera, m: DMat4) {
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
        });
    }

    /// The file's warnings, one line each; refuses a file with no triangles.
    fn finish(&self, warned: &mut BTreeSet<String>) -> Result<()> {
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
fn triangulate(mode: Mode, idx: &[u32]) -> Vec<[u32; 3]> {
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
        _ => idx
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metallic_roughness_maps_onto_lambert_phong() {
        let d = map_material("d", [0.8, 0.5, 0.2, 1.0], 0.0, 1.0, [0.0; 3], 1.0);
        assert!((d.kd - DVec3::new(0.768, 0.48, 0.192)).abs().max_element() < 1e-6);
        assert_eq!(d.ks, DVec3::splat(0.04));
        assert_eq!(d.ns, 0.0);
        let m = map_material("m", [0.9, 0.6, 0.3, 1.0], 1.0, 0.5, [0.1, 0.5, 0.9], 4.0);
        assert_eq!(m.kd, DVec3::ZERO);
        assert!((m.ks - DVec3::new(0.9, 0.6, 0.3)).abs().max_element() < 1e-6);
        // α = 0.25, 2/α² − 2 = 30.
        assert!((m.ns - 30.0).abs() < 1e-9);
        assert!((m.ke - DVec3::new(0.4, 2.0, 3.6)).abs().max_element() < 1e-6);
        assert_eq!(phong_exponent(0.01), MAX_PHONG_EXPONENT);
    }

    #[test]
    fn strips_and_fans_keep_the_winding() {
        assert_eq!(
            triangulate(Mode::TriangleStrip, &[0, 1, 2, 3]),
            vec![[0, 1, 2], [2, 1, 3]]
        );
        assert_eq!(
            triangulate(Mode::TriangleFan, &[0, 1, 2, 3]),
            vec![[1, 2, 0], [2, 3, 0]]
        );
        assert_eq!(percent_decode("a%20b.bin"), "a b.bin");
        assert_eq!(percent_decode("100%"), "100%");
    }
}
