//! Dense disparity on a rectified pair by block matching (SPEC 5.6).
//!
//! For every left pixel (x, y) and disparity d in `0..max_disparity`, the cost is the sum of
//! absolute grey differences between the `block` x `block` window around (x, y) in the left
//! image and around (x - d, y) in the right image. Costs are built row by row from running
//! column sums (one add and one subtract per pixel and disparity), so the work is
//! O(width x height x disparities) whatever the block size.
//!
//! A pixel gets the disparity of least cost, refined to sub-pixel by a parabola through the
//! costs at d - 1, d, d + 1, unless one of the tests fails (then it is invalid, NaN):
//! - uniqueness: another disparity, not adjacent to the best, costs less than
//!   at most `best * (1 + uniqueness)` (ties, as on textureless surfaces, are ambiguous);
//! - left-right consistency: the best match of the right pixel (x - d, y), searched over the
//!   same costs, is more than `lr_max_diff` pixels from d;
//! - the search is incomplete: within `block / 2` of the border, or `x < max_disparity - 1 +
//!   block / 2` (some disparities would put the right window outside the image; OpenCV's
//!   block matcher leaves this band invalid too).
//!
//! Left pixel (x, y) with disparity d matches right pixel (x - d, y) (Middlebury convention).

use crate::wta::{SubPixel, WtaRule, WtaScratch};
use crate::{GeometryError, Result};
use ocellus_image::simd::Madd;
use ocellus_image::{dispatch_kernel, Backend, Plane};

/// Parameters of [`block_match`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlockMatching {
    /// Disparities searched: `0..max_disparity`.
    pub max_disparity: usize,
    /// Odd window size, pixels.
    pub block: usize,
    /// Uniqueness margin (0.15: the best must beat every non-adjacent disparity by 15 %).
    pub uniqueness: f32,
    /// Largest left-right disagreement kept, pixels (negative disables the check).
    pub lr_max_diff: f32,
    /// Match on the horizontal Sobel derivative clipped to `[-cap, cap]` instead of grey
    /// values (OpenCV's `PREFILTER_XSOBEL`, cap 31): robust to the exposure and lighting
    /// differences of real pairs. `None` matches raw grey values.
    pub prefilter_cap: Option<u8>,
    /// Which build of the kernels runs (`Auto`: the fastest this CPU has).
    pub backend: Backend,
}

impl Default for BlockMatching {
    /// 64 disparities, 9x9 blocks, uniqueness 0.15, left-right agreement within 1 px.
    fn default() -> Self {
        Self {
            max_disparity: 64,
            block: 9,
            uniqueness: 0.15,
            lr_max_diff: 1.0,
            prefilter_cap: Some(31),
            backend: Backend::Auto,
        }
    }
}

/// `cap + clamp(sobel_x, -cap, cap)` per pixel (borders replicated). The result must fit a
/// byte: caps above 127 are taken as 127.
pub fn prefilter_xsobel(img: &Plane<u8>, cap: u8) -> Plane<u8> {
    let (w, h) = img.size();
    let c = cap.min(127) as i16;
    let mut out = Plane::new(w, h);
    // The horizontal difference of every row once, then the vertical [1 2 1] of them.
    let mut diff = vec![0i16; w * h];
    for (y, d) in diff.chunks_exact_mut(w).enumerate() {
        let r = img.row(y);
        if w == 1 {
            continue;
        }
        d[0] = r[1] as i16 - r[0] as i16;
        d[w - 1] = r[w - 1] as i16 - r[w - 2] as i16;
        for ((o, &a), &b) in d[1..w - 1].iter_mut().zip(&r[2..]).zip(&r[..w - 2]) {
            *o = a as i16 - b as i16;
        }
    }
    let row = |y: usize| &diff[y * w..(y + 1) * w];
    for y in 0..h {
        let (up, mid, down) = (row(y.saturating_sub(1)), row(y), row((y + 1).min(h - 1)));
        for (((o, &a), &b), &cc) in out.row_mut(y).iter_mut().zip(up).zip(mid).zip(down) {
            *o = ((a + 2 * b + cc).clamp(-c, c) + c) as u8;
        }
    }
    out
}

