//! The seed's elaborated SAD block matching (SPEC 6.2).
//!
//! The central `region` x `region` pixels of a frame are cut into `window` x `window` search
//! windows (400 for the defaults). In each, the `block` x `block` block at the window's centre
//! in frame n-1 is compared by the sum of absolute differences with every position it can
//! take inside the window in frame n; the best position gives the window's flow (integer
//! pixels, up to +-(window - block) / 2). Border windows are dropped (18 x 18 = 324 remain),
//! the rest are grouped `group` x `group` (36 groups); in each group the flows farther than
//! `outlier_px` from the group's median are rejected and the rest averaged: one flow vector
//! per group, at the mean position of its blocks.
//!
//! A window whose candidates all cost the same (a flat floor) has no flow. Beyond the seed, a
//! group keeps its flow only when at least `quorum` of its windows agree (5 of 9 by
//! default): on a floor whose texture drowns in noise the integer matches scatter over the
//! search range, their median is noise, and the seed's averaging would integrate it. A frame
//! where no group keeps a flow is reported as [`OdometryError::NoTexture`], so the filter
//! predicts it instead.

use crate::{OdometryError, Result};
use ocellus_image::{Backend, Plane};

/// Parameters of the flow measurement (the seed's defaults).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SadFlowConfig {
    /// Side of the central region searched, pixels.
    pub region: usize,
    /// Side of a search window, pixels.
    pub window: usize,
    /// Side of the matched block, pixels.
    pub block: usize,
    /// Windows per group side.
    pub group: usize,
    /// Flows farther than this from their group's median (per axis) are outliers, pixels.
    pub outlier_px: f64,
    /// Windows of a group that must agree (be inliers) for the group to give a flow, at
    /// least 1 (1: the seed's rule, any window will do).
    #[serde(default = "default_quorum")]
    pub quorum: usize,
    /// Which build of the block search runs (`auto`: the fastest this CPU has).
    #[serde(default)]
    pub backend: Backend,
}

fn default_quorum() -> usize {
    5
}

impl Default for SadFlowConfig {
    /// 400x400 region, 20x20 windows, 8x8 blocks, 3x3 groups, outliers beyond 1 px, a group
    /// counted when 5 of its windows agree.
    fn default() -> Self {
        Self {
            region: 400,
            window: 20,
            block: 8,
            group: 3,
            outlier_px: 1.0,
            quorum: default_quorum(),
            backend: Backend::Auto,
        }
    }
}

impl SadFlowConfig {
    pub(crate) fn check(&self, w: usize, h: usize) -> Result<usize> {
        if self.block == 0 || self.block >= self.window || !(self.window - self.block).is_multiple_of(2) {
            return Err(OdometryError::Invalid(format!(
                "block {} in window {}: the block must be smaller, with an even margin",
                self.block, self.window
            )));
        }
        let n = self.region / self.window;
        if !self.region.is_multiple_of(self.window) || n < 2 + self.group || !(n - 2).is_multiple_of(self.group) {
            return Err(OdometryError::Invalid(format!(
                "region {} in windows of {}: need a whole number of windows, and after dropping the border a multiple of {} per side",
                self.region, self.window, self.group
            )));
        }
        if !(self.outlier_px.is_finite() && self.outlier_px >= 0.0) {
            return Err(OdometryError::Invalid(format!("outlier threshold {}", self.outlier_px)));
        }
        if self.quorum == 0 || self.quorum > self.group * self.group {
            return Err(OdometryError::Invalid(format!(
                "quorum {}: between 1 and the {} windows of a group",
                self.quorum,
                self.group * self.group
            )));
        }
        if w < self.region || h < self.region {
            return Err(OdometryError::TooSmall {
                got_w: w,
                got_h: h,
                why: format!("the central region is {0}x{0}", self.region),
            });
        }
        Ok(n)
    }
}

