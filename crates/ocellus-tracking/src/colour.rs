//! Colour likelihood of an image circle (SPEC 7.2; the lecture's ball tracker after Taiana et
//! al. 2008).
//!
//! Histograms are HSV histograms after Pérez, Hue, Vermaak & Gangnet (ECCV 2002): pixels with
//! saturation above 0.1 and value above 0.2 fall into 10 x 10 hue-saturation bins; the others
//! (greys, dark pixels, whose hue is noise) into 10 value bins: 110 bins in all. A frame is
//! binned once ([`BinnedFrame`]); a hypothesis then costs a fixed number of lookups: 64 sample
//! points spread evenly over the disc and 64 over a ring (Vogel's sunflower pattern, so the
//! points cover the area evenly at any size), and 32 pairs on the rim.
//!
//! Where the samples fall decides how well the radius, and with it a 3D tracker's depth, is
//! read. Pixels on a silhouette mix the target and what lies behind it and match neither, so
//! the disc's samples stop [`EDGE_GUARD_PX`] inside the circle and the ring's start that far
//! outside it (the ring spans 1.05 to 1.5 radii of a circle grown by the guard). Without the
//! guard the best-scoring circle sat 0.3-0.7 px inside the true one on the generated
//! sequences (4 % of the depth at a radius of 10 px); with it the boosted tracker's 3D RMSE
//! without occluders fell from 2.9 % to 1.1 % of the depth (median of 9 runs). A gap between
//! disc and ring (1.2 radii was tried) lets a circle 10 % too small score as well as the true
//! one.
//!
//! The histograms say little about a circle that is too small while the ring still misses the
//! target, or about a target half hidden, which a smaller circle in its visible part fits
//! better. The rim term ([`ColourModel::rim`]) reads the edge itself: on [`RIM_SAMPLES`] rays
//! it compares the pixel the guard inside the circle with the one the guard outside. A ray
//! with the target's colour inside and not outside votes +1 (the edge is there); one with the
//! target's colour outside votes -1 (the circle is too small, or off); one with neither votes
//! 0 (hidden there, or the circle too large, which the disc's histogram punishes). A half-hidden
//! ball's true circle keeps the votes of its visible arc; a smaller circle inside the visible
//! part loses most of its rays. Weighed by [`RIM_WEIGHT`], it brought the occluded runs' 3D
//! RMSE from 6.2 % to 3.4 % of the depth (median of 18 runs).
//!
//! `score = BC(inner, model) - BC(inner, outer)`, BC the Bhattacharyya coefficient
//! `sum_b sqrt(p_b q_b)` in [0, 1]: high when the disc looks like the model and unlike its
//! surroundings, so a disc on a large region of the model's colour (a wall of the ball's
//! colour) does not score. The likelihood is `exp(lambda * (score + rim_weight * rim))`,
//! lambda = 20 by default (a score lower by 0.1 is 7.4 times less likely).

use crate::{Result, TrackingError};
use ocellus_image::{Backend, Plane};

/// Hue bins of the hue-saturation part.
pub const HUE_BINS: usize = 10;
/// Saturation bins of the hue-saturation part.
pub const SATURATION_BINS: usize = 10;
/// Value bins for pixels without a reliable hue.
pub const VALUE_BINS: usize = 10;
/// Bins in all: 10 x 10 + 10.
pub const BINS: usize = HUE_BINS * SATURATION_BINS + VALUE_BINS;
/// Pixels at or below this saturation go to the value bins.
pub const MIN_SATURATION: f32 = 0.1;
/// Pixels at or below this value go to the value bins.
pub const MIN_VALUE: f32 = 0.2;
/// Default `lambda` of the likelihood `exp(lambda * score)`.
pub const DEFAULT_LAMBDA: f64 = 20.0;
/// Half-width of the band about a circle's edge that the disc's and the ring's samples skip,
/// pixels (see the module doc).
pub const EDGE_GUARD_PX: f64 = 0.5;
/// Rays of the rim term.
pub const RIM_SAMPLES: usize = 32;
/// Weight of the rim term beside the histogram score, by default.
pub const RIM_WEIGHT: f64 = 0.25;
/// A bin is the target's colour for the rim term when it holds at least this share of the
/// model histogram.
pub const RIM_MEMBER_SHARE: f64 = 0.02;
/// Sample points on the disc, and on the outer ring.
pub const SAMPLES: usize = 64;
/// Inner and outer radius of the outer ring, in radii of the circle.
pub const RING: (f64, f64) = (1.05, 1.5);

/// The histogram bin of an 8-bit RGB pixel, in exact integer arithmetic. With
/// `M = max(r, g, b)`, `m = min(r, g, b)`, `d = M - m`: value `V = M / 255`, saturation
/// `S = d / M`, hue `H` in sextants `[0, 6)` (`(g - b) / d` for a red maximum, wrapped to
/// positive, `2 + (b - r) / d` for green, `4 + (r - g) / d` for blue). Pixels with
/// `S <= 0.1` or `V <= 0.2` go to value bin `100 + min(floor(10 V), 9)`; the others to
/// `10 min(floor(10 H / 6), 9) + min(floor(10 S), 9)`.
pub fn bin_of([r, g, b]: [u8; 3]) -> u8 {
    let (r, g, b) = (r as u32, g as u32, b as u32);
    let (mx, mn) = (r.max(g).max(b), r.min(g).min(b));
    let d = mx - mn;
    // S <= 0.1 is 10 d <= M; V <= 0.2 is M <= 51.
    if 10 * d <= mx || mx <= 51 {
        return (100 + (10 * mx / 255).min(9)) as u8;
    }
    let num = if mx == r {
        if g >= b {
            g - b
        } else {
            6 * d + g - b
        }
    } else if mx == g {
        2 * d + b - r
    } else {
        4 * d + r - g
    };
    let hb = (10 * num / (6 * d)).min(9);
    let sb = (10 * d / mx).min(9);
    (hb * 10 + sb) as u8
}

