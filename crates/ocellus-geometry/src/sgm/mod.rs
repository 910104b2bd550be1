//! Dense disparity by semi-global matching (Hirschmüller, "Stereo processing by semiglobal
//! matching and mutual information", IEEE TPAMI 30(2), 2008), beyond the seed's block matching.
//!
//! - **Matching cost:** Hamming distance between census transforms (Zabih & Woodfill 1994) of
//!   a `census_width` x `census_height` window (at most 63 neighbours, one bit each: darker
//!   than the centre). Census is invariant to monotonic brightness changes between the two
//!   cameras, which real pairs have.
//! - **Aggregation** along 4 (horizontal, vertical) or 8 (plus diagonals) straight paths, with
//!   `m = min_k L_r(p - r, k)`,
//!   `L_r(p, d) = C(p, d) + min(L_r(p - r, d), L_r(p - r, d +- 1) + P1, m + P2) - m`,
//!   summed over the paths. Two passes over the image (paths arriving
//!   from above and the left, then from below and the right), each keeping one previous row.
//!   Costs are u16 and the inner loop over disparities is written for the compiler to
//!   vectorize (AVX2 build chosen at run time).
//! - **Selection:** winner-take-all on the summed cost, a uniqueness test, sub-pixel
//!   (equiangular fit), a left-right check against the right image's winners (from the left
//!   winners, as OpenCV's SGBM does), and optionally a 3x3 median over valid neighbours.
//!   Invalid pixels are NaN.
//! - [`SgmMatcher`] owns the cost volume and every buffer, for streams of pairs.
//!
//! Left pixel (x, y) with disparity d matches right pixel (x - d, y). For `x < d` there is no
//! right pixel; the right image's first column stands in for the cost (replicated border),
//! and such a disparity, if it wins, is reported invalid.

use crate::wta::{select_row, SubPixel, WtaRule, WtaScratch};
use crate::{GeometryError, Result};
use ocellus_image::simd::Madd;
use ocellus_image::{dispatch_kernel, Backend, Plane};

/// Paths of the aggregation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SgmPaths {
    /// Left, right, up, down.
    Four,
    /// The four and the diagonals.
    Eight,
}

/// Parameters of [`sgm`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sgm {
    /// Disparities searched: `0..max_disparity` (1..=256).
    pub max_disparity: usize,
    /// Census window width, odd, pixels.
    pub census_width: usize,
    /// Census window height, odd, pixels (`width * height - 1 <= 63`).
    pub census_height: usize,
    /// Penalty of a one-pixel disparity change between neighbours (cost units: census bits).
    pub p1: u16,
    /// Penalty of a larger disparity change.
    pub p2: u16,
    /// Which paths.
    pub paths: SgmPaths,
    /// Uniqueness margin: the best must beat every non-adjacent disparity by this fraction.
    pub uniqueness: f32,
    /// Largest left-right disagreement kept, pixels (negative disables the check).
    pub lr_max_diff: f32,
    /// 3x3 median of the valid disparities afterwards.
    pub median: bool,
    /// Which build of the kernels runs (`Auto`: the fastest this CPU has).
    pub backend: Backend,
}

impl Default for Sgm {
    /// 64 disparities, census 9x7, P1 10, P2 120, 8 paths, uniqueness 0.05, left-right 1 px,
    /// no median (on the motorcycle pair it changes bad-2.0 by 0.1 point).
    fn default() -> Self {
        Self {
            max_disparity: 64,
            census_width: 9,
            census_height: 7,
            p1: 10,
            p2: 120,
            paths: SgmPaths::Eight,
            uniqueness: 0.05,
            lr_max_diff: 1.0,
            median: false,
            backend: Backend::Auto,
        }
    }
}

