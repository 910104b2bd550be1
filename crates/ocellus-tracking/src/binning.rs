//! HSV histograms after Pérez, Hue, Vermaak & Gangnet (ECCV 2002), the colour features of the
//! tracker's likelihood (SPEC 7.2): pixels with saturation above 0.1 and value above 0.2 fall
//! into 10 x 10 hue-saturation bins; the others (greys, dark pixels, whose hue is noise) into
//! 10 value bins: 110 bins in all. A frame is binned once ([`BinnedFrame`]), whole, in one
//! rectangle, or grown rectangle by rectangle; histograms compare by the Bhattacharyya
//! coefficient.

use ocellus_image::{Backend, Plane};
use rayon::prelude::*;

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

/// Bins a row 8 pixels at a time with explicit AVX2 intrinsics; returns how many pixels it
/// binned (the rest, at most 16, is left to the caller). Written by hand because the compiler
/// vectorizes [`bin_block`] only in part: it de-interleaves the RGB triplets and packs the
/// bins back lane by lane, in scalar code, and binning the frame took 0.8 ms of a 1.9 ms
/// tracker step on an AMD EPYC (Zen 3) core. The arithmetic is [`bin_block`]'s, in the same
/// order, except the value bin `floor(10 M / 255)`, taken as `floor(M * (10 / 255) + 1e-4)`:
/// `10 M / 255` is an integer or at least 1/51 below the next one, and the product is within
/// 1e-6 of it, so the floor is exact without a division.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn bin_row_avx2(src: &[[u8; 3]], dst: &mut [u8]) -> usize {
    use std::arch::x86_64::*;
    let n = src.len().min(dst.len());
    let bytes = src.as_ptr() as *const u8;
    let mut i = 0;
    // SAFETY (whole body): AVX2 is there (the caller's promise); the two 16-byte loads of a
    // block read bytes 3i..3i + 28, inside the row while 3i + 28 <= 3n; the 8-byte store
    // writes dst[i..i + 8] with i + 8 <= n.
    unsafe {
        // Each 128-bit half holds 4 pixels (12 bytes); pick one channel's byte into the low
        // byte of each 32-bit lane.
        let pick = |c: i8| {
            let z = -1i8;
            _mm256_broadcastsi128_si256(_mm_setr_epi8(c, z, z, z, c + 3, z, z, z, c + 6, z, z, z, c + 9, z, z, z))
        };
        let (pr, pg, pb) = (pick(0), pick(1), pick(2));
        let f = _mm256_set1_ps;
        let (zero, one, two, four, six, nine, ten) = (f(0.0), f(1.0), f(2.0), f(4.0), f(6.0), f(9.0), f(10.0));
        let (dark, value_scale, nudge, grey_base) = (f(51.0), f(10.0 / 255.0), f(1e-4), f(100.0));
        while i + 8 <= n && 3 * i + 28 <= 3 * n {
            let lo = _mm_loadu_si128(bytes.add(3 * i) as *const __m128i);
            let hi = _mm_loadu_si128(bytes.add(3 * i + 12) as *const __m128i);
            let v = _mm256_inserti128_si256::<1>(_mm256_castsi128_si256(lo), hi);
            let r = _mm256_cvtepi32_ps(_mm256_shuffle_epi8(v, pr));
            let g = _mm256_cvtepi32_ps(_mm256_shuffle_epi8(v, pg));
            let b = _mm256_cvtepi32_ps(_mm256_shuffle_epi8(v, pb));
            let mx = _mm256_max_ps(_mm256_max_ps(r, g), b);
            let mn = _mm256_min_ps(_mm256_min_ps(r, g), b);
            let d = _mm256_sub_ps(mx, mn);
            let grey = _mm256_or_ps(
                _mm256_cmp_ps::<_CMP_LE_OQ>(_mm256_mul_ps(ten, d), mx),
                _mm256_cmp_ps::<_CMP_LE_OQ>(mx, dark),
            );
            let vb = _mm256_min_ps(_mm256_floor_ps(_mm256_add_ps(_mm256_mul_ps(mx, value_scale), nudge)), nine);
            // Hue numerators: red maximum (wrapped by 6 d when g < b), green, blue.
            let g_b = _mm256_sub_ps(g, b);
            let wrap = _mm256_and_ps(_mm256_cmp_ps::<_CMP_LT_OQ>(g, b), _mm256_mul_ps(six, d));
            let num_r = _mm256_add_ps(g_b, wrap);
            let num_g = _mm256_add_ps(_mm256_mul_ps(two, d), _mm256_sub_ps(b, r));
            let num_b = _mm256_add_ps(_mm256_mul_ps(four, d), _mm256_sub_ps(r, g));
            let num = _mm256_blendv_ps(num_b, num_g, _mm256_cmp_ps::<_CMP_EQ_OQ>(mx, g));
            let num = _mm256_blendv_ps(num, num_r, _mm256_cmp_ps::<_CMP_EQ_OQ>(mx, r));
            let dd = _mm256_max_ps(d, one);
            let hb = _mm256_div_ps(_mm256_mul_ps(ten, num), _mm256_mul_ps(six, dd));
            let hb = _mm256_min_ps(_mm256_floor_ps(hb), nine);
            let sb = _mm256_div_ps(_mm256_mul_ps(ten, d), _mm256_max_ps(mx, one));
            let sb = _mm256_min_ps(_mm256_floor_ps(sb), nine);
            let colour = _mm256_add_ps(_mm256_mul_ps(hb, ten), sb);
            let bin = _mm256_blendv_ps(colour, _mm256_add_ps(grey_base, vb), grey);
            let bin = _mm256_max_ps(bin, zero);
            // 8 x i32 -> 8 bytes: each 128-bit half packs its 4 lanes into its low 4 bytes.
            let w = _mm256_cvttps_epi32(bin);
            let p = _mm256_packus_epi16(_mm256_packs_epi32(w, w), _mm256_packs_epi32(w, w));
            let lo4 = _mm256_cvtsi256_si32(p) as u32 as u64;
            let hi4 = _mm256_extract_epi32::<4>(p) as u32 as u64;
            (dst.as_mut_ptr().add(i) as *mut u64).write_unaligned(lo4 | hi4 << 32);
            i += 8;
        }
    }
    i
}

