//! Bottom-up ball detections (SPEC 7.4): colour segmentation blobs of a binned frame, each
//! turned into a 3D hypothesis of the ball's centre, the depth from the blob's size and the
//! known ball radius. They feed the boosted proposal of [`crate::ball::BallModel`].
//!
//! A pixel belongs to the ball's colour when its bin holds at least
//! [`DetectorConfig::min_bin_share`] of the model histogram; blobs are the 4-connected
//! components of those pixels (union-find over one pass). A blob's radius is that of the disc
//! of the same area, or half its longer side when the blob looks cut (a ball half hidden
//! keeps its full extent in one direction); its centre is the centroid, or for a cut blob the
//! middle of its longer side and one radius in from its round side.
//!
//! The distance of the centre from the camera follows from the image radius r (pixels) of a
//! sphere of radius R at distance d seen with focal f: `r = f R / sqrt(d^2 - R^2)`, so
//! `d = R sqrt(1 + f^2 / r^2)`.

use crate::binning::{BinnedFrame, Histogram, BINS};
use crate::colour::{Circle, ColourModel};
use crate::{Result, TrackingError};
use nalgebra::{Vector2, Vector3};
use ocellus_geometry::camera::PinholeCamera;
use ocellus_geometry::distortion::Distortion;
use ocellus_image::rng::SplitMix64;

/// `ln(2 pi)`.
const LN_2PI: f64 = 1.837_877_066_409_345_5;

/// Parameters of the colour-blob detector.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DetectorConfig {
    /// A bin is the ball's colour when it holds at least this share of the model histogram,
    /// in (0, 1].
    pub min_bin_share: f64,
    /// Smallest blob kept, pixels.
    pub min_area_px: usize,
    /// Largest number of blobs kept (the largest ones).
    pub max_detections: usize,
    /// Smallest area over the area of the disc of the blob's radius: blobs less round are
    /// not balls, in (0, 1].
    pub min_fill: f64,
    /// Smallest colour score `BC(inner, model) - BC(inner, outer)` of a blob's circle: a
    /// patch of the ball's colour that does not stand out from its surroundings is no ball,
    /// in [-1, 1].
    pub min_score: f64,
    /// Spread of a detection's centre across the line of sight, as a share of its image
    /// radius (at least one pixel).
    pub lateral_sigma_radii: f64,
    /// Spread of a detection's distance, as a share of the distance.
    pub depth_sigma_frac: f64,
    /// Spread of the velocity of a particle drawn from a detection about its parent's
    /// predicted velocity, across the line of sight, m/s: wide, since the image corrects it
    /// within a frame or two (after a bounce the direction of flight turns).
    pub velocity_sigma_across_mps: f64,
    /// The same along the line of sight, m/s: narrow, since the image hardly sees it (a wide
    /// one lets the depth run away after a bounce).
    pub velocity_sigma_along_mps: f64,
    /// Added to the radius of a cut blob's circle (half its longer side), pixels, in [0, 2]:
    /// the ball's limb is darkened by its shading and its last pixels fail the colour test,
    /// so the blob's box falls short of the ball's edge at both ends (see
    /// [`DEFAULT_CUT_EDGE_INSET_PX`]).
    #[serde(default = "default_cut_edge_inset_px")]
    pub cut_edge_inset_px: f64,
}

/// Default of [`DetectorConfig::cut_edge_inset_px`], pixels. On the generated sequences
/// (Lambert-shaded balls of radius 9-23 px) the radii of cut blobs from their boxes were 0.3
/// px short of the truth on average (0.0-0.7 px over 11 frames of bounce 2 and approach 2),
/// as were those of whole blobs from their areas (0.25-0.37 px). With the round side and the
/// radius moved out by this inset, the 54 runs of `ocellus track study --seeds
/// 1,2,3,4,5,6 --streams 3` (16000 particles) had a median 3D RMSE of 1.01 % of the depth, a
/// mean of 1.03 % and a worst run of 1.45 % (all 54 within 2 %), against 1.07 / 1.16 / 3.03 %
/// (53) without. A variant tried first kept the round side at the box's edge and grew only
/// the radius: insets of 0.2 / 0.3 / 0.5 px gave means of 1.04 / 0.98 / 1.10 % and worst runs
/// of 2.04 / 1.57 / 1.86 %. Growing whole blobs' radii too changed little (mean 1.00 %): their
/// depth is drawn with a spread of 12 %, while a cut blob's circle is weighed as an
/// observation with a spread of 0.65 px and starts the cloud after a loss.
pub const DEFAULT_CUT_EDGE_INSET_PX: f64 = 0.3;

