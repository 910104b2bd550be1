//! Information-based view-direction planning (seed 001, section 3; SPEC 2.3-2.5): where to turn
//! the camera next, by the expected information gain of the task (top-down) or of the surprise
//! in view (bottom-up), weighted by how familiar the context is.
//!
//! Frames and units: the robot moves in a plane (metres; x forward, y left); its heading and the
//! camera's pan are in degrees, counter-clockwise (pan 0 looks along the heading, positive pans
//! look left). In the image, x grows to the right, which is clockwise: a map cell `k` columns
//! right of the centre lies `k * deg_per_cell` degrees clockwise of the optical axis.
//!
//! - Top-down (SPEC 2.3): position belief `N(mu, R)`; for a pan the landmarks in the field of
//!   view (and in range) are observed as bearings; the predicted posterior covariance comes from
//!   the EKF ([`ocellus_estimation::bearing`]); `I_td = KL(p || q)` in bits.
//! - Bottom-up (SPEC 2.4): over the *interesting* cells of the surprise map (the seed's
//!   words: surprise of at least `interest_min_bits` and at least `interest_frac` of the
//!   map's maximum), `P = tau / d`, d the distance from the image centre in cells (at least
//!   `min_distance_cells`, so a cell at the exact centre is finite). `Q` is the same after the
//!   predicted turn: cells move by the pan change, d is measured from the new centre. The
//!   other cells with surprise form one more outcome, "background", whose mass is their sum of
//!   `tau / d` (so that a single surprising cell still has something to be compared with).
//!   Cells that leave the field of view drop out of the comparison: P and Q are both
//!   renormalized over the outcomes in view before and after, and `I_bu = KL(P || Q)` in bits.
//!   It is largest for the turn that brings the surprising region to the centre, where Q
//!   concentrates on the cells nearest the new centre; a turn that takes the region out of
//!   view leaves nothing to compare and earns 0, as do no surprise and an empty map.
//!   (Without the interest threshold, weak background surprise would dominate: turning away
//!   from the event redistributes it over the new distances and scores a large KL.)
//! - Decision (SPEC 2.5): `argmax v(s) I_td + (1 - v(s)) I_bu` over the candidates, with
//!   `v(s) = 1` if `s < S` else 0, or a logistic `1 / (1 + exp((s - S) / width))`.

use crate::{AttentionError, Result};
use nalgebra::{Matrix2, Vector2};
use ocellus_estimation::bearing::{bearing_update_covariance, Landmark};
use ocellus_estimation::gaussian::kl_bits;
use ocellus_image::simd::Madd;
use ocellus_image::{Backend, Plane};
use serde::{Deserialize, Serialize};

/// How the chaos degree weights top-down against bottom-up.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ContextWeight {
    /// `v = 1` if `s < S` else 0 (seed eq. 2).
    Hard,
    /// `v = 1 / (1 + exp((s - S) / width))`, width in bits.
    Logistic {
        /// Transition width in bits.
        width: f64,
    },
}

impl ContextWeight {
    /// `v(s)` for threshold `s_threshold`; a non-finite `s` counts as unfamiliar.
    pub fn weight(&self, s: f64, s_threshold: f64) -> f64 {
        if !s.is_finite() {
            return 0.0;
        }
        match *self {
            ContextWeight::Hard => f64::from(u8::from(s < s_threshold)),
            ContextWeight::Logistic { width } => {
                let z = (s - s_threshold) / width.max(1e-9);
                1.0 / (1.0 + z.clamp(-700.0, 700.0).exp())
            }
        }
    }
}

/// Parameters of [`ViewPlanner`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlannerConfig {
    /// Candidate pan angles, degrees.
    pub candidates_deg: Vec<f64>,
    /// Horizontal field of view of the camera, degrees.
    pub hfov_deg: f64,
    /// Landmarks further than this are not observed, metres.
    pub max_range_m: f64,
    /// Standard deviation of a bearing measurement, degrees.
    pub bearing_sigma_deg: f64,
    /// Angular size of one surprise-map cell, degrees.
    pub deg_per_cell: f64,
    /// Smallest distance from the image centre, in cells.
    pub min_distance_cells: f64,
    /// Cells with less surprise than this (bits) are not interesting.
    pub interest_min_bits: f32,
    /// Cells with less than this fraction of the map's maximum surprise are not interesting.
    pub interest_frac: f32,
    /// Chaos threshold S, bits.
    pub chaos_threshold: f64,
    /// Hard or logistic `v(s)`.
    pub weight: ContextWeight,
    /// Which build of the bottom-up kernel runs (`auto`: the fastest this CPU has).
    #[serde(default)]
    pub backend: Backend,
}

