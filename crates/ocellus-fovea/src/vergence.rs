//! Vergence (SPEC 4.3): the horizontal disparity at the gaze point of a rectified stereo
//! pair, for binocular tracking (turn the eyes until the disparity at the fovea is 0).
//!
//! The left eye's cortical image at the gaze point is compared with the right eye's at every
//! candidate position `gaze - (d, 0)`, by the zero-mean normalized correlation of the cells.
//! Cells are dense at the fovea and sparse outside, so the comparison weighs the fixated
//! surface most and its surroundings less, the way a foveal correlation window should. The
//! best integer disparity is refined by a parabola through its neighbours' scores.
//!
//! Disparity is `x_left - x_right`, pixels (SPEC 5.4), positive for points in front of
//! infinity on a rectified pair.

use crate::logpolar::{Fields, LogPolarConfig, LogPolarMap, Scratch};
use crate::{FoveaError, Result};
use ocellus_image::{Backend, Plane};

/// Parameters of the vergence search.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VergenceOptions {
    /// Log rings.
    pub rings: usize,
    /// Sectors.
    pub sectors: usize,
    /// Fovea radius, pixels.
    pub fovea_radius: f64,
    /// Outer radius of the compared field, pixels.
    pub max_radius: f64,
    /// Smallest disparity searched, pixels.
    pub min_disparity: i64,
    /// Largest disparity searched, pixels.
    pub max_disparity: i64,
    /// Which build of the log-polar kernels runs (`auto`: the fastest this CPU has).
    #[serde(default)]
    pub backend: Backend,
}

impl Default for VergenceOptions {
    /// 24 rings x 48 sectors between 2 and 24 px, disparities 0..=64 px.
    fn default() -> Self {
        Self {
            rings: 24,
            sectors: 48,
            fovea_radius: 2.0,
            max_radius: 24.0,
            min_disparity: 0,
            max_disparity: 64,
            backend: Backend::Auto,
        }
    }
}

/// A vergence estimate.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Vergence {
    /// Disparity at the gaze point, pixels (`x_left - x_right`).
    pub disparity_px: f64,
    /// Normalized correlation at the best integer disparity (1: identical).
    pub score: f64,
}

fn ncc(a: &Plane<f32>, b: &Plane<f32>) -> f64 {
    let n = (a.width() * a.height()) as f64;
    let (ma, mb) = (a.sum() / n, b.sum() / n);
    let (mut sab, mut saa, mut sbb) = (0.0f64, 0.0f64, 0.0f64);
    for (ra, rb) in a.rows().zip(b.rows()) {
        for (&x, &y) in ra.iter().zip(rb) {
            let (x, y) = (x as f64 - ma, y as f64 - mb);
            sab += x * y;
            saa += x * x;
            sbb += y * y;
        }
    }
    // A (nearly) flat field has no pattern to correlate: rounding noise must not score.
    if saa <= 1e-6 * n || sbb <= 1e-6 * n {
        0.0
    } else {
        sab / (saa * sbb).sqrt()
    }
}

/// The disparity at `gaze` (x, y in the left image, pixel centres at integers).
pub fn vergence(left: &Plane<u8>, right: &Plane<u8>, gaze: [f64; 2], opts: &VergenceOptions) -> Result<Vergence> {
    ocellus_image::check::same_size("right image (against the left)", right.size(), left.size())?;
    if opts.min_disparity > opts.max_disparity || opts.max_disparity - opts.min_disparity > 100_000 {
        return Err(FoveaError::Invalid(format!("disparity range {}..={}", opts.min_disparity, opts.max_disparity)));
    }
    let (w, h) = left.size();
    let [gx, gy] = gaze;
    if !(gx.is_finite() && gy.is_finite() && gx >= 0.0 && gy >= 0.0 && gx <= (w - 1) as f64 && gy <= (h - 1) as f64) {
        return Err(FoveaError::Invalid(format!("gaze point ({gx}, {gy}) outside the {w}x{h} image")));
    }
    let map = LogPolarMap::new(&foveal_config(opts, [gx.round(), gy.round()]), w, h)?;
    search(&map, left, right, opts)
}

