//! Directional bins (§3.1): `m` bins of exactly equal solid angle `4π/m`.
//!
//! Directions are mapped to the square `[-1,1]²` with Clarberg's equal-area octahedral map
//! ("Fast equal-area mapping of the (hemi)sphere using SIMD", JGT 2008). Because the map preserves
//! area, any `nu × nv` grid on the square gives bins of identical solid angle, and the
//! direction→bin lookup is a handful of arithmetic operations that `glsl/bins.glsl` repeats.

use crate::error::{Error, Result};
use glam::DVec3;
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// Smallest and largest supported bin counts.
pub const MIN_BINS: usize = 8;
/// Largest supported bin count (rows of the filter tables grow as m²).
pub const MAX_BINS: usize = 4096;

/// Maps a unit direction to the equal-area square `[-1,1]²`.
pub fn direction_to_square(d: DVec3) -> (f64, f64) {
    let r = (1.0 - d.z.abs()).max(0.0).sqrt();
    let phi = d.y.abs().atan2(d.x.abs());
    let mut v = r * phi / FRAC_PI_2;
    let mut u = r - v;
    if d.z < 0.0 {
        let (uu, vv) = (1.0 - v, 1.0 - u);
        u = uu;
        v = vv;
    }
    (u.copysign(d.x), v.copysign(d.y))
}

/// Maps a point of the square `[-1,1]²` back to a unit direction (inverse of [`direction_to_square`]).
pub fn square_to_direction(u: f64, v: f64) -> DVec3 {
    let (au, av) = (u.abs(), v.abs());
    let sd = 1.0 - (au + av);
    let r = 1.0 - sd.abs();
    let phi = if r == 0.0 {
        0.0
    } else {
        ((av - au) / r + 1.0) * FRAC_PI_4
    };
    let z = (1.0 - r * r).copysign(sd);
    let s = r * (2.0 - r * r).max(0.0).sqrt();
    DVec3::new(phi.cos().copysign(u) * s, phi.sin().copysign(v) * s, z).normalize()
}

/// The direction at the center of cell `cell` (row-major) of an `nu × nv` grid on the
/// equal-area square (the bins' grid, or a finer one for lookups).
pub fn grid_cell_center(nu: usize, nv: usize, cell: usize) -> DVec3 {
    let (iu, iv) = ((cell % nu) as f64, (cell / nu) as f64);
    square_to_direction(
        (iu + 0.5) / nu as f64 * 2.0 - 1.0,
        (iv + 0.5) / nv as f64 * 2.0 - 1.0,
    )
}

/// Largest angle between a cell's center and any point of the cell, over all cells of an
/// `nu × nv` grid on the equal-area square (sampled along the cells' edges, with a 1% margin).
pub fn grid_cell_radius(nu: usize, nv: usize) -> f64 {
    let mut worst: f64 = 0.0;
    for cell in 0..nu * nv {
        let c = grid_cell_center(nu, nv, cell);
        let (iu, iv) = ((cell % nu) as f64, (cell / nu) as f64);
        for k in 0..=8 {
            let t = k as f64 / 8.0;
            for (fu, fv) in [(t, 0.0), (t, 1.0), (0.0, t), (1.0, t)] {
                let u = (iu + fu) / nu as f64 * 2.0 - 1.0;
                let v = (iv + fv) / nv as f64 * 2.0 - 1.0;
                worst = worst.max(square_to_direction(u, v).dot(c).clamp(-1.0, 1.0).acos());
            }
        }
    }
    worst * 1.01
}

/// The directional discretization: grid sizes, bin centers and the bin solid angle.
#[derive(Debug, Clone)]
pub struct Bins {
    /// Number of bins `m`.
    pub count: usize,
    /// Grid columns on the equal-area square.
    pub nu: usize,
    /// Grid rows on the equal-area square.
    pub nv: usize,
    /// Solid angle of every bin, exactly `4π/m`.
    pub omega: f64,
    /// Unit direction at the center of each bin's square cell.
    pub centers: Vec<DVec3>,
}

impl Bins {
    /// Builds `m` bins. `m` must factor as `nu·nv` with `nv ≤ 2·nu` so that cells stay compact.
    pub fn new(m: usize) -> Result<Self> {
        let (nu, nv) = grid_for(m)?;
        let centers = (0..m)
            .map(|b| {
                let (iu, iv) = (b % nu, b / nu);
                let u = (iu as f64 + 0.5) / nu as f64 * 2.0 - 1.0;
                let v = (iv as f64 + 0.5) / nv as f64 * 2.0 - 1.0;
                square_to_direction(u, v)
            })
            .collect();
        Ok(Self {
            count: m,
            nu,
            nv,
            omega: 4.0 * PI / m as f64,
            centers,
        })
    }

