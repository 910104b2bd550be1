//! Lucas-Kanade refinement of one window's flow (Lucas & Kanade 1981) on pre-smoothed frames.
//!
//! Why the frames are smoothed first: Lucas-Kanade compares the block of frame n-1 at integer
//! pixels with frame n resampled bilinearly at a fractional offset, and bilinear resampling
//! low-passes the texture by an amount that depends on that fraction (nothing at 0, most at
//! one half). On texture with energy near the pixel scale (fine grain, a floor seen through
//! area-integrating pixels) the mismatch pulls every flow toward whole pixels. The pull is
//! systematic, so a fit over 400 windows does not average it away: on the generated
//! fine-grained and repetitive floors the rotation came out 0.7 % short, a heading error of
//! 0.11-0.13 degrees after 200 frames, and grass drifted 0.058 %. A Gaussian of sigma
//! [`DEFAULT_SMOOTH_SIGMA_PX`] on both frames leaves little energy where bilinear
//! interpolation is wrong. The frames are smoothed in f32, not rounded back to 8 bits: a
//! low-contrast floor has gradients below one grey level per pixel, which rounding would erase.
//!
//! The square the flow is refined over (`support`) may be larger than the block the integer
//! search matched: on a floor with little texture, the flow's noise falls with the number of
//! pixels summed.

use crate::{OdometryError, Result};
use ocellus_image::filter::{gaussian_kernel, sep_filter_u8, Border, FilterScratch};
use ocellus_image::resample::sample_bilinear;
use ocellus_image::simd::Madd;
use ocellus_image::{Backend, Plane};

/// Default sigma of the smoothing before Lucas-Kanade, pixels.
pub const DEFAULT_SMOOTH_SIGMA_PX: f32 = 1.5;

/// A frame in f32 grey levels smoothed by a Gaussian, over the part of it that Lucas-Kanade reads: a
/// rectangle of the frame plus the kernel's half-width, so that inside the rectangle the values
/// are those of the whole frame smoothed (the filter's border rule only acts where the
/// rectangle meets the frame's edge). Why not the whole frame: the windows cover the central
/// 400x400 of a 640x480 frame, and smoothing the rest was 40 % of a robust step. The buffers
/// are kept, so a stream smooths without allocating.
#[derive(Clone, Debug, Default)]
pub struct SmoothedFrame {
    plane: Plane<f32>,
    origin: (usize, usize),
    frame_size: (usize, usize),
    scratch: FilterScratch,
}

impl SmoothedFrame {
    /// Smooths `rect` = `[x0, y0, x1, y1]` (frame pixels, end exclusive) of `frame` by a
    /// Gaussian of `sigma_px` ([`ocellus_image::filter::gaussian_blur`]'s kernel; below 0.3 px:
    /// converted only).
    pub fn update(&mut self, backend: Backend, frame: &Plane<u8>, sigma_px: f32, rect: [usize; 4]) -> Result<()> {
        let (w, h) = frame.size();
        let [x0, y0, x1, y1] = rect;
        if !(x0 < x1 && y0 < y1 && x1 <= w && y1 <= h) {
            return Err(OdometryError::Invalid(format!("smoothing rectangle {rect:?} on a {w}x{h} frame")));
        }
        if !(sigma_px.is_finite() && sigma_px >= 0.0) {
            return Err(OdometryError::Invalid(format!("smoothing sigma {sigma_px} must be finite and >= 0")));
        }
        let kernel = gaussian_kernel(sigma_px);
        let reach = kernel.as_ref().map_or(0, |k| k.len() / 2);
        let (cx0, cy0) = (x0.saturating_sub(reach), y0.saturating_sub(reach));
        let (cx1, cy1) = ((x1 + reach).min(w), (y1 + reach).min(h));
        let crop = [cx0, cy0, cx1, cy1];
        if let Some(k) = kernel {
            sep_filter_u8(backend, frame, crop, &mut self.plane, &k, &k, Border::Clamp, &mut self.scratch)
                .map_err(|e| OdometryError::Invalid(format!("smoothing sigma {sigma_px}: {e}")))?;
        } else {
            self.plane.resize(cx1 - cx0, cy1 - cy0);
            for y in cy0..cy1 {
                let src = &frame.row(y)[cx0..cx1];
                self.plane.row_mut(y - cy0).iter_mut().zip(src).for_each(|(o, &v)| *o = f32::from(v));
            }
        }
        self.origin = (cx0, cy0);
        self.frame_size = (w, h);
        Ok(())
    }

