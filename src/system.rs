//! The discrete system of one scene: elements, hierarchy, bins, links and spreading tables.
//! Everything the CPU solver and the GPU passes share is built here, once.

use crate::bins::Bins;
use crate::brdf::DiscreteLobe;
use crate::elements::Element;
use crate::error::{Error, Result};
use crate::filter::FilterTables;
use crate::hierarchy::Hierarchy;
use crate::linker::{self, build_links, Link, Links};
use crate::meshed::Meshed;
use crate::plan::occlusion::{self, Occlusion};
use crate::scene::{Material, Scene, SolverSettings};
use glam::DVec3;
use std::collections::HashMap;
use std::time::Instant;

mod follow;
pub mod receivers;

/// Per-leaf constants of the local pass (the GPU stores them as element attribute images).
#[derive(Debug, Clone, PartialEq)]
pub struct LeafAttributes {
    /// Node (row) of the leaf.
    pub node: u32,
    /// Element area `a_i`.
    pub area: f64,
    /// Unit normal `n_i`.
    pub normal: DVec3,
    /// Cosine quadrature normalization (see [`Bins::cosine_normalization`]).
    pub cos_norm: f64,
    /// Material index.
    pub material: u32,
    /// Whether light arriving at its back is blocked ([`Element::blocks_back`]).
    pub blocks_back: bool,
}

/// Everything built on the CPU before solving.
#[derive(Debug, Clone)]
pub struct System {
    /// Leaf elements.
    pub elements: Vec<Element>,
    /// Hierarchy over them.
    pub hierarchy: Hierarchy,
    /// Directional bins.
    pub bins: Bins,
    /// Links.
    pub links: Links,
    /// Spreading tables for the cone classes in use.
    pub filters: FilterTables,
    /// Leaf attributes, in the order of `hierarchy.leaves`.
    pub leaves: Vec<LeafAttributes>,
    /// For every node, its index in `leaves`, or `u32::MAX` for clusters.
    pub leaf_slot: Vec<u32>,
    /// Materials (copied from the scene).
    pub materials: Vec<Material>,
    /// Time to build elements and hierarchy, ms.
    pub meshing_ms: f64,
    /// The Phong lobe of each material as sampled in the bins (`None`: not glossy).
    pub lobes: Vec<Option<DiscreteLobe>>,
    /// Per-incident-bin lobe factors of the glossy leaves ([`DiscreteLobe::factors`]), `bins`
    /// values per glossy leaf; see [`System::lobe_factors`].
    pub lobe_norm: Vec<f32>,
    /// For every leaf (index into `leaves`), its block in `lobe_norm`, or `u32::MAX`.
    pub lobe_slot: Vec<u32>,
    /// Whether antiradiance can reach anything ([`occlusion::analyze`]), when it was needed
    /// here (closed scenes); the plan reuses it.
    pub occlusion: Option<Occlusion>,
    /// Closed scenes only: the spectral radius λ of the calibrated transport at albedo one
    /// (should be exactly 1: a closed enclosure loses no light), which every form factor was
    /// divided by. See [`System::conserve_energy`].
    pub energy_normalization: Option<f64>,
    /// Scenes with keyframed objects: what moves and which links a frame recomputes (the
    /// links are made for the whole motion, [`crate::bound`]); `None` for still scenes.
    pub bound: Option<crate::bound::Bound>,
    /// Per leaf (in the order of `leaves`), the factor on the radiance pushed to it from its
    /// ancestors ([`receivers`]); empty: 1 everywhere (moving scenes, or turned off).
    pub push_scale: Vec<f64>,
}

/// Cosine margin of [`System::reads`]: bins this close to a leaf's plane count as read.
pub const READ_MARGIN: f64 = 1e-4;

/// Upper bound on host memory the CPU tables may take.
pub const CPU_TABLE_LIMIT_BYTES: u64 = 12 << 30;

/// Bytes of the CPU solver's tables for `rows × bins`: I_ex, L_in, L_push, I_total and the
/// direct light, one f64 RGB texel each.
pub fn cpu_table_bytes(rows: u64, bins: u64) -> u64 {
    rows * bins * 24 * 5
}

pub use crate::linker::estimate_links;

/// What the link stage ([`System::link_meshed`]) makes.
pub struct Linked {
    /// Directional bins.
    pub bins: Bins,
    /// Links, before calibration.
    pub links: Links,
    /// The bound of keyframed objects' motion (their links for every pose).
    pub bound: Option<crate::bound::Bound>,
}

