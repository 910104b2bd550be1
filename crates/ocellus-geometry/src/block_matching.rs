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

use crate::{GeometryError, Result};
use ocellus_image::Plane;

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
}

impl Default for BlockMatching {
    /// 64 disparities, 9x9 blocks, uniqueness 0.15, left-right agreement within 1 px.
    fn default() -> Self {
        Self { max_disparity: 64, block: 9, uniqueness: 0.15, lr_max_diff: 1.0, prefilter_cap: Some(31) }
    }
}

/// `cap + clamp(sobel_x, -cap, cap)` per pixel (borders replicated).
pub fn prefilter_xsobel(img: &Plane<u8>, cap: u8) -> Plane<u8> {
    let (w, h) = img.size();
    let c = cap as i32;
    Plane::from_fn(w, h, |x, y| {
        let g = |dx: isize, dy: isize| {
            let xx = (x as isize + dx).clamp(0, w as isize - 1) as usize;
            let yy = (y as isize + dy).clamp(0, h as isize - 1) as usize;
            img.row(yy)[xx] as i32
        };
        let s = (g(1, -1) - g(-1, -1)) + 2 * (g(1, 0) - g(-1, 0)) + (g(1, 1) - g(-1, 1));
        (s.clamp(-c, c) + c) as u8
    })
}

/// Disparity of the left image: pixels, NaN where invalid.
pub fn block_match(left: &Plane<u8>, right: &Plane<u8>, p: &BlockMatching) -> Result<Plane<f32>> {
    match p.prefilter_cap {
        Some(cap) if left.size() == right.size() => {
            let (l, r) = (prefilter_xsobel(left, cap), prefilter_xsobel(right, cap));
            block_match_raw(&l, &r, p)
        }
        _ => block_match_raw(left, right, p),
    }
}