/// One window's measurement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WindowFlow {
    /// Centre of the block in frame n-1, pixels (image coordinates).
    pub x: f64,
    /// Centre of the block in frame n-1, pixels.
    pub y: f64,
    /// Flow, pixels (`None` when every position costs the same).
    pub flow: Option<(i32, i32)>,
}

/// One group's flow vector.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlowPoint {
    /// Position relative to the principal point ((w - 1) / 2, (h - 1) / 2), pixels, x right.
    pub u: f64,
    /// Position relative to the principal point, pixels, y down.
    pub v: f64,
    /// Flow along x, pixels per frame.
    pub du: f64,
    /// Flow along y, pixels per frame.
    pub dv: f64,
    /// Windows averaged (after outlier rejection).
    pub inliers: usize,
}

/// Best offset (first in raster order on ties) and whether the costs differ at all, for the
/// block at (bx, by) searched over offsets 0..span (x and y) from (wx, wy).
#[inline(always)]
fn search_scalar(
    prev: &Plane<u8>,
    cur: &Plane<u8>,
    b: usize,
    bx: usize,
    by: usize,
    wx: usize,
    wy: usize,
    span: usize,
) -> Option<(usize, usize)> {
    let (mut best, mut worst, mut at) = (u32::MAX, 0u32, (0usize, 0usize));
    for oy in 0..span {
        for ox in 0..span {
            let mut sad = 0u32;
            for r in 0..b {
                let a = &prev.row(by + r)[bx..bx + b];
                let c = &cur.row(wy + oy + r)[wx + ox..wx + ox + b];
                sad += a.iter().zip(c).map(|(p, q)| p.abs_diff(*q) as u32).sum::<u32>();
            }
            if sad < best {
                best = sad;
                at = (ox, oy);
            }
            worst = worst.max(sad);
        }
    }
    (worst > best).then_some(at)
}

/// The running best offset of a block search over rows of 16 costs (offsets 0..8 and 8..16
/// of one vertical offset; those past `span` ignored), first in raster order on ties, and
/// the largest cost (a flat window costs the same everywhere).
#[cfg(target_arch = "x86_64")]
struct BestOffset {
    outside: std::arch::x86_64::__m128i,
    best: u32,
    at: (usize, usize),
    hi: std::arch::x86_64::__m128i,
}

#[cfg(target_arch = "x86_64")]
impl BestOffset {
    /// # Safety
    /// SSE4.1 must be available.
    #[target_feature(enable = "sse4.1")]
    unsafe fn new(span: usize) -> Self {
        use std::arch::x86_64::*;
        let lanes = _mm_setr_epi16(8, 9, 10, 11, 12, 13, 14, 15);
        Self {
            outside: _mm_cmpgt_epi16(lanes, _mm_set1_epi16(span as i16 - 1)),
            best: u32::MAX,
            at: (0, 0),
            hi: _mm_setzero_si128(),
        }
    }

    /// The costs of vertical offset `oy`: horizontal offsets 0..8 in `lo`, 8..16 in `up`.
    ///
    /// # Safety
    /// SSE4.1 must be available.
    #[target_feature(enable = "sse4.1")]
    #[inline]
    unsafe fn row(&mut self, oy: usize, lo: std::arch::x86_64::__m128i, up: std::arch::x86_64::__m128i) {
        use std::arch::x86_64::*;
        // Offsets past `span` in the second half are masked to the maximum.
        let halves = [lo, _mm_or_si128(up, self.outside)];
        for (h, v) in halves.iter().enumerate() {
            let m = _mm_minpos_epu16(*v);
            let val = _mm_extract_epi16::<0>(m) as u32;
            if val < self.best {
                self.best = val;
                self.at = (8 * h + _mm_extract_epi16::<1>(m) as usize, oy);
            }
        }
        self.hi = _mm_max_epu16(self.hi, lo);
        self.hi = _mm_max_epu16(self.hi, _mm_andnot_si128(self.outside, up));
    }