    /// The smoothed pixels; pixel (x, y) here is frame pixel `origin + (x, y)`.
    pub fn plane(&self) -> &Plane<f32> {
        &self.plane
    }

    /// The frame pixel of this plane's pixel (0, 0).
    pub fn origin(&self) -> (usize, usize) {
        self.origin
    }

    /// The size of the frame it was taken from, pixels.
    pub fn frame_size(&self) -> (usize, usize) {
        self.frame_size
    }
}

/// `x.floor()` without the library call that baseline x86-64 (no SSE4.1 `roundsd`) makes for
/// it; exact for |x| < 2^52, which covers every pixel coordinate.
fn floor(x: f64) -> f64 {
    let t = x as i64 as f64;
    if t > x {
        t - 1.0
    } else {
        t
    }
}

/// Lanes of the sums: the pixels are summed in this many independent running sums, which the
/// compiler keeps in one vector register each (a single running sum is a serial chain of adds
/// that it may not reorder, so it stays scalar).
const LANES: usize = 8;

ocellus_image::dispatch_kernel!(
    /// The Lucas-Kanade normal equations of the `b` x `b` square with top-left pixel (bx, by)
    /// (integers) of `prev`: `[sum gx^2, sum gx gy, sum gy^2, sum gx e, sum gy e, sum e^2]`
    /// with the values c, gradients g and differences e = c - prev of `cur` (times `gain`)
    /// warped by (dx, dy); the last four entries are 0 (see [`lk_sums_gain`]). The warp has
    /// one fractional part for the whole square, so `cur` is resampled once into a patch with
    /// a one-pixel border (`patch`, reused between calls) and the gradients are central
    /// differences there.
    pub(crate) fn lk_sums => lk_sums_flow(
        prev: &Plane<f32>,
        cur: &Plane<f32>,
        bx: usize,
        by: usize,
        b: usize,
        dx: f64,
        dy: f64,
        gain: f64,
        patch: &mut Vec<f32>,
    ) -> [f64; 10]
);

ocellus_image::dispatch_kernel!(
    /// [`lk_sums`] with the window's own gain as a third unknown: also `[sum c gx, sum c gy,
    /// sum c^2, sum c e]`.
    pub(crate) fn lk_sums_gain => lk_sums_flow_gain(
        prev: &Plane<f32>,
        cur: &Plane<f32>,
        bx: usize,
        by: usize,
        b: usize,
        dx: f64,
        dy: f64,
        gain: f64,
        patch: &mut Vec<f32>,
    ) -> [f64; 10]
);

#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn lk_sums_flow<M: Madd>(
    prev: &Plane<f32>,
    cur: &Plane<f32>,
    bx: usize,
    by: usize,
    b: usize,
    dx: f64,
    dy: f64,
    gain: f64,
    patch: &mut Vec<f32>,
) -> [f64; 10] {
    lk_sums_generic::<M, false>(prev, cur, bx, by, b, dx, dy, gain, patch)
}

#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn lk_sums_flow_gain<M: Madd>(
    prev: &Plane<f32>,
    cur: &Plane<f32>,
    bx: usize,
    by: usize,
    b: usize,
    dx: f64,
    dy: f64,
    gain: f64,
    patch: &mut Vec<f32>,
) -> [f64; 10] {
    lk_sums_generic::<M, true>(prev, cur, bx, by, b, dx, dy, gain, patch)
}

/// `acc[l] += a[l] b[l]` over the lanes.
#[inline(always)]
fn madd_lanes<M: Madd>(acc: &mut [f32; LANES], a: &[f32; LANES], b: &[f32; LANES]) {
    for l in 0..LANES {
        acc[l] = M::madd(a[l], b[l], acc[l]);
    }
}

