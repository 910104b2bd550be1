//! A camera looking straight down at a textured floor, moving with known planar motion:
//! ground truth for visual odometry (SPEC 6).
//!
//! - **Floor:** square tiles of a real texture (brick, grass or gravel, 512x512), each turned
//!   by a multiple of 90 degrees and possibly mirrored, or a mosaic mixing the three; all
//!   chosen per tile from the seed. Three harder floors are made from the photos by
//!   [`crate::floors`]: low-contrast (grass, smoothed, 8 grey levels of texture), fine-grained
//!   (gravel shrunk by 4) and repetitive (a 20-pixel square of gravel repeated). The floor is a grid of texels (one per ground pixel),
//!   sampled bilinearly.
//! - **Motion:** the robot's forward speed, lateral speed and yaw rate vary smoothly (sums of
//!   seeded sinusoids) within `forward_px` +- `forward_spread_px`, +- `lateral_px`, and
//!   `yaw_deg` +- `yaw_spread_deg` per frame. The camera sits at `mount_px` (right, forward)
//!   from the robot's rotation centre (seed eq. 20's offset).
//! - **Camera:** image x to the robot's right, image y backwards; one image pixel is one
//!   ground pixel at the nominal height (`metres_per_px` on the floor).
//! - **Real-camera rendering** (off in [`GroundConfig::easy`] and [`GroundConfig::hard`]):
//!   pixels that integrate light over their area (`supersample` x `supersample` point samples
//!   per pixel, averaged: a box filter over the pixel, where a point sample aliases fine
//!   texture), radial lens distortion `k1` (the Brown model of `ocellus_geometry::distortion`
//!   about the image centre with focal [`FOCAL_PX`]: the frame is what the lens shows, and
//!   the camera file carries `k1` for the odometry to undistort), and vignetting (brightness
//!   falling as `1 - vignetting (r / r_corner)^2` from the centre to the corners).
//! - **Rolling shutter** (off by default): rows read from top to bottom over a fraction of
//!   the frame interval, each row seen at its own pose, which the planar model does not know.
//! - **Hard variant:** motion blur (sub-frame renders over the exposure, centred on the frame
//!   time, averaged), gain
//!   flicker, a camera-height oscillation the planar model does not know, stronger noise.
//!
//! World frame: x right, y down on the floor (as the first image), angles clockwise from the
//! image's "up", in ground pixels and radians; [`GroundScene::pose_m`] gives metres.

use crate::{Result, SynthError};
use ocellus_image::rng::SplitMix64;
use ocellus_image::Plane;

/// Side of a floor tile, texels.
pub const TILE: usize = 512;

/// Focal length of the generated camera, pixels (its camera file says so; with a camera
/// height of 0.3 m one ground pixel is 0.5 mm).
pub const FOCAL_PX: f64 = 600.0;

/// What the floor is made of.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GroundTexture {
    /// Brick paving (strong straight mortar lines: the aperture problem).
    Brick,
    /// Grass.
    Grass,
    /// Gravel.
    Gravel,
    /// Each tile one of the three.
    Mosaic,
    /// Dim grass, smoothed, with its contrast cut to 8 grey levels ([`crate::floors::low_contrast`]).
    LowContrast,
    /// Gravel shrunk by 4: grains a few pixels across ([`crate::floors::fine_grained`]).
    FineGrained,
    /// A 20-pixel square of gravel repeated: periodic with the seed's search window
    /// ([`crate::floors::repetitive`]).
    Repetitive,
}

impl GroundTexture {
    /// Every floor, in the order of the odometry tables.
    pub const ALL: [Self; 7] =
        [Self::Brick, Self::Grass, Self::Gravel, Self::Mosaic, Self::LowContrast, Self::FineGrained, Self::Repetitive];