/// Disparity of the left image: pixels, NaN where invalid.
pub fn block_match(left: &Plane<u8>, right: &Plane<u8>, p: &BlockMatching) -> Result<Plane<f32>> {
    match p.prefilter_cap {
        // The prefiltered values are 0..=2 cap and must fit a byte.
        Some(cap) if cap == 0 || cap > 127 => {
            Err(GeometryError::Invalid(format!("prefilter cap {cap} must be 1..=127")))
        }
        Some(cap) if left.size() == right.size() => {
            let (l, r) = (prefilter_xsobel(left, cap), prefilter_xsobel(right, cap));
            block_match_raw(&l, &r, p, 2 * cap as usize)
        }
        _ => block_match_raw(left, right, p, u8::MAX as usize),
    }
}

/// `top`: the largest value the images can hold (for the 16-bit cost bound).
fn block_match_raw(left: &Plane<u8>, right: &Plane<u8>, p: &BlockMatching, top: usize) -> Result<Plane<f32>> {
    ocellus_image::check::same_size("right image (against the left)", right.size(), left.size())?;
    if p.block.is_multiple_of(2) || p.block < 3 {
        return Err(GeometryError::Invalid(format!("block size {} must be odd and at least 3", p.block)));
    }
    ocellus_image::check::within("max_disparity", p.max_disparity, 1, 256).map_err(GeometryError::Invalid)?;
    ocellus_image::check::within("uniqueness", p.uniqueness, 0.0, 0.99).map_err(GeometryError::Invalid)?;
    let (w, h) = left.size();
    if w < p.block || h < p.block {
        return Err(GeometryError::Invalid(format!("image {w}x{h} smaller than the {0}x{0} block", p.block)));
    }
    // Costs are u16: the largest window sum must fit.
    if p.block * p.block * top > u16::MAX as usize - 1 {
        return Err(GeometryError::Invalid(format!(
            "block {0}x{0} with grey values up to {top} overflows 16-bit costs: use a smaller block or the prefilter",
            p.block
        )));
    }
    let mut out = Plane::new(w, h);
    sad_kernel(p.backend, left, right, p, &mut out);
    Ok(out)
}