/// Pixels per block of the binning kernel.
const BIN_BLOCK: usize = 16;

/// Bins one block of pixels: [`bin_of`] written without branches over lanes, in f32, so that
/// the compiler vectorizes it (8 lanes with AVX2). The integer quotients are exact in f32:
/// numerators and denominators stay below 2^14, so a quotient below an integer k is at least
/// 1/1530 below it, far more than f32's rounding, and `floor` gives the integer division.
#[inline(always)]
fn bin_block(src: &[[u8; 3]], dst: &mut [u8]) {
    let mut out = [0u8; BIN_BLOCK];
    for i in 0..BIN_BLOCK {
        let [r, g, b] = src[i].map(f32::from);
        let mx = r.max(g).max(b);
        let mn = r.min(g).min(b);
        let d = mx - mn;
        let grey = 10.0 * d <= mx || mx <= 51.0;
        let vb = (10.0 * mx / 255.0).floor().min(9.0);
        let num_r = if g >= b { g - b } else { 6.0 * d + g - b };
        let num_g = 2.0 * d + b - r;
        let num_b = 4.0 * d + r - g;
        let num = if mx == r {
            num_r
        } else if mx == g {
            num_g
        } else {
            num_b
        };
        // d = 0 only for greys, whose hue is not used; keep the division finite.
        let dd = d.max(1.0);
        let hb = (10.0 * num / (6.0 * dd)).floor().min(9.0);
        let sb = (10.0 * d / mx.max(1.0)).floor().min(9.0);
        let bin = if grey { 100.0 + vb } else { hb * 10.0 + sb };
        out[i] = bin as u8;
    }
    dst.copy_from_slice(&out);
}

/// Bins the pixels of `frame` in columns `x0..x1` of rows `y0..y1` into `out` (same size as
/// the frame; the caller clamps the rectangle to it). `M` only selects the build (the kernel
/// has no multiply-add); [`ocellus_image::dispatch_kernel!`] compiles it with AVX2.
#[allow(clippy::extra_unused_type_parameters)]
#[inline(always)]
fn bin_rect_generic<M: ocellus_image::simd::Madd>(
    frame: &Plane<[u8; 3]>,
    out: &mut Plane<u8>,
    [x0, y0, x1, y1]: [usize; 4],
) {
    for y in y0..y1 {
        let (src, dst) = (&frame.row(y)[x0..x1], &mut out.row_mut(y)[x0..x1]);
        let n = src.len() / BIN_BLOCK * BIN_BLOCK;
        for (s, d) in src[..n].chunks_exact(BIN_BLOCK).zip(dst[..n].chunks_exact_mut(BIN_BLOCK)) {
            bin_block(s, d);
        }
        for (o, &p) in dst[n..].iter_mut().zip(&src[n..]) {
            *o = bin_of(p);
        }
    }
}

ocellus_image::dispatch_kernel!(
    /// Bins a rectangle of a frame (the caller sizes `out` and clamps the rectangle), with
    /// the backend's kernel.
    fn bin_rect => bin_rect_generic(frame: &Plane<[u8; 3]>, out: &mut Plane<u8>, rect: [usize; 4])
);

/// An image circle: centre (x, y) and radius, pixels.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Circle {
    /// Centre, x (pixels, right).
    pub x: f64,
    /// Centre, y (pixels, down).
    pub y: f64,
    /// Radius, pixels.
    pub r: f64,
}

/// A frame's pixels as histogram bins, computed once per frame: the whole frame, or only the
/// region a set of hypotheses can read ([`BinnedFrame::update_region`]).
#[derive(Clone, Debug, Default)]
pub struct BinnedFrame {
    bins: Plane<u8>,
    /// The binned rectangle [x0, y0, x1, y1) (x1, y1 exclusive).
    region: [usize; 4],
}

impl BinnedFrame {
    /// Bins every pixel of `frame`.
    pub fn new(frame: &Plane<[u8; 3]>) -> Self {
        let mut b = Self::default();
        b.update(frame);
        b
    }

    /// Re-bins into the same buffer (no allocation at a constant frame size), with the
    /// fastest kernel of this CPU.
    pub fn update(&mut self, frame: &Plane<[u8; 3]>) {
        self.update_with(Backend::Auto, frame);
    }

    /// [`Self::update`] with a chosen backend (all give the same bins).
    pub fn update_with(&mut self, backend: Backend, frame: &Plane<[u8; 3]>) {
        let (w, h) = frame.size();
        self.update_region_with(backend, frame, [0, 0, w, h]);
    }

