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
        slope_px2_per_px: slope,
        density_ratio,
        mean_area_centre_px: mean(&inner),
        mean_area_periphery_px: mean(&outer),
        fields: out,
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
    fn a_dead_field_is_counted_apart() {
        let disc = Disc::with_pixels(481).unwrap();
        let mut s = blobs(&disc, &[([0.0, 0.0], 2.0), ([5.0, 0.0], 2.0)]);
        s.extend(std::iter::repeat(0.0).take(481));
        let l = measure(&disc, &s, 3).unwrap();
        assert_eq!((l.fields.len(), l.dead), (2, 1));
    }
}