fn default_cut_edge_inset_px() -> f64 {
    DEFAULT_CUT_EDGE_INSET_PX
}

impl Default for DetectorConfig {
    fn default() -> Self {
        Self {
            min_bin_share: 0.04,
            min_area_px: 12,
            max_detections: 8,
            min_fill: 0.35,
            min_score: 0.3,
            lateral_sigma_radii: 0.15,
            depth_sigma_frac: 0.12,
            velocity_sigma_across_mps: 3.0,
            velocity_sigma_along_mps: 0.5,
            cut_edge_inset_px: DEFAULT_CUT_EDGE_INSET_PX,
        }
    }
}

impl DetectorConfig {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<()> {
        let unit = |v: f64| v.is_finite() && v > 0.0 && v <= 1.0;
        if !(unit(self.min_bin_share) && unit(self.min_fill)) {
            return Err(TrackingError::Invalid(format!(
                "detector min_bin_share {} and min_fill {} must be in (0, 1]",
                self.min_bin_share, self.min_fill
            )));
        }
        for (name, v) in
            [("lateral_sigma_radii", self.lateral_sigma_radii), ("depth_sigma_frac", self.depth_sigma_frac)]
        {
            if !(v.is_finite() && v > 0.0) {
                return Err(TrackingError::Invalid(format!("detector {name} = {v} must be finite and positive")));
            }
        }
        if !(self.min_score.is_finite() && (-1.0..=1.0).contains(&self.min_score)) {
            return Err(TrackingError::Invalid(format!("detector min_score {} is outside [-1, 1]", self.min_score)));
        }
        if !(self.cut_edge_inset_px.is_finite() && (0.0..=2.0).contains(&self.cut_edge_inset_px)) {
            return Err(TrackingError::Invalid(format!(
                "detector cut_edge_inset_px {} is outside [0, 2] px",
                self.cut_edge_inset_px
            )));
        }
        if self.min_area_px == 0 {
            return Err(TrackingError::Invalid("detector min_area_px must be at least 1".into()));
        }
        Ok(())
    }
}

/// A connected region of the ball's colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Blob {
    /// Pixels in the blob.
    pub area_px: usize,
    /// Centroid (x, y), pixels.
    pub centroid: [f64; 2],
    /// Bounding box `[x0, y0, x1, y1]`, inclusive pixel indices.
    pub bbox: [usize; 4],
    /// The ball's image circle fitted to the blob (see the module doc).
    pub circle: Circle,
}

impl Blob {
    /// The disc of the blob's area about its centroid, pixels: the blob's own extent, which
    /// for a ball cut by an occluder is its visible part rather than the whole ball.
    pub fn area_circle(&self) -> Circle {
        area_circle(self.area_px, self.centroid)
    }
}

fn area_circle(area_px: usize, centroid: [f64; 2]) -> Circle {
    let r = (area_px as f64 / std::f64::consts::PI).sqrt();
    Circle { x: centroid[0], y: centroid[1], r }
}