/// The foveal map of `opts` about `centre` (whole pixels, so it can be moved without a rebuild).
fn foveal_config(opts: &VergenceOptions, centre: [f64; 2]) -> LogPolarConfig {
    LogPolarConfig {
        rings: opts.rings,
        sectors: opts.sectors,
        fovea_rings: opts.fovea_radius.round().max(1.0) as usize,
        fovea_radius: opts.fovea_radius,
        max_radius: opts.max_radius,
        centre,
        max_level: 0,
        min_field_texels: 1.0,
        fields: Fields::Area,
        backend: opts.backend,
    }
}

/// The disparity search with the left eye's foveal `map` (built for this image size).
fn search(map: &LogPolarMap, left: &Plane<u8>, right: &Plane<u8>, opts: &VergenceOptions) -> Result<Vergence> {
    let (w, h) = left.size();
    let cfg = *map.config();
    let [gx, gy] = cfg.centre;
    let mut scratch = Scratch::default();
    let mut lcortex = Plane::default();
    map.sample_grey_into(left, &mut scratch, &mut lcortex)?;
    let mut rcortex = Plane::default();
    let mut scores = Vec::with_capacity((opts.max_disparity - opts.min_disparity + 1) as usize);
    for d in opts.min_disparity..=opts.max_disparity {
        let rx = gx - d as f64;
        if rx < 0.0 || rx > (w - 1) as f64 {
            scores.push(f64::NEG_INFINITY);
            continue;
        }
        if !map.sample_grey_moved_into(right, (-d, 0), &mut scratch, &mut rcortex)? {
            // Near the border the fields change: a map of their own.
            LogPolarMap::new(&LogPolarConfig { centre: [rx, gy], ..cfg }, w, h)?.sample_grey_into(
                right,
                &mut scratch,
                &mut rcortex,
            )?;
        }
        scores.push(ncc(&lcortex, &rcortex));
    }
    let (mut bi, mut best) = (usize::MAX, f64::NEG_INFINITY);
    for (i, &s) in scores.iter().enumerate() {
        if s > best {
            best = s;
            bi = i;
        }
    }
    if bi == usize::MAX || best <= 0.0 {
        return Err(FoveaError::NoEstimate(format!("no match for the gaze point ({gx}, {gy}) in the disparity range")));
    }
    let mut d = opts.min_disparity as f64 + bi as f64;
    if bi > 0 && bi + 1 < scores.len() && scores[bi - 1].is_finite() && scores[bi + 1].is_finite() {
        let (l, c, r) = (scores[bi - 1], scores[bi], scores[bi + 1]);
        let den = l - 2.0 * c + r;
        if den < 0.0 {
            d += (0.5 * (l - r) / den).clamp(-0.5, 0.5);
        }
    }
    Ok(Vergence { disparity_px: d, score: best })
}

/// Vergence over a stereo stream, for binocular tracking: the disparity at a fixated target
/// changes little from frame to frame, so each frame searches only `window` pixels around the
/// last estimate, and the whole range again when the match is lost (the best disparity on the
/// window's edge, or a correlation below `min_score`).
#[derive(Clone, Debug)]
pub struct VergenceTracker {
    opts: VergenceOptions,
    window: i64,
    min_score: f64,
    last: Option<f64>,
    full_searches: usize,
    /// The left eye's foveal map for the last gaze point (rounded) and image size.
    map: Option<LogPolarMap>,
}

impl VergenceTracker {
    /// A tracker searching `window` px around the last disparity (full range `opts`), trusting
    /// correlations of at least `min_score`.
    pub fn new(opts: VergenceOptions, window: i64, min_score: f64) -> Result<Self> {
        if window < 1 || !(min_score.is_finite() && min_score <= 1.0) {
            return Err(FoveaError::Invalid(format!("window {window} px (>= 1), min score {min_score} (<= 1)")));
        }
        Ok(Self { opts, window, min_score, last: None, full_searches: 0, map: None })
    }