/// The sums of [`lk_sums`] at gain `g0 * ratio` from the ten of [`lk_sums_gain`] at gain `g0`,
/// at the same offset. With c the warped current patch, cx and cy its gradients and p the
/// previous one, every sum is a polynomial in the gain g of the gain-free sums: g^2 sum cx^2,
/// g^2 sum cx c - g sum cx p, g^2 sum c^2 - 2 g sum c p + sum p^2, ...; the ten sums at g0
/// determine all of them. The last four entries are 0, as from [`lk_sums`].
pub(crate) fn sums_at_gain(s: &[f64; 10], ratio: f64) -> [f64; 10] {
    let [a11, a12, a22, b1, b2, ee, c1, c2, c3, b3] = *s;
    let r2 = ratio * ratio;
    // g0 sum cx p = c1 - b1; g0 sum c p = c3 - b3; sum p^2 = ee + c3 - 2 b3.
    [
        r2 * a11,
        r2 * a12,
        r2 * a22,
        r2 * c1 - ratio * (c1 - b1),
        r2 * c2 - ratio * (c2 - b2),
        r2 * c3 - 2.0 * ratio * (c3 - b3) + ee + c3 - 2.0 * b3,
        0.0,
        0.0,
        0.0,
        0.0,
    ]
}

#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn lk_sums_generic<M: Madd, const GAIN: bool>(
    prev: &Plane<f32>,
    cur: &Plane<f32>,
    bx: usize,
    by: usize,
    b: usize,
    dx: f64,
    dy: f64,
    gain: f64,
    patch: &mut Vec<f32>,
) -> [f64; 10] {
    let n = b + 2;
    let (sx, sy) = (bx as f64 - 1.0 + dx, by as f64 - 1.0 + dy);
    let (fx, fy) = (floor(sx), floor(sy));
    let (ax, ay) = ((sx - fx) as f32, (sy - fy) as f32);
    let g = gain as f32;
    // Filled by index, not by `extend`: an iterator adapter is a generic function of its own,
    // which would not be compiled with this kernel's target features (and was 14 % of a step).
    patch.resize(n * n, 0.0);
    let inside = fx >= 0.0 && fy >= 0.0 && fx as usize + n < cur.width() && fy as usize + n < cur.height();
    #[cfg(target_arch = "x86_64")]
    // SAFETY: as for `x86::sums_avx2` below; `inside` keeps rows iy..=iy + n, columns
    // ix..=ix + n in the plane.
    let done =
        M::AVX2 && inside && unsafe { x86::patch_avx2(cur, fx as usize, fy as usize, ax, ay, g, &mut patch[..n * n]) };
    #[cfg(not(target_arch = "x86_64"))]
    let done = false;
    if !done {
        fill_patch(cur, (sx, sy), (fx, fy), (ax, ay), g, inside, n, patch);
    }
    let x0 = bx.min(prev.width().saturating_sub(b));
    #[cfg(target_arch = "x86_64")]
    if M::AVX2 && b.is_multiple_of(LANES) && b <= prev.width() && patch.len() >= n * n {
        // SAFETY: `M::AVX2` is true only in kernels compiled for AVX2 and FMA, which
        // `dispatch_kernel!` runs only on CPUs that have both; the sizes were checked above.
        let acc = unsafe { x86::sums_avx2::<GAIN>(prev, &patch[..n * n], x0, by, b) };
        return acc.map(|lanes| lanes.iter().map(|&v| f64::from(v)).sum());
    }
    square_sums::<M, GAIN>(prev, patch, x0, by, b).map(|lanes| lanes.iter().map(|&v| f64::from(v)).sum())
}