    /// Index of the bin that contains direction `d` (need not be normalized; must be non-zero).
    pub fn bin_of(&self, d: DVec3) -> usize {
        let (u, v) = direction_to_square(d.normalize());
        let iu = (((u + 1.0) * 0.5 * self.nu as f64) as usize).min(self.nu - 1);
        let iv = (((v + 1.0) * 0.5 * self.nv as f64) as usize).min(self.nv - 1);
        iv * self.nu + iu
    }

    /// Largest angle between a bin's center and any point of its cell
    /// ([`grid_cell_radius`] of the bins' grid): a direction's bin center is never farther.
    pub fn cell_radius(&self) -> f64 {
        grid_cell_radius(self.nu, self.nv)
    }

    /// Angular distance between neighbouring bin centers, `√(4π/m)`: the Gaussian's deviation (§3.1).
    pub fn spacing(&self) -> f64 {
        self.omega.sqrt()
    }

    /// `π / (ω_bin Σ_j max(0, n·ω_j))`: rescales the bin quadrature of the cosine so that a uniform
    /// field integrates to exactly π for this normal (used for emission, reflection and antiradiance).
    pub fn cosine_normalization(&self, n: DVec3) -> f64 {
        let s: f64 = self.centers.iter().map(|c| c.dot(n).max(0.0)).sum();
        PI / (s * self.omega)
    }
}

/// The most square factorisation `nu·nv = m` with `nv ≤ 2·nu`, if any.
fn factor(m: usize) -> Option<(usize, usize)> {
    let root = (m as f64).sqrt() as usize;
    let nu = (1..=root).rev().find(|nu| m % nu == 0)?;
    (m / nu <= 2 * nu).then_some((nu, m / nu))
}

