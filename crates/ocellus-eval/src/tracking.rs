//! How well a tracker followed a ball (SPEC 7): 3D RMSE, image-centre error, lost frames and
//! re-acquisition delay against per-frame ground truth.
//!
//! A frame is *scored* when at least half the ball is visible in it (`visible_fraction >=
//! 0.5`); the 3D RMSE and the centre errors are over scored frames with an estimate. A scored
//! frame is *tracked* when the estimate's image centre lies within the true image radius of
//! the true centre (and the tracker does not call itself lost); *lost frames* are the scored
//! frames that are not tracked. After each full occlusion (a run of frames with nothing of the
//! ball visible) the *re-acquisition delay* counts the frames from the first scored frame
//! after it to the first tracked one (0: tracked at once; `None`: never again).

use crate::{EvalError, Result};

/// The truth of one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TruthFrame {
    /// Ball centre, metres.
    pub position: [f64; 3],
    /// Image circle `[x, y, r]`, pixels (`None`: not wholly in front of the camera).
    pub circle: Option<[f64; 3]>,
    /// Share of the ball visible, in [0, 1].
    pub visible_fraction: f64,
}

/// What a tracker said about one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EstimateFrame {
    /// Estimated centre, metres (`None`: no estimate yet).
    pub position: Option<[f64; 3]>,
    /// Estimated image centre `[x, y]`, pixels.
    pub centre_px: Option<[f64; 2]>,
    /// Whether the tracker said it was lost.
    pub lost: bool,
}

/// The figures of one tracked sequence.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TrackingScores {
    /// Frames in the sequence.
    pub frames: usize,
    /// Frames with at least half the ball visible.
    pub scored_frames: usize,
    /// 3D RMSE over scored frames with an estimate, metres.
    pub rmse_3d_m: f64,
    /// Mean true depth (z) over those frames, metres.
    pub mean_depth_m: f64,
    /// `rmse_3d_m / mean_depth_m`, percent.
    pub rmse_3d_percent_of_depth: f64,
    /// Median image-centre error over those frames, pixels.
    pub median_centre_error_px: f64,
    /// Scored frames not tracked.
    pub lost_frames: usize,
    /// The re-acquisition delay after each full occlusion, frames (`None`: never).
    pub reacquisition_delays: Vec<Option<usize>>,
}