/// The warped patch of [`lk_sums_generic`] (side `n`, the gain `g` applied) with its top-left
/// at `(sx, sy)` of `cur` (`(fx, fy)` its floor, `(ax, ay)` the fractions), in plain Rust.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn fill_patch(
    cur: &Plane<f32>,
    (sx, sy): (f64, f64),
    (fx, fy): (f64, f64),
    (ax, ay): (f32, f32),
    g: f32,
    inside: bool,
    n: usize,
    patch: &mut [f32],
) {
    if inside && ax == 0.0 && ay == 0.0 {
        // At a whole-pixel offset (the first step from an integer match: half of all calls)
        // the bilinear weights vanish and the patch is the gained pixels themselves; the same
        // values as below, without the three interpolations per pixel that were half the
        // kernel's work.
        let (ix, iy) = (fx as usize, fy as usize);
        for (j, out) in patch.chunks_exact_mut(n).enumerate() {
            for (o, &v) in out.iter_mut().zip(&cur.row(iy + j)[ix..ix + n]) {
                *o = g * v;
            }
        }
    } else if inside {
        let (ix, iy) = (fx as usize, fy as usize);
        // Along x, then y (the order of `sample_bilinear` below), without scratch rows; the gain
        // applied once here.
        for (j, out) in patch.chunks_exact_mut(n).enumerate() {
            let (r0, r1) = (&cur.row(iy + j)[ix..ix + n + 1], &cur.row(iy + j + 1)[ix..ix + n + 1]);
            // Zipped slices, so the loop has no bounds tests and vectorizes.
            for ((o, (a0, b0)), (a1, b1)) in out.iter_mut().zip(r0.iter().zip(&r0[1..])).zip(r1.iter().zip(&r1[1..])) {
                let t = a0 + ax * (b0 - a0);
                let d = a1 + ax * (b1 - a1);
                *o = g * (t + ay * (d - t));
            }
        }
    } else {
        for (j, out) in patch.chunks_exact_mut(n).enumerate() {
            for (i, o) in out.iter_mut().enumerate() {
                *o = g * sample_bilinear(cur, (sx + i as f64) as f32, (sy + j as f64) as f32);
            }
        }
    }
}

/// The lanes of the ten sums of [`lk_sums_generic`] over the `b` x `b` square at (x0, by) of
/// `prev` against the warped `patch` ((b + 2)^2 values, a one-pixel border).
#[inline(always)]
fn square_sums<M: Madd, const GAIN: bool>(
    prev: &Plane<f32>,
    patch: &[f32],
    x0: usize,
    by: usize,
    b: usize,
) -> [[f32; LANES]; 10] {
    let n = b + 2;
    // acc[k][l]: lane l of sum k; summed over the lanes at the end.
    let mut acc = [[0.0f32; LANES]; 10];
    let full = b / LANES * LANES;
    let lanes = |v: &[f32], at: usize| -> Option<[f32; LANES]> { v.get(at..at + LANES)?.try_into().ok() };
    for j in 1..=b {
        let prow = prev.row((by + j - 1).min(prev.height() - 1));
        let Some(prow) = prow.get(x0..x0 + b) else { continue };
        let (up, mid, down) =
            (&patch[(j - 1) * n..j * n], &patch[j * n..(j + 1) * n], &patch[(j + 1) * n..(j + 2) * n]);
        for c in (0..full).step_by(LANES) {
            // Fixed-size arrays, so the lane loops are plain vector operations.
            let (Some(left), Some(centre), Some(right), Some(u), Some(d), Some(p)) = (
                lanes(mid, c),
                lanes(mid, c + 1),
                lanes(mid, c + 2),
                lanes(up, c + 1),
                lanes(down, c + 1),
                lanes(prow, c),
            ) else {
                break;
            };
            let gx: [f32; LANES] = std::array::from_fn(|l| 0.5 * (right[l] - left[l]));
            let gy: [f32; LANES] = std::array::from_fn(|l| 0.5 * (d[l] - u[l]));
            let e: [f32; LANES] = std::array::from_fn(|l| centre[l] - p[l]);
            // Written out, not as a loop over pairs: the compiler did not unroll a loop over
            // ten pairs, and the robust step took 2.4x as long.
            madd_lanes::<M>(&mut acc[0], &gx, &gx);
            madd_lanes::<M>(&mut acc[1], &gx, &gy);
            madd_lanes::<M>(&mut acc[2], &gy, &gy);
            madd_lanes::<M>(&mut acc[3], &gx, &e);
            madd_lanes::<M>(&mut acc[4], &gy, &e);
            madd_lanes::<M>(&mut acc[5], &e, &e);
            if GAIN {
                madd_lanes::<M>(&mut acc[6], &centre, &gx);
                madd_lanes::<M>(&mut acc[7], &centre, &gy);
                madd_lanes::<M>(&mut acc[8], &centre, &centre);
                madd_lanes::<M>(&mut acc[9], &centre, &e);
            }
        }
        for i in full + 1..=b {
            let c = mid[i];
            let (gx, gy, e) = (0.5 * (mid[i + 1] - mid[i - 1]), 0.5 * (down[i] - up[i]), c - prow[i - 1]);
            let g = if GAIN { [c * gx, c * gy, c * c, c * e] } else { [0.0; 4] };
            for (k, v) in
                [gx * gx, gx * gy, gy * gy, gx * e, gy * e, e * e, g[0], g[1], g[2], g[3]].into_iter().enumerate()
            {
                acc[k][0] += v;
            }
        }
    }
    acc
}