fn block_match_raw(left: &Plane<u8>, right: &Plane<u8>, p: &BlockMatching) -> Result<Plane<f32>> {
    if left.size() != right.size() {
        return Err(GeometryError::Invalid(format!(
            "left image is {}x{}, right image {}x{}",
            left.width(),
            left.height(),
            right.width(),
            right.height()
        )));
    }
    if p.block % 2 == 0 || p.block < 3 || p.max_disparity == 0 || !p.uniqueness.is_finite() || p.uniqueness < 0.0 {
        return Err(GeometryError::Invalid(format!("block matching {p:?}: odd block >= 3, max_disparity >= 1")));
    }
    let (w, h) = left.size();
    let r = p.block / 2;
    if w < p.block || h < p.block {
        return Err(GeometryError::Invalid(format!("image {w}x{h} smaller than the {0}x{0} block", p.block)));
    }
    let nd = p.max_disparity.min(w);
    let mut out = Plane::from_fn(w, h, |_, _| f32::NAN);
    // colsum[d * w + x]: sum over the block's rows of |L(x, .) - R(x - d, .)|.
    let mut colsum = vec![0u32; nd * w];
    let diff =
        |y: usize, x: usize, d: usize| -> u32 { (left.row(y)[x] as i32 - right.row(y)[x - d] as i32).unsigned_abs() };
    for yy in 0..p.block {
        for d in 0..nd {
            for x in d..w {
                colsum[d * w + x] += diff(yy, x, d);
            }
        }
    }
    // cost[d * w + x] for the current row (contiguous per disparity for the box sums).
    let big = u32::MAX / 4;
    let mut cost = vec![big; w * nd];
    let (mut best_v, mut best_d) = (vec![0u32; w], vec![0u32; w]);
    let (mut right_v, mut right_d) = (vec![0u32; w], vec![0u32; w]);
    let mut ambiguous = vec![false; w];
    for y in r..h - r {
        if y > r {
            // Slide the column sums down one row.
            let (add, sub) = (y + r, y - r - 1);
            for d in 0..nd {
                let (la, ra, ls, rs) = (left.row(add), right.row(add), left.row(sub), right.row(sub));
                let cs = &mut colsum[d * w + d..(d + 1) * w];
                // Zipped slices: no bounds checks, so the loop vectorizes.
                let it = cs.iter_mut().zip(&la[d..]).zip(&ra[..w - d]).zip(ls[d..].iter().zip(&rs[..w - d]));
                for (((c, &a1), &a2), (&s1, &s2)) in it {
                    let a = (a1 as i32 - a2 as i32).unsigned_abs();
                    let s = (s1 as i32 - s2 as i32).unsigned_abs();
                    *c = *c + a - s;
                }
            }
        }
        // Horizontal box sums: windows centred at x need columns x - r ..= x + r >= d.
        cost.fill(big);
        for d in 0..nd {
            let cs = &colsum[d * w..(d + 1) * w];
            let x0 = d + r;
            if x0 + r >= w {
                continue;
            }
            let mut s: u32 = cs[x0 - r..=x0 + r].iter().sum();
            let out = &mut cost[d * w..(d + 1) * w];
            out[x0] = s;
            let (adds, subs) = (&cs[x0 + r + 1..], &cs[x0 - r..w - 2 * r - 1]);
            for ((o, &a), &b) in out[x0 + 1..w - r].iter_mut().zip(adds).zip(subs) {
                s = s + a - b;
                *o = s;
            }
        }
        // Per-row passes over the disparities (contiguous, vectorizable), in the order a
        // per-pixel scan would visit them, so ties resolve the same way (first minimum).
        best_v.fill(u32::MAX);
        best_d.fill(0);
        right_v.fill(u32::MAX);
        right_d.fill(0);
        for d in 0..nd {
            let cd = &cost[d * w..(d + 1) * w];
            for (x, &v) in cd.iter().enumerate() {
                if v < best_v[x] {
                    best_v[x] = v;
                    best_d[x] = d as u32;
                }
            }
            // Right pixel xr matches left pixel xr + d at disparity d.
            for (xr, &v) in cd[d..].iter().enumerate() {
                if v < right_v[xr] {
                    right_v[xr] = v;
                    right_d[xr] = d as u32;
                }
            }
        }
        ambiguous.fill(false);
        for d in 0..nd {
            let cd = &cost[d * w..(d + 1) * w];
            for (x, &v) in cd.iter().enumerate() {
                let limit = best_v[x] as f32 * (1.0 + p.uniqueness);
                let far = (d as u32).abs_diff(best_d[x]) > 1;
                ambiguous[x] |= far && (v as f32) <= limit && v < big;
            }
        }
        let row = out.row_mut(y);
        for x in (nd - 1 + r)..w - r {
            let (bd, best) = (best_d[x] as usize, best_v[x]);
            if best >= big || ambiguous[x] {
                continue;
            }
            if p.lr_max_diff >= 0.0 && (right_d[x - bd] as f32 - bd as f32).abs() > p.lr_max_diff {
                continue;
            }
            // Sub-pixel: vertex of the parabola through d - 1, d, d + 1.
            let mut dsub = bd as f32;
            if bd > 0 && bd + 1 < nd {
                let (cm, cp) = (cost[(bd - 1) * w + x], cost[(bd + 1) * w + x]);
                if cm < big && cp < big {
                    let den = cm as f32 + cp as f32 - 2.0 * best as f32;
                    if den > 0.0 {
                        dsub += 0.5 * (cm as f32 - cp as f32) / den;
                    }
                }
            }
            row[x] = dsub;
        }
    }
    Ok(out)
}

/// Share of pixels with known ground truth (finite) whose estimate is off by more than
/// `threshold` pixels, invalid estimates counted as bad (Middlebury "bad-2.0" for 2), and the
/// density of valid estimates over those pixels.
pub fn bad_pixels(estimate: &Plane<f32>, truth: &Plane<f32>, threshold: f32) -> Result<(f64, f64)> {
    if estimate.size() != truth.size() {
        return Err(GeometryError::Invalid("estimate and ground truth differ in size".into()));
    }
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
    fn bad_inputs_are_errors() {
        let a = Plane::new(20, 20);
        assert!(block_match(&a, &Plane::new(21, 20), &BlockMatching::default()).is_err());
        assert!(block_match(&a, &a, &BlockMatching { block: 4, ..Default::default() }).is_err());
        assert!(block_match(&Plane::new(5, 5), &Plane::new(5, 5), &BlockMatching::default()).is_err());
        // A flat pair has no unique match anywhere: all invalid, no panic.
        let flat = block_match(&a, &a, &BlockMatching { max_disparity: 8, ..Default::default() }).unwrap();
        // The prefilter of a flat image is flat too.
        assert!(prefilter_xsobel(&a, 31).to_vec().iter().all(|&v| v == 31));
        assert!(flat.to_vec().iter().all(|v| v.is_nan()));
        assert!(bad_pixels(&flat, &Plane::from_fn(20, 20, |_, _| f32::INFINITY), 2.0).is_err());
    }
}
