//! Pure CPU packing: everything the GPU solver and frame upload, laid out as the shaders read it
//! (texel formats, table layout, `#[repr(C)]` records of [`super::layout`]). No Vulkan calls, so
//! every function is unit-tested without a device.

use super::layout::{
    CornerVertex, GpuAdjEntry, GpuFrameElement, GpuLight, GpuMaterial, GpuShadowView,
};
use super::tables::TableLayout;
use crate::frame::shadow::ShadowMaps;
use crate::frame::surfaces::Surfaces;
use crate::scene::{Light, Scene};
use crate::system::System;
use ash::vk;
use glam::{DMat4, DVec3};
use half::f16;

/// `CornerVertex::leaf` bit of crack-filling input triangles (`AR_FILLER` in gbuffer.vert).
pub const FILLER: u32 = 0x8000_0000;

/// Encodes RGBA f32 texels in `format` (float16 or float32).
pub fn encode(format: vk::Format, texels: &[[f32; 4]]) -> Vec<u8> {
    // Sized once and filled texel by texel: tables run to millions of texels.
    if format == vk::Format::R16G16B16A16_SFLOAT {
        let mut out = Vec::with_capacity(texels.len() * 8);
        for t in texels {
            for &x in t {
                out.extend_from_slice(&f16::from_f32(x).to_bits().to_le_bytes());
            }
        }
        out
    } else {
        let mut out = Vec::with_capacity(texels.len() * 16);
        for t in texels {
            for &x in t {
                out.extend_from_slice(&x.to_le_bytes());
            }
        }
        out
    }
}

/// Decodes RGBA texels of `format` (float16 or float32) to f32.
pub fn decode(format: vk::Format, bytes: &[u8]) -> Vec<[f32; 4]> {
    if format == vk::Format::R16G16B16A16_SFLOAT {
        bytes
            .chunks_exact(8)
            .map(|c| {
                let h = |i: usize| {
                    f16::from_bits(u16::from_le_bytes([c[2 * i], c[2 * i + 1]])).to_f32()
                };
                [h(0), h(1), h(2), h(3)]
            })
            .collect()
    } else {
        bytes
            .chunks_exact(16)
            .map(|c| {
                let f = |i: usize| {
                    f32::from_le_bytes([c[4 * i], c[4 * i + 1], c[4 * i + 2], c[4 * i + 3]])
                };
                [f(0), f(1), f(2), f(3)]
            })
            .collect()
    }
}

/// Decodes single-channel float32 texels.
pub fn decode_r32(bytes: &[u8]) -> Vec<f32> {
    bytes
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

/// Per-row attribute texels of the leaves: (normal, area) and (cosine normalization, material,
/// leaf flag, depth parity: push leaves odd depths' incident radiance in the L_in image);
/// cluster rows are zero. `layout.columns × layout.rows_per_column` texels each.
pub fn attributes(sys: &System, layout: &TableLayout) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
    let (rw, rh) = (layout.columns, layout.rows_per_column);
    let mut na = vec![[0.0f32; 4]; (rw * rh) as usize];
    let mut lf = vec![[0.0f32; 4]; (rw * rh) as usize];
    for leaf in &sys.leaves {
        let (x, y) = layout.row_texel(leaf.node);
        let i = (y * rw + x) as usize;
        let n = leaf.normal;
        na[i] = [n.x as f32, n.y as f32, n.z as f32, leaf.area as f32];
        let odd = sys.hierarchy.nodes[leaf.node as usize].depth % 2;
        // z: a leaf (non-zero): its push factor (System::push_factor, positive), negated where
        // light arriving at its back is blocked.
        let k = sys.push_factor(leaf.node) as f32;
        let z = if leaf.blocks_back { -k } else { k };
        lf[i] = [leaf.cos_norm as f32, leaf.material as f32, z, odd as f32];
    }
    (na, lf)
}