/// The ball's circle for a blob of `area_px` pixels about `centroid` within `bbox`, whose
/// pixels are those where `on(x, y)` holds (see the module doc); a cut blob's radius is
/// grown by `inset` pixels ([`DetectorConfig::cut_edge_inset_px`]).
fn fit_circle(
    area_px: usize,
    centroid: [f64; 2],
    bbox: [usize; 4],
    inset: f64,
    on: impl Fn(usize, usize) -> bool,
) -> Circle {
    let disc = area_circle(area_px, centroid);
    let [x0, y0, x1, y1] = bbox.map(|v| v as f64);
    let (wx, wy) = (x1 - x0 + 1.0, y1 - y0 + 1.0);
    let half = wx.max(wy) / 2.0;
    if half <= 1.15 * disc.r {
        return disc;
    }
    let r = half + inset;
    // Cut by an occluder's edge: the longer side spans the whole ball, and across it the
    // round side lies one radius from the centre, at one end of the box or the other. Of
    // the two circles, the ball's is the one that holds more of the blob. (A ball more than
    // half visible, cut on one side by a panel and showing a sliver below it on the other,
    // has blob pixels on the box's edges on both sides; its centroid, or which edge holds
    // more pixels, put it 6 px to the wrong side.) On a tie the centroid decides, taking the
    // blob for less than half the disc, which is widest at the chord, so that its centroid
    // lies nearer the cut.
    let (lo_first, centre) = if wx >= wy {
        let c = |yc: f64| Circle { x: 0.5 * (x0 + x1), y: yc, r };
        ((c(y0 - 0.5 - inset + r), c(y1 + 0.5 + inset - r)), centroid[1] > 0.5 * (y0 + y1))
    } else {
        let c = |xc: f64| Circle { x: xc, y: 0.5 * (y0 + y1), r };
        ((c(x0 - 0.5 - inset + r), c(x1 + 0.5 + inset - r)), centroid[0] > 0.5 * (x0 + x1))
    };
    let (round_at_lo, round_at_hi) = lo_first;
    let held = |c: &Circle| {
        let r2 = (c.r + 0.5) * (c.r + 0.5);
        (bbox[1]..=bbox[3])
            .flat_map(|y| (bbox[0]..=bbox[2]).map(move |x| (x, y)))
            .filter(|&(x, y)| on(x, y) && (x as f64 - c.x).powi(2) + (y as f64 - c.y).powi(2) <= r2)
            .count()
    };
    match held(&round_at_lo).cmp(&held(&round_at_hi)) {
        std::cmp::Ordering::Greater => round_at_lo,
        std::cmp::Ordering::Less => round_at_hi,
        // The centroid past the middle: the cut (the widest part) on the high side.
        std::cmp::Ordering::Equal if centre => round_at_lo,
        std::cmp::Ordering::Equal => round_at_hi,
    }
}

/// The blobs of `frame` whose bins hold at least `min_bin_share` of `model`, largest first,
/// at most `max_detections`, each at least `min_area_px` and round enough (`min_fill`).
pub fn blobs(frame: &BinnedFrame, model: &Histogram, cfg: &DetectorConfig) -> Vec<Blob> {
    let member: [bool; BINS] = std::array::from_fn(|b| model.0[b] >= cfg.min_bin_share);
    let bins = frame.bins();
    let (w, h) = bins.size();
    // Union-find over provisional labels, 4-connectivity: one pass labels and merges.
    let mut label = vec![u32::MAX; w * h];
    let mut parent: Vec<u32> = Vec::new();
    fn find(parent: &mut [u32], mut a: u32) -> u32 {
        while parent[a as usize] != a {
            parent[a as usize] = parent[parent[a as usize] as usize];
            a = parent[a as usize];
        }
        a
    }
    for y in 0..h {
        let row = bins.row(y);
        for x in 0..w {
            if !member[row[x] as usize] {
                continue;
            }
            let left = if x > 0 { label[y * w + x - 1] } else { u32::MAX };
            let up = if y > 0 { label[(y - 1) * w + x] } else { u32::MAX };
            let l = match (left != u32::MAX, up != u32::MAX) {
                (false, false) => {
                    parent.push(parent.len() as u32);
                    parent.len() as u32 - 1
                }
                (true, false) => left,
                (false, true) => up,
                (true, true) => {
                    let (a, b) = (find(&mut parent, left), find(&mut parent, up));
                    let (lo, hi) = (a.min(b), a.max(b));
                    parent[hi as usize] = lo;
                    lo
                }
            };
            label[y * w + x] = l;
        }
    }
    // Statistics per root: area, sums for the centroid, bounding box.
    let roots: Vec<u32> = (0..parent.len() as u32).map(|l| find(&mut parent, l)).collect();
    let mut stats = vec![(0usize, 0.0f64, 0.0f64, [usize::MAX, usize::MAX, 0usize, 0usize]); parent.len()];
    for y in 0..h {
        for x in 0..w {
            let l = label[y * w + x];
            if l == u32::MAX {
                continue;
            }
            let s = &mut stats[roots[l as usize] as usize];
            s.0 += 1;
            s.1 += x as f64;
            s.2 += y as f64;
            s.3 = [s.3[0].min(x), s.3[1].min(y), s.3[2].max(x), s.3[3].max(y)];
        }
    }
    let mut out: Vec<Blob> = stats
        .into_iter()
        .enumerate()
        .filter(|(_, s)| s.0 >= cfg.min_area_px)
        .map(|(root, (n, sx, sy, bbox))| {
            let centroid = [sx / n as f64, sy / n as f64];
            let on = |x: usize, y: usize| {
                let l = label[y * w + x];
                l != u32::MAX && roots[l as usize] as usize == root
            };
            Blob { area_px: n, centroid, bbox, circle: fit_circle(n, centroid, bbox, cfg.cut_edge_inset_px, on) }
        })
        .filter(|b| b.area_px as f64 >= cfg.min_fill * std::f64::consts::PI * b.circle.r * b.circle.r)
        .collect();
    out.sort_by(|a, b| b.area_px.cmp(&a.area_px).then(a.bbox.cmp(&b.bbox)));
    out.truncate(cfg.max_detections);
    out
}