    /// Bins only the pixels of `frame` in the rectangle [x0, y0, x1, y1) (clamped to the
    /// frame): a filter whose hypotheses all lie there pays for their region, not the frame.
    /// Scores read the rest of the frame as missing, like pixels off the frame, so the
    /// region must hold every sample of every circle scored (see [`Circle::reach`]).
    pub fn update_region(&mut self, frame: &Plane<[u8; 3]>, region: [usize; 4]) {
        self.update_region_with(Backend::Auto, frame, region);
    }

    /// [`Self::update_region`] with a chosen backend.
    pub fn update_region_with(&mut self, backend: Backend, frame: &Plane<[u8; 3]>, [x0, y0, x1, y1]: [usize; 4]) {
        let (w, h) = frame.size();
        self.bins.resize(w, h);
        let (x1, y1) = (x1.min(w), y1.min(h));
        let region = [x0.min(x1), y0.min(y1), x1, y1];
        bin_rect(backend, frame, &mut self.bins, region);
        self.region = region;
    }

    /// Grows the binned region to also hold `rect` (clamped to the frame), binning only the
    /// pixels it adds; `frame` must be the frame binned last.
    pub fn extend_region(&mut self, frame: &Plane<[u8; 3]>, rect: [usize; 4]) {
        let (w, h) = frame.size();
        let old = self.region;
        let [x0, y0, x1, y1] = union_rect(old, [rect[0], rect[1], rect[2].min(w), rect[3].min(h)]);
        if [x0, y0, x1, y1] == old {
            return;
        }
        if old[0] >= old[2] || old[1] >= old[3] || self.bins.size() != (w, h) {
            self.update_region(frame, [x0, y0, x1, y1]);
            return;
        }
        // The union minus the old rectangle: full-width bands above and below it, and the
        // parts left and right of it in its rows.
        let backend = Backend::Auto;
        for band in
            [[x0, y0, x1, old[1]], [x0, old[3], x1, y1], [x0, old[1], old[0], old[3]], [old[2], old[1], x1, old[3]]]
        {
            if band[0] < band[2] && band[1] < band[3] {
                bin_rect(backend, frame, &mut self.bins, band);
            }
        }
        self.region = [x0, y0, x1, y1];
    }

    /// The bins, one per pixel; valid inside [`Self::region`] only.
    pub fn bins(&self) -> &Plane<u8> {
        &self.bins
    }

    /// The binned rectangle [x0, y0, x1, y1), pixels (x1, y1 exclusive).
    pub fn region(&self) -> [usize; 4] {
        self.region
    }

    /// The bin at the pixel nearest to (x, y), `None` outside the binned region.
    #[inline]
    fn at(&self, x: f64, y: f64) -> Option<u8> {
        let (xi, yi) = (nearest(x), nearest(y));
        let [x0, y0, x1, y1] = self.region;
        if xi >= x0 as i64 && yi >= y0 as i64 && xi < x1 as i64 && yi < y1 as i64 {
            Some(self.bins.get(xi as usize, yi as usize))
        } else {
            None
        }
    }
}

/// The smallest rectangle [x0, y0, x1, y1) holding both `a` and `b` (an empty one, with
/// x0 >= x1 or y0 >= y1, adds nothing).
pub fn union_rect(a: [usize; 4], b: [usize; 4]) -> [usize; 4] {
    let empty = |r: [usize; 4]| r[0] >= r[2] || r[1] >= r[3];
    if empty(a) {
        b
    } else if empty(b) {
        a
    } else {
        [a[0].min(b[0]), a[1].min(b[1]), a[2].max(b[2]), a[3].max(b[3])]
    }
}

impl Circle {
    /// How far from the centre the likelihood's samples reach, pixels (the outer ring's
    /// radius plus one pixel of rounding).
    pub fn reach(&self) -> f64 {
        self.outer_scale() * RING.1 + 1.0
    }

    /// Radius that scales the disc's sample pattern, pixels: the circle less the guard band
    /// ([`EDGE_GUARD_PX`], at most half the radius).
    pub fn inner_scale(&self) -> f64 {
        self.r - EDGE_GUARD_PX.min(0.5 * self.r)
    }

    /// Radius that scales the ring's sample pattern, pixels: the ring starts the guard band
    /// outside the circle.
    pub fn outer_scale(&self) -> f64 {
        (self.r + EDGE_GUARD_PX) / RING.0
    }

    /// The pixel rectangle [x0, y0, x1, y1) that holds every sample of this circle, clamped
    /// to a `w` x `h` frame (empty when the circle lies off it or is not finite).
    pub fn samples_rect(&self, w: usize, h: usize) -> [usize; 4] {
        let reach = self.reach();
        if !(self.x.is_finite() && self.y.is_finite() && reach.is_finite()) {
            return [0, 0, 0, 0];
        }
        let lo = |v: f64, n: usize| (v - reach).floor().clamp(0.0, n as f64) as usize;
        let hi = |v: f64, n: usize| ((v + reach).ceil() + 1.0).clamp(0.0, n as f64) as usize;
        [lo(self.x, w), lo(self.y, h), hi(self.x, w), hi(self.y, h)]
    }
}