/// Lobe factors of the glossy leaves in table layout (zero elsewhere), for an image of
/// `width × height` texels (1×1 when the scene has no glossy tables).
pub fn lobe_factors(sys: &System, layout: &TableLayout, width: u32, height: u32) -> Vec<f32> {
    let mut lobe = vec![0.0f32; (width * height) as usize];
    if width == 1 && height == 1 {
        return lobe;
    }
    for (li, leaf) in sys.leaves.iter().enumerate() {
        if let Some(f) = sys.lobe_factors(li) {
            for (j, &v) in f.iter().enumerate() {
                let (x, y) = layout.texel(leaf.node, j as u32);
                lobe[(y * width + x) as usize] = v;
            }
        }
    }
    lobe
}

/// Dense cone-filter tables: one `m × m` layer per used class (row = central bin, column =
/// receiver bin), at least one layer. The global pass's fragments find their column from their
/// offset in the rectangle of the bins' grid they draw.
pub fn filter_tables(sys: &System) -> Vec<f32> {
    let m = sys.bins.count;
    let classes = sys.filters.used_classes();
    let mut ft = vec![0.0f32; m * m * classes.len().max(1)];
    for (layer, c) in classes.into_iter().enumerate() {
        for (l, row) in sys.filters.rows[c].iter().enumerate() {
            for &(j, w) in row {
                ft[(layer * m + l) * m + j as usize] = w;
            }
        }
    }
    ft
}

/// The solver's material records: each glossy material's exponent as the bins sample it, its
/// lobe's truncation cosine (`ke.w`) and the index of its bin neighbourhoods in
/// [`lobe_bins`] (`kd.w`, −1 without a lobe).
pub fn solver_materials(sys: &System) -> Vec<GpuMaterial> {
    let mut class = 0.0f32;
    sys.materials
        .iter()
        .zip(&sys.lobes)
        .map(|(m, lobe)| {
            let mut g = GpuMaterial::with_exponent(m, lobe.map_or(m.ns, |l| l.exponent));
            if let Some(l) = lobe {
                g.kd[3] = class;
                g.ke[3] = l.cos_cut as f32;
                class += 1.0;
            } else {
                g.kd[3] = -1.0;
            }
            g
        })
        .collect()
}

/// Offset marking a lobe whose neighbourhood is every bin (the shader loops over all of them).
pub const ALL_BINS: u32 = u32::MAX;

/// The lobe lists are looked up by the mirror direction's cell in a grid this many times finer
/// (per side) than the bins': a list must hold every bin within the cone of any direction in
/// the cell, so a smaller cell lists fewer bins beyond the cone itself.
pub const LOBE_REFINE: usize = 4;

/// For every glossy material's lobe, the incident bins that can be in its truncated cone around
/// a mirror direction, per cell of the lookup grid (the bins' grid refined [`LOBE_REFINE`]
/// times per side): `cells + 1` offsets per lobe (into this same buffer, or [`ALL_BINS`] when
/// the cone is too wide to be worth a list), then the lists. Bin `l` is listed for a cell when
/// its center lies within the cone's angle plus the cell's radius of the cell's center, so every
/// term the cone keeps is found.
pub fn lobe_bins(sys: &System) -> Vec<u32> {
    use rayon::prelude::*;
    let (nu, nv) = (sys.bins.nu * LOBE_REFINE, sys.bins.nv * LOBE_REFINE);
    let cells = nu * nv;
    let lobes: Vec<_> = sys.lobes.iter().flatten().collect();
    if lobes.is_empty() {
        return Vec::new();
    }
    let radius = crate::bins::grid_cell_radius(nu, nv);
    let mut out = vec![0u32; lobes.len() * (cells + 1)];
    for (k, lobe) in lobes.iter().enumerate() {
        let reach = lobe.cos_cut.clamp(-1.0, 1.0).acos() + radius;
        let head = k * (cells + 1);
        // A cone reaching past a hemisphere lists more than half the bins: loop over all.
        if reach >= std::f64::consts::FRAC_PI_2 {
            out[head..head + cells + 1].fill(ALL_BINS);
            continue;
        }
        let cos_reach = reach.cos();
        let lists: Vec<Vec<u32>> = (0..cells)
            .into_par_iter()
            .map(|cell| {
                let c = crate::bins::grid_cell_center(nu, nv, cell);
                (0..sys.bins.count as u32)
                    .filter(|&l| sys.bins.centers[l as usize].dot(c) >= cos_reach)
                    .collect()
            })
            .collect();
        for (cell, list) in lists.into_iter().enumerate() {
            out[head + cell] = out.len() as u32;
            out.extend(list);
        }
        out[head + cells] = out.len() as u32;
    }
    out
}

