//! Image sequences with ground truth for surprise, context chaos and attention (SPEC 2.1-2.2, 3).
//!
//! The world is a cylindrical panorama: the given real images, each scaled to the frame height
//! (bilinear) and laid side by side, wrapping around horizontally. A camera of
//! `deg_per_px` degrees per pixel sees a `width` x `height` window of it; its pan angle is
//! `deg_per_px` times the window's left edge (0 at frame 0), tilt is 0. Scenarios:
//! - [`Scenario::Static`]: the camera does not move; only sensor noise changes.
//! - [`Scenario::SuddenObject`]: as static, and from `event_frame` on, an object (the centre of
//!   another real image, scaled to `object_size`) is in the frame at `object_at`.
//! - [`Scenario::Pan`]: the camera pans steadily by `pan_px_per_frame` (sub-pixel, bilinear);
//!   no events.
//!
//! Every frame gets independent Gaussian sensor noise of `noise_sigma` grey levels per channel
//! (seeded by the configuration's seed and the frame index), then is rounded to 8 bits.

use crate::texture::sample;
use crate::{Result, SynthError};
use ocellus_image::convert::RgbImage;
use ocellus_image::location::cell_centre;
use ocellus_image::rng::SplitMix64;
use ocellus_image::Plane;
use serde::{Deserialize, Serialize};

/// What happens in the sequence.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Scenario {
    /// Still camera, still world, sensor noise.
    Static,
    /// Still camera; an object appears at a known frame and place.
    SuddenObject,
    /// Steady camera pan over a still world.
    Pan,
}

/// A rectangle in frame pixels: top-left corner and size.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rect {
    /// Left column.
    pub x: usize,
    /// Top row.
    pub y: usize,
    /// Width in pixels.
    pub w: usize,
    /// Height in pixels.
    pub h: usize,
}

impl Rect {
    /// Centre (x, y) in pixels.
    pub fn center(&self) -> (f32, f32) {
        (self.x as f32 + (self.w as f32 - 1.0) / 2.0, self.y as f32 + (self.h as f32 - 1.0) / 2.0)
    }
}

/// Parameters of a sequence.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneConfig {
    /// The scenario.
    pub scenario: Scenario,
    /// Frame width in pixels.
    pub width: usize,
    /// Frame height in pixels.
    pub height: usize,
    /// Number of frames.
    pub frames: usize,
    /// Sensor noise, standard deviation in 8-bit grey levels (0: none).
    pub noise_sigma: f32,
    /// Seed of the noise.
    pub seed: u64,
    /// First frame showing the object (`SuddenObject`).
    pub event_frame: usize,
    /// Object size (width, height) in pixels.
    pub object_size: (usize, usize),
    /// Object's top-left corner in the frame, pixels.
    pub object_at: (usize, usize),
    /// Pan speed in pixels per frame (`Pan`), positive to the right.
    pub pan_px_per_frame: f32,
    /// Angle per pixel of the camera, degrees (0.1: a 64 degree field of view at 640 px).
    pub deg_per_px: f32,
}

impl SceneConfig {
    /// Defaults: 640x480, 30 frames, noise 2 grey levels, seed 1, the object (160x200 px) at
    /// (400, 160) from frame 15, pan 6 px/frame, 0.1 degree per pixel.
    pub fn new(scenario: Scenario) -> Self {
        Self {
            scenario,
            width: 640,
            height: 480,
            frames: 30,
            noise_sigma: 2.0,
            seed: 1,
            event_frame: 15,
            object_size: (160, 200),
            object_at: (400, 160),
            pan_px_per_frame: 6.0,
            deg_per_px: 0.1,
        }
    }

    fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(SynthError::InvalidConfig(m));
        if self.width < 8 || self.height < 8 || self.width > 16_384 || self.height > 16_384 {
            return bad(format!("frame {}x{}: need 8..=16384 per side", self.width, self.height));
        }
        if self.frames == 0 {
            return bad("frames must be >= 1".into());
        }
        if !(self.noise_sigma.is_finite() && self.noise_sigma >= 0.0) {
            return bad(format!("noise_sigma {} must be >= 0", self.noise_sigma));
        }
        if !(self.pan_px_per_frame.is_finite() && self.deg_per_px.is_finite() && self.deg_per_px > 0.0) {
            return bad("pan_px_per_frame must be finite and deg_per_px > 0".into());
        }
        if self.scenario == Scenario::SuddenObject {
            let (ow, oh) = self.object_size;
            let (ox, oy) = self.object_at;
            if ow == 0 || oh == 0 || ox + ow > self.width || oy + oh > self.height {
                return bad(format!(
                    "object {ow}x{oh} at ({ox}, {oy}) does not fit a {}x{} frame",
                    self.width, self.height
                ));
            }
        }
        Ok(())
    }
}