/// SAD costs `[x][d]` row by row from running sums, and the winner per pixel.
#[inline(always)]
fn sad_generic<M: Madd>(left: &Plane<u8>, right: &Plane<u8>, p: &BlockMatching, out: &mut Plane<f32>) {
    let (w, h) = left.size();
    let r = p.block / 2;
    let nd = p.max_disparity.min(w);
    // Right rows reversed, so that disparities run forward through memory:
    // reversed[w - 1 - x + d] = right[x - d].
    let reversed = |y: usize| -> Vec<u8> { right.row(y).iter().rev().copied().collect() };
    // colsum[x * nd + d]: sum over the window's rows of |L(x, .) - R(x - d, .)| (d <= x;
    // the other lanes stay 0, so the wrapping box sums below are exact where used).
    let mut colsum = vec![0u16; w * nd];
    let add_row = |colsum: &mut [u16], y: usize, sign_add: bool| {
        let (l, rr) = (left.row(y), reversed(y));
        for x in 0..w {
            let valid = nd.min(x + 1);
            let base = w - 1 - x;
            let lx = l[x];
            let cs = &mut colsum[x * nd..x * nd + valid];
            for (c, &rv) in cs.iter_mut().zip(&rr[base..base + valid]) {
                let a = lx.abs_diff(rv) as u16;
                *c = if sign_add { c.wrapping_add(a) } else { c.wrapping_sub(a) };
            }
        }
    };
    for yy in 0..p.block {
        add_row(&mut colsum, yy, true);
    }
    let mut cost = vec![0u16; nd];
    let rule = WtaRule {
        // "cost <= best (1 + u)" is "cost (1 - u / (1 + u)) <= best".
        margin: p.uniqueness / (1.0 + p.uniqueness),
        lr_max_diff: p.lr_max_diff,
        subpixel: SubPixel::Parabola,
        x_min: nd - 1 + r,
        x_max: w - r,
    };
    let mut scratch = WtaScratch::default();
    let (mut l_add, mut r_add, mut l_sub, mut r_sub) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for y in 0..h {
        if y < r || y + r >= h {
            out.row_mut(y).fill(f32::NAN);
            continue;
        }
        if y > r {
            // Slide the column sums down one row: add row y + r, remove row y - r - 1.
            let (add, sub) = (y + r, y - r - 1);
            l_add.clear();
            l_add.extend_from_slice(left.row(add));
            l_sub.clear();
            l_sub.extend_from_slice(left.row(sub));
            r_add.clear();
            r_add.extend(right.row(add).iter().rev());
            r_sub.clear();
            r_sub.extend(right.row(sub).iter().rev());
            for x in 0..w {
                let valid = nd.min(x + 1);
                let base = w - 1 - x;
                let (la, ls) = (l_add[x], l_sub[x]);
                let cs = &mut colsum[x * nd..x * nd + valid];
                for ((c, &ra), &rs) in cs.iter_mut().zip(&r_add[base..base + valid]).zip(&r_sub[base..base + valid]) {
                    // |a - b| as max - min in u8 lanes (32 per AVX2 register), then widened.
                    let a = (la.max(ra) - la.min(ra)) as u16;
                    let b = (ls.max(rs) - ls.min(rs)) as u16;
                    *c = c.wrapping_add(a).wrapping_sub(b);
                }
            }
        }
        // Box sums along x, all disparities at once (cost(x) = cost(x - 1) + col(x + r) -
        // col(x - r - 1)), each pixel selected as soon as its sums are known.
        let row = out.row_mut(y);
        scratch.begin(row, &rule);
        cost.fill(0);
        for xx in 0..=2 * r {
            for (c, &v) in cost.iter_mut().zip(&colsum[xx * nd..(xx + 1) * nd]) {
                *c = c.wrapping_add(v);
            }
        }
        for x in r..w - r {
            if x > r {
                let (a, b) = (&colsum[(x + r) * nd..(x + r + 1) * nd], &colsum[(x - r - 1) * nd..(x - r) * nd]);
                for ((c, &av), &bv) in cost.iter_mut().zip(a).zip(b) {
                    *c = c.wrapping_add(av).wrapping_sub(bv);
                }
            }
            if x >= rule.x_min && x < rule.x_max {
                scratch.pixel::<M>(x, &cost, row, &rule);
            }
        }
        scratch.finish(row, &rule);
    }
}

dispatch_kernel!(fn sad_kernel => sad_generic(left: &Plane<u8>, right: &Plane<u8>, p: &BlockMatching, out: &mut Plane<f32>));

/// Share of pixels with known ground truth (finite) whose estimate is off by more than
/// `threshold` pixels, invalid estimates counted as bad (Middlebury "bad-2.0" for 2), and the
/// density of valid estimates over those pixels.
pub fn bad_pixels(estimate: &Plane<f32>, truth: &Plane<f32>, threshold: f32) -> Result<(f64, f64)> {
    ocellus_image::check::same_size("disparity estimate (against the ground truth)", estimate.size(), truth.size())?;
    let (mut known, mut bad, mut valid) = (0usize, 0usize, 0usize);
    for y in 0..truth.height() {
        for (&e, &t) in estimate.row(y).iter().zip(truth.row(y)) {
            if !t.is_finite() {
                continue;
            }
            known += 1;
            if e.is_finite() {
                valid += 1;
                if (e - t).abs() > threshold {
                    bad += 1;
                }
            } else {
                bad += 1;
            }
        }
    }
    if known == 0 {
        return Err(GeometryError::Degenerate("no pixel has a known ground truth".into()));
    }
    Ok((bad as f64 / known as f64, valid as f64 / known as f64))
}