    /// The disparity at `gaze` in this frame pair.
    pub fn update(&mut self, left: &Plane<u8>, right: &Plane<u8>, gaze: [f64; 2]) -> Result<Vergence> {
        // Checks the inputs, and the full search when there is nothing to follow.
        let full = |t: &mut Self| -> Result<Vergence> {
            t.full_searches += 1;
            t.last = None;
            let v = vergence(left, right, gaze, &t.opts)?;
            t.last = Some(v.disparity_px);
            Ok(v)
        };
        if left.size() != right.size() {
            return full(self);
        }
        let centre = [gaze[0].round(), gaze[1].round()];
        let reuse = self.map.as_ref().is_some_and(|m| m.config().centre == centre && m.image_size() == left.size());
        if !reuse {
            self.map = None;
            let v = full(self)?;
            self.map = Some(LogPolarMap::new(&foveal_config(&self.opts, centre), left.width(), left.height())?);
            return Ok(v);
        }
        if let (Some(d), Some(map)) = (self.last, &self.map) {
            let c = d.round() as i64;
            let (lo, hi) =
                ((c - self.window).max(self.opts.min_disparity), (c + self.window).min(self.opts.max_disparity));
            let near = VergenceOptions { min_disparity: lo, max_disparity: hi, ..self.opts };
            if let Ok(v) = search(map, left, right, &near) {
                let on_edge = (lo > self.opts.min_disparity && v.disparity_px < lo as f64 + 0.5)
                    || (hi < self.opts.max_disparity && v.disparity_px > hi as f64 - 0.5);
                if v.score >= self.min_score && !on_edge {
                    self.last = Some(v.disparity_px);
                    return Ok(v);
                }
            }
        }
        full(self)
    }

    /// How many frames needed the full search (the first, and each time the target was lost).
    pub fn full_searches(&self) -> usize {
        self.full_searches
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ocellus_image::rng::SplitMix64;

    fn texture(seed: u64, w: usize, h: usize) -> Plane<u8> {
        let mut rng = SplitMix64::new(seed);
        let noise = Plane::from_fn(w + 2, h + 2, |_, _| rng.below(256) as f32);
        Plane::from_fn(w, h, |x, y| {
            let s: f32 = (0..3).flat_map(|j| (0..3).map(move |i| (i, j))).map(|(i, j)| noise.get(x + i, y + j)).sum();
            (s / 9.0) as u8
        })
    }

    #[test]
    fn the_tracker_follows_a_drifting_disparity_and_recovers_from_a_jump() {
        let (w, h) = (200, 100);
        let left = texture(6, w, h);
        let mut tracker = VergenceTracker::new(VergenceOptions::default(), 4, 0.8).unwrap();
        // The target approaches (disparity 10 -> 28 in steps of 2), then the gaze jumps to a
        // far surface (disparity 3).
        let mut disparities: Vec<usize> = (10..=28).step_by(2).collect();
        disparities.push(3);
        for &d in &disparities {
            let right = Plane::from_fn(w, h, |x, y| left.get((x + d).min(w - 1), y));
            let v = tracker.update(&left, &right, [120.0, 50.0]).unwrap();
            assert!((v.disparity_px - d as f64).abs() < 0.1, "{d}: {v:?}");
        }
        assert_eq!(tracker.full_searches(), 2, "the first frame and after the jump");
        assert!(tracker.update(&left, &Plane::new(w, h - 1), [120.0, 50.0]).is_err());
        assert!(VergenceTracker::new(VergenceOptions::default(), 0, 0.8).is_err());
    }

    #[test]
    fn a_shifted_random_texture_gives_its_shift_and_bad_input_errors() {
        let (w, h) = (160, 100);
        // Smooth random texture: 3x3 box of white noise.
        let left = texture(4, w, h);
        // Right image: the left moved 13 px to the left (disparity 13).
        let right = Plane::from_fn(w, h, |x, y| left.get((x + 13).min(w - 1), y));
        let v = vergence(&left, &right, [90.0, 50.0], &VergenceOptions::default()).unwrap();
        assert!((v.disparity_px - 13.0).abs() < 0.1 && v.score > 0.99, "{v:?}");
        let opts = VergenceOptions::default();
        assert!(vergence(&left, &right, [-1.0, 50.0], &opts).is_err());
        assert!(vergence(&left, &right, [f64::NAN, 50.0], &opts).is_err());
        assert!(vergence(&left, &Plane::new(w, h - 1), [90.0, 50.0], &opts).is_err());
        assert!(vergence(&left, &right, [90.0, 50.0], &VergenceOptions { min_disparity: 5, max_disparity: 2, ..opts })
            .is_err());
        let flat = Plane::from_fn(w, h, |_, _| 9u8);
        assert!(vergence(&flat, &flat, [90.0, 50.0], &opts).is_err());
    }
}
