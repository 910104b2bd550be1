//! Attention dynamics (SPEC 3.1-3.3; iCub attention system, Ruesch et al. 2008): where the
//! gaze goes, frame after frame.
//!
//! Per frame ([`Attention::step`]):
//! 1. habituation and inhibition of return decay (time constants in frames);
//! 2. inhibition is read from the ego-sphere at every map cell's direction, capped at 1;
//! 3. winner-take-all: if the surprise (bits) times `1 - inhibition` exceeds
//!    `surprise_threshold_bits` somewhere, its maximum wins (reason: surprising); otherwise the
//!    maximum of saliency times `1 - inhibition` (reason: salient);
//! 4. habituation grows at the winner; when it reaches `habituation_threshold` there, an
//!    inhibition-of-return blob is added at the winner and the habituation there is cleared,
//!    so the gaze dwells for a while, then moves on and does not come back while inhibited.
//!
//! Habituation and inhibition live on the ego-sphere ([`crate::egosphere`]), in head-centred
//! angles, so they stay attached to the world when the camera pans or tilts. With a still
//! camera (pan = tilt = 0) this is the usual image-frame inhibition of return.
//! Times are in frames: at f frames per second, `tau_frames / f` seconds.

use crate::egosphere::{separation_deg, BlobField, Egosphere, ViewGeometry};
use crate::{AttentionError, Result};
use ocellus_image::location::cell_centre;
use ocellus_image::Plane;
use serde::{Deserialize, Serialize};

/// Parameters of [`Attention`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AttentionConfig {
    /// Habituation added at the attended place per frame.
    pub habituation_gain: f32,
    /// Time constant of habituation decay, frames.
    pub habituation_tau_frames: f32,
    /// Habituation at which the attended place gets inhibited.
    pub habituation_threshold: f32,
    /// Size (standard deviation) of a habituation blob, degrees.
    pub habituation_sigma_deg: f32,
    /// Peak of an inhibition-of-return blob (1: the place cannot win while fresh).
    pub ior_amplitude: f32,
    /// Time constant of inhibition-of-return decay, frames.
    pub ior_tau_frames: f32,
    /// Size (standard deviation) of an inhibition-of-return blob, degrees.
    pub ior_sigma_deg: f32,
    /// Surprise (bits) above which the most surprising place wins over the most salient.
    pub surprise_threshold_bits: f32,
    /// A new winner closer than this to the current fixation is not a saccade, degrees.
    pub min_saccade_deg: f32,
    /// Cell size of the ego-sphere's saliency mosaic, degrees.
    pub egosphere_deg_per_cell: f32,
}

impl Default for AttentionConfig {
    /// Defaults for 30 frames/s and a 64 degree field of view: a fixation dwells about 14
    /// frames (0.5 s) before it is inhibited; inhibition lasts about 3 s.
    fn default() -> Self {
        Self {
            habituation_gain: 0.1,
            habituation_tau_frames: 20.0,
            habituation_threshold: 1.0,
            habituation_sigma_deg: 2.0,
            ior_amplitude: 1.0,
            ior_tau_frames: 90.0,
            ior_sigma_deg: 4.0,
            surprise_threshold_bits: 5.0,
            min_saccade_deg: 2.5,
            egosphere_deg_per_cell: 1.0,
        }
    }
}

impl AttentionConfig {
    /// Checks the ranges.
    pub fn validate(&self) -> Result<()> {
        use ocellus_image::check;
        (|| {
            for (name, v) in [
                ("habituation_gain", self.habituation_gain),
                ("habituation_tau_frames", self.habituation_tau_frames),
                ("habituation_threshold", self.habituation_threshold),
                ("habituation_sigma_deg", self.habituation_sigma_deg),
                ("ior_amplitude", self.ior_amplitude),
                ("ior_tau_frames", self.ior_tau_frames),
                ("ior_sigma_deg", self.ior_sigma_deg),
                ("egosphere_deg_per_cell", self.egosphere_deg_per_cell),
            ] {
                check::positive(name, v)?;
            }
            check::finite("surprise_threshold_bits", self.surprise_threshold_bits)?;
            check::non_negative("min_saccade_deg", self.min_saccade_deg)
        })()
        .map_err(AttentionError::InvalidConfig)
    }
}

/// Why a place was attended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Reason {
    /// The most salient uninhibited place.
    Salient,
    /// Surprise above the threshold.
    Surprising,
}

impl Reason {
    /// Lower-case name.
    pub fn as_str(&self) -> &'static str {
        match self {
            Reason::Salient => "salient",
            Reason::Surprising => "surprising",
        }
    }
}

/// Where attention is in one frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fixation {
    /// Frame index.
    pub frame: usize,
    /// Image position, pixels of the full-size frame (pixel centres at integers).
    pub x: f32,
    /// Image position, pixels.
    pub y: f32,
    /// Direction on the ego-sphere, degrees.
    pub azimuth_deg: f32,
    /// Direction on the ego-sphere, degrees.
    pub elevation_deg: f32,
    /// Why it won.
    pub reason: Reason,
    /// `true` when the gaze moved here this frame (a scanpath entry).
    pub saccade: bool,
}

