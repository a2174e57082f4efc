//! The constant environment as direct light (§3.3's direct-light initialization: "no
//! antiradiance is generated in this pass, because shadowing of the direct illumination is done"
//! by the light's own visibility). Per leaf and incident bin, the environment's radiance times
//! the fraction of rays toward it that escape the scene. Carried unoccluded into every leaf, the
//! sky had to be cancelled by antiradiance through every wall and blind between it and the
//! room, which the discretization does not do well (the breakfast room was 1.9× too bright;
//! issue 36's closed box under an environment lit its corners).

use crate::bins::square_to_direction;
use crate::raycast::RayCaster;
use crate::solver::Table;
use crate::system::System;
use glam::DVec3;
use rayon::prelude::*;

/// Rays per leaf and incident bin first, each from its own point of the leaf and direction in
/// its half of the bin's cell of the equal-area grid.
pub const RAYS_PER_BIN: u32 = 2;
/// Where those disagree, or a neighbouring bin was judged otherwise (the bin may see the sky in
/// part), this many more on a jittered 8 × 4 grid of the cell decide its visible fraction alone
/// (the roof of `tests/sky.rs`: 16 left its floor 4.9% off at worst, 32 3.5%, 64 3.1%).
pub const EDGE_RAYS: u32 = 32;

/// Incident environment radiance per node (leaf rows) and bin, by bins of travel direction (the
/// convention of [`super::lights::direct_in_table`]): `env` times the fraction of rays from the
/// leaf against that travel direction that escape ([`RAYS_PER_BIN`], then [`EDGE_RAYS`] where
/// those disagree). With nothing
/// around a leaf its bins hold `env` and the bin quadrature gives `π·env`. Returns the table and
/// the rays cast.
pub fn environment_in_table(sys: &System, env: DVec3, caster: &RayCaster) -> (Table, u64) {
    let bins = &sys.bins;
    let m = bins.count;
    let root = &sys.hierarchy.nodes[0];
    // Off the surface by a scale-relative distance (as progressive refinement's rays).
    let eps = 1e-5 * (root.radius + root.center.abs().max_element()).max(1e-300);
    let rows: Vec<(usize, Vec<DVec3>, u64)> = (0..sys.leaves.len())
        .into_par_iter()
        .map(|li| {
            let (fractions, rays) = visible_fractions(sys, li, caster, eps);
            let row = fractions.iter().map(|&v| env * v).collect();
            (sys.leaves[li].node as usize, row, rays)
        })
        .collect();
    let mut t = Table::zeros(sys.rows(), m);
    let mut rays = 0;
    for (node, row, r) in rows {
        t.row_mut(node).copy_from_slice(&row);
        rays += r;
    }
    (t, rays)
}