impl Default for PlannerConfig {
    /// 19 candidates from -90 to 90 degrees in steps of 10; a 100 degree field of view; 8 m
    /// range; bearings to 1 degree; 2.5 degree cells (40 cells across 100 degrees); S = 1.
    fn default() -> Self {
        Self {
            candidates_deg: (0..19).map(|i| -90.0 + 10.0 * i as f64).collect(),
            hfov_deg: 100.0,
            max_range_m: 8.0,
            bearing_sigma_deg: 1.0,
            deg_per_cell: 2.5,
            min_distance_cells: 0.5,
            interest_min_bits: 1.0,
            interest_frac: 0.25,
            chaos_threshold: 1.0,
            weight: ContextWeight::Hard,
            backend: Backend::Auto,
        }
    }
}

impl PlannerConfig {
    fn validate(&self) -> Result<()> {
        use ocellus_image::check;
        (|| {
            if self.candidates_deg.is_empty() {
                return Err("the planner needs at least one candidate direction".to_string());
            }
            for c in &self.candidates_deg {
                check::finite("candidate direction (degrees)", *c)?;
            }
            check::between("hfov_deg", self.hfov_deg, 0.0, 180.0)?;
            for (name, v) in [
                ("max_range_m", self.max_range_m),
                ("bearing_sigma_deg", self.bearing_sigma_deg),
                ("deg_per_cell", self.deg_per_cell),
                ("min_distance_cells", self.min_distance_cells),
            ] {
                check::positive(name, v)?;
            }
            check::finite("interest_min_bits", self.interest_min_bits)?;
            check::within("interest_frac", self.interest_frac, 0.0, 1.0)?;
            check::finite("chaos_threshold", self.chaos_threshold)
        })()
        .map_err(AttentionError::InvalidConfig)
    }
}

/// Gains of one candidate direction.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Candidate {
    /// Pan angle, degrees.
    pub pan_deg: f64,
    /// Number of landmarks it would observe.
    pub landmarks_in_view: usize,
    /// Top-down information gain, bits.
    pub top_down_bits: f64,
    /// Bottom-up information gain, bits.
    pub bottom_up_bits: f64,
    /// `v I_td + (1 - v) I_bu`.
    pub score: f64,
}

/// The planner's choice and everything behind it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Decision {
    /// The chosen pan angle, degrees.
    pub pan_deg: f64,
    /// `v(s)`.
    pub v: f64,
    /// Every candidate, in the configured order.
    pub candidates: Vec<Candidate>,
}

/// The planner: landmarks and parameters, plus scratch for the bottom-up gain.
#[derive(Debug)]
pub struct ViewPlanner {
    cfg: PlannerConfig,
    landmarks: Vec<Landmark>,
    scratch: BottomUpScratch,
}

/// Per-decision scratch: the cells with surprise as offsets from the image centre.
#[derive(Debug, Default)]
struct BottomUpScratch {
    /// (column offset, row offset, tau) of the interesting cells.
    cells: Vec<(f32, f32, f32)>,
    /// The background cells (surprise > 0 but not interesting), as columns: offset x,
    /// squared offset y, tau, and tau / d for the current view.
    bg_dx: Vec<f32>,
    bg_dy2: Vec<f32>,
    bg_t: Vec<f32>,
    bg_p: Vec<f32>,
}

impl ViewPlanner {
    /// A planner for a world with these landmarks (metres).
    pub fn new(cfg: PlannerConfig, landmarks: Vec<Landmark>) -> Result<Self> {
        cfg.validate()?;
        if landmarks.iter().any(|l| !(l.x.is_finite() && l.y.is_finite())) {
            return Err(AttentionError::InvalidInput("landmark with non-finite position".into()));
        }
        Ok(Self { cfg, landmarks, scratch: BottomUpScratch::default() })
    }

    /// The configuration.
    pub fn config(&self) -> &PlannerConfig {
        &self.cfg
    }