/// The nearest integer to `v` (ties to even) for |v| < 2^51; far outside that, some integer
/// far outside any frame. Adding 1.5 * 2^52 leaves the rounded integer in the low mantissa
/// bits: branch-free and vectorizable, unlike `round` (a libm call on the x86-64 baseline)
/// or a saturating float-to-integer cast, for each of the 128 samples of every particle.
#[inline(always)]
fn nearest(v: f64) -> i64 {
    const MAGIC: f64 = 6_755_399_441_055_744.0;
    (v + MAGIC).to_bits().wrapping_sub(MAGIC.to_bits()) as i64
}

/// A normalized 110-bin histogram.
#[derive(Clone, Debug, PartialEq)]
pub struct Histogram(pub [f64; BINS]);

impl Histogram {
    /// The histogram of `bins` (normalized); `None` for no bins.
    pub fn of(bins: impl IntoIterator<Item = u8>) -> Option<Self> {
        let mut h = [0.0; BINS];
        let mut n = 0usize;
        for b in bins {
            h[(b as usize).min(BINS - 1)] += 1.0;
            n += 1;
        }
        (n > 0).then(|| {
            h.iter_mut().for_each(|v| *v /= n as f64);
            Self(h)
        })
    }
}

/// The Bhattacharyya coefficient `sum_b sqrt(p_b q_b)` of two normalized histograms, in
/// [0, 1] (1 for equal histograms, 0 for disjoint ones).
pub fn bhattacharyya(p: &Histogram, q: &Histogram) -> f64 {
    p.0.iter().zip(&q.0).map(|(a, b)| (a * b).sqrt()).sum()
}

/// Vogel's sunflower: `n` points spreading evenly over the annulus between radii `r0` and
/// `r1` of the unit disc (equal area per point).
fn sunflower(n: usize, r0: f64, r1: f64) -> Vec<[f64; 2]> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|k| {
            let t = (k as f64 + 0.5) / n as f64;
            let r = (r0 * r0 + t * (r1 * r1 - r0 * r0)).sqrt();
            let (s, c) = (k as f64 * golden).sin_cos();
            [r * c, r * s]
        })
        .collect()
}

/// The colour model of a target and the sample pattern of its likelihood.
#[derive(Clone, Debug)]
pub struct ColourModel {
    model: Histogram,
    sqrt_model: [f64; BINS],
    sqrt_count: [f64; SAMPLES + 1],
    inner: Vec<[f64; 2]>,
    outer: Vec<[f64; 2]>,
    /// Whether each bin counts as the target's colour for the rim term.
    member: [bool; BINS],
    /// Unit directions of the rim's rays.
    rays: Vec<[f64; 2]>,
    /// `lambda` of `exp(lambda * (score + rim_weight * rim))`.
    pub lambda: f64,
    /// Weight of the rim term, at least 0 ([`RIM_WEIGHT`] by default; 0: the histograms only).
    pub rim_weight: f64,
}

impl ColourModel {
    /// The model from a histogram.
    pub fn new(model: Histogram) -> Self {
        let member = std::array::from_fn(|b| model.0[b] >= RIM_MEMBER_SHARE);
        Self {
            sqrt_model: model.0.map(f64::sqrt),
            sqrt_count: std::array::from_fn(|k| (k as f64).sqrt()),
            model,
            inner: sunflower(SAMPLES, 0.0, 1.0),
            outer: sunflower(SAMPLES, RING.0, RING.1),
            member,
            rays: (0..RIM_SAMPLES)
                .map(|k| {
                    let (s, c) = (std::f64::consts::TAU * (k as f64 + 0.5) / RIM_SAMPLES as f64).sin_cos();
                    [c, s]
                })
                .collect(),
            lambda: DEFAULT_LAMBDA,
            rim_weight: RIM_WEIGHT,
        }
    }

    /// The model of every pixel whose centre lies inside `patch` of `frame` (a reference view
    /// of the target).
    pub fn from_patch(frame: &Plane<[u8; 3]>, patch: Circle) -> Result<Self> {
        let Circle { x, y, r } = patch;
        if !(x.is_finite() && y.is_finite() && r.is_finite() && r >= 1.0) {
            return Err(TrackingError::Invalid(format!(
                "model patch ({x}, {y}) radius {r}: need a finite centre and a radius of at least 1 px"
            )));
        }
        let (w, h) = frame.size();
        let (x0, x1) = ((x - r).floor().max(0.0) as usize, ((x + r).ceil().max(0.0) as usize).min(w));
        let (y0, y1) = ((y - r).floor().max(0.0) as usize, ((y + r).ceil().max(0.0) as usize).min(h));
        let inside = (y0..y1).flat_map(|py| (x0..x1).map(move |px| (px, py)));
        let bins = inside
            .filter(|&(px, py)| (px as f64 - x).powi(2) + (py as f64 - y).powi(2) <= r * r)
            .map(|(px, py)| bin_of(frame.get(px, py)));
        let model = Histogram::of(bins).ok_or_else(|| {
            TrackingError::Invalid(format!("model patch ({x}, {y}) radius {r} lies outside the {w}x{h} frame"))
        })?;
        Ok(Self::new(model))
    }

    /// The model of one colour (all its mass in that colour's bin).
    pub fn from_colour(rgb: [u8; 3]) -> Self {
        let mut h = [0.0; BINS];
        h[bin_of(rgb) as usize] = 1.0;
        Self::new(Histogram(h))
    }

