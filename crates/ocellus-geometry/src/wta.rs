//! Winner-take-all disparity selection, shared by [`crate::block_matching`] and
//! [`crate::sgm`]: one row of costs in, one row of disparities out.
//!
//! Costs are u16, laid out `[x][d]` (the disparities of a pixel contiguous). A pixel gets the
//! disparity of least cost (the first on ties), refined to sub-pixel, unless:
//! - it lies outside `x_min..x_max`, or its disparity would put the match left of the right
//!   image (`d > x`);
//! - uniqueness fails: some disparity not adjacent to the best has `cost (1 - margin) <= best`;
//! - the left-right check fails: the right pixel `x - d` is claimed by a cheaper left pixel
//!   with a disparity more than `lr_max_diff` away. The right image's winners are taken from
//!   the left pixels' winners (one update per left pixel, as OpenCV's matchers do), not from a
//!   second search over the cost volume.
//!
//! Invalid pixels are NaN. The loops over disparities are written so that they vectorize
//! when inlined into an AVX2 kernel; for 64 disparities an explicit AVX2 version finds the
//! winner (tests compare both).

use ocellus_image::simd::Madd;

/// How the integer winner is refined.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum SubPixel {
    /// Vertex of the parabola through the costs at d - 1, d, d + 1.
    Parabola,
    /// Equiangular (V-shaped) fit through the same three costs.
    Equiangular,
}

/// The rules of [`select_row`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct WtaRule {
    /// Uniqueness margin (see the module doc).
    pub margin: f32,
    /// Largest left-right disagreement kept, pixels (negative: no check).
    pub lr_max_diff: f32,
    /// Sub-pixel refinement.
    pub subpixel: SubPixel,
    /// First pixel that may get a disparity.
    pub x_min: usize,
    /// One past the last.
    pub x_max: usize,
}

/// Reusable per-row buffers of [`select_row`].
#[derive(Clone, Debug, Default)]
pub(crate) struct WtaScratch {
    keep: u64,
    best_of: Vec<usize>,
    right_best: Vec<usize>,
    right_cost: Vec<u16>,
}

/// The least cost, its first index, and the least cost not adjacent to it.
#[inline(always)]
fn best_and_other(c: &[u16]) -> (u16, usize, u16) {
    // Cost and index packed in one word: the minimum gives both (first index on ties).
    let mut packed = u32::MAX;
    for (k, &v) in (0u32..).zip(c) {
        packed = packed.min((v as u32) << 8 | k);
    }
    let (bc, best) = ((packed >> 8) as u16, (packed & 0xff) as usize);
    // A masked full-length loop, which vectorizes, rather than two loops of data-dependent
    // length.
    let (lo, hi) = (best.saturating_sub(1) as u16, (best + 1) as u16);
    let mut other = u16::MAX;
    for (k, &v) in (0u16..).zip(c) {
        let far = k < lo || k > hi;
        other = other.min(if far { v } else { u16::MAX });
    }
    (bc, best, other)
}

/// [`best_and_other`] for exactly 64 disparities with AVX2: u16 minima with `phminposuw`, the
/// first index from a compare mask, the neighbours masked by an index range.
///
/// # Safety
/// The CPU must support AVX2 and `c` must hold 64 values.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn best_and_other_64_avx2(c: &[u16]) -> (u16, usize, u16) {
    use std::arch::x86_64::*;
    debug_assert!(c.len() >= 64);
    // SAFETY (whole body): AVX2 is enabled for this function; the four loads read the 64
    // values the caller guarantees.
    unsafe {
        let p = c.as_ptr() as *const __m256i;
        let v = [
            _mm256_loadu_si256(p),
            _mm256_loadu_si256(p.add(1)),
            _mm256_loadu_si256(p.add(2)),
            _mm256_loadu_si256(p.add(3)),
        ];
        let bc = hmin_avx2(&v);
        let b = _mm256_set1_epi16(bc as i16);
        // Two bits per lane; the first set bit of the 128-bit mask is the first minimum
        // (branch-free: the position varies from pixel to pixel).
        let m: [u64; 4] = std::array::from_fn(|i| _mm256_movemask_epi8(_mm256_cmpeq_epi16(v[i], b)) as u32 as u64);
        let (lo_half, hi_half) = (m[0] | m[1] << 32, m[2] | m[3] << 32);
        let best = if lo_half != 0 { lo_half.trailing_zeros() / 2 } else { 32 + hi_half.trailing_zeros() / 2 } as usize;
        // Lanes lo..=hi (unsigned lane - lo <= hi - lo) become the maximum.
        let lo = best.saturating_sub(1);
        let width = _mm256_set1_epi16((best + 1 - lo) as i16);
        let lov = _mm256_set1_epi16(lo as i16);
        let mut idx = _mm256_setr_epi16(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
        let step = _mm256_set1_epi16(16);
        let mut masked = v;
        for m in masked.iter_mut() {
            let rel = _mm256_sub_epi16(idx, lov);
            let inside = _mm256_cmpeq_epi16(_mm256_min_epu16(rel, width), rel);
            *m = _mm256_or_si256(*m, inside);
            idx = _mm256_add_epi16(idx, step);
        }
        (bc, best, hmin_avx2(&masked))
    }
}