/// The median of `v` (sorts it): the mean of the two middle values for an even count, 0 for
/// an empty slice.
pub fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        0.0
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Scores `estimates` against `truth`, frame by frame (equal lengths).
pub fn score(truth: &[TruthFrame], estimates: &[EstimateFrame]) -> Result<TrackingScores> {
    let undefined = |why: String| EvalError::Undefined { metric: "tracking scores", why };
    if truth.len() != estimates.len() {
        return Err(undefined(format!("{} truth frames but {} estimates", truth.len(), estimates.len())));
    }
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
    for (k, (t, e)) in truth.iter().zip(estimates).enumerate() {
        let ok = finite(&t.position)
            && t.circle.is_none_or(|c| finite(&c))
            && (0.0..=1.0).contains(&t.visible_fraction)
            && e.position.is_none_or(|p| finite(&p))
            && e.centre_px.is_none_or(|p| finite(&p));
        if !ok {
            return Err(undefined(format!("frame {k} has a non-finite or out-of-range value")));
        }
    }
    let (mut se, mut depth, mut n, mut errs, mut lost) = (0.0, 0.0, 0usize, Vec::new(), 0usize);
    let mut tracked = vec![false; truth.len()];
    let mut scored = 0;
    for (k, (t, e)) in truth.iter().zip(estimates).enumerate() {
        let Some(tc) = t.circle.filter(|_| t.visible_fraction >= 0.5) else { continue };
        scored += 1;
        if let Some(p) = e.position {
            se += (0..3).map(|i| (p[i] - t.position[i]).powi(2)).sum::<f64>();
            depth += t.position[2];
            n += 1;
        }
        let err = e.centre_px.map(|c| (c[0] - tc[0]).hypot(c[1] - tc[1]));
        if let Some(err) = err {
            errs.push(err);
        }
        tracked[k] = !e.lost && err.is_some_and(|d| d <= tc[2]);
        if !tracked[k] {
            lost += 1;
        }
    }
    if n == 0 || errs.is_empty() {
        return Err(undefined("no frame with half the ball visible has an estimate".into()));
    }
    let mut delays = Vec::new();
    let mut k = 0;
    while k < truth.len() {
        if truth[k].visible_fraction > 0.0 {
            k += 1;
            continue;
        }
        while k < truth.len() && truth[k].visible_fraction < 0.5 {
            k += 1;
        }
        if k < truth.len() {
            delays.push((k..truth.len()).position(|j| tracked[j]));
        }
    }
    let rmse = (se / n as f64).sqrt();
    let mean_depth = depth / n as f64;
    Ok(TrackingScores {
        frames: truth.len(),
        scored_frames: scored,
        rmse_3d_m: rmse,
        mean_depth_m: mean_depth,
        rmse_3d_percent_of_depth: 100.0 * rmse / mean_depth,
        median_centre_error_px: median(&mut errs),
        lost_frames: lost,
        reacquisition_delays: delays,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn truth(k: usize, vis: f64) -> TruthFrame {
        TruthFrame {
            position: [0.1 * k as f64, 0.0, 2.0],
            circle: Some([30.0 * k as f64, 100.0, 10.0]),
            visible_fraction: vis,
        }
    }

    #[test]
    fn hand_computed_scores() {
        // Six frames: 2 and 3 fully hidden; the estimate is 3 cm off in x always (and 3 px
        // off in the image), except frame 4 where it is lost, found again at 5.
        let vis = [1.0, 1.0, 0.0, 0.0, 1.0, 1.0];
        let t: Vec<TruthFrame> = vis.iter().enumerate().map(|(k, &v)| truth(k, v)).collect();
        let e: Vec<EstimateFrame> = t
            .iter()
            .enumerate()
            .map(|(k, t)| {
                let c = t.circle.unwrap();
                let off = if k == 4 { 40.0 } else { 3.0 };
                EstimateFrame {
                    position: Some([t.position[0] + 0.03, 0.0, 2.0]),
                    centre_px: Some([c[0] + off, c[1]]),
                    lost: false,
                }
            })
            .collect();
        let s = score(&t, &e).unwrap();
        assert_eq!(s.scored_frames, 4);
        assert!((s.rmse_3d_m - 0.03).abs() < 1e-12);
        assert!((s.rmse_3d_percent_of_depth - 1.5).abs() < 1e-9);
        // Errors 3, 3, 40, 3: median 3.
        assert_eq!(s.median_centre_error_px, 3.0);
        assert_eq!(s.lost_frames, 1);
        assert_eq!(s.reacquisition_delays, vec![Some(1)]);
    }

    #[test]
    fn never_found_and_bad_input() {
        let t: Vec<TruthFrame> = [1.0, 0.0, 1.0].iter().enumerate().map(|(k, &v)| truth(k, v)).collect();
        let e = vec![EstimateFrame { position: Some([0.0, 0.0, 2.0]), centre_px: Some([0.0, 100.0]), lost: true }; 3];
        let s = score(&t, &e).unwrap();
        assert_eq!(s.reacquisition_delays, vec![None]);
        assert_eq!(s.lost_frames, 2);
        assert!(score(&t, &e[..2]).is_err());
        let mut bad = e.clone();
        bad[0].position = Some([f64::NAN, 0.0, 0.0]);
        assert!(score(&t, &bad).is_err());
        let none = vec![EstimateFrame { position: None, centre_px: None, lost: true }; 3];
        assert!(score(&t, &none).is_err());
    }
}