/// Ground truth of one frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrameTruth {
    /// Frame index.
    pub frame: usize,
    /// Camera pan: azimuth of the frame centre relative to frame 0, degrees, positive right.
    pub pan_deg: f32,
    /// Camera tilt, degrees, positive down (always 0 here).
    pub tilt_deg: f32,
    /// The object's rectangle when it is in the frame.
    pub object: Option<Rect>,
    /// `true` on the frame where the object appears.
    pub event: bool,
}

/// Renders the frames of one sequence; frames can be asked in any order.
#[derive(Debug)]
pub struct SceneGenerator {
    cfg: SceneConfig,
    world: Plane<[f32; 3]>,
    object: Plane<[f32; 3]>,
}

/// `img` scaled to `w` x `h` (bilinear, pixel centres aligned).
fn scaled(img: &RgbImage, w: usize, h: usize) -> Plane<[f32; 3]> {
    let (iw, ih) = img.size();
    let src = Plane::from_fn(iw, ih, |x, y| img.get_f32(x, y));
    // Pixel (x, y) of the output is the point with the same cell position in the source.
    Plane::from_fn(w, h, |x, y| sample(&src, cell_centre(x, w, iw), cell_centre(y, h, ih), false, false))
}

impl SceneGenerator {
    /// A generator over the panorama of `world` images and with the object cut from the centre
    /// of `object_source` (its largest centred region of the object's aspect ratio).
    pub fn new(cfg: SceneConfig, world: &[RgbImage], object_source: &RgbImage) -> Result<Self> {
        cfg.validate()?;
        if world.is_empty() || world.iter().chain([object_source]).any(|i| i.size().0 == 0 || i.size().1 == 0) {
            return Err(SynthError::InvalidConfig(
                "need at least one non-empty world image and an object image".into(),
            ));
        }
        let h = cfg.height;
        let parts: Vec<Plane<[f32; 3]>> = world
            .iter()
            .map(|img| {
                let (iw, ih) = img.size();
                scaled(img, ((iw * h) as f64 / ih as f64).round().max(1.0) as usize, h)
            })
            .collect();
        let total: usize = parts.iter().map(|p| p.width()).sum();
        let mut pano = Plane::new(total, h);
        let mut x0 = 0;
        for p in &parts {
            for y in 0..h {
                pano.row_mut(y)[x0..x0 + p.width()].copy_from_slice(p.row(y));
            }
            x0 += p.width();
        }
        let (ow, oh) = (cfg.object_size.0.max(1), cfg.object_size.1.max(1));
        let (sw, sh) = object_source.size();
        // Centred crop with the object's aspect ratio, then scaled to the object size.
        let (cw, ch) = if sw * oh > sh * ow { (sh * ow / oh, sh) } else { (sw, sw * oh / ow) };
        let (cx, cy) = ((sw - cw.max(1)) / 2, (sh - ch.max(1)) / 2);
        let crop = Plane::from_fn(cw.max(1), ch.max(1), |x, y| object_source.get_f32(cx + x, cy + y));
        let crop = RgbImage::F32(crop);
        let object = scaled(&crop, ow, oh);
        Ok(Self { cfg, world: pano, object })
    }

    /// The configuration.
    pub fn config(&self) -> &SceneConfig {
        &self.cfg
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.cfg.frames
    }

    /// `true` when there are no frames (never, a configuration needs at least one).
    pub fn is_empty(&self) -> bool {
        self.cfg.frames == 0
    }

    /// Width of the panorama in pixels (360 degrees of wrap-around).
    pub fn world_width(&self) -> usize {
        self.world.width()
    }

    /// The truth of frame `k` without rendering it.
    pub fn truth(&self, k: usize) -> Result<FrameTruth> {
        if k >= self.cfg.frames {
            return Err(SynthError::NoSuchFrame { index: k, len: self.cfg.frames });
        }
        let c = &self.cfg;
        let shown = c.scenario == Scenario::SuddenObject && k >= c.event_frame;
        let object =
            shown.then_some(Rect { x: c.object_at.0, y: c.object_at.1, w: c.object_size.0, h: c.object_size.1 });
        Ok(FrameTruth {
            frame: k,
            pan_deg: self.offset_px(k) * c.deg_per_px,
            tilt_deg: 0.0,
            object,
            event: shown && k == c.event_frame,
        })
    }

    fn offset_px(&self, k: usize) -> f32 {
        match self.cfg.scenario {
            Scenario::Pan => self.cfg.pan_px_per_frame * k as f32,
            _ => 0.0,
        }
    }