/// The least u16 lane of four vectors.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn hmin_avx2(v: &[std::arch::x86_64::__m256i; 4]) -> u16 {
    use std::arch::x86_64::*;
    // Intrinsics are unsafe to call before Rust 1.87 (our MSRV is 1.80); AVX2 (and SSE4.1,
    // which it implies) is enabled for this function.
    #[allow(unused_unsafe)]
    // SAFETY: see above.
    unsafe {
        let m = _mm256_min_epu16(_mm256_min_epu16(v[0], v[1]), _mm256_min_epu16(v[2], v[3]));
        let m = _mm_min_epu16(_mm256_castsi256_si128(m), _mm256_extracti128_si256::<1>(m));
        _mm_extract_epi16::<0>(_mm_minpos_epu16(m)) as u16
    }
}

/// Selects the disparities of one row from its costs (`row.len() * d` values, `[x][d]`).
/// `M` says whether the caller runs in an AVX2 build ([`Madd::AVX2`]).
#[inline(always)]
pub(crate) fn select_row<M: Madd>(costs: &[u16], d: usize, row: &mut [f32], rule: &WtaRule, s: &mut WtaScratch) {
    let w = row.len();
    s.begin(row, rule);
    for x in rule.x_min..rule.x_max.min(w) {
        s.pixel::<M>(x, &costs[x * d..(x + 1) * d], row, rule);
    }
    s.finish(row, rule);
}

impl WtaScratch {
    /// Starts a row: everything invalid until [`WtaScratch::pixel`] says otherwise.
    #[inline(always)]
    pub(crate) fn begin(&mut self, row: &mut [f32], rule: &WtaRule) {
        let w = row.len();
        self.best_of.clear();
        self.best_of.resize(w, usize::MAX);
        self.right_best.clear();
        self.right_best.resize(w, usize::MAX);
        self.right_cost.clear();
        self.right_cost.resize(w, u16::MAX);
        row.fill(f32::NAN);
        // The uniqueness test in integers: other (1 - margin) <= best, 1 - margin in 1/65536.
        self.keep = ((1.0 - rule.margin.clamp(0.0, 1.0)) * 65536.0).round() as u64;
    }

    /// Selects pixel `x` (inside `rule.x_min..rule.x_max`) from its `d` costs.
    #[inline(always)]
    pub(crate) fn pixel<M: Madd>(&mut self, x: usize, c: &[u16], row: &mut [f32], rule: &WtaRule) {
        let d = c.len();
        #[cfg(target_arch = "x86_64")]
        // SAFETY: M::AVX2 is true only inside AVX2 builds (dispatch_kernel!); c has 64 values.
        let (bc, best, other) =
            if M::AVX2 && d == 64 { unsafe { best_and_other_64_avx2(c) } } else { best_and_other(c) };
        #[cfg(not(target_arch = "x86_64"))]
        let (bc, best, other) = best_and_other(c);
        let ambiguous = other as u64 * self.keep <= (bc as u64) << 16;
        if ambiguous || bc == u16::MAX || best > x {
            return;
        }
        let mut disp = best as f32;
        if best > 0 && best + 1 < d && c[best - 1] != u16::MAX && c[best + 1] != u16::MAX {
            let (a, b, cc) = (c[best - 1] as f32, bc as f32, c[best + 1] as f32);
            disp += match rule.subpixel {
                SubPixel::Parabola => {
                    let den = a - 2.0 * b + cc;
                    if den > 0.0 {
                        0.5 * (a - cc) / den
                    } else {
                        0.0
                    }
                }
                SubPixel::Equiangular => {
                    let den = 2.0 * (a.max(cc) - b);
                    if den > 0.0 {
                        (a - cc) / den
                    } else {
                        0.0
                    }
                }
            };
        }
        row[x] = disp;
        self.best_of[x] = best;
        let xr = x - best;
        if bc < self.right_cost[xr] {
            self.right_cost[xr] = bc;
            self.right_best[xr] = best;
        }
    }

    /// Ends a row: the left-right check.
    #[inline(always)]
    pub(crate) fn finish(&mut self, row: &mut [f32], rule: &WtaRule) {
        if rule.lr_max_diff < 0.0 {
            return;
        }
        for x in 0..row.len() {
            if row[x].is_finite() {
                let rb = self.right_best[x - self.best_of[x]];
                if rb == usize::MAX || (rb as f32 - self.best_of[x] as f32).abs() > rule.lr_max_diff {
                    row[x] = f32::NAN;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ocellus_image::rng::SplitMix64;

    #[test]
    fn avx2_winner_matches_the_portable_one() {
        if !ocellus_image::simd::avx2_available() {
            return;
        }
        let mut rng = SplitMix64::new(4);
        for case in 0..2000 {
            // Small ranges make ties and adjacent minima common.
            let range = if case % 2 == 0 { 8 } else { 60000 };
            let c: Vec<u16> = (0..64).map(|_| rng.below(range) as u16).collect();
            #[cfg(target_arch = "x86_64")]
            // SAFETY: AVX2 checked above; 64 values.
            let fast = unsafe { best_and_other_64_avx2(&c) };
            #[cfg(target_arch = "x86_64")]
            assert_eq!(fast, best_and_other(&c), "case {case}: {c:?}");
        }
    }
}