    /// The floor's name in lower case with hyphens (as the command line spells it).
    pub fn name(&self) -> &'static str {
        match self {
            Self::Brick => "brick",
            Self::Grass => "grass",
            Self::Gravel => "gravel",
            Self::Mosaic => "mosaic",
            Self::LowContrast => "low-contrast",
            Self::FineGrained => "fine-grained",
            Self::Repetitive => "repetitive",
        }
    }
}

/// A ground sequence's configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroundConfig {
    /// Floor texture.
    pub texture: GroundTexture,
    /// Image width, pixels.
    pub width: usize,
    /// Image height, pixels.
    pub height: usize,
    /// Number of frames.
    pub frames: usize,
    /// Frame rate, Hz (timestamps of the ground truth).
    pub rate_hz: f64,
    /// Seed of the tiles, the motion and the noise.
    pub seed: u64,
    /// Mean forward speed, ground pixels per frame.
    pub forward_px: f64,
    /// Forward speed variation (+-), pixels per frame.
    pub forward_spread_px: f64,
    /// Largest lateral speed, pixels per frame.
    pub lateral_px: f64,
    /// Mean yaw rate, degrees per frame.
    pub yaw_deg: f64,
    /// Yaw rate variation (+-), degrees per frame.
    pub yaw_spread_deg: f64,
    /// Camera position relative to the rotation centre, ground pixels (right, forward).
    pub mount_px: [f64; 2],
    /// Floor size of one ground pixel, metres (camera height over focal length).
    pub metres_per_px: f64,
    /// Sensor noise, grey levels (8 bit).
    pub noise_sigma: f32,
    /// Sub-frame renders averaged for motion blur (1: none).
    pub blur_subframes: usize,
    /// Fraction of the frame interval the shutter is open (motion blur length).
    pub exposure: f64,
    /// Per-frame gain flicker amplitude (0.05: +-5 %).
    pub gain_flicker: f32,
    /// Camera-height oscillation amplitude (0.01: +-1 % image scale).
    pub height_oscillation: f64,
    /// Point samples per pixel side, averaged (1: a point sample at the pixel centre; 2 and
    /// up: the pixel integrates light over its area), 1..=8.
    pub supersample: usize,
    /// Radial distortion k1 of the lens (normalized coordinates, focal [`FOCAL_PX`]), in
    /// [-0.5, 0.5]; 0: a perfect pinhole.
    pub k1: f64,
    /// Brightness lost at the image corners, in [0, 1) (0: none; 0.3: corners at 70 %).
    pub vignetting: f32,
    /// Rolling shutter: the rows are read from top to bottom over this fraction of the frame
    /// interval, in [0, 1] (0: a global shutter). The frame's timestamp is the middle row's.
    pub rolling_shutter: f64,
}

impl GroundConfig {
    /// The easy sequence: 640x480, 200 frames at 200 Hz, forward 3 +- 1 px, lateral +-0.4 px,
    /// yaw 0.1 +- 0.35 degrees per frame, camera 100 px ahead of the rotation centre, floor
    /// pixel 0.5 mm, noise sigma 2.
    pub fn easy(texture: GroundTexture, seed: u64) -> Self {
        Self {
            texture,
            width: 640,
            height: 480,
            frames: 200,
            rate_hz: 200.0,
            seed,
            forward_px: 3.0,
            forward_spread_px: 1.0,
            lateral_px: 0.4,
            yaw_deg: 0.1,
            yaw_spread_deg: 0.35,
            mount_px: [0.0, 100.0],
            metres_per_px: 0.0005,
            noise_sigma: 2.0,
            blur_subframes: 1,
            exposure: 0.5,
            gain_flicker: 0.0,
            height_oscillation: 0.0,
            supersample: 1,
            k1: 0.0,
            vignetting: 0.0,
            rolling_shutter: 0.0,
        }
    }

    /// `self` seen by a real camera: pixels integrating over their area (2 x 2 samples), lens
    /// distortion k1 = -0.05 and 25 % vignetting at the corners.
    pub fn real_camera(self) -> Self {
        Self { supersample: 2, k1: -0.05, vignetting: 0.25, ..self }
    }