    /// Frame `k` (8-bit RGB) and its truth.
    pub fn frame(&self, k: usize) -> Result<(RgbImage, FrameTruth)> {
        let truth = self.truth(k)?;
        let c = &self.cfg;
        let off = self.offset_px(k);
        // Each frame's noise has its own seed: frames can be rendered in any order.
        let mut rng = SplitMix64::new(c.seed ^ (k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
        let sigma = c.noise_sigma / 255.0;
        let img = Plane::from_fn(c.width, c.height, |x, y| {
            let mut p = match truth.object {
                Some(r) if (r.x..r.x + r.w).contains(&x) && (r.y..r.y + r.h).contains(&y) => {
                    self.object.get(x - r.x, y - r.y)
                }
                _ => sample(&self.world, (off + x as f32) as f64, y as f64, true, false),
            };
            if sigma > 0.0 {
                p.iter_mut().for_each(|v| *v += sigma * rng.normal() as f32);
            }
            p.map(|v| (v * 255.0).round().clamp(0.0, 255.0) as u8)
        });
        Ok((RgbImage::U8(img), truth))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gen(s: Scenario, noise: f32) -> SceneGenerator {
        let world = RgbImage::U8(Plane::from_fn(200, 50, |x, y| [(x % 200) as u8, (y * 5) as u8, 77]));
        let object = RgbImage::U8(Plane::from_fn(40, 40, |_, _| [250, 10, 10]));
        let cfg = SceneConfig {
            width: 64,
            height: 50,
            frames: 10,
            noise_sigma: noise,
            event_frame: 4,
            object_size: (16, 12),
            object_at: (30, 20),
            pan_px_per_frame: 2.5,
            ..SceneConfig::new(s)
        };
        SceneGenerator::new(cfg, &[world], &object).unwrap()
    }

    #[test]
    fn object_appears_at_its_frame_and_place() {
        let g = gen(Scenario::SuddenObject, 0.0);
        let (before, t) = g.frame(3).unwrap();
        assert!(t.object.is_none() && !t.event);
        let (after, t) = g.frame(4).unwrap();
        assert!(t.event && t.object == Some(Rect { x: 30, y: 20, w: 16, h: 12 }));
        assert_eq!(after.get_f32(30, 20), [250.0 / 255.0, 10.0 / 255.0, 10.0 / 255.0]);
        assert_eq!(before.get_f32(29, 20), after.get_f32(29, 20), "outside the object nothing changes");
        assert!(!g.frame(5).unwrap().1.event);
    }

    #[test]
    fn pan_shifts_the_world_and_wraps() {
        let g = gen(Scenario::Pan, 0.0);
        let (f0, _) = g.frame(0).unwrap();
        let (f2, t2) = g.frame(2).unwrap();
        // 2 frames at 2.5 px = 5 px: column x of frame 2 is column x + 5 of frame 0.
        for x in 0..50 {
            assert_eq!(f2.get_f32(x, 7), f0.get_f32(x + 5, 7));
        }
        assert!((t2.pan_deg - 0.5).abs() < 1e-6);
        assert!(g.frame(9).is_ok() && g.frame(10).is_err());
    }

    #[test]
    fn noise_is_seeded_and_has_the_asked_sigma() {
        let (a, b) = (gen(Scenario::Static, 2.0), gen(Scenario::Static, 2.0));
        let clean = gen(Scenario::Static, 0.0);
        let (fa, fb, fc) = (a.frame(1).unwrap().0, b.frame(1).unwrap().0, clean.frame(1).unwrap().0);
        assert_eq!(fa.to_u8().to_vec(), fb.to_u8().to_vec(), "same seed, same frame");
        assert_ne!(fa.to_u8().to_vec(), a.frame(2).unwrap().0.to_u8().to_vec(), "noise differs per frame");
        let d: Vec<f64> = fa
            .to_u8()
            .to_vec()
            .iter()
            .zip(fc.to_u8().to_vec())
            .flat_map(|(p, q)| (0..3).map(move |k| p[k] as f64 - q[k] as f64))
            .collect();
        let sd = (d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64).sqrt();
        assert!((sd - 2.0).abs() < 0.15, "noise sd {sd} grey levels");
    }

    #[test]
    fn bad_configs_are_errors() {
        let world = RgbImage::U8(Plane::from_fn(20, 20, |_, _| [0, 0, 0]));
        let mut c = SceneConfig::new(Scenario::SuddenObject);
        c.object_at = (600, 400);
        assert!(SceneGenerator::new(c, std::slice::from_ref(&world), &world).is_err());
        assert!(SceneGenerator::new(SceneConfig::new(Scenario::Static), &[], &world).is_err());
        let c = SceneConfig { frames: 0, ..SceneConfig::new(Scenario::Static) };
        assert!(SceneGenerator::new(c, std::slice::from_ref(&world), &world).is_err());
    }
}
