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
//! when inlined into an AVX2 kernel.

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
    best_of: Vec<usize>,
    right_best: Vec<usize>,
    right_cost: Vec<u16>,
}

/// Selects the disparities of one row from its costs (`row.len() * d` values, `[x][d]`).
#[inline(always)]
pub(crate) fn select_row(costs: &[u16], d: usize, row: &mut [f32], rule: &WtaRule, s: &mut WtaScratch) {
    let w = row.len();
    s.best_of.clear();
    s.best_of.resize(w, usize::MAX);
    s.right_best.clear();
    s.right_best.resize(w, usize::MAX);
    s.right_cost.clear();
    s.right_cost.resize(w, u16::MAX);
    row.fill(f32::NAN);
    for x in rule.x_min..rule.x_max.min(w) {
        let c = &costs[x * d..(x + 1) * d];
        // Cost and index packed in one word: the minimum gives both (first index on ties).
        let mut packed = u32::MAX;
        for (k, &v) in (0u32..).zip(c) {
            packed = packed.min((v as u32) << 8 | k);
        }
        let (bc, best) = ((packed >> 8) as u16, (packed & 0xff) as usize);
        // The cheapest disparity not adjacent to the best (a masked full-length loop, which
        // vectorizes, rather than two loops of data-dependent length).
        let (lo, hi) = (best.saturating_sub(1) as u16, (best + 1) as u16);
        let mut other = u16::MAX;
        for (k, &v) in (0u16..).zip(c) {
            let far = k < lo || k > hi;
            other = other.min(if far { v } else { u16::MAX });
        }
        let ambiguous = (other as f32) * (1.0 - rule.margin) <= bc as f32;
        if ambiguous || bc == u16::MAX || best > x {
            continue;
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
        s.best_of[x] = best;
        let xr = x - best;
        if bc < s.right_cost[xr] {
            s.right_cost[xr] = bc;
            s.right_best[xr] = best;
        }
    }
    if rule.lr_max_diff >= 0.0 {
        for x in 0..w {
            if row[x].is_finite() {
                let rb = s.right_best[x - s.best_of[x]];
                if rb == usize::MAX || (rb as f32 - s.best_of[x] as f32).abs() > rule.lr_max_diff {
                    row[x] = f32::NAN;
                }
            }
        }
    }
}