    /// The best offset, or `None` when every cost was the same.
    ///
    /// # Safety
    /// SSE4.1 must be available.
    #[target_feature(enable = "sse4.1")]
    unsafe fn result(&self) -> Option<(usize, usize)> {
        use std::arch::x86_64::*;
        // Flat: the largest cost equals the smallest.
        let worst =
            0xffff - _mm_extract_epi16::<0>(_mm_minpos_epu16(_mm_sub_epi16(_mm_set1_epi16(-1), self.hi))) as u32;
        (worst > self.best).then_some(self.at)
    }
}

/// [`search_scalar`] for 8x8 blocks and up to 16 offsets per axis with SSE4.1's `mpsadbw`
/// (eight 4-byte SADs at consecutive offsets per instruction) and `phminposuw`.
///
/// # Safety
/// The CPU must support SSE4.1; the rows `wy..wy + span + 7` of `cur` must have 32 bytes
/// from `wx`, and the block must lie inside `prev`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "sse4.1")]
unsafe fn search_8x8_sse41(
    prev: &Plane<u8>,
    cur: &Plane<u8>,
    bx: usize,
    by: usize,
    wx: usize,
    wy: usize,
    span: usize,
) -> Option<(usize, usize)> {
    use std::arch::x86_64::*;
    debug_assert!(span <= 16);
    // SAFETY (whole body): the caller guarantees the feature and the bounds of every load.
    unsafe {
        let mut acc = [[_mm_setzero_si128(); 2]; 16];
        // As in `search_8x8_avx2`: row wy + k of the window at wx is `k` strides past `base`.
        let stride = cur.stride();
        let base = cur.as_slice().as_ptr().add(wy * stride + wx);
        for r in 0..8 {
            let brow = _mm_loadl_epi64(prev.row(by + r)[bx..bx + 8].as_ptr() as *const __m128i);
            for (oy, a) in acc.iter_mut().enumerate().take(span) {
                let row = base.add((oy + r) * stride);
                let c0 = _mm_loadu_si128(row as *const __m128i);
                let c1 = _mm_loadu_si128(row.add(8) as *const __m128i);
                // Bytes 0-3 of the block against offsets 0..8, bytes 4-7 against 4..12.
                a[0] = _mm_add_epi16(
                    a[0],
                    _mm_add_epi16(_mm_mpsadbw_epu8::<0b000>(c0, brow), _mm_mpsadbw_epu8::<0b101>(c0, brow)),
                );
                a[1] = _mm_add_epi16(
                    a[1],
                    _mm_add_epi16(_mm_mpsadbw_epu8::<0b000>(c1, brow), _mm_mpsadbw_epu8::<0b101>(c1, brow)),
                );
            }
        }
        let mut best = BestOffset::new(span);
        for (oy, a) in acc.iter().enumerate().take(span) {
            best.row(oy, a[0], a[1]);
        }
        best.result()
    }
}