#[cfg(test)]
mod tests {
    use super::*;
    use ocellus_image::rng::SplitMix64;

    #[test]
    fn random_dot_pair_with_known_shift() {
        // Random texture; the right image is the left shifted by 7 px, and a square region
        // shifted by 12 px (a nearer object).
        let mut rng = SplitMix64::new(5);
        let tex: Vec<u8> = (0..200 * 120).map(|_| (rng.next_u64() & 255) as u8).collect();
        let left = Plane::from_fn(160, 100, |x, y| tex[y * 200 + x + 20]);
        // Truth where the search is complete (x >= 19 + 4, 4 px from the borders).
        let truth = Plane::from_fn(160, 100, |x, y| {
            if !(23..156).contains(&x) || !(4..96).contains(&y) {
                f32::INFINITY
            } else if (60..100).contains(&x) && (30..70).contains(&y) {
                12.0f32
            } else {
                7.0
            }
        });
        let right = Plane::from_fn(160, 100, |x, y| {
            // Right pixel x shows the left pixel x + d of the surface it belongs to.
            let near = (60 - 12..100 - 12).contains(&x) && (30..70).contains(&y);
            let d = if near { 12 } else { 7 };
            tex[y * 200 + (x + d).min(199) + 20]
        });
        let est = block_match(&left, &right, &BlockMatching { max_disparity: 20, ..Default::default() }).unwrap();
        let (bad, density) = bad_pixels(&est, &truth, 0.5).unwrap();
        // What fails is the occlusion and edge band of the near square.
        assert!(bad < 0.1 && density > 0.9, "bad {bad}, density {density}");
        // Away from borders and object edges every estimate is exact.
        for (x, y, want) in [(30usize, 50usize, 7.0f32), (80, 50, 12.0), (130, 15, 7.0)] {
            assert!((est.get(x, y) - want).abs() < 0.1, "({x}, {y}): {}", est.get(x, y));
        }
    }

    #[test]
    fn prefilter_matches_a_direct_sobel() {
        let mut rng = SplitMix64::new(6);
        let img = Plane::from_fn(37, 23, |_, _| (rng.next_u64() & 255) as u8);
        let f = prefilter_xsobel(&img, 31);
        for y in 0..23 {
            for x in 0..37 {
                let g = |dx: isize, dy: isize| {
                    img.get((x as isize + dx).clamp(0, 36) as usize, (y as isize + dy).clamp(0, 22) as usize) as i32
                };
                let s = (g(1, -1) - g(-1, -1)) + 2 * (g(1, 0) - g(-1, 0)) + (g(1, 1) - g(-1, 1));
                assert_eq!(f.get(x, y) as i32, s.clamp(-31, 31) + 31, "({x}, {y})");
            }
        }
    }

    #[test]
    fn bad_inputs_are_errors() {
        let a = Plane::new(20, 20);
        assert!(block_match(&a, &Plane::new(21, 20), &BlockMatching::default()).is_err());
        assert!(block_match(&a, &a, &BlockMatching { block: 4, ..Default::default() }).is_err());
        assert!(block_match(&a, &a, &BlockMatching { prefilter_cap: Some(200), ..Default::default() }).is_err());
        assert!(block_match(&Plane::new(5, 5), &Plane::new(5, 5), &BlockMatching::default()).is_err());
        // A flat pair has no unique match anywhere: all invalid, no panic.
        let flat = block_match(&a, &a, &BlockMatching { max_disparity: 8, ..Default::default() }).unwrap();
        // The prefilter of a flat image is flat too.
        assert!(prefilter_xsobel(&a, 31).to_vec().iter().all(|&v| v == 31));
        assert!(flat.to_vec().iter().all(|v| v.is_nan()));
        assert!(bad_pixels(&flat, &Plane::from_fn(20, 20, |_, _| f32::INFINITY), 2.0).is_err());
    }
}