/// A 3D hypothesis of the ball's centre from a blob, with the spread of the proposal drawn
/// about it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BallDetection {
    /// The blob's image circle, pixels.
    pub circle: Circle,
    /// The ball's centre, metres, world frame.
    pub position: [f64; 3],
    /// Unit line of sight through the centre, world frame.
    pub direction: [f64; 3],
    /// Distance of the centre from the camera centre along the line of sight, metres.
    pub distance_m: f64,
    /// Standard deviation across the line of sight, metres.
    pub sigma_lateral_m: f64,
    /// Standard deviation along the line of sight, metres.
    pub sigma_depth_m: f64,
    /// Whether the blob looked cut by an occluder (its circle from its longer side).
    pub cut: bool,
}

/// Two unit vectors orthogonal to `u` and to each other.
fn basis(u: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let a = if u.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
    let e1 = u.cross(&a).normalize();
    (e1, u.cross(&e1))
}

impl BallDetection {
    /// The hypothesis of `blob` for a ball of `radius_m` seen by `camera` with `distortion`;
    /// `None` when the blob's centre cannot be undistorted.
    pub fn from_blob(
        blob: &Blob,
        camera: &PinholeCamera,
        distortion: &Distortion,
        radius_m: f64,
        cfg: &DetectorConfig,
    ) -> Option<Self> {
        let circle = blob.circle;
        let (ux, uy) = distortion.undistort_pixel(&camera.k, circle.x, circle.y).ok()?;
        let (centre, dir) = camera.back_project(&Vector2::new(ux, uy));
        let f = 0.5 * (camera.k.fx + camera.k.fy);
        let d = radius_m * (1.0 + (f / circle.r).powi(2)).sqrt();
        let p = centre + d * dir;
        let sigma_lateral_m = (cfg.lateral_sigma_radii * circle.r).max(1.0) * d / f;
        let ok = p.iter().all(|v| v.is_finite()) && sigma_lateral_m.is_finite();
        ok.then_some(Self {
            circle,
            position: p.into(),
            direction: dir.into(),
            distance_m: d,
            sigma_lateral_m,
            sigma_depth_m: cfg.depth_sigma_frac * d,
            cut: circle != blob.area_circle(),
        })
    }

    /// The same line of sight with the centre at `distance_m` instead (spread
    /// `depth_sigma_frac` of it along the line, the lateral spread scaled with the distance):
    /// a detection whose depth is taken from elsewhere (the track's prediction), since a
    /// blob's size gives the depth only roughly.
    pub fn at_distance(&self, distance_m: f64, depth_sigma_frac: f64) -> Self {
        let u = Vector3::from(self.direction);
        let p = Vector3::from(self.position) + (distance_m - self.distance_m) * u;
        Self {
            position: p.into(),
            distance_m,
            sigma_lateral_m: self.sigma_lateral_m * distance_m / self.distance_m,
            sigma_depth_m: depth_sigma_frac * distance_m,
            ..*self
        }
    }