/// [`fill_patch`] and [`square_sums`] by hand in AVX2. Why by hand: the generic sums loop
/// keeps its ten sums in `[f32; 8]` arrays, which the AVX-512 build packs in pairs into
/// 512-bit registers with a shuffle for every multiply-add, plus a bounds test per load, and
/// the patch rows of 18 ended in a scalar tail of two. Here each sum is one 256-bit register
/// and every value the same operations, in the same order, as the generic code with `Fused`,
/// so the results are bit-identical (tested below). The sums took a robust step (`ocellus
/// bench odometry`) from 0.59-0.61 to 0.54-0.56 ms, the patch later from 0.53 to 0.49-0.50.
#[cfg(target_arch = "x86_64")]
mod x86 {
    use super::LANES;
    use ocellus_image::Plane;
    use std::arch::x86_64::*;

    /// The warped patch of [`super::lk_sums_generic`] (side n = `patch.len()`'s root, 8 to 32)
    /// from the pixels ix..=ix + n, rows iy..=iy + n of `cur` (all inside), the same values:
    /// each source row is interpolated along x once (not once for each of the two patch rows
    /// it enters), and the last vector of a row overlaps the one before instead of a scalar
    /// tail. False (nothing written) for another side.
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn patch_avx2(
        cur: &Plane<f32>,
        ix: usize,
        iy: usize,
        ax: f32,
        ay: f32,
        g: f32,
        patch: &mut [f32],
    ) -> bool {
        let n = (patch.len() as f64).sqrt() as usize;
        if !(8..=32).contains(&n) || n * n != patch.len() || ix + n >= cur.width() || iy + n >= cur.height() {
            return false;
        }
        let vecs = n.div_ceil(8);
        let at = |v: usize| (8 * v).min(n - 8);
        let (vax, vay, vg) = (_mm256_set1_ps(ax), _mm256_set1_ps(ay), _mm256_set1_ps(g));
        let out = patch.as_mut_ptr();
        // SAFETY (all loads and stores): at(v) + 8 <= n, so a row's loads read columns
        // ix..=ix + n of rows iy..=iy + n (checked above), and the stores patch[j n, j n + n).
        unsafe {
            if ax == 0.0 && ay == 0.0 {
                for j in 0..n {
                    let r = cur.row(iy + j).as_ptr().add(ix);
                    for v in 0..vecs {
                        _mm256_storeu_ps(out.add(j * n + at(v)), _mm256_mul_ps(vg, _mm256_loadu_ps(r.add(at(v)))));
                    }
                }
                return true;
            }
            // Row r interpolated along x: a0 + ax (b0 - a0), as the generic kernel.
            let along_x = |r: usize, v: usize| {
                let p = cur.row(iy + r).as_ptr().add(ix + at(v));
                let (a, b) = (_mm256_loadu_ps(p), _mm256_loadu_ps(p.add(1)));
                _mm256_add_ps(a, _mm256_mul_ps(vax, _mm256_sub_ps(b, a)))
            };
            let mut upper = [_mm256_setzero_ps(); 4];
            for (v, u) in upper.iter_mut().enumerate().take(vecs) {
                *u = along_x(0, v);
            }
            for j in 0..n {
                for (v, u) in upper.iter_mut().enumerate().take(vecs) {
                    let (t, d) = (*u, along_x(j + 1, v));
                    let o = _mm256_mul_ps(vg, _mm256_add_ps(t, _mm256_mul_ps(vay, _mm256_sub_ps(d, t))));
                    _mm256_storeu_ps(out.add(j * n + at(v)), o);
                    *u = d;
                }
            }
        }
        true
    }

