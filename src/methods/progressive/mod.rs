//! Progressive refinement radiosity (Cohen et al. 1988; on the GPU after Coombe and Harris, GPU
//! Gems 2 ch. 39): every element keeps its gathered irradiance H and its unshot radiosity U; a
//! shot takes the element with the most unshot power, sends U to every element it sees, and sets
//! its own U to zero. Elements are the leaves of the engine's discretization; the GPU backend
//! ([`gpu`]) finds the shooter, rasterizes a hemicube item buffer of element ids from it and
//! gathers per receiver in compute passes, the CPU backend ([`cpu`]) does the same shot with rays.
//!
//! What each element receives from a shot is the shooter's radiance `U/π` times the projected
//! solid angle of the shooter's triangle (exact, Lambert's polygon formula) seen from points of
//! the receiver, visibility tested from the shooter's center. **Adaptive subdivision** where the
//! received light's gradient is large ([`receive`]): a receiver takes its centroid's value unless
//! the visibility at three probes differs from the centroid's (a shadow boundary crosses it);
//! then it is integrated over its 4 sub-triangles, over 16 where those spread by more than
//! `gradient` of their largest, and so on to 4^`subdivision`. It refines each shot's integration
//! over the receiver, not the displayed resolution: the frame draws one value per element, as for
//! antiradiance.
//!
//! Sources as in antiradiance: area emitters (`Ke`) shoot their exitance π·Ke; analytic lights'
//! direct light (shadow-mapped, [`crate::frame::lights::direct_in_table`]) is reflected once into
//! the unshot radiosity but drawn per pixel; the environment's irradiance (its visible fraction by
//! cosine-weighted rays) is gathered at the start. **Diffuse only**: a glossy material reflects
//! its `kd + ks` diffusely (energy kept, the lobe's direction lost), and the render says so.

pub mod cpu;
pub mod gpu;
pub mod shooter;

use super::{MethodSettings, Sequence};
use crate::linker::projected_solid_angle;
use crate::raycast::RayCaster;
use crate::solver::Table;
use crate::system::System;
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Rays per element for the environment's visible fraction.
pub const ENVIRONMENT_RAYS: usize = 64;

/// Per-leaf constants of shooting, in leaf-slot order.
#[derive(Debug, Clone)]
pub struct Elements {
    /// Triangle corners.
    pub corners: Vec<[DVec3; 3]>,
    /// Centroids.
    pub center: Vec<DVec3>,
    /// Unit front normals.
    pub normal: Vec<DVec3>,
    /// Areas.
    pub area: Vec<f64>,
    /// Diffuse albedo used for reflection: `kd + ks` (energy of a glossy lobe kept, reflected
    /// diffusely), each channel below 1.
    pub albedo: Vec<DVec3>,
    /// Exitance of emission, π·Ke.
    pub emission: Vec<DVec3>,
}

impl Elements {
    /// The leaves of `sys`.
    pub fn new(sys: &System) -> Self {
        let el = |l: &crate::system::LeafAttributes| {
            &sys.elements[sys.hierarchy.element(l.node).expect("leaf") as usize]
        };
        let mat = |l: &crate::system::LeafAttributes| &sys.materials[l.material as usize];
        Self {
            // Systems without links are built without face clusters: one face per leaf.
            corners: sys.leaves.iter().map(|l| el(l).faces[0].corners).collect(),
            center: sys.leaves.iter().map(|l| el(l).center).collect(),
            normal: sys.leaves.iter().map(|l| l.normal).collect(),
            area: sys.leaves.iter().map(|l| l.area).collect(),
            albedo: sys
                .leaves
                .iter()
                .map(|l| (mat(l).kd + mat(l).ks).min(DVec3::splat(0.999)))
                .collect(),
            emission: sys.leaves.iter().map(|l| mat(l).ke * PI).collect(),
        }
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.area.len()
    }

    /// True without elements.
    pub fn is_empty(&self) -> bool {
        self.area.is_empty()
    }

    /// Whether any material is glossy (reflected diffusely here).
    pub fn glossy_note(sys: &System) -> Option<String> {
        sys.leaves
            .iter()
            .any(|l| sys.materials[l.material as usize].is_glossy())
            .then(|| {
                "progressive radiosity is diffuse: glossy materials reflect kd + ks diffusely between surfaces (their lobe is drawn only for direct light)".to_string()
            })
    }
}