impl Sgm {
    fn check(&self, left: &Plane<u8>, right: &Plane<u8>) -> Result<()> {
        ocellus_image::check::same_size("right image (against the left)", right.size(), left.size())?;
        ocellus_image::check::within("max_disparity", self.max_disparity, 1, 256).map_err(GeometryError::Invalid)?;
        ocellus_image::check::within("uniqueness", self.uniqueness, 0.0, 0.99).map_err(GeometryError::Invalid)?;
        let (cw, ch) = (self.census_width, self.census_height);
        if cw % 2 == 0 || ch % 2 == 0 || cw * ch - 1 > 63 || cw * ch < 9 {
            return Err(GeometryError::Invalid(format!(
                "census window {cw}x{ch}: both sides odd, at least 3x3, at most 63 neighbours"
            )));
        }
        if self.p1 == 0 || self.p2 < self.p1 || self.p2 > 1000 {
            return Err(GeometryError::Invalid(format!(
                "penalties P1 {} and P2 {}: need 0 < P1 <= P2 <= 1000",
                self.p1, self.p2
            )));
        }
        let (w, h) = left.size();
        if w < cw || h < ch || w < 2 {
            return Err(GeometryError::Invalid(format!("images {w}x{h} are smaller than the census window {cw}x{ch}")));
        }
        Ok(())
    }
}

/// Census transform: bit k set when neighbour k is darker than the centre (borders
/// replicated).
pub fn census(backend: Backend, img: &Plane<u8>, width: usize, height: usize) -> Plane<u64> {
    let mut out = Plane::<u64>::new(img.width(), img.height());
    census_kernel(backend, img, width, height, &mut out);
    out
}

#[inline(always)]
// The dispatch macro instantiates kernels per multiply-add flavour; integer kernels ignore it.
#[allow(clippy::extra_unused_type_parameters)]
fn census_generic<M: Madd>(img: &Plane<u8>, width: usize, height: usize, out: &mut Plane<u64>) {
    let (w, h) = img.size();
    let (hw, hh) = ((width / 2) as isize, (height / 2) as isize);
    out.resize(w, h);
    let mut padded = vec![0u8; w + 2 * hw as usize];
    // Bits are gathered in eight byte planes (32 comparisons per AVX2 instruction), then
    // interleaved into the u64 words once per row.
    let mut planes = vec![0u8; 8 * w];
    for y in 0..h {
        let centre = img.row(y);
        planes.fill(0);
        let mut bit = 0usize;
        for dy in -hh..=hh {
            let src = img.row((y as isize + dy).clamp(0, h as isize - 1) as usize);
            padded[hw as usize..hw as usize + w].copy_from_slice(src);
            let (first, last) = (src[0], src[w - 1]);
            padded[..hw as usize].fill(first);
            padded[hw as usize + w..].fill(last);
            for dx in -hw..=hw {
                if dx == 0 && dy == 0 {
                    continue;
                }
                let shifted = &padded[(hw + dx) as usize..(hw + dx) as usize + w];
                let plane = &mut planes[(bit / 8) * w..(bit / 8 + 1) * w];
                let sh = (bit % 8) as u32;
                for ((o, &s), &c) in plane.iter_mut().zip(shifted).zip(centre) {
                    *o |= u8::from(s < c) << sh;
                }
                bit += 1;
            }
        }
        let row_out = out.row_mut(y);
        for (x, o) in row_out.iter_mut().enumerate() {
            let mut v = 0u64;
            for b in 0..8 {
                v |= (planes[b * w + x] as u64) << (8 * b);
            }
            *o = v;
        }
    }
}

dispatch_kernel!(fn census_kernel => census_generic(img: &Plane<u8>, width: usize, height: usize, out: &mut Plane<u64>));