    /// The lanes of the ten sums over the `b` x `b` square at (x0, by) of `prev` against the
    /// warped `patch` ((b + 2)^2 values, a one-pixel border); `b` a multiple of 8, at most
    /// `prev`'s width, and x0 + b within it.
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn sums_avx2<const GAIN: bool>(
        prev: &Plane<f32>,
        patch: &[f32],
        x0: usize,
        by: usize,
        b: usize,
    ) -> [[f32; LANES]; 10] {
        let n = b + 2;
        let mut acc = [_mm256_setzero_ps(); 10];
        let half = _mm256_set1_ps(0.5);
        for j in 1..=b {
            let prow = &prev.row((by + j - 1).min(prev.height() - 1))[x0..x0 + b];
            let (up, mid, down) = (&patch[(j - 1) * n..j * n], &patch[j * n..(j + 1) * n], &patch[(j + 1) * n..]);
            // SAFETY: c + 8 <= b, so the loads read prow[c, c + 8) of b values, mid and up
            // [c, c + 10) of n = b + 2, and down [c + 1, c + 9) of at least n.
            unsafe {
                for c in (0..b).step_by(LANES) {
                    let m = mid.as_ptr().add(c);
                    let (left, centre, right) =
                        (_mm256_loadu_ps(m), _mm256_loadu_ps(m.add(1)), _mm256_loadu_ps(m.add(2)));
                    let (u, d) = (_mm256_loadu_ps(up.as_ptr().add(c + 1)), _mm256_loadu_ps(down.as_ptr().add(c + 1)));
                    let p = _mm256_loadu_ps(prow.as_ptr().add(c));
                    let gx = _mm256_mul_ps(half, _mm256_sub_ps(right, left));
                    let gy = _mm256_mul_ps(half, _mm256_sub_ps(d, u));
                    let e = _mm256_sub_ps(centre, p);
                    acc[0] = _mm256_fmadd_ps(gx, gx, acc[0]);
                    acc[1] = _mm256_fmadd_ps(gx, gy, acc[1]);
                    acc[2] = _mm256_fmadd_ps(gy, gy, acc[2]);
                    acc[3] = _mm256_fmadd_ps(gx, e, acc[3]);
                    acc[4] = _mm256_fmadd_ps(gy, e, acc[4]);
                    acc[5] = _mm256_fmadd_ps(e, e, acc[5]);
                    if GAIN {
                        acc[6] = _mm256_fmadd_ps(centre, gx, acc[6]);
                        acc[7] = _mm256_fmadd_ps(centre, gy, acc[7]);
                        acc[8] = _mm256_fmadd_ps(centre, centre, acc[8]);
                        acc[9] = _mm256_fmadd_ps(centre, e, acc[9]);
                    }
                }
            }
        }
        let mut out = [[0f32; LANES]; 10];
        for (o, a) in out.iter_mut().zip(&acc) {
            // SAFETY: `o` holds 8 floats.
            unsafe { _mm256_storeu_ps(o.as_mut_ptr(), *a) };
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The hand-written sums equal the generic loop's with fused multiply-adds bit for bit,
    /// with and without the gain's sums, on a square at the plane's right edge too.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx2_sums_equal_the_generic_loop_bit_for_bit() {
        if !(is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")) {
            return;
        }
        let prev = Plane::from_fn(40, 30, |x, y| ((x * 37 + y * 91) % 113) as f32 * 0.7 + 3.0);
        for (b, x0, by) in [(8, 3, 2), (16, 10, 5), (16, 24, 13), (24, 16, 0)] {
            let n = b + 2;
            let patch: Vec<f32> = (0..n * n).map(|i| ((i * 53) % 97) as f32 * 0.9 + 1.5).collect();
            let want = square_sums::<ocellus_image::simd::Fused, true>(&prev, &patch, x0, by, b);
            // SAFETY: AVX2 and FMA were checked above; b is a multiple of 8 within the width.
            let got = unsafe { x86::sums_avx2::<true>(&prev, &patch, x0, by, b) };
            assert_eq!(want.map(|l| l.map(f32::to_bits)), got.map(|l| l.map(f32::to_bits)), "b {b} at ({x0}, {by})");
            let want = square_sums::<ocellus_image::simd::Fused, false>(&prev, &patch, x0, by, b);
            // SAFETY: as above.
            let got = unsafe { x86::sums_avx2::<false>(&prev, &patch, x0, by, b) };
            assert_eq!(want.map(|l| l.map(f32::to_bits)), got.map(|l| l.map(f32::to_bits)), "b {b} at ({x0}, {by})");
        }
    }

    /// The hand-written patch equals the plain one bit for bit, at whole-pixel and fractional
    /// offsets and every side it takes; other sides are left to the plain code.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx2_patch_equals_the_plain_one_bit_for_bit() {
        if !(is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")) {
            return;
        }
        let cur = Plane::from_fn(50, 45, |x, y| ((x * 29 + y * 71) % 89) as f32 * 1.3 + 0.25);
        for n in [6usize, 8, 10, 13, 18, 26, 32, 34] {
            for (ax, ay) in [(0.0f32, 0.0f32), (0.375, 0.0), (0.0, 0.8), (0.62, 0.11)] {
                let (fx, fy) = (3.0, 5.0);
                let mut want = vec![0f32; n * n];
                fill_patch(
                    &cur,
                    (fx + f64::from(ax), fy + f64::from(ay)),
                    (fx, fy),
                    (ax, ay),
                    1.07,
                    true,
                    n,
                    &mut want,
                );
                let mut got = vec![f32::NAN; n * n];
                // SAFETY: AVX2 and FMA were checked above.
                if unsafe { x86::patch_avx2(&cur, 3, 5, ax, ay, 1.07, &mut got) } {
                    assert!((8..=32).contains(&n));
                    assert_eq!(
                        want.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                        got.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                        "side {n}, fractions ({ax}, {ay})"
                    );
                } else {
                    assert!(!(8..=32).contains(&n), "side {n} refused");
                }
            }
        }
    }

