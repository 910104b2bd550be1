//! Context chaos degree (seed 001, section 3.5; SPEC 2.2): how unfamiliar the current context is.
//!
//! From three successive grey frames `I_(k-2)`, `I_(k-1)`, `I_k`, two motion maps
//! `M_1 = |I_(k-1) - I_(k-2)|` and `M_2 = |I_k - I_(k-1)|`; their histograms (`bins` bins
//! over `[0, max_difference]`, larger differences in the last bin), normalized to
//! probabilities and smoothed as `(h + eps) / (1 + bins * eps)` with `eps =
//! empty_bin_probability` (so the divergence is always finite); the chaos degree is the
//! relative entropy `s = KL(h_2 || h_1)` in bits: the new motion statistics measured against
//! the expectation set by the previous ones. The context is familiar when `s < threshold`
//! (seed: S = 1.0).
//!
//! What S = 1 bit means with the default `eps = 1e-9`: a fraction f of the pixels moving into
//! bins that were empty adds about `f log2(f / (bins eps))` bits, so S is crossed when
//! roughly 4 % of the view changes suddenly; a few noisy pixels add hundredths of a bit.
//!
//! The frames may be any resolution; the saliency engine's intensity pyramid level 2 (160x120
//! for 640x480) costs a sixteenth of full size and removes most sensor noise. Each update
//! costs one difference and one histogram: the previous histogram is kept.

use crate::{AttentionError, Result};
use ocellus_image::Plane;
use serde::{Deserialize, Serialize};

/// Parameters of [`ChaosDegree`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChaosConfig {
    /// Histogram bins of the motion maps.
    pub bins: usize,
    /// Absolute grey difference (grey values in [0, 1]) at the top of the last bin.
    pub max_difference: f32,
    /// Probability floor of every bin (smoothing; see the module documentation).
    pub empty_bin_probability: f64,
    /// Threshold S: the context is familiar when the chaos degree is below it.
    pub threshold: f64,
}

impl Default for ChaosConfig {
    fn default() -> Self {
        Self { bins: 64, max_difference: 1.0, empty_bin_probability: 1e-9, threshold: 1.0 }
    }
}

impl ChaosConfig {
    /// Checks the ranges.
    pub fn validate(&self) -> Result<()> {
        use ocellus_image::check;
        (|| {
            check::within("chaos bins", self.bins, 2, 65_536)?;
            check::positive("chaos max_difference", self.max_difference)?;
            check::between("chaos empty_bin_probability", self.empty_bin_probability, 0.0, 0.1)?;
            check::finite("chaos threshold", self.threshold)
        })()
        .map_err(AttentionError::InvalidConfig)
    }
}

/// Chaos degree over a stream of grey frames of one size.
#[derive(Debug)]
pub struct ChaosDegree {
    cfg: ChaosConfig,
    prev: Plane<f32>,
    /// Counts of the previous motion map, and of the current one.
    hist_prev: Vec<f64>,
    hist: Vec<f64>,
    /// Scratch: four interleaved integer histograms (see [`histogram_into`]).
    counts: Vec<u32>,
    frames: usize,
}