/// One path step at one pixel: `cur[d + 1]` from `prev[d..d + 3]` (padded by one on each
/// side with a large value) and the cost, stored into (`store`) or added to `sum`; returns the
/// minimum of `cur`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn path_step_sum<const K: usize>(
    cost: &[u8],
    prev: &[u16],
    prev_min: u16,
    cur: &mut [u16],
    sum: &mut [u16],
    p1: u16,
    p2: u16,
    store: bool,
) -> u16 {
    let lim = prev_min.saturating_add(p2);
    let mut m = u16::MAX;
    // K > 0: the disparity count known at compile time (fully unrolled loop).
    let n = if K > 0 { K } else { cost.len() };
    let (cost, prev, cur, sum) = (&cost[..n], &prev[..n + 2], &mut cur[..n + 2], &mut sum[..n]);
    // Storing is adding to zero: a mask instead of a branch keeps the loop vectorized.
    let keep = if store { 0 } else { u16::MAX };
    for d in 0..n {
        let near = prev[d].min(prev[d + 2]).saturating_add(p1);
        let v = prev[d + 1].min(near).min(lim);
        let val = cost[d] as u16 + v - prev_min;
        cur[d + 1] = val;
        m = m.min(val);
        sum[d] = (sum[d] & keep).saturating_add(val);
    }
    m
}

/// [`path_step_sum`] without the sum (tests).
#[cfg(test)]
fn path_step(cost: &[u8], prev: &[u16], prev_min: u16, cur: &mut [u16], p1: u16, p2: u16) -> u16 {
    let mut sum = vec![0u16; cost.len()];
    path_step_sum::<0>(cost, prev, prev_min, cur, &mut sum, p1, p2, true)
}

/// Large value for the padding of path buffers (never chosen; adding P1 cannot overflow).
const PAD: u16 = 0x7000;

/// Buffers of one pass: per path, the previous and current row of L (padded), and minima.
struct PassBuffers {
    dp: usize,
    /// Per vertical-ish path (up to 3): previous row, current row, their minima.
    prev: Vec<Vec<u16>>,
    cur: Vec<Vec<u16>>,
    prev_min: Vec<Vec<u16>>,
    cur_min: Vec<Vec<u16>>,
    /// Horizontal path: previous and current pixel.
    h_prev: Vec<u16>,
    h_cur: Vec<u16>,
    zeros: Vec<u16>,
}

impl PassBuffers {
    fn new(w: usize, d: usize, vertical_paths: usize) -> Self {
        let dp = d + 2;
        let padded = |len: usize| {
            let mut v = vec![0u16; len * dp];
            for k in 0..len {
                v[k * dp] = PAD;
                v[k * dp + dp - 1] = PAD;
            }
            v
        };
        Self {
            dp,
            prev: (0..vertical_paths).map(|_| padded(w)).collect(),
            cur: (0..vertical_paths).map(|_| padded(w)).collect(),
            prev_min: vec![vec![0; w]; vertical_paths],
            cur_min: vec![vec![0; w]; vertical_paths],
            h_prev: padded(1),
            h_cur: padded(1),
            zeros: padded(1),
        }
    }
}

/// One aggregation pass: rows in `forward` order (top to bottom, pixels left to right) or
/// reversed; adds every path's L into `sum` (or stores it when `first`).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
// The dispatch macro instantiates kernels per multiply-add flavour; integer kernels ignore it.
#[allow(clippy::extra_unused_type_parameters)]
fn pass_generic<M: Madd>(
    cost: &[u8],
    sum: &mut [u16],
    w: usize,
    h: usize,
    d: usize,
    p1: u16,
    p2: u16,
    diagonals: bool,
    forward: bool,
) {
    match d {
        64 => pass_d::<64>(cost, sum, w, h, d, p1, p2, diagonals, forward),
        128 => pass_d::<128>(cost, sum, w, h, d, p1, p2, diagonals, forward),
        _ => pass_d::<0>(cost, sum, w, h, d, p1, p2, diagonals, forward),
    }
}