/// Irradiance each leaf receives from the analytic lights: the direct-light table's bins
/// integrated with the solver's cosine quadrature (what the local pass reflects).
pub fn direct_irradiance(sys: &System, table: &Table) -> Vec<DVec3> {
    sys.leaves
        .iter()
        .map(|l| {
            let row = table.row(l.node as usize);
            let e: DVec3 = sys
                .bins
                .centers
                .iter()
                .zip(row)
                .map(|(c, v)| *v * (-c.dot(l.normal)).max(0.0))
                .sum();
            e * sys.bins.omega * l.cos_norm
        })
        .collect()
}

/// Irradiance from a constant environment of radiance `env` at every leaf: π·env times the
/// cosine-weighted fraction of [`ENVIRONMENT_RAYS`] rays (from stratified points of the leaf)
/// that escape. Returns the irradiances and the rays cast.
pub fn environment_irradiance(
    els: &Elements,
    caster: &RayCaster,
    env: DVec3,
    eps: f64,
) -> (Vec<DVec3>, u64) {
    if env == DVec3::ZERO {
        return (vec![DVec3::ZERO; els.len()], 0);
    }
    let e = (0..els.len())
        .into_par_iter()
        .map(|i| {
            let n = els.normal[i];
            let (t, b) = n.any_orthonormal_pair();
            let seq = Sequence::<4>::new(0xe5 ^ (i as u64) << 8);
            let open = (0..ENVIRONMENT_RAYS)
                .filter(|&k| {
                    let u = seq.point(k);
                    let p = super::triangle_point(&els.corners[i], u[0], u[1]);
                    // Cosine-weighted direction (Malley).
                    let (r, phi) = (u[2].sqrt(), 2.0 * PI * u[3]);
                    let d = t * (r * phi.cos())
                        + b * (r * phi.sin())
                        + n * (1.0 - u[2]).max(0.0).sqrt();
                    !caster.occluded(p + n * eps, d, 0.0, f64::INFINITY)
                })
                .count();
            env * (PI * open as f64 / ENVIRONMENT_RAYS as f64)
        })
        .collect();
    (e, (els.len() * ENVIRONMENT_RAYS) as u64)
}

/// The shooting state: gathered irradiance and unshot radiosity per leaf.
#[derive(Debug, Clone, PartialEq)]
pub struct State {
    /// Irradiance gathered from shots and the environment (what the display reflects).
    pub gathered: Vec<DVec3>,
    /// Radiosity not yet shot.
    pub unshot: Vec<DVec3>,
    /// Radiosity that does not change: emission plus the reflected direct light.
    pub base: Vec<DVec3>,
}

impl State {
    /// Before any shot: emitters and the reflected direct light and environment unshot, the
    /// environment gathered.
    pub fn initial(els: &Elements, direct: &[DVec3], environment: &[DVec3]) -> Self {
        let base: Vec<DVec3> = (0..els.len())
            .map(|i| els.emission[i] + els.albedo[i] * direct[i])
            .collect();
        Self {
            gathered: environment.to_vec(),
            unshot: (0..els.len())
                .map(|i| base[i] + els.albedo[i] * environment[i])
                .collect(),
            base,
        }
    }

    /// Unshot power (W, mean of RGB) of element `i`.
    pub fn power(&self, els: &Elements, i: usize) -> f64 {
        els.area[i] * self.unshot[i].element_sum() / 3.0
    }

    /// The element with the most unshot power and that power, or `None` when nothing is left.
    pub fn shooter(&self, els: &Elements) -> Option<(usize, f64)> {
        (0..els.len()).map(|i| (i, self.power(els, i))).fold(
            None,
            |best: Option<(usize, f64)>, c| match best {
                Some(b) if b.1 >= c.1 => Some(b),
                _ if c.1 > 0.0 => Some(c),
                b => b,
            },
        )
    }

    /// Unshot power of all elements (W, mean of RGB).
    pub fn unshot_power(&self, els: &Elements) -> f64 {
        (0..els.len()).map(|i| self.power(els, i)).sum()
    }

    /// Radiosity leaving element `i` (emission, reflected direct light, reflected gathered light).
    pub fn radiosity(&self, els: &Elements, i: usize) -> DVec3 {
        self.base[i] + els.albedo[i] * self.gathered[i]
    }

    /// Flux leaving all elements (W, mean of RGB).
    pub fn flux(&self, els: &Elements) -> f64 {
        (0..els.len())
            .map(|i| els.area[i] * self.radiosity(els, i).element_sum() / 3.0)
            .sum()
    }
}

