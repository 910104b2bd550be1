//! Center-surround differences across scales (SPEC 1.5).

use ocellus_image::Plane;

/// One center-surround pair of pyramid levels (level 0 = input).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ScalePair {
    /// Centre (finer) level c.
    pub center: usize,
    /// Surround (coarser) level s = c + delta.
    pub surround: usize,
}

/// All (c, c + delta) pairs, centres outer, deltas inner: (2,5) (2,6) (3,6) (3,7) (4,7) (4,8)
/// for the standard parameters.
pub fn scale_pairs(centers: &[usize], deltas: &[usize]) -> Vec<ScalePair> {
    centers.iter().flat_map(|&c| deltas.iter().map(move |&d| ScalePair { center: c, surround: c + d })).collect()
}

/// `out = |center - surround|`, both already at the map level.
pub fn abs_difference(center: &Plane<f32>, surround: &Plane<f32>, out: &mut Plane<f32>) {
    let (w, h) = center.size();
    out.resize(w, h);
    for y in 0..h {
        let (c, s) = (center.row(y), surround.row(y));
        for ((o, a), b) in out.row_mut(y).iter_mut().zip(c).zip(s) {
            *o = (a - b).abs();
        }
    }
}

/// Border ramp width in pixels: `round(frac * max(w, h))`.
pub fn ramp_width(w: usize, h: usize, frac: f32) -> usize {
    (frac * w.max(h) as f32).round() as usize
}

/// Multiplies the outer `n` rows and columns by a linear ramp `k / (n + 1)`, k = 1..n from
/// the edge (SaliencyToolbox `attenuateBorders`); `n` is reduced to fit the map.
pub fn attenuate_borders(map: &mut Plane<f32>, n: usize) {
    let (w, h) = map.size();
    let n = n.min(h / 2).min(w / 2);
    if n == 0 {
        return;
    }
    for k in 0..n {
        let c = (k + 1) as f32 / (n + 1) as f32;
        map.row_mut(k).iter_mut().for_each(|v| *v *= c);
        map.row_mut(h - 1 - k).iter_mut().for_each(|v| *v *= c);
    }
    for y in 0..h {
        let row = map.row_mut(y);
        for k in 0..n {
            let c = (k + 1) as f32 / (n + 1) as f32;
            row[k] *= c;
            row[w - 1 - k] *= c;
        }
    }
}