/// Phong-sum terms the local pass evaluates per propagation (the glossy leaves' front bins times
/// the incident bins listed for each one's mirror direction).
pub fn glossy_terms(sys: &System, lobe_bins: &[u32]) -> u64 {
    let m = sys.bins.count;
    let (nu, nv) = (sys.bins.nu * LOBE_REFINE, sys.bins.nv * LOBE_REFINE);
    let cells = nu * nv;
    let mut class = vec![None; sys.materials.len()];
    let mut k = 0;
    for (i, l) in sys.lobes.iter().enumerate() {
        if l.is_some() {
            class[i] = Some(k);
            k += 1;
        }
    }
    sys.leaves
        .iter()
        .map(|leaf| {
            // Lambertian leaves (in the Phong pass only with every pass on) have no lobe to sum.
            let Some(k) = class[leaf.material as usize] else {
                return 0;
            };
            let head = k * (cells + 1);
            sys.bins
                .centers
                .iter()
                .filter(|d| d.dot(leaf.normal) > 0.0)
                .map(|d| {
                    let (u, v) =
                        crate::bins::direction_to_square(crate::brdf::mirror(*d, leaf.normal));
                    let iu = (((u + 1.0) * 0.5 * nu as f64) as usize).min(nu - 1);
                    let iv = (((v + 1.0) * 0.5 * nv as f64) as usize).min(nv - 1);
                    let b = iv * nu + iu;
                    if lobe_bins[head + b] == ALL_BINS {
                        m as u64
                    } else {
                        (lobe_bins[head + b + 1] - lobe_bins[head + b]) as u64
                    }
                })
                .sum::<u64>()
        })
        .sum()
}

/// The emitting triangles as the compose pass reads them (`frame/edges.rs`).
pub fn emitter_triangles(
    t: &crate::frame::edges::EmitterTriangles,
) -> Vec<super::layout::GpuEmitterTriangle> {
    t.corners
        .iter()
        .zip(&t.ke)
        .map(|(c, ke)| super::layout::GpuEmitterTriangle {
            c0: v4(c[0], 0.0),
            c1: v4(c[1], 0.0),
            c2: v4(c[2], 0.0),
            ke: v4(*ke, 0.0),
        })
        .collect()
}

/// Storage buffers may not be empty: one unused record pads an empty list.
pub fn padded<T: Copy + Default>(v: Vec<T>) -> Vec<T> {
    if v.is_empty() {
        vec![T::default()]
    } else {
        v
    }
}

fn v4(v: DVec3, w: f32) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w]
}

/// A column-major f32 matrix.
pub fn mat(m: DMat4) -> [[f32; 4]; 4] {
    m.to_cols_array_2d().map(|c| c.map(|v| v as f32))
}

/// Face corners for the shadow and G-buffer passes: three per face slot, then every input
/// triangle again, flagged [`FILLER`] and drawn behind the elements (bisection leaves
/// T-junctions whose float rounding opens pinhole cracks between elements; these fill them).
pub fn corners(scene: &Scene, _sys: &System, surf: &Surfaces) -> Vec<CornerVertex> {
    let mut out: Vec<CornerVertex> = (0..surf.leaf.len())
        .flat_map(|li| (0..3).map(move |k| (li, surf.corners[li][k], k)))
        .map(|(li, p, k)| CornerVertex {
            position: [p.x as f32, p.y as f32, p.z as f32],
            leaf: li as u32,
            vertex: surf.corner_vertex[li][k],
            normal: v3(surf.corner_normal[li][k]),
        })
        .collect();
    let mut tri = 0usize;
    for m in &scene.meshes {
        for (ti, t) in m.triangles.iter().enumerate() {
            let leaf = surf.triangle_leaf[tri];
            if leaf != u32::MAX {
                let normals = m.corner_normals(ti);
                for k in 0..3 {
                    let p = m.positions[t[k] as usize];
                    out.push(CornerVertex {
                        position: [p.x as f32, p.y as f32, p.z as f32],
                        leaf: leaf | FILLER,
                        vertex: surf.triangle_vertices[tri][k],
                        normal: v3(normals[k]),
                    });
                }
            }
            tri += 1;
        }
    }
    out
}