/// Barycentric coordinates of the centroid of sub-triangle `k` of level `level`: the triangle
/// split into 4^level congruent ones by repeated midpoint subdivision, `k`'s base-4 digits
/// choosing the child from the top (`glsl/pr_common.glsl` has the same).
pub fn subtriangle_centroid(level: u32, k: u32) -> [f64; 3] {
    let mut c = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let mid = |a: [f64; 3], b: [f64; 3]| std::array::from_fn(|i| 0.5 * (a[i] + b[i]));
    for l in (0..level).rev() {
        let (ab, bc, ca) = (mid(c[0], c[1]), mid(c[1], c[2]), mid(c[2], c[0]));
        c = match (k >> (2 * l)) & 3 {
            0 => [c[0], ab, ca],
            1 => [ab, c[1], bc],
            2 => [ca, bc, c[2]],
            _ => [bc, ca, ab],
        };
    }
    std::array::from_fn(|i| (c[0][i] + c[1][i] + c[2][i]) / 3.0)
}

/// Barycentric probes of a receiver's visibility beside its centroid: the centroids of its three
/// corner sub-triangles (inside the element, off the edges it shares with its neighbours).
pub const PROBES: [[f64; 3]; 3] = [
    [2.0 / 3.0, 1.0 / 6.0, 1.0 / 6.0],
    [1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0],
    [1.0 / 6.0, 1.0 / 6.0, 2.0 / 3.0],
];

/// What a receiver gets from one shot, as a fraction of the shooter's radiance: `sample(b)` gives
/// the kernel (projected solid angle) and the visibility at the point with barycentric
/// coordinates `b`, `visible(b)` the visibility alone. The centroid's kernel × visibility, unless
/// the visibility at [`PROBES`] differs from the centroid's (a shadow boundary crosses the
/// element): then the mean over its 4 sub-triangle centroids, over 16 where those spread by more
/// than `gradient` of their largest, and so on to 4^`subdivision`. Returns the mean and the
/// kernels evaluated. A smooth kernel needs no refinement: the centroid rule is exact to first
/// order, and the shooters around a point tile its hemisphere exactly.
pub fn receive(
    settings: &MethodSettings,
    mut sample: impl FnMut([f64; 3]) -> (f64, bool),
    mut visible: impl FnMut([f64; 3]) -> bool,
) -> (f64, u32) {
    let (k, v) = sample([1.0 / 3.0; 3]);
    let centroid = if v { k } else { 0.0 };
    if settings.subdivision == 0 || PROBES.iter().all(|&b| visible(b) == v) {
        return (centroid, 1);
    }
    let mut taken = 1;
    let mut level = 1;
    loop {
        let n = 1u32 << (2 * level);
        let (mut sum, mut lo, mut hi) = (0.0, f64::INFINITY, 0.0f64);
        for j in 0..n {
            let (k, v) = sample(subtriangle_centroid(level, j));
            let x = if v { k } else { 0.0 };
            sum += x;
            lo = lo.min(x);
            hi = hi.max(x);
        }
        taken += n;
        if level >= settings.subdivision || hi - lo <= settings.gradient * hi {
            return (sum / n as f64, taken);
        }
        level += 1;
    }
}

/// Whether shooter `s` and receiver `r` can exchange light at all: part of each lies in front of
/// the other's plane (else every kernel is zero, and the receiver is skipped).
pub fn facing(els: &Elements, s: usize, r: usize) -> bool {
    let front = |a: usize, b: usize| {
        els.corners[b]
            .iter()
            .any(|p| (*p - els.center[a]).dot(els.normal[a]) > 0.0)
    };
    front(s, r) && front(r, s)
}

/// The shot's kernel at receiver point `x` (normal `n`) from shooter `s`: the projected solid
/// angle of the shooter's triangle (zero behind it, or behind the receiver).
pub fn kernel(els: &Elements, s: usize, x: DVec3, n: DVec3) -> f64 {
    if (x - els.center[s]).dot(els.normal[s]) <= 0.0 {
        return 0.0;
    }
    projected_solid_angle(x, n, &els.corners[s])
}

/// What the engine's tables are laid out by: rows, bins, and each leaf's row, normal, area and
/// cosine normalization (kept so that a backend can make tables without the prepared scene).
#[derive(Debug, Clone)]
pub struct TableShape {
    rows: usize,
    bins: crate::bins::Bins,
    leaves: Vec<crate::system::LeafAttributes>,
}