    #[test]
    fn the_sums_are_the_definition() {
        // A smooth pattern; the sums at a fractional warp against a direct evaluation with
        // the clamped bilinear sampler.
        let img = Plane::from_fn(64, 48, |x, y| 100.0 + 30.0 * ((x as f32) * 0.3).sin() * ((y as f32) * 0.2).cos());
        let cur = Plane::from_fn(64, 48, |x, y| {
            100.0 + 30.0 * ((x as f32 - 0.4) * 0.3).sin() * ((y as f32 + 0.3) * 0.2).cos()
        });
        let mut patch = Vec::new();
        // Every build of the kernel; supports with and without a part narrower than the lanes.
        // Whole-pixel offsets take a path of their own.
        let cases = [
            (20, 15, 8, 0.4, -0.3),
            (10, 10, 16, 0.25, 0.0),
            (0, 0, 8, -1.5, 0.7),
            (30, 20, 12, 0.6, 0.45),
            (12, 9, 16, 1.0, -2.0),
            (5, 5, 8, 0.0, 0.0),
        ];
        for (backend, (bx, by, b, dx, dy)) in Backend::available().into_iter().flat_map(|k| cases.map(|c| (k, c))) {
            let got = lk_sums_gain(backend, &img, &cur, bx, by, b, dx, dy, 1.1, &mut patch);
            let flow_only = lk_sums(backend, &img, &cur, bx, by, b, dx, dy, 1.1, &mut patch);
            assert_eq!(flow_only[..6], got[..6]);
            assert_eq!(flow_only[6..], [0.0; 4]);
            let mut want = [0.0f64; 10];
            for j in 0..b {
                for i in 0..b {
                    let (x, y) = ((bx + i) as f64 + dx, (by + j) as f64 + dy);
                    let c = |x: f64, y: f64| 1.1 * sample_bilinear(&cur, x as f32, y as f32) as f64;
                    let gx = 0.5 * (c(x + 1.0, y) - c(x - 1.0, y));
                    let gy = 0.5 * (c(x, y + 1.0) - c(x, y - 1.0));
                    let v = c(x, y);
                    let e = v - img.get(bx + i, by + j) as f64;
                    for (k, v) in [gx * gx, gx * gy, gy * gy, gx * e, gy * e, e * e, v * gx, v * gy, v * v, v * e]
                        .into_iter()
                        .enumerate()
                    {
                        want[k] += v;
                    }
                }
            }
            for k in 0..10 {
                assert!(
                    (got[k] - want[k]).abs() <= 1e-3 * want[k].abs().max(1.0),
                    "{backend:?} {bx} {by} {b}: {got:?} vs {want:?}"
                );
            }
        }
    }