    /// Draws a centre from the detection's Gaussian.
    pub fn sample_position(&self, rng: &mut SplitMix64) -> [f64; 3] {
        sample_about_line(&self.position, &self.direction, self.sigma_lateral_m, self.sigma_depth_m, rng)
    }

    /// `ln` of the detection's Gaussian density at `position`.
    pub fn log_density(&self, position: &[f64; 3]) -> f64 {
        log_density_about_line(&self.position, &self.direction, self.sigma_lateral_m, self.sigma_depth_m, position)
    }

    /// Draws a velocity about `mean` (m/s): `across` m/s across this line of sight, `along`
    /// m/s along it.
    pub fn sample_velocity(&self, mean: &[f64; 3], across: f64, along: f64, rng: &mut SplitMix64) -> [f64; 3] {
        sample_about_line(mean, &self.direction, across, along, rng)
    }

    /// `ln` of the density of [`Self::sample_velocity`] at `v`.
    pub fn log_velocity_density(&self, mean: &[f64; 3], across: f64, along: f64, v: &[f64; 3]) -> f64 {
        log_density_about_line(mean, &self.direction, across, along, v)
    }
}

/// A draw of the Gaussian about `mean` with spread `across` perpendicular to the unit
/// `direction` and `along` on it.
fn sample_about_line(mean: &[f64; 3], direction: &[f64; 3], across: f64, along: f64, rng: &mut SplitMix64) -> [f64; 3] {
    let u = Vector3::from(*direction);
    let (e1, e2) = basis(&u);
    let (a, b) = rng.normal_pair();
    let p = Vector3::from(*mean) + across * (a * e1 + b * e2) + along * rng.normal() * u;
    p.into()
}

/// `ln` of that Gaussian's density at `x`.
fn log_density_about_line(mean: &[f64; 3], direction: &[f64; 3], across: f64, along: f64, x: &[f64; 3]) -> f64 {
    let u = Vector3::from(*direction);
    let d = Vector3::from(*x) - Vector3::from(*mean);
    let on = d.dot(&u);
    let off2 = (d - on * u).norm_squared();
    -1.5 * LN_2PI - 2.0 * across.ln() - along.ln() - 0.5 * (off2 / (across * across) + on * on / (along * along))
}

