//! Measures of a learned sensor layout (SPEC 8.3): where each receptive field sits, how large
//! it is, and whether fields grow with eccentricity (a fovea).

use crate::disc::Disc;
use crate::{Real, Result, RetinaError};

/// One receptive field (a row of S) summarized.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Field {
    /// Index of the row of S.
    pub index: usize,
    /// Centre: the weighted mean of the pixels at or above half the field's maximum,
    /// pixels from the gaze point (x right, y down).
    pub centre: [f64; 2],
    /// Distance of the centre from the gaze point, pixels.
    pub eccentricity: f64,
    /// Size: the number of pixels at or above half the maximum (pixels, i.e. px^2).
    pub area_px: f64,
    /// The largest weight.
    pub peak: f64,
}

/// The layout of all live fields and the relations the seed's figures show.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Layout {
    /// The live fields (peak above 1e-3 of the largest peak; the others have died out).
    pub fields: Vec<Field>,
    /// Fields that died out.
    pub dead: usize,
    /// The fovea index: Pearson correlation of size (area) with eccentricity over the live
    /// fields; positive when fields grow toward the periphery. 0 with fewer than 3 fields
    /// or no spread.
    pub fovea_index: f64,
    /// The fovea index over the interior fields only: those whose half-maximum disc (of the
    /// field's area) lies inside the sensor, 0.5 px from its rim. The rim cuts the fields
    /// there and makes them look smaller or larger than they are; this index is free of that.
    /// 0 with fewer than 3 interior fields.
    pub fovea_index_interior: f64,
    /// Interior fields counted in [`fovea_index_interior`](Self::fovea_index_interior).
    pub interior_fields: usize,
    /// 95 % confidence interval of [`fovea_index`](Self::fovea_index) ([`correlation_ci95`]):
    /// an index is told apart from 0 only when the interval excludes 0.
    #[serde(default = "full_interval")]
    pub fovea_index_ci95: [f64; 2],
    /// 95 % confidence interval of [`fovea_index_interior`](Self::fovea_index_interior).
    #[serde(default = "full_interval")]
    pub fovea_index_interior_ci95: [f64; 2],
    /// Least-squares slope of area against eccentricity, px^2 per px.
    pub slope_px2_per_px: f64,
    /// Field centres per unit area inside half the disc radius over those outside it
    /// (1 for a uniform layout); `None` when no centre lies outside.
    pub density_ratio: Option<f64>,
    /// Mean area of the fields whose centres lie inside half the radius, px^2.
    pub mean_area_centre_px: f64,
    /// Mean area of those outside it, px^2.
    pub mean_area_periphery_px: f64,
}

/// Summarizes each row of `s` (fields x pixels over `disc`).
pub fn measure<T: Real>(disc: &Disc, s: &[T], fields: usize) -> Result<Layout> {
    let n = disc.len();
    if fields == 0 || s.len() != fields * n {
        return Err(RetinaError::Invalid(format!("S has {} entries, not {fields} fields x {n} pixels", s.len())));
    }
    let peaks: Vec<f64> =
        (0..fields).map(|i| s[i * n..(i + 1) * n].iter().map(|v| v.to_f64()).fold(0.0, f64::max)).collect();
    let top = peaks.iter().copied().fold(0.0, f64::max);
    let mut out = Vec::new();
    for i in 0..fields {
        let peak = peaks[i];
        // NaN peaks count as dead too.
        if peak.is_nan() || peak <= 1e-3 * top {
            continue;
        }
        let (mut w, mut cx, mut cy, mut area) = (0.0, 0.0, 0.0, 0.0);
        for (j, &[x, y]) in disc.offsets().iter().enumerate() {
            let v = s[i * n + j].to_f64();
            if v >= 0.5 * peak {
                area += 1.0;
                w += v;
                cx += v * x as f64;
                cy += v * y as f64;
            }
        }
        let centre = [cx / w, cy / w];
        out.push(Field { index: i, centre, eccentricity: centre[0].hypot(centre[1]), area_px: area, peak });
    }
    let dead = fields - out.len();
    let (fovea_index, slope) = correlation(&out);
    let rim = disc.radius() - 0.5;
    let interior: Vec<Field> =
        out.iter().filter(|f| f.eccentricity + (f.area_px / std::f64::consts::PI).sqrt() < rim).copied().collect();
    let (fovea_index_interior, _) = correlation(&interior);
    let half = 0.5 * disc.radius();
    let (inner, outer): (Vec<&Field>, Vec<&Field>) = out.iter().partition(|f| f.eccentricity < half);
    let mean =
        |v: &[&Field]| if v.is_empty() { 0.0 } else { v.iter().map(|f| f.area_px).sum::<f64>() / v.len() as f64 };
    // Areas: a disc of half the radius holds a quarter of the disc.
    let density_ratio = (!outer.is_empty()).then(|| 3.0 * inner.len() as f64 / outer.len() as f64);
    Ok(Layout {
        dead,
        fovea_index,
        fovea_index_interior,
        interior_fields: interior.len(),
        fovea_index_ci95: correlation_ci95(fovea_index, out.len()),
        fovea_index_interior_ci95: correlation_ci95(fovea_index_interior, interior.len()),
        slope_px2_per_px: slope,
        density_ratio,
        mean_area_centre_px: mean(&inner),
        mean_area_periphery_px: mean(&outer),
        fields: out,
    })
}