    /// The landmarks visible from `mu` with heading `heading_deg` and camera pan `pan_deg`:
    /// within half the field of view of the optical axis and within range.
    pub fn visible_landmarks(&self, mu: &Vector2<f64>, heading_deg: f64, pan_deg: f64) -> Vec<Landmark> {
        let axis = (heading_deg + pan_deg).to_radians();
        let half = (self.cfg.hfov_deg / 2.0).to_radians();
        self.landmarks
            .iter()
            .copied()
            .filter(|l| {
                let (dx, dy) = (l.x - mu.x, l.y - mu.y);
                let r = (dx * dx + dy * dy).sqrt();
                let off = (dy.atan2(dx) - axis + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI)
                    - std::f64::consts::PI;
                r > 1e-6 && r <= self.cfg.max_range_m && off.abs() <= half
            })
            .collect()
    }

    /// Top-down gain of looking at `pan_deg`: KL(prior || predicted posterior) in bits, and the
    /// number of landmarks observed.
    pub fn top_down_gain(
        &self,
        mu: &Vector2<f64>,
        cov: &Matrix2<f64>,
        heading_deg: f64,
        pan_deg: f64,
    ) -> Result<(f64, usize)> {
        let seen = self.visible_landmarks(mu, heading_deg, pan_deg);
        let post = bearing_update_covariance(mu, cov, &seen, self.cfg.bearing_sigma_deg.to_radians())?;
        let kl = kl_bits(mu, cov, mu, &post)?;
        Ok((kl, seen.len()))
    }

    /// Chooses the pan angle. `surprise` is the current surprise map (bits, any size; empty
    /// allowed), seen with the camera at `current_pan_deg`; `chaos` the chaos degree s.
    pub fn decide(
        &mut self,
        mu: &Vector2<f64>,
        cov: &Matrix2<f64>,
        heading_deg: f64,
        current_pan_deg: f64,
        surprise: &Plane<f32>,
        chaos: f64,
    ) -> Result<Decision> {
        if !(heading_deg.is_finite() && current_pan_deg.is_finite()) {
            return Err(AttentionError::InvalidInput("non-finite heading or pan".into()));
        }
        let v = self.cfg.weight.weight(chaos, self.cfg.chaos_threshold);
        self.prepare_bottom_up(surprise);
        let mut candidates = Vec::with_capacity(self.cfg.candidates_deg.len());
        for i in 0..self.cfg.candidates_deg.len() {
            let pan = self.cfg.candidates_deg[i];
            let (td, seen) = self.top_down_gain(mu, cov, heading_deg, pan)?;
            let bu = self.bottom_up_prepared((pan - current_pan_deg) / self.cfg.deg_per_cell, surprise.width());
            candidates.push(Candidate {
                pan_deg: pan,
                landmarks_in_view: seen,
                top_down_bits: td,
                bottom_up_bits: bu,
                score: v * td + (1.0 - v) * bu,
            });
        }
        // Highest score; among equal scores the smallest turn (no reason to move).
        let turn = |c: &Candidate| (c.pan_deg - current_pan_deg).abs();
        let best = candidates.iter().fold(None::<&Candidate>, |b, c| match b {
            Some(b) if b.score > c.score || (b.score == c.score && turn(b) <= turn(c)) => Some(b),
            _ => Some(c),
        });
        let pan_deg = best.map_or(current_pan_deg, |c| c.pan_deg);
        Ok(Decision { pan_deg, v, candidates })
    }

    /// Bottom-up gain of turning by `pan_change_deg` (positive: left) with `surprise` in view.
    pub fn bottom_up_gain(&mut self, surprise: &Plane<f32>, pan_change_deg: f64) -> f64 {
        self.prepare_bottom_up(surprise);
        self.bottom_up_prepared(pan_change_deg / self.cfg.deg_per_cell, surprise.width())
    }

    /// Keeps the interesting cells (finite surprise above both thresholds, and > 0), as
    /// offsets from the image centre.
    fn prepare_bottom_up(&mut self, surprise: &Plane<f32>) {
        let dmin2 = (self.cfg.min_distance_cells * self.cfg.min_distance_cells) as f32;
        let BottomUpScratch { cells, bg_dx, bg_dy2, bg_t, bg_p } = &mut self.scratch;
        cells.clear();
        for v in [&mut *bg_dx, &mut *bg_dy2, &mut *bg_t, &mut *bg_p] {
            v.clear();
        }
        let max = surprise.rows().flatten().copied().filter(|t| t.is_finite()).fold(0.0f32, f32::max);
        let floor = (self.cfg.interest_frac * max).max(self.cfg.interest_min_bits);
        let (cx, cy) = ((surprise.width() as f32 - 1.0) / 2.0, (surprise.height() as f32 - 1.0) / 2.0);
        for y in 0..surprise.height() {
            for (x, &t) in surprise.row(y).iter().enumerate() {
                if t > 0.0 && t.is_finite() {
                    let (dx, dy) = (x as f32 - cx, y as f32 - cy);
                    if t >= floor {
                        cells.push((dx, dy, t));
                    } else {
                        bg_dx.push(dx);
                        bg_dy2.push(dy * dy);
                        bg_t.push(t);
                        bg_p.push(t / (dx * dx + dy * dy).max(dmin2).sqrt());
                    }
                }
            }
        }
    }