    /// The model histogram.
    pub fn histogram(&self) -> &Histogram {
        &self.model
    }

    /// `BC(inner, model) - BC(inner, outer)` of `circle`, in [-1, 1]; -1 when no inner sample
    /// falls on the frame or the circle is not finite with a positive radius. Inner samples
    /// off the frame count as matching nothing (the inner histogram then sums to the share on
    /// the frame); the outer histogram is over the ring's samples on the frame.
    pub fn score(&self, frame: &BinnedFrame, circle: Circle) -> f64 {
        let Circle { x, y, r } = circle;
        if !(x.is_finite() && y.is_finite() && r.is_finite() && r > 0.0) {
            return -1.0;
        }
        // The disc's bins are counted in four interleaved tables: inside a ball most samples
        // fall in one or two bins, and incrementing one counter 64 times in a row is a chain
        // of store-to-load forwards (about 5 cycles each); four tables cut the chain by four.
        // The Bhattacharyya sums then run over the bins the disc touched, with square roots
        // from tables: a hypothesis costs its 128 lookups and no pass over the 110 bins.
        let mut ci = [[0u8; BINS]; 4];
        let mut co = [0u8; BINS];
        let mut inner = [0u8; SAMPLES];
        let mut ni_on = 0usize;
        let mut no = 0u32;
        let [x0, y0, x1, y1] = frame.region.map(|v| v as f64);
        let reach = circle.reach();
        let (ri, ro) = (circle.inner_scale(), circle.outer_scale());
        if x - reach >= x0 && y - reach >= y0 && x + reach < x1 && y + reach < y1 {
            // The whole pattern lies on the frame: no per-sample bounds test, and the pixel
            // indices are computed in one loop the compiler vectorizes.
            let (data, stride) = (frame.bins.as_slice(), frame.bins.stride() as i64);
            let mut idx = [0usize; SAMPLES];
            for (i, p) in self.inner.iter().enumerate() {
                idx[i] = (nearest(y + ri * p[1]) * stride + nearest(x + ri * p[0])) as usize;
            }
            for (i, &k) in idx.iter().enumerate() {
                let b = data[k];
                inner[i] = b;
                ci[i & 3][b as usize] += 1;
            }
            ni_on = SAMPLES;
            for (i, p) in self.outer.iter().enumerate() {
                idx[i] = (nearest(y + ro * p[1]) * stride + nearest(x + ro * p[0])) as usize;
            }
            idx.iter().for_each(|&k| co[data[k] as usize] += 1);
            no = SAMPLES as u32;
        } else {
            for p in &self.inner {
                if let Some(b) = frame.at(x + ri * p[0], y + ri * p[1]) {
                    inner[ni_on] = b;
                    ci[ni_on & 3][b as usize] += 1;
                    ni_on += 1;
                }
            }
            for p in &self.outer {
                if let Some(b) = frame.at(x + ro * p[0], y + ro * p[1]) {
                    co[b as usize] += 1;
                    no += 1;
                }
            }
        }
        if ni_on == 0 {
            return -1.0;
        }
        let (mut sm, mut so) = (0.0, 0.0);
        for &b in &inner[..ni_on] {
            let b = b as usize;
            let n = ci[0][b] + ci[1][b] + ci[2][b] + ci[3][b];
            if n > 0 {
                let sc = self.sqrt_count[n as usize];
                sm += sc * self.sqrt_model[b];
                so += sc * self.sqrt_count[co[b] as usize];
                // Counted once: the bin's later samples find zero.
                (ci[0][b], ci[1][b], ci[2][b], ci[3][b]) = (0, 0, 0, 0);
            }
        }
        // The inner histogram is over all the disc's samples: those off the frame are
        // evidence missing, not evidence of the model, so a disc half out of view scores at
        // most sqrt(1/2) on its match (a light at the frame's edge must not beat the ball).
        let ni = SAMPLES as f64;
        sm / ni.sqrt() - so / (ni * no.max(1) as f64).sqrt()
    }

    /// The rim term of `circle`, in [-1, 1] (see the module doc): over [`RIM_SAMPLES`] rays,
    /// +1 for the target's colour [`EDGE_GUARD_PX`] inside the circle and not as far outside,
    /// -1 for it outside, 0 for neither, averaged. Rays off the frame vote 0. -1 when the
    /// circle is not finite with a positive radius.
    pub fn rim(&self, frame: &BinnedFrame, circle: Circle) -> f64 {
        let Circle { x, y, r } = circle;
        if !(x.is_finite() && y.is_finite() && r.is_finite() && r > 0.0) {
            return -1.0;
        }
        let (ri, ro) = (circle.inner_scale(), r + EDGE_GUARD_PX);
        let vote = |inside: bool, outside: bool| match (inside, outside) {
            (_, true) => -1,
            (true, false) => 1,
            (false, false) => 0,
        };
        let [x0, y0, x1, y1] = frame.region.map(|v| v as f64);
        if x - ro - 1.0 >= x0 && y - ro - 1.0 >= y0 && x + ro + 1.0 < x1 && y + ro + 1.0 < y1 {
            // Every ray on the frame: no per-sample bounds test (as in `score`).
            let (data, stride) = (frame.bins.as_slice(), frame.bins.stride() as i64);
            let at = |rad: f64, p: &[f64; 2]| {
                self.member[data[(nearest(y + rad * p[1]) * stride + nearest(x + rad * p[0])) as usize] as usize]
            };
            let votes: i32 = self.rays.iter().map(|p| vote(at(ri, p), at(ro, p))).sum();
            return f64::from(votes) / RIM_SAMPLES as f64;
        }
        let member = |b: Option<u8>| b.is_some_and(|b| self.member[b as usize]);
        let votes: i32 = self
            .rays
            .iter()
            .map(|p| {
                let outside = member(frame.at(x + ro * p[0], y + ro * p[1]));
                vote(member(frame.at(x + ri * p[0], y + ri * p[1])), outside)
            })
            .sum();
        f64::from(votes) / RIM_SAMPLES as f64
    }