/// What an interval says when nothing is known: the whole range of a correlation.
fn full_interval() -> [f64; 2] {
    [-1.0, 1.0]
}

/// Two-sided 95 % quantile of the standard normal.
const Z95: f64 = 1.959_963_984_540_054;

/// 95 % confidence interval of a Pearson correlation `r` over `n` pairs, by Fisher's z
/// transformation: `atanh(r)` is close to normal with standard error `1 / sqrt(n - 3)` (Fisher
/// 1921). With 48 fields an index within about +-0.28 of 0 is not told apart from 0.
/// `[-1, 1]` for fewer than 4 pairs or a non-finite `r`.
pub fn correlation_ci95(r: f64, n: usize) -> [f64; 2] {
    pooled_correlation(&[(r, n)]).map(|p| p.ci95).unwrap_or_else(full_interval)
}

/// Correlations of several runs (e.g. seeds) pooled into one.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Pooled {
    /// The pooled correlation.
    pub r: f64,
    /// Its 95 % confidence interval.
    pub ci95: [f64; 2],
    /// Runs pooled.
    pub runs: usize,
    /// Pairs (fields) over all runs.
    pub pairs: usize,
}

/// Pools correlations `(r, n)` of independent runs: the mean of their Fisher z weighted by
/// `n - 3` (the inverse of each z's variance), with the standard error `1 / sqrt(sum(n - 3))`
/// (the fixed-effect estimate of Hedges & Olkin 1985, ch. 11). Runs with fewer than 4 pairs
/// or a non-finite `r` are left out; `None` when none is left.
pub fn pooled_correlation(runs: &[(f64, usize)]) -> Option<Pooled> {
    // |r| = 1 has an infinite z; clamp just inside.
    let lim = 1.0 - 1e-12;
    let used: Vec<(f64, f64, usize)> = runs
        .iter()
        .filter(|(r, n)| r.is_finite() && *n >= 4)
        .map(|&(r, n)| (r.clamp(-lim, lim).atanh(), (n - 3) as f64, n))
        .collect();
    let w: f64 = used.iter().map(|u| u.1).sum();
    if used.is_empty() || w <= 0.0 {
        return None;
    }
    let z = used.iter().map(|u| u.0 * u.1).sum::<f64>() / w;
    let se = 1.0 / w.sqrt();
    Some(Pooled {
        r: z.tanh(),
        ci95: [(z - Z95 * se).tanh(), (z + Z95 * se).tanh()],
        runs: used.len(),
        pairs: used.iter().map(|u| u.2).sum(),
    })
}

