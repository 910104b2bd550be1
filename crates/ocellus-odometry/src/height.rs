//! Following the camera height through the image-scale change (robust mode, SPEC 6.5).
//!
//! Each robust fit gives the image-scale change k between two frames: frame n is frame n-1
//! magnified by 1 + k, so the camera came down by the factor 1 / (1 + k). Integrating k
//! follows a height that oscillates as the robot rocks; but k carries noise, which integrated
//! wanders without bound and, on a floor whose height is constant, only adds drift. Two
//! guards:
//!
//! - **Pull.** The followed height loses a share of its offset from the calibrated height
//!   every frame ([`crate::robust::RobustConfig::height_pull`]), which bounds the random walk.
//! - **Shrinkage by the measured signal-to-noise ratio.** Each k is multiplied by the Wiener
//!   gain `max(0, 1 - noise / power)`, with `power` the running mean of k^2 and `noise` the
//!   running mean of `(k_n - k_(n-1))^2 / 2`. A true height change is smooth from frame to
//!   frame, so differencing removes it and leaves twice the variance of k's noise: on a floor
//!   whose height does not change, power and noise agree and k is mostly discarded; on a
//!   rocking robot, power exceeds noise by orders of magnitude and k is used whole. Both
//!   means are exponential over [`crate::robust::RobustConfig::height_noise_frames`] frames
//!   (plain means until that many frames were seen).

/// The state of the height follower: the followed height as a share of the calibrated one,
/// and the running moments of the scale change.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeightFollower {
    /// Followed height over the calibrated height.
    ratio: f64,
    /// Scale changes seen.
    seen: u64,
    /// Running mean of k^2.
    power: f64,
    /// Running mean of (k_n - k_(n-1))^2 / 2.
    noise: f64,
    /// The last scale change.
    last: f64,
}

impl Default for HeightFollower {
    fn default() -> Self {
        Self { ratio: 1.0, seen: 0, power: 0.0, noise: 0.0, last: 0.0 }
    }
}

impl HeightFollower {
    /// The followed height over the calibrated height (1 at the start).
    pub fn ratio(&self) -> f64 {
        self.ratio
    }

    /// The gain the next scale change would be shrunk by, in [0, 1] (1 until two changes
    /// were seen; 1 with `window_frames = 0`).
    pub fn gain(&self, window_frames: f64) -> f64 {
        if window_frames == 0.0 || self.seen < 2 || self.power <= 0.0 {
            return 1.0;
        }
        (1.0 - self.noise / self.power).clamp(0.0, 1.0)
    }

    /// Takes one frame's scale change `k` (frame n is frame n-1 magnified by 1 + k) with
    /// the pull toward the calibrated height `pull` (per frame, in [0, 1]) and the window of
    /// the noise estimate `window_frames` (0: no shrinkage); returns the new ratio. The
    /// running moments take k first, so the gain k is shrunk by includes it; the first
    /// change, with no difference to read the noise from, is followed whole.
    pub fn update(&mut self, k: f64, pull: f64, window_frames: f64) -> f64 {
        self.seen += 1;
        let a = if window_frames > 0.0 { (1.0 / self.seen as f64).max(1.0 / window_frames) } else { 1.0 };
        self.power += a * (k * k - self.power);
        if self.seen >= 2 {
            // The first difference has one frame fewer: its mean starts a frame later.
            let b = if window_frames > 0.0 { (1.0 / (self.seen - 1) as f64).max(1.0 / window_frames) } else { 1.0 };
            let d = k - self.last;
            self.noise += b * (0.5 * d * d - self.noise);
        }
        self.last = k;
        let used = k * self.gain(window_frames);
        self.ratio = 1.0 + (self.ratio / (1.0 + used) - 1.0) * (1.0 - pull);
        self.ratio
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ocellus_image::rng::SplitMix64;

    /// The scale changes of a camera whose height follows `height(n)` (ratio to the
    /// calibrated one), with white noise of `sigma` added.
    fn changes(height: impl Fn(usize) -> f64, sigma: f64, n: usize, seed: u64) -> Vec<f64> {
        let mut rng = SplitMix64::new(seed);
        (1..n).map(|i| height(i - 1) / height(i) - 1.0 + sigma * rng.normal()).collect()
    }

    #[test]
    fn without_noise_or_shrinkage_the_height_is_followed_exactly() {
        let h = |i: usize| 1.0 + 0.01 * (i as f64 * std::f64::consts::TAU / 37.0).sin();
        let mut f = HeightFollower::default();
        for (i, k) in changes(h, 0.0, 200, 1).into_iter().enumerate() {
            let r = f.update(k, 0.0, 0.0);
            assert!((r - h(i + 1)).abs() < 1e-12, "{i}: {r} vs {}", h(i + 1));
        }
    }

    #[test]
    fn a_constant_height_discards_most_of_the_noise() {
        // Noise of 4e-5 per frame, the noisiest real floor's: integrated over 2000 frames
        // with the default pull, against shrunk.
        let (pull, window) = (0.002, 32.0);
        let mut spread = [0.0f64; 2];
        for seed in 0..20 {
            for (j, w) in [0.0, window].into_iter().enumerate() {
                let mut f = HeightFollower::default();
                let mut sq = 0.0;
                for k in changes(|_| 1.0, 4e-5, 2000, seed) {
                    sq += (f.update(k, pull, w) - 1.0).powi(2);
                }
                spread[j] += sq / 2000.0 / 20.0;
            }
        }
        // Unshrunk: the pulled random walk's variance sigma^2 / (2 pull) = (6.3e-4)^2.
        let unshrunk = spread[0].sqrt();
        assert!((unshrunk / 6.3e-4 - 1.0).abs() < 0.3, "{unshrunk}");
        assert!(spread[1].sqrt() < 0.4 * unshrunk, "{} vs {unshrunk}", spread[1].sqrt());
    }

    #[test]
    fn a_rocking_camera_is_still_followed() {
        // The hard floors' oscillation: 1 % over 37 frames, with noise of 2e-5.
        let h = |i: usize| 1.0 + 0.01 * (i as f64 * std::f64::consts::TAU / 37.0).sin();
        let mut f = HeightFollower::default();
        let mut worst = 0.0f64;
        for (i, k) in changes(h, 2e-5, 400, 3).into_iter().enumerate() {
            let r = f.update(k, 0.0, 32.0);
            if i > 50 {
                worst = worst.max((r - h(i + 1)).abs());
                assert!(f.gain(32.0) > 0.95, "{i}: gain {}", f.gain(32.0));
            }
        }
        // Within a tenth of the amplitude after the start.
        assert!(worst < 1e-3, "{worst}");
    }
}