    /// `log p(z | circle) = lambda * (score + rim_weight * rim)` (up to a constant).
    pub fn log_likelihood(&self, frame: &BinnedFrame, circle: Circle) -> f64 {
        let rim = if self.rim_weight > 0.0 { self.rim_weight * self.rim(frame, circle) } else { 0.0 };
        self.lambda * (self.score(frame, circle) + rim)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bins_of_known_colours() {
        // Pure red: hue 0, saturation 1 -> hue bin 0, saturation bin 9.
        assert_eq!(bin_of([255, 0, 0]), 9);
        // Pure green: hue 2 sextants = 120 deg -> hue bin 3 (120 / 36 = 3.33).
        assert_eq!(bin_of([0, 255, 0]), 3 * 10 + 9);
        // Pure blue: 240 deg -> bin 6.
        assert_eq!(bin_of([0, 0, 255]), 6 * 10 + 9);
        // Greys and dark colours have no reliable hue: value bins 100..110.
        assert_eq!(bin_of([0, 0, 0]), 100);
        assert_eq!(bin_of([255, 255, 255]), 109);
        assert_eq!(bin_of([128, 128, 128]), 105);
        assert_eq!(bin_of([40, 0, 0]), 100 + 1, "dark red (value 0.16) is a value bin");
        // Hue wraps: a red with a little blue is near 360 deg, the last hue bin.
        assert_eq!(bin_of([255, 0, 20]) / 10, 9);
    }

    #[test]
    fn every_backend_bins_every_colour_as_the_integer_definition() {
        // All 2^24 colours would take long in a debug build; a 2^18 lattice that includes
        // the extremes and every value of one channel at a time.
        let steps: Vec<u8> = (0..=255u8).step_by(4).chain([1, 2, 3, 254, 255, 51, 52, 25, 26]).collect();
        let mut colours = Vec::new();
        for &r in &steps {
            for &g in &steps {
                for &b in &steps {
                    colours.push([r, g, b]);
                }
            }
        }
        let w = 73; // not a multiple of the block: the remainder path too
        let h = colours.len().div_ceil(w);
        let frame = Plane::from_fn(w, h, |x, y| colours.get(y * w + x).copied().unwrap_or([9, 200, 30]));
        for backend in Backend::available() {
            let mut b = BinnedFrame::default();
            b.update_with(backend, &frame);
            for y in 0..h {
                for x in 0..w {
                    assert_eq!(b.bins().get(x, y), bin_of(frame.get(x, y)), "{backend:?} {:?}", frame.get(x, y));
                }
            }
        }
        // Boundaries: S = 0.1 exactly is grey (10 d = M), just above is coloured.
        assert_eq!(bin_of([250, 225, 225]), 109);
        assert!(bin_of([250, 224, 224]) < 100);
        assert_eq!(bin_of([51, 0, 0]), 102, "V = 0.2 exactly is a value bin");
        assert_eq!(bin_of([52, 0, 0]), 9);
    }

    #[test]
    fn extending_the_region_bins_what_the_union_adds() {
        let frame = Plane::from_fn(40, 30, |x, y| [(x * 6) as u8, (y * 8) as u8, ((x + y) * 3) as u8]);
        let whole = BinnedFrame::new(&frame);
        for (a, b) in [([5, 6, 20, 18], [15, 2, 38, 25]), ([5, 6, 20, 18], [8, 8, 12, 12]), ([0; 4], [3, 4, 9, 9])] {
            let mut part = BinnedFrame::default();
            part.update_region(&frame, a);
            part.extend_region(&frame, b);
            let u = union_rect(a, b);
            assert_eq!(part.region(), u);
            for y in u[1]..u[3] {
                for x in u[0]..u[2] {
                    assert_eq!(part.bins().get(x, y), whole.bins().get(x, y), "({x}, {y}) of {u:?}");
                }
            }
        }
        assert_eq!(union_rect([2, 2, 2, 9], [1, 1, 3, 3]), [1, 1, 3, 3]);
    }

    #[test]
    fn nearest_rounds() {
        for (v, n) in [(0.0, 0), (0.49, 0), (0.51, 1), (1.5, 2), (2.5, 2), (-0.51, -1), (-3.2, -3), (639.4, 639)] {
            assert_eq!(nearest(v), n, "{v}");
        }
        assert!(nearest(1e300) > 1 << 40 || nearest(1e300) < -(1 << 40));
        assert!(nearest(-1e300).abs() > 1 << 40);
    }

    #[test]
    fn bhattacharyya_closed_forms() {
        let a = Histogram::of([1u8, 1, 2, 2]).unwrap();
        let b = Histogram::of([3u8, 4]).unwrap();
        assert!((bhattacharyya(&a, &a) - 1.0).abs() < 1e-12);
        assert_eq!(bhattacharyya(&a, &b), 0.0);
        // Half the mass shared: sqrt(0.5 * 1) for the common bin.
        let c = Histogram::of([1u8]).unwrap();
        assert!((bhattacharyya(&a, &c) - 0.5f64.sqrt()).abs() < 1e-12);
        assert!(Histogram::of(std::iter::empty()).is_none());
    }

    #[test]
    fn the_sample_pattern_covers_the_disc_and_ring_evenly() {
        let inner = sunflower(SAMPLES, 0.0, 1.0);
        assert!(inner.iter().all(|p| p[0].hypot(p[1]) <= 1.0));
        // Half the points inside radius 1/sqrt(2) (half the area).
        let half = inner.iter().filter(|p| p[0].hypot(p[1]) < std::f64::consts::FRAC_1_SQRT_2).count();
        assert_eq!(half, SAMPLES / 2);
        let ring = sunflower(SAMPLES, RING.0, RING.1);
        assert!(ring.iter().all(|p| (RING.0..=RING.1).contains(&p[0].hypot(p[1]))));
        let sum = ring.iter().fold([0.0, 0.0], |m, p| [m[0] + p[0], m[1] + p[1]]);
        let mean = [sum[0] / SAMPLES as f64, sum[1] / SAMPLES as f64];
        assert!(mean[0].abs() < 0.05 && mean[1].abs() < 0.05, "ring points spread around: {mean:?}");
    }

    /// A real photo (the astronaut; the coffee photo is itself orange) with an orange disc of radius 15 at (100, 70); `hide` covers its left half
    /// with the photo.
    fn scene(hide: bool) -> (Plane<[u8; 3]>, Circle) {
        let photo = ocellus_io::read_image(ocellus_testdata::data_file("astronaut.png")).unwrap().to_u8();
        let c = Circle { x: 100.0, y: 70.0, r: 15.0 };
        let frame = Plane::from_fn(200, 150, |x, y| {
            let (dx, dy) = (x as f64 - c.x, y as f64 - c.y);
            let shade = 1.0 - 0.3 * (dx + dy) / (2.0 * c.r);
            if dx * dx + dy * dy <= c.r * c.r && !(hide && dx < 0.0) {
                [(245.0 * shade) as u8, (120.0 * shade) as u8, (20.0 * shade) as u8]
            } else {
                photo.get(x + 200, y + 150)
            }
        });
        (frame, c)
    }

    #[test]
    fn the_true_circle_scores_best_even_half_hidden() {
        let (frame, truth) = scene(false);
        let model = ColourModel::from_patch(&frame, Circle { r: 12.0, ..truth }).unwrap();
        for hide in [false, true] {
            let (frame, _) = scene(hide);
            let binned = BinnedFrame::new(&frame);
            let best = model.score(&binned, truth);
            assert!(best > if hide { 0.1 } else { 0.8 }, "hide {hide}: {best}");
            for (dx, dy, dr) in
                [(20.0, 0.0, 0.0), (0.0, -25.0, 0.0), (40.0, 30.0, 0.0), (0.0, 0.0, 12.0), (0.0, 0.0, -10.0)]
            {
                let other = Circle { x: truth.x + dx, y: truth.y + dy, r: truth.r + dr };
                let s = model.score(&binned, other);
                // Half hidden, a circle on the visible half (dx > 0) is as good: only far ones lose.
                if !(hide && dx > 0.0 && dx < 25.0) {
                    assert!(s < best, "hide {hide}: {other:?} scores {s} >= {best}");
                }
            }
        }
    }

    /// The score straight from its definition: both histograms normalized, BC summed over
    /// all bins.
    fn slow_score(m: &ColourModel, frame: &BinnedFrame, c: Circle) -> f64 {
        let sample = |pattern: &[[f64; 2]], scale: f64| -> Vec<u8> {
            pattern.iter().filter_map(|p| frame.at(c.x + scale * p[0], c.y + scale * p[1])).collect()
        };
        let (inner, outer) = (sample(&m.inner, c.inner_scale()), sample(&m.outer, c.outer_scale()));
        if inner.is_empty() {
            return -1.0;
        }
        let mut hi = [0.0; BINS];
        inner.iter().for_each(|&b| hi[b as usize] += 1.0 / SAMPLES as f64);
        let mut ho = [0.0; BINS];
        outer.iter().for_each(|&b| ho[b as usize] += 1.0 / outer.len().max(1) as f64);
        bhattacharyya(&Histogram(hi), m.histogram()) - bhattacharyya(&Histogram(hi), &Histogram(ho))
    }

    #[test]
    fn the_fast_score_is_the_definition() {
        let (frame, truth) = scene(false);
        let model = ColourModel::from_patch(&frame, Circle { r: 12.0, ..truth }).unwrap();
        let binned = BinnedFrame::new(&frame);
        let mut rng = ocellus_image::rng::SplitMix64::new(4);
        for _ in 0..2000 {
            let c = Circle { x: 220.0 * rng.unit() - 10.0, y: 170.0 * rng.unit() - 10.0, r: 0.5 + 40.0 * rng.unit() };
            let (fast, slow) = (model.score(&binned, c), slow_score(&model, &binned, c));
            assert!((fast - slow).abs() < 1e-12, "{c:?}: {fast} vs {slow}");
        }
    }

    #[test]
    fn the_fast_rim_is_the_bounds_checked_one() {
        let (frame, truth) = scene(false);
        let model = ColourModel::from_patch(&frame, Circle { r: 12.0, ..truth }).unwrap();
        let binned = BinnedFrame::new(&frame);
        let mut rng = ocellus_image::rng::SplitMix64::new(5);
        for _ in 0..2000 {
            let c = Circle { x: 220.0 * rng.unit() - 10.0, y: 170.0 * rng.unit() - 10.0, r: 0.5 + 40.0 * rng.unit() };
            let slow: i32 = model
                .rays
                .iter()
                .map(|p| {
                    let m = |rad: f64| frame_member(&model, &binned, c.x + rad * p[0], c.y + rad * p[1]);
                    match (m(c.inner_scale()), m(c.r + EDGE_GUARD_PX)) {
                        (_, true) => -1,
                        (true, false) => 1,
                        (false, false) => 0,
                    }
                })
                .sum();
            assert_eq!(model.rim(&binned, c), f64::from(slow) / RIM_SAMPLES as f64, "{c:?}");
        }
    }

    fn frame_member(m: &ColourModel, frame: &BinnedFrame, x: f64, y: f64) -> bool {
        frame.at(x, y).is_some_and(|b| m.member[b as usize])
    }

    #[test]
    fn the_rim_sees_the_edge_where_the_ball_is_visible() {
        let (frame, truth) = scene(false);
        let model = ColourModel::from_colour([245, 120, 20]);
        let rim = |frame: &Plane<[u8; 3]>, c: Circle| model.rim(&BinnedFrame::new(frame), c);
        // The whole edge votes for the true circle; a circle 2 px too small sees the ball
        // outside it all round; one 2 px too large sees it on neither side.
        assert!(rim(&frame, truth) > 0.9, "{}", rim(&frame, truth));
        assert!(rim(&frame, Circle { r: truth.r - 2.0, ..truth }) < -0.9);
        assert!(rim(&frame, Circle { r: truth.r + 2.0, ..truth }).abs() < 0.1);
        // Half hidden: the visible arc still votes for the true circle, and a smaller circle
        // in the visible half loses the rays that end inside the ball.
        let (half, _) = scene(true);
        let t = rim(&half, truth);
        assert!((0.35..0.65).contains(&t), "{t}");
        let inside = Circle { x: truth.x + 7.0, y: truth.y, r: 7.5 };
        assert!(rim(&half, inside) < t - 0.3, "{} vs {t}", rim(&half, inside));
        assert_eq!(rim(&frame, Circle { r: f64::NAN, ..truth }), -1.0);
    }

    #[test]
    fn a_large_region_of_the_model_colour_does_not_score() {
        // Inside an orange wall the ring looks like the disc: BC(inner, outer) cancels the match.
        let wall = Plane::from_fn(100, 100, |_, _| [245u8, 120, 20]);
        let model = ColourModel::from_colour([245, 120, 20]);
        let s = model.score(&BinnedFrame::new(&wall), Circle { x: 50.0, y: 50.0, r: 10.0 });
        assert!(s.abs() < 1e-9, "{s}");
    }

    #[test]
    fn degenerate_circles_and_patches() {
        let frame = Plane::from_fn(50, 40, |x, _| [x as u8 * 5, 100, 30]);
        let binned = BinnedFrame::new(&frame);
        let m = ColourModel::from_colour([200, 100, 30]);
        for c in [
            Circle { x: f64::NAN, y: 1.0, r: 3.0 },
            Circle { x: 1.0, y: 1.0, r: 0.0 },
            Circle { x: 1e9, y: 1.0, r: 3.0 },
            Circle { x: 1.0, y: 1.0, r: f64::INFINITY },
        ] {
            assert_eq!(m.score(&binned, c), -1.0, "{c:?}");
        }
        assert!(ColourModel::from_patch(&frame, Circle { x: 500.0, y: 5.0, r: 3.0 }).is_err());
        assert!(ColourModel::from_patch(&frame, Circle { x: 5.0, y: 5.0, r: 0.5 }).is_err());
        assert!(ColourModel::from_patch(&frame, Circle { x: 5.0, y: f64::NAN, r: 3.0 }).is_err());
    }

    proptest::proptest! {
        #[test]
        fn scores_stay_in_range(x in -1e4f64..1e4, y in -1e4f64..1e4, r in -10.0f64..1e4, seed in 0u64..1000) {
            let mut rng = ocellus_image::rng::SplitMix64::new(seed);
            let frame = Plane::from_fn(40, 30, |_, _| [rng.below(256) as u8, rng.below(256) as u8, rng.below(256) as u8]);
            let binned = BinnedFrame::new(&frame);
            let m = ColourModel::from_colour([200, 30, 30]);
            let s = m.score(&binned, Circle { x, y, r });
            proptest::prop_assert!((-1.0..=1.0).contains(&s), "{}", s);
        }
    }
}