    /// The hard sequence: as [`GroundConfig::easy`] with noise sigma 5, motion blur over half
    /// the frame interval (4 sub-frames), +-5 % gain flicker and +-1 % height oscillation.
    pub fn hard(texture: GroundTexture, seed: u64) -> Self {
        Self {
            noise_sigma: 5.0,
            blur_subframes: 4,
            gain_flicker: 0.05,
            height_oscillation: 0.01,
            ..Self::easy(texture, seed)
        }
    }

    fn check(&self) -> Result<()> {
        let bad = |m: String| Err(SynthError::InvalidConfig(m));
        if self.width < 16 || self.height < 16 || self.width > 8192 || self.height > 8192 {
            return bad(format!("image {}x{}: 16..=8192 per side", self.width, self.height));
        }
        if self.frames == 0 || self.frames > 1_000_000 {
            return bad(format!("{} frames", self.frames));
        }
        let finite = [
            self.rate_hz,
            self.forward_px,
            self.forward_spread_px,
            self.lateral_px,
            self.yaw_deg,
            self.yaw_spread_deg,
            self.metres_per_px,
            self.exposure,
            self.height_oscillation,
            self.mount_px[0],
            self.mount_px[1],
        ];
        if finite.iter().any(|v| !v.is_finite()) || !(self.noise_sigma.is_finite() && self.gain_flicker.is_finite()) {
            return bad("non-finite parameter".into());
        }
        if self.rate_hz <= 0.0 || self.metres_per_px <= 0.0 || !(0.0..=1.0).contains(&self.exposure) {
            return bad(format!("rate {} Hz, {} m/px, exposure {}", self.rate_hz, self.metres_per_px, self.exposure));
        }
        if !(1..=64).contains(&self.blur_subframes) || self.height_oscillation.abs() >= 0.5 {
            return bad(format!("{} sub-frames, height oscillation {}", self.blur_subframes, self.height_oscillation));
        }
        let usable = (1..=8).contains(&self.supersample)
            && self.k1.is_finite()
            && self.k1.abs() <= 0.5
            && self.vignetting.is_finite()
            && (0.0..1.0).contains(&self.vignetting)
            && (0.0..=1.0).contains(&self.rolling_shutter);
        if !usable {
            return bad(format!(
                "supersample {} (1..=8), k1 {} ([-0.5, 0.5]), vignetting {} ([0, 1)), rolling shutter {} ([0, 1])",
                self.supersample, self.k1, self.vignetting, self.rolling_shutter
            ));
        }
        Ok(())
    }
}

/// Planar poses of the rotation centre, here in ground pixels.
pub use ocellus_geometry::planar::Pose2;

/// Per-frame body velocities: (lateral px, forward px, yaw rad), the robot frame of the start
/// of the frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyMotion {
    /// Rightward, ground pixels per frame.
    pub lateral_px: f64,
    /// Forward, ground pixels per frame.
    pub forward_px: f64,
    /// Yaw, radians per frame (clockwise).
    pub yaw_rad: f64,
}

/// A seeded smooth signal in [-1, 1]: the mean of three sinusoids with random periods
/// (40-240 frames) and phases, renormalized.
#[derive(Clone, Copy, Debug)]
struct Smooth {
    waves: [(f64, f64); 3],
}

impl Smooth {
    fn new(rng: &mut SplitMix64) -> Self {
        Self { waves: std::array::from_fn(|_| (40.0 + 200.0 * rng.unit(), std::f64::consts::TAU * rng.unit())) }
    }
    fn at(&self, t: f64) -> f64 {
        self.waves.iter().map(|(p, ph)| (std::f64::consts::TAU * t / p + ph).sin()).sum::<f64>() / 3.0
    }
}