/// [`search_8x8_sse41`] with AVX2: one 256-bit `mpsadbw` covers the offsets 0..8 in its low
/// lane and 8..16 in its high lane, so each block row costs half the instructions.
///
/// # Safety
/// As [`search_8x8_sse41`], with AVX2 instead of SSE4.1.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn search_8x8_avx2(
    prev: &Plane<u8>,
    cur: &Plane<u8>,
    bx: usize,
    by: usize,
    wx: usize,
    wy: usize,
    span: usize,
) -> Option<(usize, usize)> {
    use std::arch::x86_64::*;
    debug_assert!(span <= 16);
    // SAFETY (whole body): the caller guarantees the feature and the bounds of every load.
    unsafe {
        // The block's rows stay in registers; each offset row's costs are summed in one
        // register and reduced at once (no accumulator array going through memory).
        let brows: [__m256i; 8] = std::array::from_fn(|r| {
            _mm256_broadcastsi128_si256(_mm_loadl_epi64(prev.row(by + r)[bx..bx + 8].as_ptr() as *const __m128i))
        });
        let mut best = BestOffset::new(span);
        // Row wy + k of the window at wx is `k` strides past `base`: pointer steps instead of
        // a checked row slice per load (a third of the search's instructions).
        let stride = cur.stride();
        let base = cur.as_slice().as_ptr().add(wy * stride + wx);
        // Each of the window's span + 7 rows (at most 16 + 7), loaded and arranged once (bytes
        // 0..16 in the low lane, 8..24 in the high lane): every row serves up to 8 offset rows,
        // and arranging it again for each took the seed step from 0.106 to 0.115 ms (Zen 3).
        let mut rows = [_mm256_setzero_si256(); 16 + 7];
        for (q, row) in rows.iter_mut().enumerate().take(span + 7) {
            let c = _mm256_loadu_si256(base.add(q * stride) as *const __m256i);
            *row = _mm256_permute4x64_epi64::<0b10_01_01_00>(c);
        }
        for oy in 0..span {
            let mut a = _mm256_setzero_si256();
            for (r, brow) in brows.iter().enumerate() {
                let c = rows[oy + r];
                a = _mm256_add_epi16(
                    a,
                    _mm256_add_epi16(
                        _mm256_mpsadbw_epu8::<0b000_000>(c, *brow),
                        _mm256_mpsadbw_epu8::<0b101_101>(c, *brow),
                    ),
                );
            }
            best.row(oy, _mm256_castsi256_si128(a), _mm256_extracti128_si256::<1>(a));
        }
        best.result()
    }
}

/// The block search of every window with `cfg.backend`'s build: the 8x8 searches have
/// hand-written SSE4.1 and AVX2 kernels (`mpsadbw`, `phminposuw`: the compiler
/// does not find these from the scalar loop); other block sizes run the scalar search.
fn windows_kernel(prev: &Plane<u8>, cur: &Plane<u8>, cfg: &SadFlowConfig, n: usize, out: &mut Vec<WindowFlow>) {
    let (w, h) = prev.size();
    let (x0, y0) = ((w - cfg.region) / 2, (h - cfg.region) / 2);
    let (b, m) = (cfg.block, (cfg.window - cfg.block) / 2);
    let span = 2 * m + 1;
    let backend = cfg.backend.resolve();
    #[cfg(target_arch = "x86_64")]
    let fast = b == 8 && span <= 16 && x0 + (n - 1) * cfg.window + 32 <= w && backend != Backend::Scalar;
    #[cfg(target_arch = "x86_64")]
    let avx2 = fast && backend.has_avx2();
    #[cfg(not(target_arch = "x86_64"))]
    let _ = backend;
    out.clear();
    for j in 0..n {
        for i in 0..n {
            let (wx, wy) = (x0 + i * cfg.window, y0 + j * cfg.window);
            let (bx, by) = (wx + m, wy + m);
            #[cfg(target_arch = "x86_64")]
            // SAFETY: resolve() gives Sse41 or Avx2 only where the CPU has SSE4.1 (and AVX2 for `avx2`); `fast` checked that 32 bytes from wx fit every row, and
            // the window (rows wy..wy + span + 7) lies inside the region.
            let at = if avx2 {
                unsafe { search_8x8_avx2(prev, cur, bx, by, wx, wy, span) }
            } else if fast {
                unsafe { search_8x8_sse41(prev, cur, bx, by, wx, wy, span) }
            } else {
                search_scalar(prev, cur, b, bx, by, wx, wy, span)
            };
            #[cfg(not(target_arch = "x86_64"))]
            let at = search_scalar(prev, cur, b, bx, by, wx, wy, span);
            let flow = at.map(|(ox, oy)| (ox as i32 - m as i32, oy as i32 - m as i32));
            out.push(WindowFlow { x: bx as f64 + (b as f64 - 1.0) / 2.0, y: by as f64 + (b as f64 - 1.0) / 2.0, flow });
        }
    }
}