/// Pearson correlation and least-squares slope of area against eccentricity.
fn correlation(f: &[Field]) -> (f64, f64) {
    if f.len() < 3 {
        return (0.0, 0.0);
    }
    let n = f.len() as f64;
    let (mx, my) = (f.iter().map(|v| v.eccentricity).sum::<f64>() / n, f.iter().map(|v| v.area_px).sum::<f64>() / n);
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for v in f {
        let (dx, dy) = (v.eccentricity - mx, v.area_px - my);
        sxx += dx * dx;
        syy += dy * dy;
        sxy += dx * dy;
    }
    if sxx <= 0.0 || syy <= 0.0 {
        return (0.0, if sxx > 0.0 { sxy / sxx } else { 0.0 });
    }
    (sxy / (sxx * syy).sqrt(), sxy / sxx)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Fields as Gaussian blobs of a given width at given centres.
    fn blobs(disc: &Disc, spec: &[([f64; 2], f64)]) -> Vec<f64> {
        let mut s = Vec::new();
        for &(c, w) in spec {
            for &[x, y] in disc.offsets() {
                let d2 = (x as f64 - c[0]).powi(2) + (y as f64 - c[1]).powi(2);
                s.push((-d2 / (2.0 * w * w)).exp());
            }
        }
        s
    }

    #[test]
    fn growing_fields_give_a_positive_fovea_index_and_equal_ones_zero() {
        let disc = Disc::with_pixels(2877).unwrap();
        // Fields on a spiral, their width growing with eccentricity.
        let spec: Vec<([f64; 2], f64)> = (0..24)
            .map(|i| {
                let (r, a) = (1.0 + i as f64, i as f64 * 2.4);
                ([r * a.cos(), r * a.sin()], 1.0 + 0.15 * r)
            })
            .collect();
        let l = measure(&disc, &blobs(&disc, &spec), 24).unwrap();
        assert_eq!(l.fields.len(), 24);
        assert!(l.fovea_index > 0.9, "{}", l.fovea_index);
        // Every half-maximum disc lies inside (r + 1.18 w < 29.7 up to r = 24).
        assert_eq!(l.interior_fields, 24);
        assert!((l.fovea_index_interior - l.fovea_index).abs() < 1e-12);
        // A field at the rim is cut and counts only in the plain index.
        let mut rimmed = spec.clone();
        rimmed.push(([29.0, 0.0], 3.0));
        let l = measure(&disc, &blobs(&disc, &rimmed), 25).unwrap();
        assert_eq!((l.fields.len(), l.interior_fields), (25, 24));
        // The area above half maximum of a Gaussian of width w is about 2 ln 2 pi w^2 px^2:
        // the slope follows from d/dr of that at the mean width.
        assert!(l.slope_px2_per_px > 0.0 && l.mean_area_periphery_px > l.mean_area_centre_px);
        // The centre of a blob is where it was put.
        assert!((l.fields[5].centre[0] - spec[5].0[0]).abs() < 0.3);
        let same: Vec<([f64; 2], f64)> = spec.iter().map(|&(c, _)| (c, 2.0)).collect();
        let l = measure(&disc, &blobs(&disc, &same), 24).unwrap();
        assert!(l.fovea_index.abs() < 0.3, "{}", l.fovea_index);
        assert!(l.fovea_index_interior.abs() < 0.3, "{}", l.fovea_index_interior);
        assert!(measure(&disc, &[0.0f64; 10], 2).is_err());
    }

    #[test]
    fn the_interval_of_a_correlation_is_fishers() {
        // r = 0.5, n = 28: z = atanh 0.5 = 0.549306, se = 0.2, z +- 1.96 se -> tanh.
        let [lo, hi] = correlation_ci95(0.5, 28);
        assert!((lo - 0.156_5).abs() < 1e-3 && (hi - 0.735_6).abs() < 1e-3, "{lo} {hi}");
        assert_eq!(correlation_ci95(0.3, 3), [-1.0, 1.0]);
        assert_eq!(correlation_ci95(f64::NAN, 30), [-1.0, 1.0]);
        let [lo, hi] = correlation_ci95(1.0, 10);
        assert!(lo > 0.99 && hi <= 1.0);
        // Equal runs pool to the same r with the interval of all their pairs together.
        let p = pooled_correlation(&[(0.5, 28), (0.5, 28), (f64::NAN, 40), (0.9, 2)]).unwrap();
        assert!((p.r - 0.5).abs() < 1e-12);
        assert_eq!((p.runs, p.pairs), (2, 56));
        let direct = correlation_ci95(0.5, 53);
        assert!((p.ci95[0] - direct[0]).abs() < 1e-12 && (p.ci95[1] - direct[1]).abs() < 1e-12);
        assert!(pooled_correlation(&[(0.2, 3)]).is_none());
    }

    /// The interval covers the true correlation of bivariate normal samples 95 % of the time.
    #[test]
    fn the_interval_covers_the_true_correlation_as_often_as_it_says() {
        let mut rng = ocellus_image::rng::SplitMix64::new(7);
        let mut normal = move || {
            // Box-Muller.
            let (u, v) = (rng.unit().max(1e-300), rng.unit());
            (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
        };
        let (rho, n, reps) = (0.4f64, 40, 4000);
        let mut covered = 0;
        for _ in 0..reps {
            let pairs: Vec<(f64, f64)> = (0..n)
                .map(|_| {
                    let (a, b) = (normal(), normal());
                    (a, rho * a + (1.0 - rho * rho).sqrt() * b)
                })
                .collect();
            let fields: Vec<Field> = pairs
                .iter()
                .map(|&(x, y)| Field { index: 0, centre: [0.0; 2], eccentricity: x, area_px: y, peak: 1.0 })
                .collect();
            let [lo, hi] = correlation_ci95(correlation(&fields).0, n);
            covered += usize::from(lo <= rho && rho <= hi);
        }
        // Binomial standard deviation of the share: sqrt(0.95 0.05 / 4000) = 0.0034.
        let share = covered as f64 / reps as f64;
        assert!((share - 0.95).abs() < 0.012, "{share}");
    }

    #[test]
    fn a_dead_field_is_counted_apart() {
        let disc = Disc::with_pixels(481).unwrap();
        let mut s = blobs(&disc, &[([0.0, 0.0], 2.0), ([5.0, 0.0], 2.0)]);
        s.extend(std::iter::repeat_n(0.0, 481));
        let l = measure(&disc, &s, 3).unwrap();
        assert_eq!((l.fields.len(), l.dead), (2, 1));
    }
}