impl TableShape {
    /// The shape of `sys`'s tables.
    pub fn of(sys: &System) -> Self {
        Self {
            rows: sys.rows(),
            bins: sys.bins.clone(),
            leaves: sys.leaves.clone(),
        }
    }

    /// The display table I_total of a gathered irradiance: in leaf `i`'s front bins
    /// `area · cos_norm · cos · albedo/π · H` (light reflected from what arrived through shots
    /// and the environment; emission and the analytic lights' first bounce are drawn per
    /// pixel), as the antiradiance solver fills it for a Lambertian leaf.
    pub fn display(&self, els: &Elements, gathered: &[DVec3]) -> Table {
        self.leaf_table(|i| els.albedo[i] / PI * gathered[i])
    }

    /// The exitant table I_ex of a state (all radiosity, emission included), for
    /// [`crate::backend::Solve::i_ex`].
    pub fn exitant(&self, els: &Elements, state: &State) -> Table {
        self.leaf_table(|i| state.radiosity(els, i) / PI)
    }

    /// A table with leaf `i`'s front bins holding `area · cos_norm · cos · radiance(i)`.
    fn leaf_table(&self, radiance: impl Fn(usize) -> DVec3 + Sync) -> Table {
        let m = self.bins.count;
        let mut t = Table::zeros(self.rows, m);
        let rows: Vec<(usize, Vec<DVec3>)> = self
            .leaves
            .par_iter()
            .enumerate()
            .map(|(i, l)| {
                let r = radiance(i) * (l.area * l.cos_norm);
                let row = self
                    .bins
                    .centers
                    .iter()
                    .map(|c| r * c.dot(l.normal).max(0.0))
                    .collect();
                (l.node as usize, row)
            })
            .collect();
        for (node, row) in rows {
            t.row_mut(node).copy_from_slice(&row);
        }
        t
    }
}

/// Shots per iteration for `els` under `settings` (a quarter of the elements by default).
pub fn shots_per_iteration(settings: &MethodSettings, elements: usize) -> usize {
    settings
        .shots_per_iteration
        .map_or(elements.div_ceil(4), |n| n as usize)
        .max(1)
}

/// Offset of ray origins and the hemicube's eye off a surface: far below any element, far above
/// the rounding of the coordinates.
pub fn surface_offset(sys: &System) -> f64 {
    let root = &sys.hierarchy.nodes[0];
    1e-5 * (root.radius + root.center.abs().max_element()).max(1e-300)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn subtriangles_tile_the_triangle() {
        for level in 0..4 {
            let n = 1u32 << (2 * level);
            let mut mean = [0.0; 3];
            let mut seen = std::collections::HashSet::new();
            for k in 0..n {
                let b = subtriangle_centroid(level, k);
                assert!((b.iter().sum::<f64>() - 1.0).abs() < 1e-12);
                assert!(b.iter().all(|&x| x > 0.0));
                assert!(seen.insert(b.map(|x| (x * 1e9).round() as i64)));
                for i in 0..3 {
                    mean[i] += b[i] / n as f64;
                }
            }
            // Equal areas: the centroids' mean is the triangle's centroid.
            for m in mean {
                assert!((m - 1.0 / 3.0).abs() < 1e-12, "level {level}: {mean:?}");
            }
        }
    }

    #[test]
    fn adaptive_receive_refines_only_where_visibility_changes() {
        let s = MethodSettings {
            subdivision: 3,
            gradient: 0.1,
            ..Default::default()
        };
        // Visible everywhere, smooth kernel: the centroid alone.
        assert_eq!(
            receive(&s, |b| (1.0 + b[0], true), |_| true),
            (4.0 / 3.0, 1)
        );
        // A shadow edge across the element: refined to the deepest level, area-exact there.
        let lit = |b: [f64; 3]| b[0] > 0.5;
        let (v, n) = receive(&s, |b| (1.0, lit(b)), lit);
        assert_eq!(n, 1 + 4 + 16 + 64);
        assert!((v - 0.25).abs() < 0.05, "{v}");
        // Without subdivision the centroid decides.
        let off = MethodSettings {
            subdivision: 0,
            ..s
        };
        assert_eq!(receive(&off, |b| (1.0, lit(b)), lit), (0.0, 1));
    }
}