    /// Background sums of P and Q over the cells still in view after the turn (the
    /// configured backend's build).
    fn background_sums(&self, shift: f32, half_w: f32, dmin2: f32) -> (f64, f64) {
        let sc = &self.scratch;
        background_sums_kernel(self.cfg.backend, &sc.bg_dx, &sc.bg_dy2, &sc.bg_t, &sc.bg_p, [shift, half_w, dmin2])
    }

    /// `KL(P || Q)` in bits for a turn of `shift_cells` (positive: left, so cells move right).
    fn bottom_up_prepared(&self, shift_cells: f64, width: usize) -> f64 {
        let (shift, half_w) = (shift_cells as f32, width as f32 / 2.0);
        let dmin2 = (self.cfg.min_distance_cells * self.cfg.min_distance_cells) as f32;
        // (tau / d, tau / d') of a cell, None when it leaves the field of view.
        let pq = |&(dx, dy, t): &(f32, f32, f32)| {
            let nx = dx + shift;
            (nx.abs() <= half_w).then(|| {
                let d2 = (dx * dx + dy * dy).max(dmin2);
                let n2 = (nx * nx + dy * dy).max(dmin2);
                (t / d2.sqrt(), t / n2.sqrt(), n2 / d2)
            })
        };
        // Unnormalized P and Q sums, and sum p ln(p / q): for a cell ln(p/q) = ln(d'/d).
        let (mut zp, mut zq, mut cross) = (0f64, 0f64, 0f64);
        for (p, q, ratio2) in self.scratch.cells.iter().filter_map(pq) {
            zp += p as f64;
            zq += q as f64;
            cross += p as f64 * 0.5 * (ratio2 as f64).ln();
        }
        let (bp, bq) = self.background_sums(shift, half_w, dmin2);
        if bp > 0.0 && bq > 0.0 {
            zp += bp;
            zq += bq;
            cross += bp * (bp / bq).ln();
        }
        if zp <= 0.0 || zq <= 0.0 || !zp.is_finite() || !zq.is_finite() {
            return 0.0;
        }
        // KL = sum (p/Zp) ln((p/Zp) / (q/Zq)) = cross / Zp + ln(Zq / Zp)
        let nats = cross / zp + (zq / zp).ln();
        if nats.is_finite() {
            nats.max(0.0) / std::f64::consts::LN_2
        } else {
            0.0
        }
    }
}

ocellus_image::dispatch_kernel!(
    fn background_sums_kernel => background_sums_generic(
        dx: &[f32],
        dy2: &[f32],
        t: &[f32],
        p: &[f32],
        shift_half_dmin2: [f32; 3],
    ) -> (f64, f64)
);