/// Attention over a stream of maps.
#[derive(Debug)]
pub struct Attention {
    cfg: AttentionConfig,
    view: ViewGeometry,
    habituation: BlobField,
    inhibition: BlobField,
    egosphere: Egosphere,
    inhibition_map: Plane<f32>,
    /// Scratch: azimuth of each map column and elevation of each map row this frame.
    col_az: Vec<f32>,
    row_el: Vec<f32>,
    current: Option<Fixation>,
    frame: usize,
}

/// The cell (x, y) maximizing `map * (1 - inhibition)`, and the value, if it is > 0.
fn argmax_free(map: &Plane<f32>, inhibition: &Plane<f32>) -> Option<((usize, usize), f32)> {
    let mut best: Option<((usize, usize), f32)> = None;
    for y in 0..map.height() {
        for (x, (&m, &i)) in map.row(y).iter().zip(inhibition.row(y)).enumerate() {
            let v = m * (1.0 - i);
            if v > 0.0 && !matches!(best, Some((_, b)) if v <= b) {
                best = Some(((x, y), v));
            }
        }
    }
    best
}

impl Attention {
    /// Attention for a camera described by `view` (the full-size frame).
    pub fn new(cfg: AttentionConfig, view: ViewGeometry) -> Result<Self> {
        cfg.validate()?;
        view.validate()?;
        Ok(Self {
            egosphere: Egosphere::new(cfg.egosphere_deg_per_cell)?,
            cfg,
            view,
            habituation: BlobField::default(),
            inhibition: BlobField::default(),
            inhibition_map: Plane::default(),
            col_az: Vec::new(),
            row_el: Vec::new(),
            current: None,
            frame: 0,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &AttentionConfig {
        &self.cfg
    }

    /// Inhibition (0..1) at each map cell in the last frame, for display.
    pub fn inhibition_map(&self) -> &Plane<f32> {
        &self.inhibition_map
    }

    /// Inhibition-of-return blobs.
    pub fn inhibition_of_return(&self) -> &BlobField {
        &self.inhibition
    }

    /// Habituation blobs.
    pub fn habituation(&self) -> &BlobField {
        &self.habituation
    }

    /// The ego-sphere with its saliency mosaic.
    pub fn egosphere(&self) -> &Egosphere {
        &self.egosphere
    }

    /// The current fixation.
    pub fn fixation(&self) -> Option<&Fixation> {
        self.current.as_ref()
    }

    /// One frame: `saliency` (and optionally `surprise` in bits, same size) at any map size
    /// covering the view; camera at (`pan_deg`, `tilt_deg`). Returns the fixation, or `None`
    /// when nothing in view is salient (a flat or fully inhibited map).
    pub fn step(
        &mut self,
        saliency: &Plane<f32>,
        surprise: Option<&Plane<f32>>,
        pan_deg: f32,
        tilt_deg: f32,
    ) -> Result<Option<Fixation>> {
        if saliency.is_empty() || !saliency.all_finite() {
            return Err(AttentionError::InvalidInput("attention needs a non-empty, finite saliency map".into()));
        }
        if let Some(s) = surprise {
            ocellus_image::check::same_size("surprise map (against the saliency map)", s.size(), saliency.size())?;
            if !s.all_finite() {
                return Err(AttentionError::InvalidInput("the surprise map must be finite".into()));
            }
        }
        if !(pan_deg.is_finite() && tilt_deg.is_finite()) {
            return Err(AttentionError::InvalidInput(format!("camera angles pan {pan_deg}, tilt {tilt_deg}")));
        }
        let c = &self.cfg;
        self.habituation.decay((-1.0 / c.habituation_tau_frames).exp());
        self.inhibition.decay((-1.0 / c.ior_tau_frames).exp());
        self.egosphere.splat(saliency, &self.view, pan_deg, tilt_deg);
        // Map cell centres in full-frame pixels and on the sphere (azimuth depends on the
        // column only, elevation on the row only, in the equiangular model).
        let (mw, mh) = saliency.size();
        let (vw, vh) = (self.view.width, self.view.height);
        let pixel = |x: usize, y: usize| (cell_centre(x, mw, vw) as f32, cell_centre(y, mh, vh) as f32);
        self.col_az.clear();
        self.col_az.extend((0..mw).map(|x| self.view.direction(pixel(x, 0).0, 0.0, pan_deg, tilt_deg).0));
        self.row_el.clear();
        self.row_el.extend((0..mh).map(|y| self.view.direction(0.0, pixel(0, y).1, pan_deg, tilt_deg).1));
        self.inhibition_map.resize(mw, mh);
        for y in 0..mh {
            let el = self.row_el[y];
            let out = self.inhibition_map.row_mut(y);
            out.fill(0.0);
            // Blobs further than 4 sigma in elevation cannot reach this row.
            for b in self.inhibition.blobs.iter().filter(|b| (b.el - el).abs() <= 4.0 * b.sigma_deg) {
                for (o, &az) in out.iter_mut().zip(&self.col_az) {
                    *o += b.value(az, el);
                }
            }
            out.iter_mut().for_each(|v| *v = v.min(1.0));
        }
        let surprising = surprise
            .and_then(|s| argmax_free(s, &self.inhibition_map))
            .filter(|&(_, v)| v > self.cfg.surprise_threshold_bits);
        let winner = match surprising {
            Some((cell, _)) => Some((cell, Reason::Surprising)),
            None => argmax_free(saliency, &self.inhibition_map).map(|(cell, _)| (cell, Reason::Salient)),
        };
        let frame = self.frame;
        self.frame += 1;
        let Some(((cx, cy), reason)) = winner else {
            self.current = None;
            return Ok(None);
        };
        let (x, y) = pixel(cx, cy);
        let (az, el) = self.view.direction(x, y, pan_deg, tilt_deg);
        let c = &self.cfg;
        let saccade =
            self.current.is_none_or(|f| separation_deg((az, el), (f.azimuth_deg, f.elevation_deg)) > c.min_saccade_deg);
        // Neighbouring map cells of one object share a habituation blob.
        self.habituation.add(az, el, c.habituation_gain, c.habituation_sigma_deg, c.habituation_sigma_deg);
        if self.habituation.value(az, el) >= c.habituation_threshold {
            self.inhibition.add(az, el, c.ior_amplitude, c.ior_sigma_deg, c.ior_sigma_deg / 2.0);
            self.habituation.clear_near(az, el, c.habituation_sigma_deg);
        }
        let f = Fixation { frame, x, y, azimuth_deg: az, elevation_deg: el, reason, saccade };
        self.current = Some(f);
        Ok(Some(f))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn view() -> ViewGeometry {
        ViewGeometry { width: 320, height: 240, deg_per_px: 0.2 }
    }

    /// Three bright spots of different strength on a 20x15 map.
    fn spots() -> Plane<f32> {
        let mut m = Plane::new(20, 15);
        m.set(3, 3, 1.0);
        m.set(15, 4, 0.8);
        m.set(10, 11, 0.6);
        m
    }

    #[test]
    fn dwells_then_visits_every_spot_in_order_of_saliency() {
        let mut a = Attention::new(AttentionConfig::default(), view()).unwrap();
        let m = spots();
        let mut scanpath = Vec::new();
        for _ in 0..60 {
            let f = a.step(&m, None, 0.0, 0.0).unwrap().unwrap();
            if f.saccade {
                scanpath.push(((f.x / 16.0) as usize, (f.y / 16.0) as usize));
            }
        }
        assert_eq!(&scanpath[..3], &[(3, 3), (15, 4), (10, 11)], "{scanpath:?}");
        // Dwell: the first saccade happens only after habituation reached the threshold.
        let mut b = Attention::new(AttentionConfig::default(), view()).unwrap();
        let n = (0..30).take_while(|_| b.step(&m, None, 0.0, 0.0).unwrap().unwrap().x < 100.0).count();
        assert!((10..=20).contains(&n), "dwelt {n} frames");
    }

    #[test]
    fn surprise_wins_over_saliency_above_its_threshold() {
        let mut a = Attention::new(AttentionConfig::default(), view()).unwrap();
        let m = spots();
        let mut s = Plane::new(20, 15);
        s.set(18, 13, 2.0);
        assert_eq!(a.step(&m, Some(&s), 0.0, 0.0).unwrap().unwrap().reason, Reason::Salient);
        s.set(18, 13, 20.0);
        let f = a.step(&m, Some(&s), 0.0, 0.0).unwrap().unwrap();
        assert_eq!((f.reason, (f.x / 16.0) as usize, (f.y / 16.0) as usize), (Reason::Surprising, 18, 13));
        assert!(f.saccade);
    }

    #[test]
    fn flat_maps_and_bad_input() {
        let mut a = Attention::new(AttentionConfig::default(), view()).unwrap();
        assert!(a.step(&Plane::new(20, 15), None, 0.0, 0.0).unwrap().is_none());
        assert!(a.step(&Plane::from_fn(20, 15, |_, _| f32::NAN), None, 0.0, 0.0).is_err());
        assert!(a.step(&spots(), Some(&Plane::new(3, 3)), 0.0, 0.0).is_err());
        assert!(a.step(&spots(), None, f32::INFINITY, 0.0).is_err());
        let bad = AttentionConfig { ior_tau_frames: 0.0, ..Default::default() };
        assert!(Attention::new(bad, view()).is_err());
    }
}