/// One tile's look: which texture, turned by `rot` quarter turns, mirrored or not.
#[derive(Clone, Copy, Debug)]
struct TileLook {
    texture: usize,
    rot: u8,
    flip: bool,
}

/// A generated ground sequence.
#[derive(Clone, Debug)]
pub struct GroundScene {
    cfg: GroundConfig,
    /// The tiles' textures: the three photos, or the one floor made from them.
    textures: Vec<Plane<f32>>,
    motion: Vec<BodyMotion>,
    poses: Vec<Pose2>,
    /// Per pixel (row-major), its `supersample^2` sample points as ideal (undistorted)
    /// offsets from the image centre, pixels (right, back).
    rays: Vec<[f64; 2]>,
    /// Per pixel, the vignetting factor times 1 / supersample^2.
    shading: Vec<f32>,
}

impl GroundScene {
    /// Builds the sequence from the three textures (brick, grass, gravel; grey in [0, 1] as
    /// [`ocellus_image::convert::RgbImage::to_grey`] makes it, each `TILE` x `TILE`); the
    /// low-contrast, fine-grained and repetitive floors are made from them.
    pub fn new(cfg: GroundConfig, textures: [Plane<f32>; 3]) -> Result<Self> {
        cfg.check()?;
        if textures.iter().any(|t| t.size() != (TILE, TILE)) {
            return Err(SynthError::InvalidConfig(format!("ground textures must be {TILE}x{TILE}")));
        }
        if textures.iter().any(|t| t.rows().flatten().any(|v| !(0.0..=1.0).contains(v))) {
            return Err(SynthError::InvalidConfig("ground textures must hold grey levels in [0, 1]".into()));
        }
        let [brick, grass, gravel] = textures;
        let textures = match cfg.texture {
            GroundTexture::LowContrast => vec![crate::floors::low_contrast(&grass)?],
            GroundTexture::FineGrained => vec![crate::floors::fine_grained(&gravel)?],
            GroundTexture::Repetitive => vec![crate::floors::repetitive(&gravel)?],
            _ => vec![brick, grass, gravel],
        };
        let mut rng = SplitMix64::new(cfg.seed ^ 0x6f64_6f6d);
        let (sf, sl, sy) = (Smooth::new(&mut rng), Smooth::new(&mut rng), Smooth::new(&mut rng));
        let motion: Vec<BodyMotion> = (0..cfg.frames)
            .map(|k| {
                let t = k as f64;
                BodyMotion {
                    lateral_px: cfg.lateral_px * sl.at(t),
                    forward_px: cfg.forward_px + cfg.forward_spread_px * sf.at(t),
                    yaw_rad: (cfg.yaw_deg + cfg.yaw_spread_deg * sy.at(t)).to_radians(),
                }
            })
            .collect();
        // The rotation centre starts at the origin facing up; frame k is taken at poses[k].
        let mut poses = Vec::with_capacity(cfg.frames);
        let mut p = Pose2::default();
        for m in &motion {
            poses.push(p);
            p = p.step(m.lateral_px, m.forward_px, m.yaw_rad);
        }
        let (rays, shading) = sample_rays(&cfg)?;
        Ok(Self { cfg, textures, motion, poses, rays, shading })
    }

    /// The configuration.
    pub fn config(&self) -> &GroundConfig {
        &self.cfg
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.cfg.frames
    }

    /// Always false (a sequence has at least one frame).
    pub fn is_empty(&self) -> bool {
        self.cfg.frames == 0
    }

    /// Pose of the rotation centre at frame `k`, ground pixels.
    pub fn pose(&self, k: usize) -> Option<Pose2> {
        self.poses.get(k).copied()
    }

    /// Pose at frame `k` in metres (x, y) and radians.
    pub fn pose_m(&self, k: usize) -> Option<(f64, f64, f64)> {
        let m = self.cfg.metres_per_px;
        self.pose(k).map(|p| (p.x * m, p.y * m, p.theta))
    }