/// A vector as three floats.
fn v3(v: DVec3) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}

/// The shared vertices' positions (xyz, w = 1), as the CPU's vertex values take them.
pub fn vertex_positions(surf: &Surfaces) -> Vec<[f32; 4]> {
    surf.vertices
        .iter()
        .map(|p| [p.x as f32, p.y as f32, p.z as f32, 1.0])
        .collect()
}

/// The shared-vertex leaf lists with each leaf's shading normal at the vertex.
pub fn adjacency(surf: &Surfaces) -> Vec<GpuAdjEntry> {
    surf.adjacency
        .iter()
        .zip(&surf.adjacency_normal)
        .zip(&surf.adjacency_weight)
        .map(|((&leaf, &n), &w)| GpuAdjEntry {
            leaf,
            normal: v3(n),
            weight: w as f32,
        })
        .collect()
}

/// Face slots splatted by the frame (one per flat-surface leaf, when the plan splats).
pub fn splat_instances(surf: &Surfaces, splat: bool) -> Vec<u32> {
    if !splat {
        return Vec::new();
    }
    surf.splat_slots().collect()
}

/// Per-face records of the frame passes, in face-slot order.
pub fn frame_elements(sys: &System, surf: &Surfaces) -> Vec<GpuFrameElement> {
    (0..surf.leaf.len())
        .map(|li| {
            let l = &sys.leaves[surf.leaf[li] as usize];
            GpuFrameElement {
                center_radius: v4(surf.center[li], surf.radius[li] as f32),
                normal_area: v4(l.normal, l.area as f32),
                ids: [l.node, surf.surface[li], surf.mode[li], l.material],
                cos_norm: [l.cos_norm as f32, surf.shaded[li] as u32 as f32, 0.0, 0.0],
                face_normal: v4(surf.normal[li], 0.0),
            }
        })
        .collect()
}

/// The lights as the compose pass reads them, each with its range of shadow views.
pub fn lights(lights: &[Light], maps: &ShadowMaps) -> Vec<GpuLight> {
    lights
        .iter()
        .zip(&maps.light_views)
        .map(|(l, &(first, count))| {
            let (kind, pos, dir, power, cutoff, beam) = match *l {
                Light::Directional {
                    direction,
                    irradiance,
                } => (0, DVec3::ZERO, direction, irradiance, 0.0, 0.0),
                Light::Point {
                    position,
                    intensity,
                } => (1, position, DVec3::Z, intensity, 0.0, 0.0),
                Light::Spot {
                    position,
                    axis,
                    intensity,
                    cutoff,
                    beam_width,
                } => (2, position, axis, intensity, cutoff, beam_width),
                Light::EmitterSample {
                    position,
                    normal,
                    radiance,
                    area,
                    ..
                } => (3, position, normal, radiance, 0.0, area),
            };
            let cell = match *l {
                Light::EmitterSample { cell: Some(c), .. } => Some(c),
                _ => None,
            };
            let corner = |i: usize| cell.map_or([0.0; 4], |c| v4(c[i], 0.0));
            GpuLight {
                kind_views: [kind, first, count, cell.is_some() as u32],
                position: v4(pos, 0.0),
                direction: v4(dir, 0.0),
                power: v4(power, cutoff as f32),
                params: [beam as f32, 0.0, 0.0, 0.0],
                cell: [corner(0), corner(1), corner(2)],
            }
        })
        .collect()
}