impl System {
    /// Discretizes a scene with its `[solver]` settings.
    pub fn build(scene: &Scene) -> Result<Self> {
        Self::build_with(scene, &scene.solver, &|_, _| Ok(()))
    }

    /// Discretizes `scene` with `settings`. `budget(rows, bins)` runs after meshing, before
    /// linking and before anything is allocated: the engine refuses there when a device's
    /// tables would not fit.
    pub fn build_with(
        scene: &Scene,
        settings: &SolverSettings,
        budget: &dyn Fn(u64, usize) -> Result<()>,
    ) -> Result<Self> {
        Self::build_linked(scene, settings, budget, true, u64::MAX)
    }

    /// [`System::build_with`], linking only when `link` (a method that computes its own form
    /// factors, like progressive refinement, gets an empty link set and spends no time on it),
    /// and refusing with [`Error::LinkBudget`] past `max_links` links (or what this machine's
    /// memory holds), stopping as soon as it is passed.
    pub fn build_linked(
        scene: &Scene,
        settings: &SolverSettings,
        budget: &dyn Fn(u64, usize) -> Result<()>,
        link: bool,
        max_links: u64,
    ) -> Result<Self> {
        let meshed = Meshed::new(scene, settings, link)?;
        let linked = Self::link_meshed(scene, &meshed, settings, budget, link, max_links)?;
        Ok(Self::from_stages(scene, settings, meshed, linked))
    }

    /// The link stage on a meshed scene: the budget's checks, then the links (none when not
    /// `link`). Leaves `meshed` as it was, so that a try past the budget can link it again at
    /// another τ.
    pub fn link_meshed(
        scene: &Scene,
        meshed: &Meshed,
        settings: &SolverSettings,
        budget: &dyn Fn(u64, usize) -> Result<()>,
        link: bool,
        max_links: u64,
    ) -> Result<Linked> {
        let bins = Bins::new(settings.bins)?;
        let (elements, hierarchy) = (&meshed.elements, &meshed.hierarchy);
        if elements.is_empty() {
            return Err(Error::Setting {
                field: "element_size",
                message: "scene has no elements".into(),
            });
        }
        let rows = 2 * elements.len() as u64 - 1;
        // The node × bin tables are antiradiance's (and hierarchical radiosity's); the methods
        // without links (instant radiosity, progressive refinement) allocate none, so a dense
        // mesh's triangles as their elements are not refused for them.
        if link {
            budget(rows, bins.count)?;
        }
        let needed = cpu_table_bytes(rows, bins.count as u64);
        if link && needed > CPU_TABLE_LIMIT_BYTES {
            return Err(Error::TooLarge {
                what: format!("CPU tables for {rows} nodes × {} bins", bins.count),
                needed_bytes: needed,
                limit_bytes: CPU_TABLE_LIMIT_BYTES,
            });
        }
        let machine = crate::scene::max_links_limit();
        let max_links = max_links.min(machine);
        let estimate = estimate_links(elements.len(), bins.count, settings.oracle);
        if link && estimate > machine as f64 {
            return Err(Error::Setting {
                field: "oracle",
                message: format!(
                    "about {estimate:.2e} links for {} elements × {} bins at τ = {}, more than the {machine} this machine's memory holds; use a larger solver.oracle or element size, or fewer bins",
                    elements.len(),
                    bins.count,
                    settings.oracle
                ),
            });
        }
        // Far past the budget by the estimate (which runs low, never far high): refuse before
        // linking, so that fitting a budget does not spend a linking on each try.
        if link && estimate > 4.0 * max_links as f64 {
            return Err(Error::LinkBudget {
                budget: max_links,
                elements: elements.len(),
                oracle: settings.oracle,
                estimate,
            });
        }
        let (links, bound) = match &meshed.groups {
            Some((objects, mesh_group)) => {
                let (links, bound) = crate::bound::build_bounded_links(
                    scene,
                    hierarchy,
                    elements,
                    &bins,
                    settings.oracle,
                    max_links,
                    objects.clone(),
                    mesh_group,
                )?;
                (links, Some(bound))
            }
            None if link => (
                build_links(hierarchy, elements, &bins, settings.oracle, max_links)?,
                None,
            ),
            None => (
                Links {
                    offsets: vec![0; hierarchy.len() + 1],
                    used_classes: vec![false; crate::filter::class_count(&bins)],
                    ..Links::default()
                },
                None,
            ),
        };
        Ok(Linked { bins, links, bound })
    }