    #[test]
    fn the_sums_at_one_gain_give_those_at_another() {
        let img = Plane::from_fn(64, 48, |x, y| 100.0 + 30.0 * ((x as f32) * 0.3).sin() * ((y as f32) * 0.2).cos());
        let cur = Plane::from_fn(64, 48, |x, y| {
            97.0 + 33.0 * ((x as f32 - 0.4) * 0.3).sin() * ((y as f32 + 0.3) * 0.2).cos()
        });
        let mut patch = Vec::new();
        for (bx, by, dx, dy) in [(20, 15, 1.0, -1.0), (10, 12, 0.4, 0.25)] {
            let at = lk_sums_gain(Backend::Auto, &img, &cur, bx, by, 16, dx, dy, 1.1, &mut patch);
            for ratio in [0.9, 1.0, 1.07] {
                let want = lk_sums(Backend::Auto, &img, &cur, bx, by, 16, dx, dy, 1.1 * ratio, &mut patch);
                let got = sums_at_gain(&at, ratio);
                for k in 0..6 {
                    // Relative to the largest term the sum is made of (f32 sums of ~1e6).
                    let scale = want[k].abs().max(1e-3 * at[8].abs());
                    assert!((got[k] - want[k]).abs() <= 1e-4 * scale, "{k} {ratio}: {got:?} vs {want:?}");
                }
                assert_eq!(got[6..], [0.0; 4]);
            }
        }
    }

    #[test]
    fn a_smoothed_rectangle_is_the_whole_frame_smoothed_there() {
        let f = Plane::from_fn(90, 70, |x, y| ((x * 37 + y * 101 + x * y) % 251) as u8);
        let whole = ocellus_image::filter::gaussian_blur(Backend::Auto, &f.map(f32::from), 1.5).unwrap();
        let mut part = SmoothedFrame::default();
        // Inside the frame, and against its edges (where both clamp).
        for rect in [[20, 15, 60, 50], [0, 0, 30, 25], [70, 40, 90, 70]] {
            part.update(Backend::Auto, &f, 1.5, rect).unwrap();
            let (ox, oy) = part.origin();
            assert_eq!(part.frame_size(), (90, 70));
            for y in rect[1]..rect[3] {
                for x in rect[0]..rect[2] {
                    let (a, b) = (part.plane().get(x - ox, y - oy), whole.get(x, y));
                    assert!((a - b).abs() <= 1e-4, "{rect:?} ({x}, {y}): {a} vs {b}");
                }
            }
        }
        part.update(Backend::Auto, &f, 0.0, [5, 5, 10, 10]).unwrap();
        assert_eq!((part.origin(), part.plane().get(0, 0)), ((5, 5), f32::from(f.get(5, 5))));
        for rect in [[10, 10, 10, 20], [0, 0, 91, 10], [20, 5, 10, 30]] {
            assert!(part.update(Backend::Auto, &f, 1.5, rect).is_err(), "{rect:?}");
        }
        assert!(part.update(Backend::Auto, &f, f32::NAN, [0, 0, 10, 10]).is_err());
    }

    #[test]
    fn smoothing_keeps_the_mean_and_zero_is_a_copy() {
        let f = Plane::from_fn(40, 30, |x, y| ((x * 7 + y * 13) % 256) as u8);
        let smooth = |sigma: f32| {
            let mut s = SmoothedFrame::default();
            s.update(Backend::Auto, &f, sigma, [0, 0, 40, 30]).map(|_| s.plane().clone())
        };
        let s0 = smooth(0.0).unwrap();
        assert_eq!(s0.get(5, 7), f.get(5, 7) as f32);
        let s = smooth(1.0).unwrap();
        let mean = |p: &Plane<f32>| p.rows().flatten().sum::<f32>() / (40.0 * 30.0);
        assert!((mean(&s) - mean(&s0)).abs() < 1.0);
        assert!(smooth(f32::NAN).is_err());
    }
}