/// Per incident bin of leaf `li`, the cosine-weighted fraction of its directions that see the
/// sky (0 for bins behind the leaf), and the rays cast: [`RAYS_PER_BIN`] per bin, then
/// [`EDGE_RAYS`] where those disagree or a neighbouring bin of the grid was judged otherwise (the
/// sky's edge crosses those; two rays alike in a bin it cuts would judge it whole).
fn visible_fractions(sys: &System, li: usize, caster: &RayCaster, eps: f64) -> (Vec<f64>, u64) {
    let bins = &sys.bins;
    let (nu, nv) = (bins.nu, bins.nv);
    let n = sys.leaves[li].normal;
    let e = sys.leaf_element(li);
    let mut rays = 0u64;
    // Ray k of su × sv strata of bin j's cell: its cosine to the normal and whether it escapes.
    let mut cast = |j: usize, k: u32, su: u32, sv: u32| -> (f64, bool) {
        let h = uniforms(li as u64, j as u64, (k + su * sv * 7) as u64);
        let (iu, iv) = ((j % nu) as f64, (j / nu) as f64);
        let (ku, kv) = ((k % su) as f64, (k / su) as f64);
        let u = (iu + (ku + h[0]) / su as f64) / nu as f64 * 2.0 - 1.0;
        let v = (iv + (kv + h[1]) / sv as f64) / nv as f64 * 2.0 - 1.0;
        // Toward the sky: against the travel direction; a direction of the cell that grazes or
        // passes the plane is replaced by the bin's center.
        let mut d = -square_to_direction(u, v);
        if d.dot(n) < 0.05 {
            d = -bins.centers[j];
        }
        let p = e.point(h[2], h[3]) + n * eps;
        rays += 1;
        (d.dot(n), !caster.occluded(p, d, 0.0, f64::INFINITY))
    };
    let front: Vec<bool> = bins.centers.iter().map(|c| -c.dot(n) > 0.0).collect();
    // First pass: 0 all blocked, 1 all open, 2 mixed (u8::MAX behind the leaf).
    let class: Vec<u8> = (0..bins.count)
        .map(|j| {
            if !front[j] {
                return u8::MAX;
            }
            let open = (0..RAYS_PER_BIN).filter(|&k| cast(j, k, 2, 1).1).count() as u32;
            match open {
                0 => 0,
                o if o == RAYS_PER_BIN => 1,
                _ => 2,
            }
        })
        .collect();
    let differs = |j: usize| {
        let (iu, iv) = (j % nu, j / nu);
        let mut near = Vec::with_capacity(4);
        if iu > 0 {
            near.push(j - 1);
        }
        if iu + 1 < nu {
            near.push(j + 1);
        }
        if iv > 0 {
            near.push(j - nu);
        }
        if iv + 1 < nv {
            near.push(j + nu);
        }
        near.into_iter()
            .any(|k| class[k] != u8::MAX && class[k] != class[j])
    };
    let fractions = (0..bins.count)
        .map(|j| match class[j] {
            u8::MAX => 0.0,
            c if c == 2 || differs(j) => {
                // The cosine-weighted visible fraction: where only part of the bin sees the
                // sky, that part's own cosines weigh it.
                let s: Vec<(f64, bool)> = (0..EDGE_RAYS).map(|k| cast(j, k, 8, 4)).collect();
                let all: f64 = s.iter().map(|x| x.0).sum();
                s.iter().filter(|x| x.1).map(|x| x.0).sum::<f64>() / all
            }
            c => c as f64,
        })
        .collect();
    (fractions, rays)
}

/// [`environment_in_table`] of `env`, or `None` where there is no environment.
pub fn shadowed(sys: &System, env: DVec3, caster: &RayCaster) -> Option<Table> {
    (env != DVec3::ZERO).then(|| environment_in_table(sys, env, caster).0)
}

/// Four uniforms in [0, 1) from a hash of (leaf, bin, ray): the same table on every run and any
/// number of threads.
fn uniforms(a: u64, b: u64, c: u64) -> [f64; 4] {
    let mut z = a
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add(b.wrapping_mul(0xD1B5_4A32_D192_ED03))
        .wrapping_add(c.wrapping_mul(0x8CB9_2BA7_2F3D_8DD7));
    let mut next = || {
        z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut x = z;
        x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        x ^= x >> 31;
        (x >> 11) as f64 / (1u64 << 53) as f64
    };
    [next(), next(), next(), next()]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An open plane under a sky of 1 receives π (the bin quadrature's cosine normalization).
    /// The closed box under a sky is `tests/known_answers.rs`.
    #[test]
    fn an_open_plane_sees_the_sky_and_a_closed_box_does_not() {
        let sys = System::build(&crate::scene::test_plane(0.0)).unwrap();
        let caster = RayCaster::new(&sys);
        let (t, rays) = environment_in_table(&sys, DVec3::ONE, &caster);
        assert!(rays > 0);
        for leaf in &sys.leaves {
            let row = t.row(leaf.node as usize);
            let e: f64 = sys
                .bins
                .centers
                .iter()
                .zip(row)
                .map(|(c, l)| (-c.dot(leaf.normal)).max(0.0) * l.x)
                .sum::<f64>()
                * sys.bins.omega
                * leaf.cos_norm;
            assert!((e - std::f64::consts::PI).abs() < 1e-9, "{e}");
        }
    }
}