/// The shadow-map views.
pub fn shadow_views(maps: &ShadowMaps) -> Vec<GpuShadowView> {
    maps.views
        .iter()
        .map(|v| GpuShadowView {
            view_proj: mat(v.view_proj),
            origin: v4(v.origin, if v.ortho { 1.0 } else { 0.0 }),
            forward: v4(v.forward, v.half as f32),
            atlas: [v.atlas.0, v.atlas.1, v.size, 0],
            right: v4(v.right, 0.0),
            up: v4(v.up, 0.0),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plane() -> (Scene, System) {
        let s = crate::scene::test_plane(0.3);
        let sys = System::build(&s).unwrap();
        (s, sys)
    }

    #[test]
    fn texels_round_trip_in_both_formats() {
        let t = [[1.5f32, -2.25, 65504.0, 0.0], [1e-3, 0.0, -0.5, 7.0]];
        for f in [
            vk::Format::R16G16B16A16_SFLOAT,
            vk::Format::R32G32B32A32_SFLOAT,
        ] {
            let back = decode(f, &encode(f, &t));
            for (a, b) in t.iter().flatten().zip(back.iter().flatten()) {
                assert!((a - b).abs() <= a.abs() * 1e-3, "{f:?}: {a} vs {b}");
            }
        }
        assert_eq!(encode(vk::Format::R16G16B16A16_SFLOAT, &t).len(), 16);
        assert_eq!(decode_r32(&2.5f32.to_le_bytes()), [2.5]);
    }

    #[test]
    fn attributes_and_lobes_sit_on_the_leaf_rows() {
        let (_, sys) = plane();
        let layout = TableLayout::with_column_height(sys.rows() as u32, 32, 16384, 3).unwrap();
        let (na, lf) = attributes(&sys, &layout);
        assert_eq!(na.len(), (layout.columns * layout.rows_per_column) as usize);
        // A leaf row holds its push factor, negated where the leaf blocks light from behind (a
        // lone plane does); other rows 0.
        let rows_with_leaf = lf.iter().filter(|t| t[2] != 0.0).count();
        assert_eq!(rows_with_leaf, sys.leaves.len());
        assert!(sys.leaves.iter().all(|l| l.blocks_back));
        for leaf in &sys.leaves {
            let (x, y) = layout.row_texel(leaf.node);
            let z = lf[(y * layout.columns + x) as usize][2];
            assert_eq!(
                z,
                -(sys.push_factor(leaf.node) as f32),
                "blocking leaf's factor"
            );
            let t = na[(y * layout.columns + x) as usize];
            assert_eq!(t[1], 1.0, "normal is +y");
            assert!((t[3] as f64 - leaf.area).abs() < 1e-6);
        }
        let (w, h) = (layout.width(), layout.rows_per_column);
        let lobe = lobe_factors(&sys, &layout, w, h);
        let nonzero = lobe.iter().filter(|v| **v != 0.0).count();
        assert!(nonzero > 0 && nonzero <= sys.leaves.len() * 32);
        for (li, leaf) in sys.leaves.iter().enumerate() {
            let f = sys.lobe_factors(li).unwrap();
            let (x, y) = layout.texel(leaf.node, 5);
            assert_eq!(lobe[(y * w + x) as usize], f[5]);
        }
        assert_eq!(lobe_factors(&sys, &layout, 1, 1), [0.0]);
    }

    #[test]
    fn filter_tables_hold_every_used_row() {
        let (_, sys) = plane();
        let m = sys.bins.count;
        let ft = filter_tables(&sys);
        let classes = sys.filters.used_classes();
        assert_eq!(ft.len(), m * m * classes.len().max(1));
        for (layer, c) in classes.into_iter().enumerate() {
            for (l, row) in sys.filters.rows[c].iter().enumerate() {
                let sum: f32 = ft[(layer * m + l) * m..(layer * m + l + 1) * m]
                    .iter()
                    .sum();
                let want: f32 = row.iter().map(|e| e.1).sum();
                assert!((sum - want).abs() < 1e-5);
                for &(j, w) in row {
                    assert_eq!(ft[(layer * m + l) * m + j as usize], w);
                }
            }
        }
    }

    #[test]
    fn corners_cover_every_leaf_and_filler_triangle() {
        let (s, sys) = plane();
        let surf = Surfaces::new(&s, &sys);
        let c = corners(&s, &sys, &surf);
        let fillers = c.iter().filter(|v| v.leaf & FILLER != 0).count();
        assert_eq!(c.len() - fillers, 3 * sys.leaves.len());
        assert_eq!(fillers, 3 * s.triangle_count());
        assert_eq!(frame_elements(&sys, &surf).len(), sys.leaves.len());
        assert_eq!(splat_instances(&surf, true).len(), sys.leaves.len());
        assert!(splat_instances(&surf, false).is_empty());
        assert_eq!(padded(Vec::<u32>::new()), [0]);
    }
}