/// The 3D hypotheses of the blobs of the ball's colour in `frame` whose circles score at
/// least `min_score` under `colour`, best score first.
pub fn detect_balls(
    frame: &BinnedFrame,
    colour: &ColourModel,
    camera: &PinholeCamera,
    distortion: &Distortion,
    radius_m: f64,
    cfg: &DetectorConfig,
) -> Vec<BallDetection> {
    // A blob cut by an occluder is scored on the disc of its area about its centroid as well
    // as on the ball's circle: the circle is then half occluder, and scores low however
    // plainly the visible part stands out (a ball half behind a panel scored 0.29 on its true
    // circle and 0.39 on the visible part's disc, generated approach 3, frame 43).
    let mut scored: Vec<(f64, BallDetection)> = blobs(frame, colour.histogram(), cfg)
        .iter()
        .filter_map(|b| BallDetection::from_blob(b, camera, distortion, radius_m, cfg).map(|d| (b, d)))
        .map(|(b, d)| {
            let visible = b.area_circle();
            let s = colour.score(frame, d.circle);
            (if visible == d.circle { s } else { s.max(colour.score(frame, visible)) }, d)
        })
        .filter(|(s, _)| *s >= cfg.min_score)
        .collect();
    scored.sort_by(|a, b| b.0.total_cmp(&a.0));
    scored.into_iter().map(|(_, d)| d).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ball::project_ball;
    use nalgebra::Matrix3;
    use ocellus_geometry::camera::Intrinsics;
    use ocellus_image::Plane;

    fn camera() -> PinholeCamera {
        let k = Intrinsics { fx: 600.0, fy: 600.0, cx: 319.5, cy: 239.5, skew: 0.0 };
        PinholeCamera { k, r: Matrix3::identity(), t: Vector3::zeros() }
    }

    /// A real photo with an orange ball at `centre`, and optionally a second orange disc.
    fn frame(c: Circle, other: Option<Circle>, hide_left: bool) -> Plane<[u8; 3]> {
        let photo = ocellus_io::read_image(ocellus_testdata::data_file("astronaut.png")).unwrap().to_u8();
        Plane::from_fn(640, 480, |x, y| {
            let inside = |c: &Circle| (x as f64 - c.x).powi(2) + (y as f64 - c.y).powi(2) <= c.r * c.r;
            if (inside(&c) && !(hide_left && (x as f64) < c.x)) || other.as_ref().is_some_and(inside) {
                [240, 118, 22]
            } else {
                photo.get(x * 512 / 640, y * 512 / 480)
            }
        })
    }

    #[test]
    fn a_blob_gives_the_ball_in_3d() {
        let cam = camera();
        let d = Distortion::default();
        let truth = Vector3::new(0.3, -0.1, 2.2);
        let c = project_ball(&cam, &d, &truth, 0.05).unwrap();
        let f = frame(c, Some(Circle { x: 120.0, y: 110.0, r: 30.0 }), false);
        let binned = BinnedFrame::new(&f);
        let model = crate::colour::ColourModel::from_colour([240, 118, 22]);
        let cfg = DetectorConfig::default();
        let found = detect_balls(&binned, &model, &cam, &d, 0.05, &cfg);
        assert_eq!(found.len(), 2, "{found:?}");
        // The photo's own orange patches do not stand out from their surroundings (scores
        // below 0.1); the larger disc scores best: a nearer ball (30 px: about 1 m away).
        let dist = Vector3::from(found[0].position).norm();
        assert!((dist - 0.05 * (1.0f64 + 400.0).sqrt()).abs() < 0.01, "{:?}", found[0]);
        let ball = found[1];
        let err = (Vector3::from(ball.position) - truth).norm();
        // Radius 13.6 px: half a pixel of radius is 3.7 % of the depth.
        assert!(err < 0.04 * truth.z, "{ball:?} vs {truth}");
        assert!((ball.circle.x - c.x).abs() < 0.5 && (ball.circle.y - c.y).abs() < 0.5);
        assert!(!found[0].cut && !ball.cut);
        // Half hidden, a ball's blob is cut.
        let c = Circle { x: 300.0, y: 200.0, r: 20.0 };
        let b = blobs(&BinnedFrame::new(&frame(c, None, true)), model.histogram(), &cfg);
        let half = b.iter().find(|b| (b.circle.x - c.x).abs() < 2.0 && (b.circle.y - c.y).abs() < 2.0).unwrap();
        assert!(BallDetection::from_blob(half, &cam, &d, 0.05, &cfg).unwrap().cut);
    }

    #[test]
    fn half_hidden_keeps_the_extent() {
        let c = Circle { x: 300.0, y: 200.0, r: 20.0 };
        let f = frame(c, None, true);
        let model = crate::colour::ColourModel::from_colour([240, 118, 22]);
        let b = blobs(&BinnedFrame::new(&f), model.histogram(), &DetectorConfig::default());
        // The photo has orange patches too: take the blob at the half disc.
        let got =
            b.iter().map(|b| b.circle).find(|c| (c.x - 300.0).abs() < 20.0 && (c.y - 200.0).abs() < 20.0).unwrap();
        assert!((got.r - 20.0).abs() < 1.0, "{got:?}");
        // The centre is found again, though the centroid of the half disc lies 4r / 3 pi
        // right of it.
        assert!((got.x - 300.0).abs() < 1.0 && (got.y - 200.0).abs() < 1.0, "{got:?}");
    }

    #[test]
    fn the_edge_inset_grows_a_cut_blob_about_the_same_centre_and_leaves_whole_blobs() {
        let model = crate::colour::ColourModel::from_colour([240, 118, 22]);
        let c = Circle { x: 300.0, y: 200.0, r: 20.0 };
        let at = |hide: bool, inset: f64| {
            let cfg = DetectorConfig { cut_edge_inset_px: inset, ..DetectorConfig::default() };
            let b = blobs(&BinnedFrame::new(&frame(c, None, hide)), model.histogram(), &cfg);
            b.iter().map(|b| b.circle).find(|c| (c.x - 300.0).abs() < 20.0 && (c.y - 200.0).abs() < 20.0).unwrap()
        };
        // The round side moves out with the radius: the centre stays where the box puts it.
        let (bare, grown) = (at(true, 0.0), at(true, 0.3));
        assert!((grown.r - bare.r - 0.3).abs() < 1e-12, "{bare:?} {grown:?}");
        assert_eq!((grown.x, grown.y), (bare.x, bare.y));
        assert_eq!(at(false, 0.0), at(false, 0.3));
    }

    #[test]
    fn a_ball_more_than_half_visible_is_placed_by_the_blob_it_covers() {
        // A panel hides the ball right of x = 306 down to y = 212, below which a sliver of
        // its lower right shows: the blob's box spans 280..=316 across (the round left side
        // and the sliver) and 180..=220 down. Its centroid lies left of the box's middle, so
        // the centroid's rule took the left end for the cut and put the centre 3.5 px left.
        let c = Circle { x: 300.0, y: 200.0, r: 20.0 };
        let photo = ocellus_io::read_image(ocellus_testdata::data_file("astronaut.png")).unwrap().to_u8();
        let f = Plane::from_fn(640, 480, |x, y| {
            let (px, py) = (x as f64, y as f64);
            let on_ball = (px - c.x).powi(2) + (py - c.y).powi(2) <= c.r * c.r;
            if on_ball && !(px > 306.0 && py < 212.0) {
                [240, 118, 22]
            } else {
                photo.get(x * 512 / 640, y * 512 / 480)
            }
        });
        let model = crate::colour::ColourModel::from_colour([240, 118, 22]);
        let b = blobs(&BinnedFrame::new(&f), model.histogram(), &DetectorConfig::default());
        let blob = b.iter().find(|b| (b.centroid[0] - 300.0).abs() < 20.0 && (b.centroid[1] - 200.0).abs() < 20.0);
        let blob = blob.unwrap();
        assert!(blob.centroid[0] < 0.5 * (blob.bbox[0] + blob.bbox[2]) as f64, "{blob:?}");
        let got = blob.circle;
        assert!((got.r - 20.0).abs() < 1.0, "{got:?}");
        assert!((got.x - 300.0).abs() < 1.0 && (got.y - 200.0).abs() < 1.0, "{got:?}");
    }

    #[test]
    fn the_proposal_density_matches_its_samples() {
        let det = BallDetection {
            circle: Circle { x: 0.0, y: 0.0, r: 10.0 },
            position: [0.2, 0.1, 2.0],
            direction: Vector3::new(0.1, 0.05, 1.0).normalize().into(),
            distance_m: 2.0,
            sigma_lateral_m: 0.01,
            sigma_depth_m: 0.2,
            cut: false,
        };
        let mut rng = SplitMix64::new(9);
        // E[-ln q] over samples is the Gaussian's entropy: 1.5 (1 + ln 2 pi) + ln(sl^2 sd).
        let n = 50_000;
        let h: f64 = (0..n).map(|_| -det.log_density(&det.sample_position(&mut rng))).sum::<f64>() / n as f64;
        let want = 1.5 * (1.0 + LN_2PI) + (0.01f64 * 0.01 * 0.2).ln();
        assert!((h - want).abs() < 0.02, "{h} vs {want}");
    }

    #[test]
    fn unusable_detector_settings_are_refused() {
        let ok = DetectorConfig::default();
        assert!(ok.validate().is_ok());
        for c in [
            DetectorConfig { min_bin_share: 0.0, ..ok },
            DetectorConfig { min_fill: f64::NAN, ..ok },
            DetectorConfig { depth_sigma_frac: -0.1, ..ok },
            DetectorConfig { min_area_px: 0, ..ok },
            DetectorConfig { cut_edge_inset_px: f64::NAN, ..ok },
            DetectorConfig { cut_edge_inset_px: -0.1, ..ok },
            DetectorConfig { cut_edge_inset_px: 2.5, ..ok },
        ] {
            assert!(c.validate().is_err(), "{c:?}");
        }
    }
}