/// The background is most of the map: branch-free, eight lanes of partial sums, so that the
/// loop vectorizes (cells that leave the view are masked out).
#[inline(always)]
fn background_sums_generic<M: Madd>(
    dx: &[f32],
    dy2: &[f32],
    t: &[f32],
    p: &[f32],
    [shift, half_w, dmin2]: [f32; 3],
) -> (f64, f64) {
    const L: usize = 8;
    let (mut ap, mut aq) = ([0f32; L], [0f32; L]);
    let chunks = dx.chunks_exact(L).zip(dy2.chunks_exact(L)).zip(t.chunks_exact(L).zip(p.chunks_exact(L)));
    for ((dx, dy2), (t, p)) in chunks {
        for l in 0..L {
            let nx = dx[l] + shift;
            let keep = if nx.abs() <= half_w { 1.0 } else { 0.0 };
            let n2 = M::madd(nx, nx, dy2[l]);
            // max without the NaN rule of f32::max (inputs are finite): it vectorizes.
            let n2 = if n2 > dmin2 { n2 } else { dmin2 };
            ap[l] = M::madd(keep, p[l], ap[l]);
            aq[l] += keep * t[l] / n2.sqrt();
        }
    }
    let (mut bp, mut bq) = (ap.iter().sum::<f32>() as f64, aq.iter().sum::<f32>() as f64);
    for i in dx.len() / L * L..dx.len() {
        let nx = dx[i] + shift;
        if nx.abs() <= half_w {
            bp += p[i] as f64;
            bq += (t[i] / (nx * nx + dy2[i]).max(dmin2).sqrt()) as f64;
        }
    }
    (bp, bq)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn planner() -> ViewPlanner {
        let lms = vec![Landmark { x: 3.0, y: 2.5 }, Landmark { x: 6.0, y: 0.0 }];
        ViewPlanner::new(PlannerConfig::default(), lms).unwrap()
    }

    /// The direct definition: P and Q over the common cells, both normalized, KL in bits.
    fn bottom_up_direct(s: &Plane<f32>, shift: f64, dmin: f64) -> f64 {
        let (w, h) = s.size();
        let floor = (0.25 * s.min_max().1).max(1.0) as f64;
        let (cx, cy) = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
        let mut pq = Vec::new();
        let mut bg = (0.0, 0.0);
        for y in 0..h {
            for x in 0..w {
                let t = s.get(x, y) as f64;
                let (dx, dy) = (x as f64 - cx, y as f64 - cy);
                if t <= 0.0 || (dx + shift).abs() > w as f64 / 2.0 {
                    continue;
                }
                let d = (dx * dx + dy * dy).sqrt().max(dmin);
                let n = ((dx + shift).powi(2) + dy * dy).sqrt().max(dmin);
                if t >= floor {
                    pq.push((t / d, t / n));
                } else {
                    bg = (bg.0 + t / d, bg.1 + t / n);
                }
            }
        }
        if bg.0 > 0.0 {
            pq.push(bg);
        }
        let (zp, zq) = pq.iter().fold((0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
        if zp == 0.0 {
            return 0.0;
        }
        pq.iter().map(|&(p, q)| (p / zp) * ((p / zp) / (q / zq)).log2()).sum()
    }

    #[test]
    fn bottom_up_matches_the_direct_definition_and_prefers_turning_to_the_surprise() {
        let mut s = Plane::from_fn(40, 30, |x, y| 0.01 * ((x * 7 + y * 3) % 5) as f32);
        // A surprising blob right of centre (columns 30-32).
        for y in 12..16 {
            for x in 30..33 {
                s.set(x, y, 20.0);
            }
        }
        let mut p = planner();
        for shift_deg in [-30.0, -10.0, 0.0, 10.0, 30.0, 60.0] {
            let g = p.bottom_up_gain(&s, shift_deg);
            let d = bottom_up_direct(&s, shift_deg / 2.5, 0.5);
            assert!((g - d).abs() < 1e-4 * (1.0 + d), "{shift_deg}: {g} vs {d}");
        }
        // The blob is ~11.5 cells (29 degrees) right: turning right (negative pan) by about
        // that much brings it to the centre and gains most.
        let gains: Vec<(f64, f64)> =
            (-9..=9).map(|i| (i as f64 * 10.0, p.bottom_up_gain(&s, i as f64 * 10.0))).collect();
        let best = gains.iter().fold(gains[0], |b, &g| if g.1 > b.1 { g } else { b });
        assert!((best.0 + 30.0).abs() <= 10.0, "{gains:?}");
        assert_eq!(p.bottom_up_gain(&s, 0.0), 0.0);
    }

    #[test]
    fn background_kernels_agree() {
        let n = 1203;
        let dx: Vec<f32> = (0..n).map(|i| (i % 40) as f32 - 19.5).collect();
        let dy2: Vec<f32> = (0..n).map(|i| ((i / 40) as f32 - 14.5).powi(2)).collect();
        let t: Vec<f32> = (0..n).map(|i| 0.01 + (i % 7) as f32 * 0.03).collect();
        let p: Vec<f32> = (0..n).map(|i| t[i] / (dx[i] * dx[i] + dy2[i]).max(0.25).sqrt()).collect();
        for shift in [-30.0f32, -4.2, 0.0, 7.7, 25.0] {
            let a = background_sums_kernel(Backend::Scalar, &dx, &dy2, &t, &p, [shift, 20.0, 0.25]);
            for backend in Backend::available() {
                let b = background_sums_kernel(backend, &dx, &dy2, &t, &p, [shift, 20.0, 0.25]);
                let close = (a.0 - b.0).abs() < 1e-5 * a.0.max(1.0) && (a.1 - b.1).abs() < 1e-5 * a.1.max(1.0);
                assert!(close, "{backend:?}: {a:?} {b:?}");
            }
        }
    }

    #[test]
    fn bottom_up_is_finite_for_any_input() {
        let mut p = planner();
        assert_eq!(p.bottom_up_gain(&Plane::new(0, 0), 10.0), 0.0);
        assert_eq!(p.bottom_up_gain(&Plane::new(40, 30), 10.0), 0.0);
        let mut centre = Plane::new(41, 31);
        centre.set(20, 15, 5.0);
        for shift in [-1000.0, -5.0, 0.0, 1.25, 90.0, 1e9] {
            let g = p.bottom_up_gain(&centre, shift);
            assert!(g.is_finite() && g >= 0.0, "{shift}: {g}");
        }
        let weird = Plane::from_fn(5, 5, |x, _| [f32::NAN, f32::INFINITY, -1.0, 0.0, 1e30][x]);
        assert!(p.bottom_up_gain(&weird, 10.0).is_finite());
    }

    proptest::proptest! {
        #[test]
        fn bottom_up_and_decisions_are_finite_for_any_map(
            w in 0usize..12, h in 0usize..9, vals in proptest::collection::vec(proptest::num::f32::ANY, 108),
            shift in proptest::num::f64::ANY, chaos in proptest::num::f64::ANY,
        ) {
            let map = Plane::from_fn(w, h, |x, y| vals[(y * 12 + x) % vals.len()]);
            let mut p = planner();
            let g = p.bottom_up_gain(&map, shift);
            proptest::prop_assert!(g.is_finite() && g >= 0.0);
            let (mu, cov) = (Vector2::new(1.0, 1.25), Matrix2::new(0.01, 0.0, 0.0, 0.01));
            let d = p.decide(&mu, &cov, 0.0, 0.0, &map, chaos).unwrap();
            proptest::prop_assert!(d.pan_deg.is_finite());
            proptest::prop_assert!(d.candidates.iter().all(|c| c.score.is_finite()));
        }
    }

    #[test]
    fn top_down_prefers_directions_with_landmarks() {
        let p = planner();
        let (mu, cov) = (Vector2::new(0.0, 1.25), Matrix2::new(0.05, 0.0, 0.0, 0.05));
        // Landmark 1 at 3 m ahead, 1.25 m left: bearing 22.6 degrees; landmark 2 at -11.8.
        let (g_left, n_left) = p.top_down_gain(&mu, &cov, 0.0, 30.0).unwrap();
        let (g_back, n_back) = p.top_down_gain(&mu, &cov, 0.0, 180.0).unwrap();
        assert_eq!((n_left, n_back), (2, 0));
        assert!(g_left > 1.0 && g_back == 0.0, "{g_left} {g_back}");
        assert!(p.top_down_gain(&mu, &cov, 0.0, 85.0).unwrap().1 < 2);
    }

    #[test]
    fn context_switches_between_top_down_and_bottom_up() {
        let mut p = planner();
        let (mu, cov) = (Vector2::new(0.0, 1.25), Matrix2::new(0.05, 0.0, 0.0, 0.05));
        // One surprising cell over weak background surprise.
        let mut s = Plane::from_fn(40, 30, |x, y| 0.05 + 0.01 * ((x + y) % 3) as f32);
        s.set(35, 14, 30.0);
        let calm = p.decide(&mu, &cov, 0.0, 0.0, &s, 0.1).unwrap();
        let chaotic = p.decide(&mu, &cov, 0.0, 0.0, &s, 2.0).unwrap();
        assert_eq!((calm.v, chaotic.v), (1.0, 0.0));
        assert!(calm.candidates.iter().find(|c| c.pan_deg == calm.pan_deg).unwrap().landmarks_in_view > 0);
        // The surprise is 15.5 cells = 39 degrees right: the bottom-up choice turns right.
        assert!((chaotic.pan_deg + 40.0).abs() <= 10.0, "{}", chaotic.pan_deg);
        let soft = ContextWeight::Logistic { width: 0.1 };
        assert!((soft.weight(1.0, 1.0) - 0.5).abs() < 1e-12 && soft.weight(3.0, 1.0) < 1e-6);
        assert_eq!(ContextWeight::Hard.weight(f64::NAN, 1.0), 0.0);
    }
}