    /// The system of a meshed and linked scene: spreading tables, calibrated form factors,
    /// leaf attributes, lobes, the bound's moving links and the energy normalization.
    pub fn from_stages(
        scene: &Scene,
        settings: &SolverSettings,
        meshed: Meshed,
        linked: Linked,
    ) -> Self {
        let Meshed {
            elements,
            hierarchy,
            meshing_ms,
            ..
        } = meshed;
        let Linked {
            bins,
            mut links,
            bound,
        } = linked;
        let filters = FilterTables::new(&bins, &links.used_classes, settings.filter_cutoff);
        let t1 = Instant::now();
        crate::linker::calibrate_form_factors(&mut links, &hierarchy, &elements, &bins, &filters);
        links.linking_ms += t1.elapsed().as_secs_f64() * 1e3;
        let leaves: Vec<LeafAttributes> = hierarchy
            .leaves
            .iter()
            .map(|&node| {
                let e = &elements[hierarchy.element(node).unwrap() as usize];
                LeafAttributes {
                    node,
                    area: e.area,
                    normal: e.normal,
                    cos_norm: bins.cosine_normalization(e.normal),
                    material: e.material,
                    blocks_back: e.blocks_back,
                }
            })
            .collect();
        let mut leaf_slot = vec![u32::MAX; hierarchy.len()];
        for (i, &n) in hierarchy.leaves.iter().enumerate() {
            leaf_slot[n as usize] = i as u32;
        }
        let materials = scene.materials.clone();
        let lobes: Vec<Option<DiscreteLobe>> = materials
            .iter()
            .map(|m| m.is_glossy().then(|| DiscreteLobe::new(m.ns, &bins)))
            .collect();
        let (lobe_norm, lobe_slot) = lobe_factors(&leaves, &lobes, &bins);
        let mut sys = Self {
            elements,
            hierarchy,
            bins,
            links,
            filters,
            leaves,
            leaf_slot,
            materials,
            meshing_ms,
            lobes,
            lobe_norm,
            lobe_slot,
            occlusion: None,
            energy_normalization: None,
            bound: None,
            push_scale: Vec::new(),
        };
        // Still scenes only (receivers::applies).
        if receivers::applies(&sys, scene, settings) {
            let t = Instant::now();
            sys.push_scale = receivers::push_scales(&sys);
            sys.links.linking_ms += t.elapsed().as_secs_f64() * 1e3;
        }
        if let Some(b) = bound {
            // The moving links' values at this pose exactly as every frame will compute them.
            let t = Instant::now();
            sys.refresh_moving_links(&b, None);
            sys.bound = Some(b);
            sys.links.linking_ms += t.elapsed().as_secs_f64() * 1e3;
        }
        if closed_surfaces(scene) {
            let t2 = Instant::now();
            sys.conserve_energy(scene);
            sys.links.linking_ms += t2.elapsed().as_secs_f64() * 1e3;
        }
        sys
    }

    /// Makes the discrete transport of a closed scene conserve energy exactly.
    ///
    /// In a closed enclosure every bounce keeps all the light: the transport at albedo one has
    /// spectral radius exactly 1. The calibrated links ([`crate::linker::calibrate_form_factors`])
    /// get within about 2·10⁻⁴ of it (a cluster receiver pushes one radiance to leaves that
    /// should get more or less); at ρ = 0.999 that is amplified a thousandfold. Here λ is
    /// measured by power iteration — propagations of the solver itself (global, push, local,
    /// pull) with every material white and Lambertian, antiradiance as the plan will run it —
    /// and every form factor is divided by it, so λ = 1 up to rounding. Skipped (left `None`)
    /// when λ is not within 5% of 1 (the surfaces are closed but enclose nothing that faces
    /// in, as a solid alone in the void) or does not converge in [`POWER_ROUNDS`].
    pub fn conserve_energy(&mut self, scene: &Scene) {
        let occ = occlusion::analyze(scene);
        let antiradiance = occ != Occlusion::Impossible;
        self.occlusion = Some(occ);
        let lambda = transport_radius(self, antiradiance);
        if let Some(lambda) = lambda.filter(|l| (l - 1.0).abs() < 0.05) {
            for l in &mut self.links.links {
                l.form_factor /= lambda;
            }
            self.energy_normalization = Some(lambda);
        }
    }

    /// The lobe factors of leaf `li` per incident bin, or `None` for a non-glossy leaf.
    pub fn lobe_factors(&self, li: usize) -> Option<&[f32]> {
        let k = *self.lobe_slot.get(li)?;
        let m = self.bins.count;
        (k != u32::MAX).then(|| &self.lobe_norm[k as usize * m..(k as usize + 1) * m])
    }

