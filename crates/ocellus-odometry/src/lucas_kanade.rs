//! Lucas-Kanade refinement of one window's flow (Lucas & Kanade 1981) on frames smoothed and
//! made into cubic B-splines ([`crate::spline`]): frame n-1 is read at its pixels, frame n
//! through its spline at the window's fractional offset (why the spline: see that module).
//!
//! The square the flow is refined over (`support`) may be larger than the block the integer
//! search matched: on a floor with little texture, the flow's noise falls with the number of
//! pixels summed.

use crate::spline::{floor, sample_spline, spline_weights};
use ocellus_image::resample::sample_bilinear;
use ocellus_image::simd::Madd;
use ocellus_image::Plane;

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
        coeffs: &Plane<f32>,
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
        coeffs: &Plane<f32>,
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
    coeffs: &Plane<f32>,
    bx: usize,
    by: usize,
    b: usize,
    dx: f64,
    dy: f64,
    gain: f64,
    patch: &mut Vec<f32>,
) -> [f64; 10] {
    lk_sums_generic::<M, false>(prev, cur, coeffs, bx, by, b, dx, dy, gain, patch)
}

#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn lk_sums_flow_gain<M: Madd>(
    prev: &Plane<f32>,
    cur: &Plane<f32>,
    coeffs: &Plane<f32>,
    bx: usize,
    by: usize,
    b: usize,
    dx: f64,
    dy: f64,
    gain: f64,
    patch: &mut Vec<f32>,
) -> [f64; 10] {
    lk_sums_generic::<M, true>(prev, cur, coeffs, bx, by, b, dx, dy, gain, patch)
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
    coeffs: &Plane<f32>,
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
    let whole = ax == 0.0 && ay == 0.0;
    // The patch, then (fractional offsets) its n + 3 rows along x of the spline; one length
    // for both, so that the buffer is not shrunk and zero-filled again from call to call.
    patch.resize(n * n + (n + 3) * n, 0.0);
    let inside = fx >= 0.0 && fy >= 0.0 && fx as usize + n < cur.width() && fy as usize + n < cur.height();
    #[cfg(target_arch = "x86_64")]
    // SAFETY: as for `x86::sums_avx2` below; `inside` keeps rows iy..=iy + n, columns
    // ix..=ix + n in the plane, and the spline patch checks the part it reads itself.
    let done = M::AVX2
        && if whole {
            inside && unsafe { x86::patch_avx2(cur, fx as usize, fy as usize, g, &mut patch[..n * n]) }
        } else {
            fx >= 1.0
                && fy >= 1.0
                && unsafe { x86::patch_spline_avx2(coeffs, fx as usize - 1, fy as usize - 1, ax, ay, g, n, patch) }
        };
    #[cfg(not(target_arch = "x86_64"))]
    let done = false;
    if !done {
        fill_patch::<M>(cur, coeffs, (sx, sy), (fx, fy), (ax, ay), g, n, patch);
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
/// at `(sx, sy)` (`(fx, fy)` its floor, `(ax, ay)` the fractions): at a whole-pixel offset the
/// pixels of `cur`, otherwise the cubic B-spline with coefficients `coeffs` (see
/// [`SmoothedFrame`]), in plain Rust. `patch` holds the patch and, at a fractional offset,
/// (n + 3) n values after it for the spline's rows.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn fill_patch<M: Madd>(
    cur: &Plane<f32>,
    coeffs: &Plane<f32>,
    (sx, sy): (f64, f64),
    (fx, fy): (f64, f64),
    (ax, ay): (f32, f32),
    g: f32,
    n: usize,
    patch: &mut [f32],
) {
    let whole = ax == 0.0 && ay == 0.0;
    let inside = |p: &Plane<f32>, lo: f64, hi: usize| {
        fx >= lo && fy >= lo && fx as usize + n + hi <= p.width() && fy as usize + n + hi <= p.height()
    };
    if whole && inside(cur, 0.0, 1) {
        // At a whole-pixel offset (the first step from an integer match: half of all calls)
        // the spline's values are the smoothed pixels themselves.
        let (ix, iy) = (fx as usize, fy as usize);
        for (j, out) in patch[..n * n].chunks_exact_mut(n).enumerate() {
            for (o, &v) in out.iter_mut().zip(&cur.row(iy + j)[ix..ix + n]) {
                *o = g * v;
            }
        }
    } else if !whole && inside(coeffs, 1.0, 2) {
        let (ix, iy) = (fx as usize - 1, fy as usize - 1);
        let (wx, wy) = (spline_weights(ax), spline_weights(ay));
        let (out, rows) = patch.split_at_mut(n * n);
        // Along x over the n + 3 rows the patch reads, then along y with the gain; each tap
        // is one pass of zipped slices (no bounds tests, so every pass is vector code).
        for (j, r) in rows[..(n + 3) * n].chunks_exact_mut(n).enumerate() {
            let src = &coeffs.row(iy + j)[ix..ix + n + 3];
            r.iter_mut().zip(src).for_each(|(o, &v)| *o = wx[0] * v);
            for (k, &w) in wx.iter().enumerate().skip(1) {
                r.iter_mut().zip(&src[k..]).for_each(|(o, &v)| *o = M::madd(w, v, *o));
            }
        }
        for (j, o) in out.chunks_exact_mut(n).enumerate() {
            let r = |k: usize| &rows[(j + k) * n..(j + k + 1) * n];
            o.iter_mut().zip(r(0)).for_each(|(o, &v)| *o = wy[0] * v);
            for (k, &w) in wy.iter().enumerate().skip(1) {
                o.iter_mut().zip(r(k)).for_each(|(o, &v)| *o = M::madd(w, v, *o));
            }
            o.iter_mut().for_each(|v| *v *= g);
        }
    } else {
        for (j, out) in patch[..n * n].chunks_exact_mut(n).enumerate() {
            for (i, o) in out.iter_mut().enumerate() {
                let (x, y) = (sx + i as f64, sy + j as f64);
                *o = g * if whole { sample_bilinear(cur, x as f32, y as f32) } else { sample_spline(coeffs, x, y) };
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

    /// The whole-pixel patch of [`super::fill_patch`] (side n = `patch.len()`'s root, 8 to 32):
    /// the pixels ix..ix + n, rows iy..iy + n of `cur` (all inside, with one more column and
    /// row) times `g`, the last vector of a row overlapping the one before instead of a
    /// scalar tail. False (nothing written) for another side.
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn patch_avx2(cur: &Plane<f32>, ix: usize, iy: usize, g: f32, patch: &mut [f32]) -> bool {
        let n = (patch.len() as f64).sqrt() as usize;
        if !(8..=32).contains(&n) || n * n != patch.len() || ix + n >= cur.width() || iy + n >= cur.height() {
            return false;
        }
        let vecs = n.div_ceil(8);
        let at = |v: usize| (8 * v).min(n - 8);
        let vg = _mm256_set1_ps(g);
        let out = patch.as_mut_ptr();
        // SAFETY: at(v) + 8 <= n, so a row's loads read columns ix..ix + n of rows
        // iy..iy + n (checked above), and the stores patch[j n, j n + n).
        unsafe {
            for j in 0..n {
                let r = cur.row(iy + j).as_ptr().add(ix);
                for v in 0..vecs {
                    _mm256_storeu_ps(out.add(j * n + at(v)), _mm256_mul_ps(vg, _mm256_loadu_ps(r.add(at(v)))));
                }
            }
        }
        true
    }

    /// The fractional-offset patch of [`super::fill_patch`] (side `n`, 8 to 32; `patch` holds
    /// n^2 + (n + 3) n values) from the cubic B-spline coefficients `coeffs`, columns
    /// ix..ix + n + 3 and rows iy..iy + n + 3 (false, nothing written, when they are not all
    /// inside or another side is asked for): the same operations in the same order as the
    /// plain code with `Fused`, so the same values, with the last vector of a row overlapping
    /// the one before instead of a scalar tail.
    #[allow(clippy::too_many_arguments)]
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn patch_spline_avx2(
        coeffs: &Plane<f32>,
        ix: usize,
        iy: usize,
        ax: f32,
        ay: f32,
        g: f32,
        n: usize,
        patch: &mut [f32],
    ) -> bool {
        if !(8..=32).contains(&n)
            || patch.len() < n * n + (n + 3) * n
            || ix + n + 3 > coeffs.width()
            || iy + n + 3 > coeffs.height()
        {
            return false;
        }
        let (wx, wy) = (super::spline_weights(ax), super::spline_weights(ay));
        let vecs = n.div_ceil(8);
        let at = |v: usize| (8 * v).min(n - 8);
        let (out, rows) = patch.split_at_mut(n * n);
        let (out, rows) = (out.as_mut_ptr(), rows.as_mut_ptr());
        let wxv = wx.map(|w| _mm256_set1_ps(w));
        let wyv = wy.map(|w| _mm256_set1_ps(w));
        let vg = _mm256_set1_ps(g);
        // SAFETY (all loads and stores): at(v) + 8 <= n, so a source row's loads read columns
        // ix + at(v) .. ix + at(v) + 11 <= ix + n + 3 of rows iy..iy + n + 3 (checked above),
        // the row stores rows[r n + at(v) ..][..8] with r < n + 3, and the patch stores
        // out[j n + at(v) ..][..8] with j < n.
        unsafe {
            for r in 0..n + 3 {
                let src = coeffs.row(iy + r).as_ptr().add(ix);
                for v in 0..vecs {
                    let p = src.add(at(v));
                    let mut acc = _mm256_mul_ps(wxv[0], _mm256_loadu_ps(p));
                    acc = _mm256_fmadd_ps(wxv[1], _mm256_loadu_ps(p.add(1)), acc);
                    acc = _mm256_fmadd_ps(wxv[2], _mm256_loadu_ps(p.add(2)), acc);
                    acc = _mm256_fmadd_ps(wxv[3], _mm256_loadu_ps(p.add(3)), acc);
                    _mm256_storeu_ps(rows.add(r * n + at(v)), acc);
                }
            }
            for j in 0..n {
                for v in 0..vecs {
                    let p = rows.add(j * n + at(v));
                    let mut acc = _mm256_mul_ps(wyv[0], _mm256_loadu_ps(p));
                    acc = _mm256_fmadd_ps(wyv[1], _mm256_loadu_ps(p.add(n)), acc);
                    acc = _mm256_fmadd_ps(wyv[2], _mm256_loadu_ps(p.add(2 * n)), acc);
                    acc = _mm256_fmadd_ps(wyv[3], _mm256_loadu_ps(p.add(3 * n)), acc);
                    _mm256_storeu_ps(out.add(j * n + at(v)), _mm256_mul_ps(acc, vg));
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
    use crate::spline::tests::spline_direct;
    use ocellus_image::Backend;

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

    /// The hand-written patches equal the plain ones bit for bit, at whole-pixel and fractional
    /// offsets and every side they take; other sides are left to the plain code.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx2_patches_equal_the_plain_ones_bit_for_bit() {
        if !(is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")) {
            return;
        }
        let cur = Plane::from_fn(50, 45, |x, y| ((x * 29 + y * 71) % 89) as f32 * 1.3 + 0.25);
        let coeffs = Plane::from_fn(50, 45, |x, y| ((x * 31 + y * 67) % 83) as f32 * 1.1 - 7.5);
        let bits = |v: &[f32]| v.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        for n in [6usize, 8, 10, 13, 18, 26, 32, 34] {
            for (ax, ay) in [(0.0f32, 0.0f32), (0.375, 0.0), (0.0, 0.8), (0.62, 0.11)] {
                let (fx, fy) = (3.0, 5.0);
                let mut want = vec![0f32; n * n + (n + 3) * n];
                fill_patch::<ocellus_image::simd::Fused>(
                    &cur,
                    &coeffs,
                    (fx + f64::from(ax), fy + f64::from(ay)),
                    (fx, fy),
                    (ax, ay),
                    1.07,
                    n,
                    &mut want,
                );
                let mut got = vec![f32::NAN; n * n + (n + 3) * n];
                // SAFETY: AVX2 and FMA were checked above.
                let done = unsafe {
                    if ax == 0.0 && ay == 0.0 {
                        x86::patch_avx2(&cur, 3, 5, 1.07, &mut got[..n * n])
                    } else {
                        x86::patch_spline_avx2(&coeffs, 2, 4, ax, ay, 1.07, n, &mut got)
                    }
                };
                if done {
                    assert!((8..=32).contains(&n));
                    assert_eq!(bits(&want[..n * n]), bits(&got[..n * n]), "side {n}, fractions ({ax}, {ay})");
                } else {
                    assert!(!(8..=32).contains(&n), "side {n} refused");
                }
            }
        }
        // A spline patch that would read past the plane is refused.
        let mut got = vec![0f32; 18 * 18 + 21 * 18];
        // SAFETY: as above.
        assert!(!unsafe { x86::patch_spline_avx2(&coeffs, 30, 4, 0.5, 0.5, 1.0, 18, &mut got) });
    }

    #[test]
    fn the_sums_are_the_definition() {
        // A smooth pattern; the sums at a fractional warp against a direct evaluation of the
        // spline (whole-pixel warps: of the pixels, which are the spline at the pixels).
        let img = Plane::from_fn(64, 48, |x, y| 100.0 + 30.0 * ((x as f32) * 0.3).sin() * ((y as f32) * 0.2).cos());
        let coeffs = Plane::from_fn(64, 48, |x, y| {
            100.0 + 33.0 * ((x as f32 - 0.4) * 0.3).sin() * ((y as f32 + 0.3) * 0.2).cos()
        });
        let cur = Plane::from_fn(64, 48, |x, y| spline_direct(&coeffs, x as f64, y as f64) as f32);
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
            (40, 28, 16, 1.3, 2.9),
        ];
        for (backend, (bx, by, b, dx, dy)) in Backend::available().into_iter().flat_map(|k| cases.map(|c| (k, c))) {
            let got = lk_sums_gain(backend, &img, &cur, &coeffs, bx, by, b, dx, dy, 1.1, &mut patch);
            let flow_only = lk_sums(backend, &img, &cur, &coeffs, bx, by, b, dx, dy, 1.1, &mut patch);
            assert_eq!(flow_only[..6], got[..6]);
            assert_eq!(flow_only[6..], [0.0; 4]);
            let mut want = [0.0f64; 10];
            let whole = dx == dx.floor() && dy == dy.floor();
            for j in 0..b {
                for i in 0..b {
                    let (x, y) = ((bx + i) as f64 + dx, (by + j) as f64 + dy);
                    let c = |x: f64, y: f64| {
                        1.1 * if whole {
                            f64::from(cur.get(x as usize, y as usize))
                        } else {
                            spline_direct(&coeffs, x, y)
                        }
                    };
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
            let at = lk_sums_gain(Backend::Auto, &img, &cur, &cur, bx, by, 16, dx, dy, 1.1, &mut patch);
            for ratio in [0.9, 1.0, 1.07] {
                let want = lk_sums(Backend::Auto, &img, &cur, &cur, bx, by, 16, dx, dy, 1.1 * ratio, &mut patch);
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
}