/// Every window's flow between `prev` and `cur`, row by row (window rows of the region).
pub fn window_flows(prev: &Plane<u8>, cur: &Plane<u8>, cfg: &SadFlowConfig) -> Result<Vec<WindowFlow>> {
    ocellus_image::check::same_size("frame (against the previous one)", cur.size(), prev.size())?;
    let n = cfg.check(prev.width(), prev.height())?;
    let mut out = Vec::with_capacity(n * n);
    windows_kernel(prev, cur, cfg, n, &mut out);
    Ok(out)
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let k = v.len() / 2;
    if v.len() % 2 == 1 {
        v[k]
    } else {
        0.5 * (v[k - 1] + v[k])
    }
}

/// The seed's 36 group flows: border windows dropped, groups of `group` x `group`, outliers
/// beyond `outlier_px` of the group median rejected, the rest averaged. Groups with fewer
/// than `quorum` inliers are left out; no flow at all is [`OdometryError::NoTexture`].
pub fn group_flows(prev: &Plane<u8>, cur: &Plane<u8>, cfg: &SadFlowConfig) -> Result<Vec<FlowPoint>> {
    let windows = window_flows(prev, cur, cfg)?;
    let n = cfg.region / cfg.window;
    let (cx, cy) = ((prev.width() as f64 - 1.0) / 2.0, (prev.height() as f64 - 1.0) / 2.0);
    let groups = (n - 2) / cfg.group;
    let mut out = Vec::with_capacity(groups * groups);
    let (mut xs, mut ys) = (Vec::new(), Vec::new());
    for gj in 0..groups {
        for gi in 0..groups {
            let members: Vec<&WindowFlow> = (0..cfg.group)
                .flat_map(|dj| (0..cfg.group).map(move |di| (1 + gi * cfg.group + di, 1 + gj * cfg.group + dj)))
                .map(|(i, j)| &windows[j * n + i])
                .collect();
            xs.clear();
            ys.clear();
            for m in &members {
                if let Some((fx, fy)) = m.flow {
                    xs.push(fx as f64);
                    ys.push(fy as f64);
                }
            }
            if xs.is_empty() {
                continue;
            }
            let (mx, my) = (median(&mut xs.clone()), median(&mut ys.clone()));
            let (mut sx, mut sy, mut su, mut sv, mut k) = (0.0, 0.0, 0.0, 0.0, 0usize);
            for m in &members {
                if let Some((fx, fy)) = m.flow {
                    if (fx as f64 - mx).abs() <= cfg.outlier_px && (fy as f64 - my).abs() <= cfg.outlier_px {
                        sx += fx as f64;
                        sy += fy as f64;
                        su += m.x;
                        sv += m.y;
                        k += 1;
                    }
                }
            }
            if k >= cfg.quorum {
                let kf = k as f64;
                out.push(FlowPoint { u: su / kf - cx, v: sv / kf - cy, du: sx / kf, dv: sy / kf, inliers: k });
            }
        }
    }
    if out.is_empty() {
        return Err(OdometryError::NoTexture(format!(
            "no group of search windows agreed on a match ({} of {} needed)",
            cfg.quorum,
            cfg.group * cfg.group
        )));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use ocellus_image::rng::SplitMix64;

    fn texture(w: usize, h: usize, seed: u64) -> Plane<u8> {
        let mut rng = SplitMix64::new(seed);
        Plane::from_fn(w, h, |_, _| (rng.next_u64() & 255) as u8)
    }

    #[test]
    fn a_shifted_frame_gives_its_shift_everywhere() {
        let big = texture(700, 540, 1);
        let prev = Plane::from_fn(640, 480, |x, y| big.get(x + 30, y + 30));
        // The floor moves by (+3, -2) pixels in the image.
        let cur = Plane::from_fn(640, 480, |x, y| big.get(x + 30 - 3, y + 30 + 2));
        let g = group_flows(&prev, &cur, &SadFlowConfig::default()).unwrap();
        assert_eq!(g.len(), 36);
        for p in &g {
            assert_eq!((p.du, p.dv, p.inliers), (3.0, -2.0, 9));
        }
        // Group centres cover the region symmetrically around the principal point.
        let (su, sv): (f64, f64) = g.iter().fold((0.0, 0.0), |a, p| (a.0 + p.u, a.1 + p.v));
        assert!(su.abs() < 1e-9 && sv.abs() < 1e-9, "{su} {sv}");
    }

    #[test]
    fn simd_searches_match_the_scalar_one() {
        if !is_x86_feature_detected!("sse4.1") {
            return;
        }
        let avx2 = is_x86_feature_detected!("avx2");
        let mut rng = SplitMix64::new(9);
        for case in 0..300 {
            // Low-contrast textures make ties common.
            let levels = if case % 3 == 0 { 3 } else { 256 };
            let prev = Plane::from_fn(64, 48, |_, _| rng.below(levels) as u8);
            let cur = Plane::from_fn(64, 48, |_, _| rng.below(levels) as u8);
            let fast = unsafe { search_8x8_sse41(&prev, &cur, 12, 10, 6, 4, 13) };
            assert_eq!(fast, search_scalar(&prev, &cur, 8, 12, 10, 6, 4, 13), "case {case}");
            if avx2 {
                // Spans of 13 (the default) and 16 (every lane used).
                for span in [13, 16] {
                    let wide = unsafe { search_8x8_avx2(&prev, &cur, 12, 10, 6, 4, span) };
                    assert_eq!(wide, search_scalar(&prev, &cur, 8, 12, 10, 6, 4, span), "case {case} span {span}");
                }
            }
        }
        if avx2 {
            assert_eq!(unsafe { search_8x8_avx2(&flat_of(7), &flat_of(7), 12, 10, 6, 4, 13) }, None);
        }
        let flat = Plane::from_fn(64, 48, |_, _| 7u8);
        assert_eq!(unsafe { search_8x8_sse41(&flat, &flat, 12, 10, 6, 4, 13) }, None);
    }

    fn flat_of(v: u8) -> Plane<u8> {
        Plane::from_fn(64, 48, |_, _| v)
    }

    #[test]
    fn frames_of_unrelated_noise_fail_the_quorum() {
        // Two frames with nothing in common: every window finds some best match, but they
        // scatter, and no group of 9 has 5 that agree.
        let (a, b) = (texture(640, 480, 11), texture(640, 480, 12));
        let cfg = SadFlowConfig::default();
        assert!(matches!(group_flows(&a, &b, &cfg), Err(OdometryError::NoTexture(_))));
        // The seed's rule (any window will do) integrates them.
        assert!(group_flows(&a, &b, &SadFlowConfig { quorum: 1, ..cfg }).is_ok());
        // A real shift passes the quorum everywhere.
        let shifted = Plane::from_fn(600, 440, |x, y| a.get(x + 3, y + 2));
        let a0 = Plane::from_fn(600, 440, |x, y| a.get(x, y));
        let flows = group_flows(&a0, &shifted, &cfg).unwrap();
        assert_eq!(flows.len(), 36);
        assert!(flows.iter().all(|f| f.du == -3.0 && f.dv == -2.0 && f.inliers == 9), "{flows:?}");
        for q in [0, 10] {
            assert!(group_flows(&a, &b, &SadFlowConfig { quorum: q, ..cfg }).is_err());
        }
    }

    #[test]
    fn a_flat_floor_is_reported_and_bad_sizes_are_errors() {
        let flat = Plane::from_fn(640, 480, |_, _| 90u8);
        assert!(matches!(group_flows(&flat, &flat, &SadFlowConfig::default()), Err(OdometryError::NoTexture(_))));
        let small = Plane::new(320, 240);
        assert!(group_flows(&small, &small, &SadFlowConfig::default()).is_err());
        assert!(group_flows(&flat, &small, &SadFlowConfig::default()).is_err());
        assert!(group_flows(&flat, &flat, &SadFlowConfig { window: 21, ..Default::default() }).is_err());
    }
}