    /// Whether the local pass reads link `l`'s light in `bin`: a leaf reads light arriving at
    /// the sides the link reaches ([`Link::sides`]; the front for reflection and antiradiance
    /// out the back, the back for antiradiance out the front); clusters pass everything down.
    /// The global pass skips the rest of the link's spread. Bins within [`READ_MARGIN`] of the
    /// leaf's plane count as both sides, so that a float32 shader and this f64 test never
    /// disagree about a bin the local pass uses.
    pub fn reads(&self, l: &Link, bin: usize) -> bool {
        match self.leaf_slot[l.receiver as usize] {
            u32::MAX => true,
            slot => {
                let c = self.bins.centers[bin].dot(self.leaves[slot as usize].normal);
                (l.sides & linker::FRONT != 0 && c < READ_MARGIN)
                    || (l.sides & linker::BACK != 0 && c > -READ_MARGIN)
            }
        }
    }

    /// Whether the push adds the parent's incident radiance to `node` in `bin`: everywhere for a
    /// cluster; for a leaf only on its front (bins arriving at it within [`READ_MARGIN`]). A
    /// cluster's incident light is meant for the leaves that face its sender; at the back of the
    /// others it would be blocked where it does not arrive (in a closed box under an environment
    /// that took 0.5% of the light per bounce and put the worst pixel 2.5% off, against 0.98%).
    /// Light arriving at a leaf's back is blocked when it comes through the leaf's own links.
    pub fn pushes(&self, node: u32, bin: usize) -> bool {
        match self.leaf_slot[node as usize] {
            u32::MAX => true,
            slot => self.bins.centers[bin].dot(self.leaves[slot as usize].normal) < READ_MARGIN,
        }
    }

    /// The factor on the radiance pushed to `node` from its ancestors: a leaf's
    /// [`System::push_scale`], 1 for clusters.
    pub fn push_factor(&self, node: u32) -> f64 {
        match self.leaf_slot[node as usize] {
            u32::MAX => 1.0,
            slot => self.push_scale.get(slot as usize).copied().unwrap_or(1.0),
        }
    }

    /// The element of leaf `li` (index into [`System::leaves`]).
    pub fn leaf_element(&self, li: usize) -> &Element {
        &self.elements[self.hierarchy.element(self.leaves[li].node).expect("leaf") as usize]
    }

    /// The frame's face slots as (leaf, face of its element): every leaf's first face, so that
    /// slot `li` is a face of leaf `li`, then the other faces of face clusters, leaf by leaf.
    pub fn face_slots(&self) -> Vec<(u32, u32)> {
        let n = self.leaves.len() as u32;
        let mut slots: Vec<(u32, u32)> = (0..n).map(|li| (li, 0)).collect();
        for li in 0..n {
            let faces = self.leaf_element(li as usize).faces.len() as u32;
            slots.extend((1..faces).map(|k| (li, k)));
        }
        slots
    }

    /// Number of table rows (hierarchy nodes).
    pub fn rows(&self) -> usize {
        self.hierarchy.len()
    }
}

/// Power-iteration rounds at most for [`System::conserve_energy`] (a closed box converges to
/// 10⁻¹² in about 30).
pub const POWER_ROUNDS: usize = 200;