    /// Body motion from frame `k` to `k + 1`.
    pub fn motion(&self, k: usize) -> Option<BodyMotion> {
        self.motion.get(k).copied()
    }

    /// Timestamp of frame `k`, seconds.
    pub fn time_s(&self, k: usize) -> f64 {
        k as f64 / self.cfg.rate_hz
    }

    fn look(&self, cx: i64, cy: i64) -> TileLook {
        let mut r = SplitMix64::new(
            self.cfg.seed
                ^ (cx as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
                ^ (cy as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F),
        );
        let v = r.next_u64();
        let texture = match self.cfg.texture {
            GroundTexture::Brick => 0,
            GroundTexture::Grass => 1,
            GroundTexture::Gravel => 2,
            GroundTexture::Mosaic => ((v >> 8) % 3) as usize,
            GroundTexture::LowContrast | GroundTexture::FineGrained | GroundTexture::Repetitive => 0,
        };
        TileLook { texture, rot: (v & 3) as u8, flip: v & 4 != 0 }
    }

    /// The floor texel at integer ground coordinates.
    fn texel(&self, gx: i64, gy: i64, cache: &mut ((i64, i64), TileLook)) -> f32 {
        let t = TILE as i64;
        let cell = (gx.div_euclid(t), gy.div_euclid(t));
        if cache.0 != cell {
            *cache = (cell, self.look(cell.0, cell.1));
        }
        let look = cache.1;
        let (mut lx, mut ly) = (gx.rem_euclid(t) as usize, gy.rem_euclid(t) as usize);
        if look.flip {
            lx = TILE - 1 - lx;
        }
        for _ in 0..look.rot {
            (lx, ly) = (ly, TILE - 1 - lx);
        }
        self.textures[look.texture].get(lx, ly)
    }

    /// The floor at a ground point, bilinear between texels.
    fn floor(&self, x: f64, y: f64, cache: &mut ((i64, i64), TileLook)) -> f32 {
        let (fx, fy) = (x.floor(), y.floor());
        let (ax, ay) = ((x - fx) as f32, (y - fy) as f32);
        let (ix, iy) = (fx as i64, fy as i64);
        let a = self.texel(ix, iy, cache);
        let b = self.texel(ix + 1, iy, cache);
        let c = self.texel(ix, iy + 1, cache);
        let d = self.texel(ix + 1, iy + 1, cache);
        let top = a + ax * (b - a);
        let bot = c + ax * (d - c);
        top + ay * (bot - top)
    }

    /// Image scale (ground pixels per image pixel) at time `t` in frames: 1, or the height
    /// oscillation of the hard variant (period 37 frames).
    fn scale(&self, t: f64) -> f64 {
        1.0 + self.cfg.height_oscillation * (std::f64::consts::TAU * t / 37.0).sin()
    }

    /// Adds `weight` times the view at time `t` (frames; grey in [0, 1], before gain and
    /// noise) to `out`: each pixel's sample rays (see [`sample_rays`]) on the floor, averaged
    /// and shaded. With a rolling shutter each row is seen at its own time, `t` being the
    /// middle row's.
    fn render_at(&self, t: f64, out: &mut Plane<f32>, weight: f32) {
        let (w, h) = (self.cfg.width, self.cfg.height);
        let n = self.cfg.supersample * self.cfg.supersample;
        let rs = self.cfg.rolling_shutter;
        let view = |t: f64| {
            let pose = self.pose_at(t);
            (pose.point(self.cfg.mount_px[0], self.cfg.mount_px[1]), pose.axes(), self.scale(t))
        };
        let mut at = view(t);
        let mut cache = ((i64::MAX, i64::MAX), TileLook { texture: 0, rot: 0, flip: false });
        for v in 0..h {
            if rs > 0.0 {
                at = view(t + rs * (v as f64 / (h - 1).max(1) as f64 - 0.5));
            }
            let (cam, (r, f), scale) = at;
            let row = out.row_mut(v);
            for (u, o) in row.iter_mut().enumerate() {
                let i = v * w + u;
                let mut sum = 0.0f32;
                for ray in &self.rays[i * n..(i + 1) * n] {
                    let (right, back) = (ray[0] * scale, ray[1] * scale);
                    let gx = cam[0] + r[0] * right - f[0] * back;
                    let gy = cam[1] + r[1] * right - f[1] * back;
                    sum += self.floor(gx, gy, &mut cache);
                }
                *o += weight * (self.shading[i] * sum);
            }
        }
    }

    /// The pose at a fractional frame time (between frames the motion of the frame interval
    /// is followed proportionally), clamped to the sequence.
    fn pose_at(&self, t: f64) -> Pose2 {
        let t = t.clamp(0.0, self.len() as f64 - 1.0 + 0.999);
        let j = t.floor() as usize;
        let a = t - j as f64;
        match (self.poses.get(j), self.motion.get(j)) {
            (Some(p), Some(m)) if a > 0.0 => p.step(m.lateral_px * a, m.forward_px * a, m.yaw_rad * a),
            (Some(p), _) => *p,
            _ => Pose2::default(),
        }
    }

    /// Frame `k` as 8-bit grey: rendered (with motion blur in the hard variant: sub-frames over
    /// the exposure, centred on the frame time, as timestamps at mid-exposure), gain flicker,
    /// sensor noise, rounded and clamped.
    pub fn frame(&self, k: usize) -> Result<Plane<u8>> {
        if k >= self.len() {
            return Err(SynthError::NoSuchFrame { index: k, len: self.len() });
        }
        let (w, h) = (self.cfg.width, self.cfg.height);
        let mut acc = Plane::<f32>::new(w, h);
        let n = self.cfg.blur_subframes;
        for s in 0..n {
            let offset = if n > 1 { self.cfg.exposure * (s as f64 / (n - 1) as f64 - 0.5) } else { 0.0 };
            let t = k as f64 + offset;
            self.render_at(t, &mut acc, 1.0 / n as f32);
        }
        let mut rng = SplitMix64::new(self.cfg.seed.wrapping_mul(0x2545_F491_4F6C_DD1D) ^ k as u64);
        let gain = 1.0 + self.cfg.gain_flicker * (2.0 * rng.unit() as f32 - 1.0);
        let sigma = self.cfg.noise_sigma;
        Ok(Plane::from_fn(w, h, |x, y| {
            let v = acc.get(x, y) * gain * 255.0 + if sigma > 0.0 { sigma * rng.normal() as f32 } else { 0.0 };
            v.round().clamp(0.0, 255.0) as u8
        }))
    }
}

/// Each pixel's sample points and shading for `cfg`: `supersample^2` points spread evenly
/// over the pixel (offsets `(i + 1/2) / s - 1/2`), each taken through the lens (distorted
/// pixel to ideal pixel by the Brown model with `k1` about the centre, focal [`FOCAL_PX`]) as
/// offsets (right, back) from the image centre; and per pixel the vignetting factor over the
/// number of samples. With one sample, no distortion and no vignetting the ray is the pixel's
/// own offset and the factor exactly 1: the point-sampled rendering.
fn sample_rays(cfg: &GroundConfig) -> Result<(Vec<[f64; 2]>, Vec<f32>)> {
    use ocellus_geometry::camera::Intrinsics;
    use ocellus_geometry::distortion::Distortion;
    let (w, h, s) = (cfg.width, cfg.height, cfg.supersample);
    let (cx, cy) = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
    let k = Intrinsics::centred(FOCAL_PX, w, h);
    let lens = Distortion { k1: cfg.k1, ..Distortion::default() };
    let offsets: Vec<f64> = (0..s).map(|i| if s == 1 { 0.0 } else { (i as f64 + 0.5) / s as f64 - 0.5 }).collect();
    let mut rays = Vec::with_capacity(w * h * s * s);
    let mut shading = Vec::with_capacity(w * h);
    let corner2 = cx * cx + cy * cy;
    for v in 0..h {
        for u in 0..w {
            for &dy in &offsets {
                for &dx in &offsets {
                    let (pu, pv) = (u as f64 + dx, v as f64 + dy);
                    let (iu, iv) = if cfg.k1 == 0.0 {
                        (pu, pv)
                    } else {
                        lens.undistort_pixel(&k, pu, pv).map_err(|e| {
                            SynthError::InvalidConfig(format!("k1 {}: pixel ({pu}, {pv}) has no ray: {e}", cfg.k1))
                        })?
                    };
                    rays.push([iu - cx, iv - cy]);
                }
            }
            let r2 = ((u as f64 - cx).powi(2) + (v as f64 - cy).powi(2)) / corner2.max(1e-12);
            shading.push((1.0 - cfg.vignetting * r2 as f32) / (s * s) as f32);
        }
    }
    Ok((rays, shading))
}

/// One wheel-odometry sample: the robot-frame motion reported over one encoder interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EncoderSample {
    /// End of the interval, seconds.
    pub time_s: f64,
    /// Forward distance reported, metres.
    pub forward_m: f64,
    /// Yaw change reported, radians (clockwise).
    pub yaw_rad: f64,
    /// Extra forward distance from wheel slip in this interval (0 when none), metres.
    pub slip_m: f64,
}