impl ChaosDegree {
    /// A chaos-degree tracker.
    pub fn new(cfg: ChaosConfig) -> Result<Self> {
        cfg.validate()?;
        Ok(Self {
            hist_prev: vec![0.0; cfg.bins],
            hist: vec![0.0; cfg.bins],
            counts: vec![0; 4 * cfg.bins],
            prev: Plane::default(),
            frames: 0,
            cfg,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &ChaosConfig {
        &self.cfg
    }

    /// `true` when `s` is below the threshold S (familiar context: top-down attention).
    pub fn is_familiar(&self, s: f64) -> bool {
        s < self.cfg.threshold
    }

    /// Forgets the past frames.
    pub fn reset(&mut self) {
        self.frames = 0;
    }

    /// Adds a frame (grey, finite); returns the chaos degree in bits once three frames of the
    /// same size have been seen, else `None`. A size change restarts the count.
    pub fn update(&mut self, grey: &Plane<f32>) -> Result<Option<f64>> {
        let bad = || AttentionError::InvalidInput("chaos degree needs a non-empty, finite frame".into());
        if grey.is_empty() {
            return Err(bad());
        }
        if grey.size() != self.prev.size() {
            self.frames = 0;
        }
        if self.frames == 0 {
            if !grey.all_finite() {
                return Err(bad());
            }
            self.prev.resize(grey.width(), grey.height());
            self.prev.copy_from(grey);
            self.frames = 1;
            return Ok(None);
        }
        std::mem::swap(&mut self.hist, &mut self.hist_prev);
        // One pass: histogram of |I_t - I_(t-1)|, finiteness check, and I_t kept for next time.
        let finite =
            histogram_and_store(grey, &mut self.prev, self.cfg.max_difference, &mut self.counts, &mut self.hist);
        if !finite {
            self.frames = 0;
            return Err(bad());
        }
        let s = (self.frames >= 2)
            .then(|| relative_entropy_bits(&self.hist, &self.hist_prev, self.cfg.empty_bin_probability));
        self.frames += 1;
        Ok(s)
    }
}

/// Histogram (counts) of `|a - b|` over `out.len()` bins spanning `[0, max_difference]`;
/// differences beyond go to the last bin. `a` and `b` have the same size.
pub fn motion_histogram(a: &Plane<f32>, b: &Plane<f32>, max_difference: f32, out: &mut [f64]) {
    let mut counts = vec![0; 4 * out.len()];
    let mut b = b.clone();
    histogram_and_store(a, &mut b, max_difference, &mut counts, out);
}

/// [`motion_histogram`] of `a` against `b` that then copies `a` into `b`, with a scratch of
/// `4 * bins` counters: four histograms filled by interleaved pixels, so that runs of equal
/// bins (a still scene puts almost every pixel in bin 0) do not serialize on one counter.
/// Returns `false` if `a` has a non-finite value.
fn histogram_and_store(
    a: &Plane<f32>,
    b: &mut Plane<f32>,
    max_difference: f32,
    counts: &mut [u32],
    out: &mut [f64],
) -> bool {
    let n = out.len();
    if n == 0 {
        return true;
    }
    counts.iter_mut().for_each(|c| *c = 0);
    let scale = n as f32 / max_difference;
    let last = n - 1;
    let bin = |p: f32, q: f32| (((p - q).abs() * scale) as usize).min(last);
    let (c0, rest) = counts.split_at_mut(n);
    let (c1, rest) = rest.split_at_mut(n);
    let (c2, c3) = rest.split_at_mut(n);
    // p * 0 is 0 for finite p and NaN otherwise; the sum flags any non-finite pixel.
    let mut finite_probe = 0.0f32;
    for y in 0..a.height() {
        let (ra, rb) = (a.row(y), b.row_mut(y));
        let mut pa = ra.chunks_exact(4);
        let mut pb = rb.chunks_exact_mut(4);
        for (p, q) in pa.by_ref().zip(pb.by_ref()) {
            c0[bin(p[0], q[0])] += 1;
            c1[bin(p[1], q[1])] += 1;
            c2[bin(p[2], q[2])] += 1;
            c3[bin(p[3], q[3])] += 1;
            finite_probe += p[0] * 0.0 + p[1] * 0.0 + p[2] * 0.0 + p[3] * 0.0;
            q.copy_from_slice(p);
        }
        for (p, q) in pa.remainder().iter().zip(pb.into_remainder()) {
            c0[bin(*p, *q)] += 1;
            finite_probe += p * 0.0;
            *q = *p;
        }
    }
    for (k, o) in out.iter_mut().enumerate() {
        *o = (c0[k] as u64 + c1[k] as u64 + c2[k] as u64 + c3[k] as u64) as f64;
    }
    finite_probe == 0.0
}

/// `KL(p || q)` in bits between two histograms of counts, each normalized and smoothed as
/// `(h / total + eps) / (1 + bins * eps)`. Finite for any counts when `eps > 0`.
pub fn relative_entropy_bits(p: &[f64], q: &[f64], eps: f64) -> f64 {
    let dist = |h: &[f64]| {
        let total: f64 = h.iter().sum();
        let inv = if total > 0.0 { 1.0 / total } else { 0.0 };
        let norm = 1.0 + h.len() as f64 * eps;
        move |c: f64| (c * inv + eps) / norm
    };
    let (dp, dq) = (dist(p), dist(q));
    let kl: f64 = p
        .iter()
        .zip(q)
        .map(|(&a, &b)| {
            let (pa, qb) = (dp(a), dq(b));
            pa * (pa / qb).log2()
        })
        .sum();
    kl.max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_entropy_matches_hand_computation() {
        // eps = 0.25: p = (3/4 + 1/4, 1/4 + 1/4) / 1.5 = (2/3, 1/3); q = (1/3, 2/3).
        let kl = relative_entropy_bits(&[3.0, 1.0], &[1.0, 3.0], 0.25);
        let want = 2.0 / 3.0 * 2f64.log2() + 1.0 / 3.0 * 0.5f64.log2();
        assert!((kl - want).abs() < 1e-12);
        assert_eq!(relative_entropy_bits(&[5.0, 0.0], &[5.0, 0.0], 1e-9), 0.0);
        // All mass moved to an empty bin: log2((1 + eps) / eps) bits, about 29.9 for 1e-9.
        let k = relative_entropy_bits(&[0.0, 1e6], &[1e6, 0.0], 1e-9);
        assert!((k - 29.897).abs() < 0.01, "{k}");
        assert!(relative_entropy_bits(&[0.0, 0.0], &[1.0, 0.0], 1e-9).is_finite());
    }

    #[test]
    fn interleaved_histogram_equals_a_plain_count() {
        let a = Plane::from_fn(13, 7, |x, y| ((x * 31 + y * 17) % 97) as f32 / 97.0);
        let b = Plane::from_fn(13, 7, |x, y| ((x * 7 + y * 3) % 89) as f32 / 89.0);
        let mut h = vec![0.0; 10];
        motion_histogram(&a, &b, 0.8, &mut h);
        let mut want = vec![0.0; 10];
        for y in 0..7 {
            for x in 0..13 {
                let d = (a.get(x, y) - b.get(x, y)).abs();
                want[((d * 10.0 / 0.8) as usize).min(9)] += 1.0;
            }
        }
        assert_eq!(h, want);
    }

    #[test]
    fn histogram_bins_and_saturation() {
        let a = Plane::from_vec(4, 1, vec![0.0, 0.3, 0.6, 1.0]).unwrap();
        let b = Plane::new(4, 1);
        let mut h = vec![0.0; 4];
        motion_histogram(&a, &b, 0.5, &mut h);
        // 0 -> bin 0, 0.3 -> bin 2, 0.6 and 1.0 saturate to bin 3.
        assert_eq!(h, vec![1.0, 0.0, 1.0, 2.0]);
    }

    #[test]
    fn needs_three_frames_and_flags_a_sudden_change() {
        let mut c = ChaosDegree::new(ChaosConfig::default()).unwrap();
        let still = Plane::from_fn(32, 32, |x, y| ((x * 7 + y * 3) % 11) as f32 / 11.0);
        assert_eq!(c.update(&still).unwrap(), None);
        assert_eq!(c.update(&still).unwrap(), None);
        assert_eq!(c.update(&still).unwrap(), Some(0.0));
        let mut changed = still.clone();
        for y in 8..24 {
            for x in 8..24 {
                changed.set(x, y, 1.0 - still.get(x, y));
            }
        }
        let s = c.update(&changed).unwrap().unwrap();
        assert!(!c.is_familiar(s), "s = {s}");
        assert!(c.update(&Plane::new(8, 8)).unwrap().is_none(), "size change restarts");
        assert!(c.update(&Plane::from_fn(8, 8, |_, _| f32::NAN)).is_err());
        // A non-finite pixel in a later frame (the fused histogram pass) is caught too.
        let mut d = ChaosDegree::new(ChaosConfig::default()).unwrap();
        d.update(&still).unwrap();
        let mut bad = still.clone();
        bad.set(31, 31, f32::INFINITY);
        assert!(d.update(&bad).is_err());
    }
}