/// [`pass_generic`] for `K` disparities known at compile time (0: any).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn pass_d<const K: usize>(
    cost: &[u8],
    sum: &mut [u16],
    w: usize,
    h: usize,
    d: usize,
    p1: u16,
    p2: u16,
    diagonals: bool,
    forward: bool,
) {
    let vertical_paths = if diagonals { 3 } else { 1 };
    let mut b = PassBuffers::new(w, d, vertical_paths);
    let dp = b.dp;
    // Offsets (in x, iteration order) of the previous row's pixel for each vertical path:
    // straight, then the two diagonals.
    let offsets: [isize; 3] = [0, -1, 1];
    for step_y in 0..h {
        let y = if forward { step_y } else { h - 1 - step_y };
        let mut h_min = 0u16;
        b.h_prev.copy_from_slice(&b.zeros);
        for step_x in 0..w {
            let x = if forward { step_x } else { w - 1 - step_x };
            let c = &cost[(y * w + x) * d..(y * w + x + 1) * d];
            let s = &mut sum[(y * w + x) * d..(y * w + x + 1) * d];
            // Horizontal path.
            let m = if step_x == 0 {
                path_step_sum::<K>(c, &b.zeros, 0, &mut b.h_cur, s, p1, p2, forward)
            } else {
                path_step_sum::<K>(c, &b.h_prev, h_min, &mut b.h_cur, s, p1, p2, forward)
            };
            h_min = m;
            std::mem::swap(&mut b.h_prev, &mut b.h_cur);
            for (k, &off) in offsets.iter().take(vertical_paths).enumerate() {
                let px = step_x as isize + off;
                let from = (step_y > 0 && px >= 0 && (px as usize) < w).then_some(px as usize);
                let cur = &mut b.cur[k][step_x * dp..(step_x + 1) * dp];
                let (prev, prev_min) = match from {
                    Some(px) => (&b.prev[k][px * dp..(px + 1) * dp], b.prev_min[k][px]),
                    None => (&b.zeros[..], 0),
                };
                b.cur_min[k][step_x] = path_step_sum::<K>(c, prev, prev_min, cur, s, p1, p2, false);
            }
        }
        for k in 0..vertical_paths {
            std::mem::swap(&mut b.prev[k], &mut b.cur[k]);
            std::mem::swap(&mut b.prev_min[k], &mut b.cur_min[k]);
        }
    }
}

dispatch_kernel!(fn pass_kernel => pass_generic(
    cost: &[u8], sum: &mut [u16], w: usize, h: usize, d: usize, p1: u16, p2: u16, diagonals: bool, forward: bool
));

#[inline(always)]
fn costs_generic(cl: &Plane<u64>, cr: &Plane<u64>, cost: &mut [u8], d: usize) {
    let (w, h) = cl.size();
    // The right row reversed, so that disparities run forward through memory:
    // reversed[w - 1 - x + k] = right[x - k].
    let mut reversed = vec![0u64; w];
    for y in 0..h {
        let (l, r) = (cl.row(y), cr.row(y));
        reversed.iter_mut().zip(r.iter().rev()).for_each(|(a, b)| *a = *b);
        for x in 0..w {
            let c = &mut cost[(y * w + x) * d..(y * w + x + 1) * d];
            let lx = l[x];
            let valid = d.min(x + 1);
            let base = w - 1 - x;
            for (v, &rv) in c[..valid].iter_mut().zip(&reversed[base..base + valid]) {
                *v = (lx ^ rv).count_ones() as u8;
            }
            // Past the right image's border, its first column repeats (a neutral cost: a
            // fixed maximum would leak along the paths into flat regions).
            let edge = (lx ^ r[0]).count_ones() as u8;
            c[valid..].fill(edge);
        }
    }
}

/// Census Hamming costs; the fast build uses the POPCNT instruction.
fn costs_kernel(backend: Backend, cl: &Plane<u64>, cr: &Plane<u64>, cost: &mut [u8], d: usize) {
    #[cfg(target_arch = "x86_64")]
    {
        #[target_feature(enable = "avx2,popcnt")]
        unsafe fn fast(cl: &Plane<u64>, cr: &Plane<u64>, cost: &mut [u8], d: usize) {
            costs_generic(cl, cr, cost, d)
        }
        if backend.has_avx2() && is_x86_feature_detected!("popcnt") {
            // SAFETY: the CPU has AVX2 (resolve) and POPCNT (checked).
            return unsafe { fast(cl, cr, cost, d) };
        }
    }
    let _ = backend;
    costs_generic(cl, cr, cost, d)
}