/// Simulated wheel encoders at `rate_hz`: the true forward distance and yaw change over each
/// interval (lateral motion is invisible to wheels), with 1 % scale noise, and slip events:
/// from `slip_every_s` on, every so often, the wheels report `slip_m` more than the floor moved.
pub fn encoders(
    scene: &GroundScene,
    rate_hz: f64,
    slip_every_s: f64,
    slip_m: f64,
    seed: u64,
) -> Result<Vec<EncoderSample>> {
    if !(rate_hz > 0.0 && rate_hz.is_finite() && slip_every_s > 0.0 && slip_m.is_finite()) {
        return Err(SynthError::InvalidConfig(format!("encoders at {rate_hz} Hz, slip every {slip_every_s} s")));
    }
    let cfg = scene.config();
    let m = cfg.metres_per_px;
    let end = scene.time_s(scene.len().saturating_sub(1));
    let mut rng = SplitMix64::new(seed ^ 0x656e_636f);
    let mut out = Vec::new();
    let mut t = 1.0 / rate_hz;
    let mut next_slip = slip_every_s;
    while t <= end + 1e-12 {
        // The motion between the frame times t0 and t (in frames, fractional).
        let (f0, f1) = ((t - 1.0 / rate_hz) * cfg.rate_hz, t * cfg.rate_hz);
        let (mut fwd, mut yaw) = (0.0, 0.0);
        let mut a = f0;
        while a < f1 - 1e-12 {
            let k = a.floor() as usize;
            let b = ((k + 1) as f64).min(f1);
            if let Some(mo) = scene.motion(k) {
                fwd += mo.forward_px * (b - a);
                yaw += mo.yaw_rad * (b - a);
            }
            a = b;
        }
        let slip = if t >= next_slip {
            next_slip += slip_every_s;
            slip_m
        } else {
            0.0
        };
        let noise = 1.0 + 0.01 * rng.normal();
        out.push(EncoderSample { time_s: t, forward_m: fwd * m * noise + slip, yaw_rad: yaw * noise, slip_m: slip });
        t += 1.0 / rate_hz;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn textures() -> [Plane<f32>; 3] {
        // Smooth but unique patterns, so that frames are comparable by resampling.
        std::array::from_fn(|i| {
            Plane::from_fn(TILE, TILE, |x, y| {
                let (x, y) = (x as f32, y as f32);
                (128.0 + 60.0 * ((x * 0.07 + i as f32).sin() * (y * 0.05).cos()) + 30.0 * ((x + 2.0 * y) * 0.031).sin())
                    / 255.0
            })
        })
    }

    fn small(texture: GroundTexture) -> GroundConfig {
        GroundConfig { width: 96, height: 64, frames: 30, noise_sigma: 0.0, ..GroundConfig::easy(texture, 3) }
    }

    #[test]
    fn motion_stays_in_its_ranges_and_integrates_to_the_poses() {
        let s = GroundScene::new(GroundConfig::easy(GroundTexture::Brick, 1), textures()).unwrap();
        let mut p = s.pose(0).unwrap();
        for k in 0..s.len() - 1 {
            let m = s.motion(k).unwrap();
            assert!((2.0..=4.0).contains(&m.forward_px) && m.lateral_px.abs() <= 0.4);
            assert!(m.yaw_rad.to_degrees() >= -0.25 - 1e-9 && m.yaw_rad.to_degrees() <= 0.45 + 1e-9);
            p = p.step(m.lateral_px, m.forward_px, m.yaw_rad);
            let q = s.pose(k + 1).unwrap();
            assert!((p.x - q.x).abs() < 1e-9 && (p.y - q.y).abs() < 1e-9 && (p.theta - q.theta).abs() < 1e-12);
        }
    }

    #[test]
    fn pure_translation_shifts_the_image() {
        // No rotation, no lateral motion, 2 px forward per frame: frame 1 is frame 0 moved
        // down by 2 rows (the floor comes toward the bottom of the image).
        let cfg = GroundConfig {
            forward_px: 2.0,
            forward_spread_px: 0.0,
            lateral_px: 0.0,
            yaw_deg: 0.0,
            yaw_spread_deg: 0.0,
            ..small(GroundTexture::Mosaic)
        };
        let s = GroundScene::new(cfg, textures()).unwrap();
        let (a, b) = (s.frame(0).unwrap(), s.frame(1).unwrap());
        for y in 0..60 {
            for x in 0..96 {
                assert_eq!(b.get(x, y + 2), a.get(x, y), "({x}, {y})");
            }
        }
    }

    #[test]
    fn same_seed_same_frames_and_bad_configs_are_errors() {
        let t = textures();
        let cfg = GroundConfig { width: 64, height: 48, ..GroundConfig::hard(GroundTexture::Gravel, 9) };
        let a = GroundScene::new(cfg, t.clone()).unwrap();
        let b = GroundScene::new(cfg, t.clone()).unwrap();
        assert_eq!(a.frame(5).unwrap(), b.frame(5).unwrap());
        assert!(a.frame(500).is_err());
        assert!(GroundScene::new(GroundConfig { frames: 0, ..cfg }, t.clone()).is_err());
        assert!(GroundScene::new(GroundConfig { rate_hz: f64::NAN, ..cfg }, t.clone()).is_err());
        let wrong = [Plane::new(10, 10), Plane::new(10, 10), Plane::new(10, 10)];
        assert!(GroundScene::new(cfg, wrong).is_err());
    }

    #[test]
    fn encoders_add_up_to_the_true_distance_plus_slip() {
        let s = GroundScene::new(GroundConfig::easy(GroundTexture::Grass, 2), textures()).unwrap();
        let e = encoders(&s, 30.0, 0.25, 0.002, 1).unwrap();
        assert_eq!(e.len(), 29);
        let true_fwd: f64 = (0..s.len() - 1).map(|k| s.motion(k).unwrap().forward_px).sum::<f64>() * 0.0005;
        let reported: f64 = e.iter().map(|x| x.forward_m - x.slip_m).sum();
        let slips = e.iter().filter(|x| x.slip_m > 0.0).count();
        assert_eq!(slips, 3);
        // 29/30 s of the 199/200 s covered; 1 % noise per sample.
        assert!((reported - true_fwd).abs() < 0.03 * true_fwd, "{reported} vs {true_fwd}");
    }
}