/// Bins the pixels of `frame` in columns `x0..x1` of rows `y0..y1` into `rows`, which holds
/// those rows of the bin plane (row `y` at `(y - y0) * w`, `w` the frame's width; the
/// caller clamps the rectangle to the frame). `M` only selects the build (the kernel has no
/// multiply-add); [`ocellus_image::dispatch_kernel!`] compiles it with AVX2.
#[allow(clippy::extra_unused_type_parameters)]
#[inline(always)]
fn bin_rows_generic<M: ocellus_image::simd::Madd>(
    frame: &Plane<[u8; 3]>,
    rows: &mut [u8],
    w: usize,
    [x0, y0, x1, y1]: [usize; 4],
) {
    for (y, out) in (y0..y1).zip(rows.chunks_exact_mut(w)) {
        let (src, dst) = (&frame.row(y)[x0..x1], &mut out[x0..x1]);
        #[cfg(target_arch = "x86_64")]
        let (src, dst) = if M::AVX2 {
            // SAFETY: M::AVX2 is only instantiated inside functions compiled with AVX2.
            let done = unsafe { bin_row_avx2(src, dst) };
            (&src[done..], &mut dst[done..])
        } else {
            (src, dst)
        };
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
    /// Bins a band of rows of a frame (see [`bin_rows_generic`]) with the backend's kernel.
    fn bin_rows => bin_rows_generic(frame: &Plane<[u8; 3]>, rows: &mut [u8], w: usize, rect: [usize; 4])
);

/// Pixels per task of [`bin_rect`]: about 10 us of binning, so that the tasks outweigh
/// rayon's cost of handing them out, and a 640x480 frame still makes 37 of them.
const BIN_TASK_PIXELS: usize = 8192;

/// Bins the rectangle [x0, y0, x1, y1) of `frame` (clamped by the caller) into `out` (the
/// frame's size), in bands of rows on the rayon pool: the bins are per pixel, so the result
/// is the same at any thread count. Binning was the one serial stage of a tracker step, and
/// at 10^4 particles on 2 cores it held the speed-up to about 1.75x.
fn bin_rect(backend: Backend, frame: &Plane<[u8; 3]>, out: &mut Plane<u8>, [x0, y0, x1, y1]: [usize; 4]) {
    let w = out.width();
    if x0 >= x1 || y0 >= y1 {
        return;
    }
    let band = (BIN_TASK_PIXELS / (x1 - x0)).max(1);
    match out.as_contiguous_mut() {
        Some(all) => all[y0 * w..y1 * w].par_chunks_mut(band * w).enumerate().for_each(|(i, rows)| {
            let ya = y0 + i * band;
            bin_rows(backend, frame, rows, w, [x0, ya, x1, (ya + band).min(y1)]);
        }),
        // The bin plane is always contiguous (`Plane::resize` sets stride = width); a strided
        // one is binned row by row.
        None => {
            for y in y0..y1 {
                bin_rows(backend, frame, out.row_mut(y), w, [x0, y, x1, y + 1]);
            }
        }
    }
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
    /// region must hold every sample of every circle scored (see [`crate::colour::Circle::reach`]).
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
    pub(crate) fn at(&self, x: f64, y: f64) -> Option<u8> {
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

/// The nearest integer to `v` (ties to even) for |v| < 2^51; far outside that, some integer
/// far outside any frame. Adding 1.5 * 2^52 leaves the rounded integer in the low mantissa
/// bits: branch-free and vectorizable, unlike `round` (a libm call on the x86-64 baseline)
/// or a saturating float-to-integer cast, for each of the 128 samples of every particle.
#[inline(always)]
pub(crate) fn nearest(v: f64) -> i64 {
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
        // Every maximum, as a grey and as a pure and a half-saturated red, green and blue (the
        // value bins' boundaries sit at maxima 51, 102, 153, 204 and 255).
        let mut colours: Vec<[u8; 3]> = (0..=255u8)
            .flat_map(|v| [[v, v, v], [v, 0, 0], [0, v, 0], [0, 0, v], [v, v / 2, v / 2], [v / 2, v, 0], [0, v / 3, v]])
            .collect();
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
    fn every_backend_bins_all_2_pow_24_colours_as_the_integer_definition() {
        // One 256 x 256 frame per red level, green along x and blue along y.
        let mut bf = BinnedFrame::default();
        for r in 0..=255u8 {
            let frame = Plane::from_fn(256, 256, |g, b| [r, g as u8, b as u8]);
            for backend in Backend::available() {
                bf.update_with(backend, &frame);
                for b in 0..256 {
                    for g in 0..256 {
                        let want = bin_of([r, g as u8, b as u8]);
                        assert_eq!(bf.bins().get(g, b), want, "{backend:?} ({r}, {g}, {b})");
                    }
                }
            }
        }
    }

    #[test]
    fn a_region_binned_in_bands_on_any_pool_is_the_per_pixel_definition() {
        // 283 columns: bands of 28 rows from row 3, the last one partial; outside the
        // rectangle the bins stay as they were (0).
        let frame = Plane::from_fn(300, 200, |x, y| [(x * 7 + y) as u8, (y * 5) as u8, (x * 3 + y * 11) as u8]);
        let rect = [7, 3, 290, 197];
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            for backend in Backend::available() {
                let mut b = BinnedFrame::default();
                b.bins.resize(300, 200);
                b.bins.fill(0);
                pool.install(|| b.update_region_with(backend, &frame, rect));
                for y in 0..200 {
                    for x in 0..300 {
                        let inside = (7..290).contains(&x) && (3..197).contains(&y);
                        let want = if inside { bin_of(frame.get(x, y)) } else { 0 };
                        assert_eq!(b.bins().get(x, y), want, "{threads} threads {backend:?} ({x}, {y})");
                    }
                }
            }
        }
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
}