/// SGM for one image size, owning every buffer: after the first pair, computing a
/// disparity map allocates nothing.
#[derive(Clone, Debug)]
pub struct SgmMatcher {
    params: Sgm,
    size: (usize, usize),
    census_left: Plane<u64>,
    census_right: Plane<u64>,
    cost: Vec<u8>,
    sum: Vec<u16>,
    raw: Plane<f32>,
    out: Plane<f32>,
    timings: SgmTimings,
}

/// Wall time of each stage of the last [`SgmMatcher::compute`], milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SgmTimings {
    /// Census transforms of both images.
    pub census_ms: f64,
    /// Hamming cost volume.
    pub cost_ms: f64,
    /// Path aggregation (both passes).
    pub aggregation_ms: f64,
    /// Winner selection, uniqueness, sub-pixel, left-right check.
    pub selection_ms: f64,
    /// Median filter (0 when off).
    pub median_ms: f64,
}

impl SgmMatcher {
    /// A matcher for `width` x `height` pairs; errors for invalid parameters or sizes.
    pub fn new(params: Sgm, width: usize, height: usize) -> Result<Self> {
        let probe = Plane::<u8>::new(width, height);
        params.check(&probe, &probe)?;
        let n = width
            .checked_mul(height)
            .and_then(|v| v.checked_mul(params.max_disparity))
            .filter(|&v| v <= 1 << 32)
            .ok_or_else(|| {
            GeometryError::Invalid(format!("cost volume {width}x{height}x{} is too large", params.max_disparity))
        })?;
        Ok(Self {
            params,
            size: (width, height),
            census_left: Plane::new(width, height),
            census_right: Plane::new(width, height),
            cost: vec![0; n],
            sum: vec![0; n],
            raw: Plane::new(width, height),
            out: Plane::new(width, height),
            timings: SgmTimings::default(),
        })
    }

    /// Stage times of the last computation.
    pub fn timings(&self) -> SgmTimings {
        self.timings
    }

    /// Disparity of the left image: pixels, NaN where invalid.
    pub fn compute(&mut self, left: &Plane<u8>, right: &Plane<u8>) -> Result<&Plane<f32>> {
        let p = self.params;
        p.check(left, right)?;
        ocellus_image::check::same_size("images (against the matcher's)", left.size(), self.size)?;
        let (w, h) = self.size;
        let d = p.max_disparity;
        let ms = |t: std::time::Instant| t.elapsed().as_secs_f64() * 1e3;
        let t = std::time::Instant::now();
        census_kernel(p.backend, left, p.census_width, p.census_height, &mut self.census_left);
        census_kernel(p.backend, right, p.census_width, p.census_height, &mut self.census_right);
        self.timings.census_ms = ms(t);
        let t = std::time::Instant::now();
        costs_kernel(p.backend, &self.census_left, &self.census_right, &mut self.cost, d);
        self.timings.cost_ms = ms(t);
        let t = std::time::Instant::now();
        let diagonals = p.paths == SgmPaths::Eight;
        pass_kernel(p.backend, &self.cost, &mut self.sum, w, h, d, p.p1, p.p2, diagonals, true);
        pass_kernel(p.backend, &self.cost, &mut self.sum, w, h, d, p.p1, p.p2, diagonals, false);
        self.timings.aggregation_ms = ms(t);
        let t = std::time::Instant::now();
        select_kernel(p.backend, &self.sum, &mut self.raw, &p);
        self.timings.selection_ms = ms(t);
        let t = std::time::Instant::now();
        self.timings.median_ms = 0.0;
        if p.median {
            median3(&self.raw, &mut self.out);
            self.timings.median_ms = ms(t);
            Ok(&self.out)
        } else {
            Ok(&self.raw)
        }
    }
}