/// Chooses the most square `nu × nv` factorisation of `m` with `nu ≤ nv ≤ 2·nu`.
fn grid_for(m: usize) -> Result<(usize, usize)> {
    if !(MIN_BINS..=MAX_BINS).contains(&m) {
        return Err(Error::Setting {
            field: "bins",
            message: format!("{m} is outside the supported range {MIN_BINS}..={MAX_BINS}"),
        });
    }
    if let Some(g) = factor(m) {
        return Ok(g);
    }
    let near: Vec<usize> = (m.saturating_sub(16)..=m + 16)
        .filter(|&k| (MIN_BINS..=MAX_BINS).contains(&k) && factor(k).is_some())
        .collect();
    Err(Error::Setting {
        field: "bins",
        message: format!(
            "{m} bins cannot be laid out as an nu×nv grid with nv ≤ 2·nu; nearby valid counts: {near:?}"
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_map_round_trips() {
        for i in 0..2000 {
            let t = i as f64 * 0.618_033_988_7;
            let z = 1.0 - 2.0 * ((i as f64 + 0.5) / 2000.0);
            let r = (1.0 - z * z).sqrt();
            let d = DVec3::new(r * (t * 2.0 * PI).cos(), r * (t * 2.0 * PI).sin(), z);
            let (u, v) = direction_to_square(d);
            assert!(u.abs() <= 1.0 + 1e-12 && v.abs() <= 1.0 + 1e-12);
            let back = square_to_direction(u, v);
            assert!((back - d).length() < 1e-9, "{d:?} -> ({u},{v}) -> {back:?}");
        }
    }

    #[test]
    fn solid_angles_sum_to_four_pi_and_are_equal() {
        // Monte-Carlo-free check: count a dense stratified set of directions per bin.
        for m in [32, 128, 200, 512, 1024] {
            let bins = Bins::new(m).unwrap();
            assert!((bins.omega * m as f64 - 4.0 * PI).abs() < 1e-12);
            let n = 400_000usize;
            let mut counts = vec![0usize; m];
            // Fibonacci sphere: close to uniform, so counts are proportional to solid angle.
            let golden = (1.0 + 5f64.sqrt()) / 2.0;
            for i in 0..n {
                let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
                let r = (1.0 - z * z).sqrt();
                let phi = 2.0 * PI * i as f64 / golden;
                counts[bins.bin_of(DVec3::new(r * phi.cos(), r * phi.sin(), z))] += 1;
            }
            let expect = n as f64 / m as f64;
            let total: f64 = counts.iter().map(|&c| c as f64 / n as f64 * 4.0 * PI).sum();
            assert!((total - 4.0 * PI).abs() < 1e-9);
            for (b, &c) in counts.iter().enumerate() {
                let rel = (c as f64 - expect).abs() / expect;
                assert!(rel < 0.03, "m={m} bin {b}: {c} samples vs {expect}");
            }
        }
    }

    #[test]
    fn direction_bin_center_round_trip() {
        for m in [32, 64, 128, 256, 512, 1024] {
            let bins = Bins::new(m).unwrap();
            for (b, c) in bins.centers.iter().enumerate() {
                assert!((c.length() - 1.0).abs() < 1e-12);
                assert_eq!(bins.bin_of(*c), b, "m={m}");
            }
        }
    }

    #[test]
    fn rejects_unfactorable_counts() {
        assert!(Bins::new(0).is_err());
        let e = Bins::new(127).unwrap_err().to_string();
        assert!(e.contains("bins") && e.contains("128"), "{e}");
        assert!(Bins::new(100_000).is_err());
    }

    /// `∫ f dω` over the sphere by a fine midpoint rule on the octahedral square: `sub × sub`
    /// cells per bin, each of solid angle ω/sub² (the map is equal-area), independent of the bin
    /// centers.
    fn fine_quadrature(bins: &Bins, sub: usize, f: impl Fn(DVec3) -> f64) -> f64 {
        let (nu, nv) = (bins.nu * sub, bins.nv * sub);
        let mut sum = 0.0;
        for iv in 0..nv {
            for iu in 0..nu {
                let u = (iu as f64 + 0.5) / nu as f64 * 2.0 - 1.0;
                let v = (iv as f64 + 0.5) / nv as f64 * 2.0 - 1.0;
                sum += f(square_to_direction(u, v));
            }
        }
        sum * 4.0 * PI / (nu * nv) as f64
    }

    /// The cosine normalization against the hemisphere integral `∫ cos⁺ dω = π`, computed by an
    /// independent fine quadrature: it integrates to π for every normal; the normalized bin
    /// quadrature of the cosine equals it; the raw bin quadrature is close to it (the correction
    /// is small); and a smooth non-uniform field integrates to its fine quadrature within the
    /// bins' resolution.
    #[test]
    fn cosine_normalization_matches_the_hemisphere_integral() {
        let golden = (1.0 + 5f64.sqrt()) / 2.0;
        let mut normals = vec![
            DVec3::X,
            DVec3::Y,
            DVec3::Z,
            -DVec3::Z,
            DVec3::ONE.normalize(),
        ];
        for i in 0..24 {
            let z = 1.0 - (2.0 * i as f64 + 1.0) / 24.0;
            let r = (1.0 - z * z).sqrt();
            let phi = 2.0 * PI * i as f64 / golden;
            normals.push(DVec3::new(r * phi.cos(), r * phi.sin(), z));
        }
        let a = DVec3::new(0.3, -0.5, 0.8).normalize();
        let field = |d: DVec3| 1.0 + 0.5 * a.dot(d) + 0.3 * (d.x * d.y);
        // Measured (worst over the normals): the fine quadrature of the cosine 1.9e-5 from π; the raw
        // bin quadrature 6.7e-2, 1.8e-2, 4.7e-3 and the smooth field 2.7e-2, 5.8e-3, 1.2e-3 at 32,
        // 128, 512 bins (bounds 1.5×: a property of the bins' geometry, not of rounding).
        for (m, raw_bound, field_bound) in [
            (32, 0.1, 4.1e-2),
            (128, 2.7e-2, 8.7e-3),
            (512, 7e-3, 1.8e-3),
        ] {
            let bins = Bins::new(m).unwrap();
            // About 130K fine cells whatever the bin count.
            let sub = ((131_072 / m) as f64).sqrt().round() as usize;
            let (mut fine_err, mut raw_err, mut field_err): (f64, f64, f64) = (0.0, 0.0, 0.0);
            for &n in &normals {
                let cos = |d: DVec3| d.dot(n).max(0.0);
                let exact = fine_quadrature(&bins, sub, cos);
                fine_err = fine_err.max((exact - PI).abs() / PI);
                let raw: f64 = bins.centers.iter().map(|&c| cos(c)).sum::<f64>() * bins.omega;
                raw_err = raw_err.max((raw - PI).abs() / PI);
                let k = bins.cosine_normalization(n);
                assert!(
                    (k * raw - exact).abs() < 1e-4 * PI,
                    "m={m} n={n:?}: {k}·{raw} vs {exact}"
                );
                let want = fine_quadrature(&bins, sub, |d| field(d) * cos(d));
                let got =
                    bins.centers.iter().map(|&c| field(c) * cos(c)).sum::<f64>() * bins.omega * k;
                field_err = field_err.max((got - want).abs() / want);
            }
            println!(
                "{m} bins: fine quadrature of the cosine {fine_err:.1e} from π, raw bin quadrature {raw_err:.2e}, smooth field {field_err:.2e}"
            );
            assert!(fine_err < 6e-5, "m={m}: fine quadrature {fine_err}");
            assert!(raw_err < raw_bound, "m={m}: raw quadrature {raw_err}");
            assert!(field_err < field_bound, "m={m}: smooth field {field_err}");
        }
    }
}
