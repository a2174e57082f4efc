//! Random numbers and the sampling routines of the path tracer: a PCG32 generator seeded per
//! pixel (so images do not depend on thread scheduling), cosine-weighted and Phong-lobe
//! directions, uniform points on triangles and a discrete distribution over emitters.

use glam::DVec3;
use std::f64::consts::PI;

/// PCG32 (O'Neill, XSH-RR): small, fast and statistically sound for Monte Carlo.
#[derive(Debug, Clone)]
pub struct Rng {
    state: u64,
    inc: u64,
}

/// SplitMix64 finalizer: decorrelates nearby seeds (pixel indices).
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

impl Rng {
    /// A generator for stream `stream` (e.g. a pixel index) of run seed `seed`.
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut r = Self {
            state: 0,
            inc: (mix(stream ^ 0x9e37_79b9_7f4a_7c15) << 1) | 1,
        };
        r.next_u32();
        r.state = r.state.wrapping_add(mix(seed));
        r.next_u32();
        r
    }

    /// Next 32 random bits.
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1) with 53 random bits.
    pub fn uniform(&mut self) -> f64 {
        let hi = (self.next_u32() as u64) << 21;
        let lo = (self.next_u32() >> 11) as u64;
        (hi | lo) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// An orthonormal basis `(t, b)` completing the unit vector `n` (Duff et al. 2017).
pub fn basis(n: DVec3) -> (DVec3, DVec3) {
    let s = 1f64.copysign(n.z);
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + s * n.x * n.x * a, s * b, -s * n.x),
        DVec3::new(b, s + n.y * n.y * a, -n.y),
    )
}

/// Direction around `axis` with density `cos^k(θ)·(k+1)/(2π)` (k = 1 gives the cosine-weighted
/// hemisphere, density cos θ/π).
pub fn sample_power_cosine(axis: DVec3, k: f64, u1: f64, u2: f64) -> DVec3 {
    let cos = (1.0 - u1).powf(1.0 / (k + 1.0));
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = 2.0 * PI * u2;
    let (t, b) = basis(axis);
    (t * (sin * phi.cos()) + b * (sin * phi.sin()) + axis * cos).normalize()
}

/// Density of [`sample_power_cosine`] at a direction making cosine `cos` with the axis.
pub fn power_cosine_pdf(k: f64, cos: f64) -> f64 {
    if cos <= 0.0 {
        0.0
    } else {
        (k + 1.0) / (2.0 * PI) * cos.powf(k)
    }
}

/// Uniform point on the triangle `c` from two uniform numbers.
pub fn sample_triangle(c: &[DVec3; 3], u1: f64, u2: f64) -> DVec3 {
    let su = u1.sqrt();
    c[0] * (1.0 - su) + c[1] * (su * (1.0 - u2)) + c[2] * (su * u2)
}

/// A discrete distribution proportional to non-negative weights (inverse-CDF sampling).
#[derive(Debug, Clone, Default)]
pub struct Discrete {
    cdf: Vec<f64>,
    total: f64,
}

impl Discrete {
    /// The distribution of `weights` (all zero or empty: nothing can be sampled).
    pub fn new(weights: &[f64]) -> Self {
        let mut acc = 0.0;
        let cdf = weights
            .iter()
            .map(|w| {
                acc += w.max(0.0);
                acc
            })
            .collect();
        Self { cdf, total: acc }
    }

    /// True when nothing can be sampled.
    pub fn is_empty(&self) -> bool {
        !(self.total > 0.0)
    }

    /// An index drawn with probability weight/total.
    pub fn sample(&self, u: f64) -> usize {
        let x = u * self.total;
        self.cdf
            .partition_point(|&c| c <= x)
            .min(self.cdf.len() - 1)
    }

    /// Probability of index `i`.
    pub fn pmf(&self, i: usize) -> f64 {
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        (self.cdf[i] - lo) / self.total
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_numbers_are_uniform_and_streams_differ() {
        let mut r = Rng::new(7, 3);
        let n = 100_000;
        let mean = (0..n).map(|_| r.uniform()).sum::<f64>() / n as f64;
        assert!((mean - 0.5).abs() < 0.005, "{mean}");
        let (mut a, mut b) = (Rng::new(7, 3), Rng::new(7, 4));
        assert_ne!(a.next_u32(), b.next_u32());
        assert_eq!(Rng::new(1, 2).next_u32(), Rng::new(1, 2).next_u32());
    }

    #[test]
    fn power_cosine_sampling_matches_its_density() {
        // Under density (k+1)/(2π)·cos^k θ, E[cos θ] = (k+1)/(k+2); and the density integrates
        // to one over the hemisphere (midpoint rule in θ).
        let mut r = Rng::new(1, 1);
        let axis = DVec3::new(0.3, -0.2, 0.9).normalize();
        for k in [1.0, 10.0, 1000.0] {
            let n = 200_000;
            let mean = (0..n)
                .map(|_| sample_power_cosine(axis, k, r.uniform(), r.uniform()).dot(axis))
                .sum::<f64>()
                / n as f64;
            let want = (k + 1.0) / (k + 2.0);
            assert!(
                (mean - want).abs() < 3e-3 * want,
                "k={k}: E[cos] {mean} vs {want}"
            );
            let steps = 20_000;
            let integral: f64 = (0..steps)
                .map(|i| {
                    let th = (i as f64 + 0.5) / steps as f64 * PI / 2.0;
                    power_cosine_pdf(k, th.cos()) * 2.0 * PI * th.sin() * (PI / 2.0 / steps as f64)
                })
                .sum();
            assert!((integral - 1.0).abs() < 1e-3, "k={k}: ∫pdf = {integral}");
        }
    }

    #[test]
    fn discrete_distribution_follows_weights() {
        let d = Discrete::new(&[1.0, 0.0, 3.0]);
        assert!((d.pmf(0) - 0.25).abs() < 1e-12 && d.pmf(1) == 0.0);
        assert_eq!(d.sample(0.1), 0);
        assert_eq!(d.sample(0.3), 2);
        assert_eq!(d.sample(0.999_999), 2);
        assert!(Discrete::new(&[]).is_empty() && Discrete::new(&[0.0]).is_empty());
    }
}