/// The spectral radius of `sys`'s transport at albedo one (every leaf white and Lambertian),
/// antiradiance on or off: power iteration from uniform radiance on every front, the flux ratio
/// of successive propagations until it changes by less than 10⁻¹² (relative). One channel of
/// exactly the solver's operations ([`crate::solver`]: global with the links' spreading rows,
/// push, the local pass's reflection and antiradiance, pull), so it needs a third of the
/// memory of the solver's tables.
fn transport_radius(sys: &System, antiradiance: bool) -> Option<f64> {
    let (rows, m) = (sys.rows(), sys.bins.count);
    let mut l_in = vec![0.0; rows * m];
    let mut l_push = vec![0.0; rows * m];
    let cos: Vec<Vec<f64>> = sys
        .leaves
        .iter()
        .map(|l| sys.bins.centers.iter().map(|c| c.dot(l.normal)).collect())
        .collect();
    let flux = |i_ex: &[f64]| -> f64 {
        sys.leaves
            .iter()
            .zip(&cos)
            .map(|(l, cj)| {
                let row = &i_ex[l.node as usize * m..(l.node as usize + 1) * m];
                row.iter()
                    .zip(cj)
                    .filter(|(_, &c)| c > 0.0)
                    .map(|(v, _)| v)
                    .sum::<f64>()
            })
            .sum()
    };
    // Local pass (white Lambertian): front bins a·c·cos·(E/π − L), back bins −a·c·|cos|·L.
    let local = |i_ex: &mut [f64], l_push: &[f64]| {
        for (l, cj) in sys.leaves.iter().zip(&cos) {
            let r = l.node as usize;
            let lp = &l_push[r * m..(r + 1) * m];
            let e: f64 = lp
                .iter()
                .zip(cj)
                .filter(|(_, &c)| c < 0.0)
                .map(|(v, c)| v * -c)
                .sum::<f64>()
                * sys.bins.omega
                * l.cos_norm;
            let row = &mut i_ex[r * m..(r + 1) * m];
            for j in 0..m {
                let k = l.area * l.cos_norm;
                row[j] = if cj[j] > 0.0 {
                    // Light arriving at the back is blocked (the local pass's front bins).
                    let blocked = if antiradiance && l.blocks_back {
                        lp[j]
                    } else {
                        0.0
                    };
                    k * cj[j] * (e / std::f64::consts::PI - blocked)
                } else if cj[j] < 0.0 && antiradiance {
                    k * cj[j] * lp[j]
                } else {
                    0.0
                };
            }
        }
        receivers::pull_sums(sys, i_ex);
    };
    // Uniform radiance 1 everywhere to start from.
    let mut i_ex = receivers::unit_field(sys);
    let mut lambda = f64::NAN;
    for _ in 0..POWER_ROUNDS {
        let before = flux(&i_ex);
        receivers::gather(sys, &i_ex, &mut l_in);
        receivers::push_down(sys, &l_in, &mut l_push);
        local(&mut i_ex, &l_push);
        let ratio = flux(&i_ex) / before;
        if !ratio.is_finite() || ratio <= 0.0 {
            return None;
        }
        if (ratio - lambda).abs() <= 1e-12 * ratio {
            return Some(ratio);
        }
        lambda = ratio;
        i_ex.iter_mut().for_each(|v| *v /= ratio);
    }
    None
}

/// True when the scene's triangles form closed, consistently oriented surfaces: every edge is
/// used as often in one direction as in the other (by exact coordinates, as shared vertices or
/// coincident corners give them; T-junctions count as open). Then no open edge can be swept
/// across, and the net number of surfaces a ray from a leaf crosses (front faces minus backs,
/// what U plus antiradiance delivers from a uniform field) is the same in every direction.
pub fn closed_surfaces(scene: &Scene) -> bool {
    let key = |p: DVec3| [p.x + 0.0, p.y + 0.0, p.z + 0.0].map(f64::to_bits);
    let mut edges: HashMap<([u64; 3], [u64; 3]), i64> = HashMap::new();
    for mesh in &scene.meshes {
        for t in &mesh.triangles {
            for i in 0..3 {
                let a = key(mesh.positions[t[i] as usize]);
                let b = key(mesh.positions[t[(i + 1) % 3] as usize]);
                match a.cmp(&b) {
                    std::cmp::Ordering::Less => *edges.entry((a, b)).or_default() += 1,
                    std::cmp::Ordering::Greater => *edges.entry((b, a)).or_default() -= 1,
                    std::cmp::Ordering::Equal => {}
                }
            }
        }
    }
    !edges.is_empty() && edges.values().all(|&c| c == 0)
}

/// Lobe factors of every glossy leaf (in parallel) and each leaf's block index.
pub(crate) fn lobe_factors(
    leaves: &[LeafAttributes],
    lobes: &[Option<DiscreteLobe>],
    bins: &Bins,
) -> (Vec<f32>, Vec<u32>) {
    use rayon::prelude::*;
    let mut slot = vec![u32::MAX; leaves.len()];
    let glossy: Vec<usize> = (0..leaves.len())
        .filter(|&i| lobes[leaves[i].material as usize].is_some())
        .collect();
    for (k, &i) in glossy.iter().enumerate() {
        slot[i] = k as u32;
    }
    let albedo: Vec<Option<crate::brdf::AlbedoTable>> = lobes
        .iter()
        .map(|l| l.map(|l| crate::brdf::AlbedoTable::new(l.ns)))
        .collect();
    let norm: Vec<f32> = glossy
        .par_iter()
        .flat_map_iter(|&i| {
            let l = &leaves[i];
            let lobe = lobes[l.material as usize].expect("glossy leaf");
            let table = albedo[l.material as usize].as_ref().expect("glossy leaf");
            lobe.factors_with(bins, l.normal, l.cos_norm, |ct| table.at(ct))
                .into_iter()
                .map(|f| f as f32)
        })
        .collect();
    (norm, slot)
}