/// Disparity of the left image by SGM (allocating; see [`SgmMatcher`] for streams).
///
/// ```
/// use ocellus_geometry::sgm::{sgm, Sgm};
/// use ocellus_image::{rng::SplitMix64, Plane};
/// // A random texture seen 6 px further left by the right camera: disparity 6 everywhere.
/// let mut rng = SplitMix64::new(1);
/// let texture: Vec<u8> = (0..200 * 80).map(|_| (rng.unit() * 255.0) as u8).collect();
/// let left = Plane::from_vec(200, 80, texture)?;
/// let right = Plane::from_fn(200, 80, |x, y| left.get((x + 6).min(199), y));
/// let d = sgm(&left, &right, &Sgm { max_disparity: 16, ..Sgm::default() })?;
/// assert!((d.get(100, 40) - 6.0).abs() < 0.25, "{}", d.get(100, 40));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn sgm(left: &Plane<u8>, right: &Plane<u8>, p: &Sgm) -> Result<Plane<f32>> {
    p.check(left, right)?;
    let mut m = SgmMatcher::new(*p, left.width(), left.height())?;
    Ok(m.compute(left, right)?.clone())
}

/// Winner-take-all with uniqueness, sub-pixel and the left-right check ([`crate::wta`]), row
/// by row.
#[inline(always)]
fn select_generic<M: Madd>(sum: &[u16], out: &mut Plane<f32>, p: &Sgm) {
    let (w, h) = out.size();
    let d = p.max_disparity;
    // Uniqueness needs at least three possible disparities (x >= 2). Equiangular sub-pixel:
    // on a shifted smooth texture its mean error is 0.18 px against 0.23 px for a parabola
    // (test below); both are pulled toward integers by the census cost and P1.
    let rule = WtaRule {
        margin: p.uniqueness,
        lr_max_diff: p.lr_max_diff,
        subpixel: SubPixel::Equiangular,
        x_min: 2,
        x_max: w,
    };
    let mut scratch = WtaScratch::default();
    for y in 0..h {
        select_row::<M>(&sum[y * w * d..(y + 1) * w * d], d, out.row_mut(y), &rule, &mut scratch);
    }
}

dispatch_kernel!(fn select_kernel => select_generic(sum: &[u16], out: &mut Plane<f32>, p: &Sgm));

/// 3x3 median over the valid (finite) values; invalid pixels stay invalid.
fn median3(src: &Plane<f32>, dst: &mut Plane<f32>) {
    let (w, h) = src.size();
    dst.resize(w, h);
    let mut buf = [0f32; 9];
    for y in 0..h {
        let rows = [src.row(y.saturating_sub(1)), src.row(y), src.row((y + 1).min(h - 1))];
        let out = dst.row_mut(y);
        for x in 0..w {
            let v = rows[1][x];
            if !v.is_finite() {
                out[x] = v;
                continue;
            }
            let mut n = 0;
            let (x0, x1) = (x.saturating_sub(1), (x + 1).min(w - 1));
            for (r, row) in rows.iter().enumerate() {
                // Replicated border rows would count twice; skip them.
                if (r == 0 && y == 0) || (r == 2 && y + 1 == h) {
                    continue;
                }
                for &q in &row[x0..=x1] {
                    if q.is_finite() {
                        buf[n] = q;
                        n += 1;
                    }
                }
            }
            // Insertion sort: at most 9 finite values.
            let vals = &mut buf[..n];
            for i in 1..n {
                let mut j = i;
                while j > 0 && vals[j - 1] > vals[j] {
                    vals.swap(j - 1, j);
                    j -= 1;
                }
            }
            out[x] = vals[n / 2];
        }
    }
}

#[cfg(test)]
mod tests;
