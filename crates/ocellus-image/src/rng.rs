//! SplitMix64 (Steele, Lea & Flood 2014): a small, seeded, reproducible generator for every
//! random choice in ocellus (metric jitter and sampling, synthetic sensor noise, ...). The
//! same seed gives the same sequence on every platform.

/// Seeded generator (not for cryptography).
#[derive(Clone, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// A generator starting from `seed`.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform integer in [0, n), n > 0.
    pub fn below(&mut self, n: usize) -> usize {
        ((self.next_u64() as u128 * n as u128) >> 64) as usize
    }

    /// Standard normal deviate (Box-Muller; one of the pair is discarded for simplicity).
    pub fn normal(&mut self) -> f64 {
        // 1 - unit() is in (0, 1], so the log is finite.
        let (u1, u2) = (1.0 - self.unit(), self.unit());
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }

    /// Two independent standard normal deviates (both of a Box-Muller pair: one logarithm
    /// and one `sin_cos` for two draws, where hot loops need many). The first equals what
    /// [`Self::normal`] returns from the same state.
    pub fn normal_pair(&mut self) -> (f64, f64) {
        let (u1, u2) = (1.0 - self.unit(), self.unit());
        let rho = (-2.0 * u1.ln()).sqrt();
        let (s, c) = (2.0 * std::f64::consts::PI * u2).sin_cos();
        (rho * c, rho * s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reproducible_and_moments_are_right() {
        let (mut a, mut b) = (SplitMix64::new(7), SplitMix64::new(7));
        assert!((0..100).all(|_| a.next_u64() == b.next_u64()));
        let mut r = SplitMix64::new(1);
        let n = 200_000;
        let v: Vec<f64> = (0..n).map(|_| r.normal()).collect();
        let m = v.iter().sum::<f64>() / n as f64;
        let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / n as f64;
        assert!(m.abs() < 0.01 && (var - 1.0).abs() < 0.02, "mean {m}, var {var}");
        assert!((0..1000).all(|_| r.below(7) < 7));
        // The pair: the first is normal()'s; both standard and uncorrelated.
        let (mut p, mut q) = (SplitMix64::new(3), SplitMix64::new(3));
        assert_eq!(p.normal_pair().0, q.normal());
        let pairs: Vec<(f64, f64)> = (0..n).map(|_| r.normal_pair()).collect();
        let (sa, sb, sab) = pairs.iter().fold((0.0, 0.0, 0.0), |(a, b, c), &(x, y)| (a + x * x, b + y * y, c + x * y));
        let nf = n as f64;
        assert!((sa / nf - 1.0).abs() < 0.02 && (sb / nf - 1.0).abs() < 0.02 && (sab / nf).abs() < 0.01);
    }
}
