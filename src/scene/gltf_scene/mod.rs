//! glTF 2.0 (`.gltf`, `.glb`) with the `gltf` crate: triangle meshes under the node hierarchy,
//! metallic-roughness materials mapped onto the Lambert + Phong model, emission,
//! `KHR_lights_punctual` and the first perspective camera. Every accessor is checked against its
//! buffer before it is read, so a malformed file is an error naming the file and the part, not a
//! panic. The mappings are stated in the README ("glTF 2.0").

mod buffers;
mod state;

use super::format::MaterialOverride;
use super::load::{mesh_err, scene_err};
use super::{Camera, Material, Scene};
use crate::error::Result;
use buffers::{parse, read_buffers};
use glam::{DMat4, DVec3};
use state::State;
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
            g.nodes()
                .filter(|n| !children.contains(&n.index()))
                .collect()
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
    let mut stack: Vec<(gltf::Node, DMat4, usize)> = roots
        .into_iter()
        .rev()
        .map(|n| (n, DMat4::IDENTITY, 0))
        .collect();
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

/// The name a material goes by (for overrides and in the scene).
fn material_name(m: &gltf::Material) -> String {
    match (m.name(), m.index()) {
        (Some(n), _) if !n.trim().is_empty() => n.trim().to_string(),
        (_, Some(i)) => format!("material{i}"),
        _ => super::object::DEFAULT_MATERIAL.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::buffers::percent_decode;
    use super::state::triangulate;
    use super::*;
    use gltf::mesh::Mode;

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
