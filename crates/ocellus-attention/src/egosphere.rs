//! The ego-sphere (SPEC 3.3): attention's memory in head-centred angles, so that what was
//! attended stays inhibited after the camera turns ("saliency mosaic", iCub attention system,
//! Ruesch et al. 2008).
//!
//! Directions are (azimuth, elevation) in degrees: azimuth positive to the right, in
//! (-180, 180]; elevation positive downwards (image y), in [-90, 90]. A camera with pan and
//! tilt (degrees, same signs) sees image pixel (x, y) in direction
//! `(pan + (x - cx) * deg_per_px, tilt + (y - cy) * deg_per_px)`, `(cx, cy)` the image centre
//! in pixel-centre coordinates (the equiangular small-angle model of [`ViewGeometry`]).
//!
//! Inhibition and habituation are sums of Gaussian blobs on the sphere ([`BlobField`]): exact
//! at any resolution, cheap (a handful of blobs), and they decay by scaling amplitudes. The
//! saliency mosaic is a grid ([`Egosphere`]) updated where the camera looks.

use crate::{AttentionError, Result};
use ocellus_image::Plane;
use serde::{Deserialize, Serialize};

/// Wraps an angle difference to (-180, 180] degrees.
#[inline]
pub fn wrap_deg(a: f32) -> f32 {
    if a > -180.0 && a <= 180.0 {
        return a; // the common case, without a float remainder
    }
    let r = (a + 180.0).rem_euclid(360.0) - 180.0;
    if r == -180.0 {
        180.0
    } else {
        r
    }
}

/// How image pixels map to directions.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ViewGeometry {
    /// Image width in pixels.
    pub width: usize,
    /// Image height in pixels.
    pub height: usize,
    /// Angle per pixel, degrees (horizontal field of view = width * deg_per_px).
    pub deg_per_px: f32,
}

impl ViewGeometry {
    /// Checks the values.
    pub fn validate(&self) -> Result<()> {
        use ocellus_image::check;
        (|| {
            check::within("view width", self.width, 1, usize::MAX)?;
            check::within("view height", self.height, 1, usize::MAX)?;
            check::positive("deg_per_px", self.deg_per_px)?;
            check::within(
                "horizontal field of view (width x deg_per_px, degrees)",
                self.width as f32 * self.deg_per_px,
                0.0,
                360.0,
            )
        })()
        .map_err(AttentionError::InvalidConfig)
    }

    /// Direction (azimuth, elevation) in degrees of pixel (x, y) for a camera at (pan, tilt).
    pub fn direction(&self, x: f32, y: f32, pan_deg: f32, tilt_deg: f32) -> (f32, f32) {
        let cx = (self.width as f32 - 1.0) / 2.0;
        let cy = (self.height as f32 - 1.0) / 2.0;
        let el = (tilt_deg + (y - cy) * self.deg_per_px).clamp(-90.0, 90.0);
        (wrap_deg(pan_deg + (x - cx) * self.deg_per_px), el)
    }

    /// Pixel (x, y) where direction (az, el) appears for a camera at (pan, tilt); `None` when
    /// outside the image.
    pub fn pixel(&self, az: f32, el: f32, pan_deg: f32, tilt_deg: f32) -> Option<(f32, f32)> {
        let x = wrap_deg(az - pan_deg) / self.deg_per_px + (self.width as f32 - 1.0) / 2.0;
        let y = (el - tilt_deg) / self.deg_per_px + (self.height as f32 - 1.0) / 2.0;
        let inside = x > -0.5 && y > -0.5 && x < self.width as f32 - 0.5 && y < self.height as f32 - 0.5;
        inside.then_some((x, y))
    }
}

/// Angular distance squared (degrees^2) for small separations: azimuth difference scaled by
/// the cosine of the elevation, plus the elevation difference.
#[inline]
fn dist2(az: f32, el: f32, b: &Blob) -> f32 {
    let da = wrap_deg(az - b.az) * b.cos_el;
    let de = el - b.el;
    da * da + de * de
}

/// Angular separation of two directions (azimuth, elevation), degrees, small-angle form
/// (azimuth difference scaled by the cosine of `b`'s elevation).
pub fn separation_deg(a: (f32, f32), b: (f32, f32)) -> f32 {
    let da = wrap_deg(a.0 - b.0) * b.1.to_radians().cos();
    let de = a.1 - b.1;
    (da * da + de * de).sqrt()
}

/// One Gaussian blob on the sphere.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Blob {
    /// Centre azimuth, degrees.
    pub az: f32,
    /// Centre elevation, degrees.
    pub el: f32,
    /// Peak value.
    pub amplitude: f32,
    /// Standard deviation, degrees.
    pub sigma_deg: f32,
    cos_el: f32,
}

impl Blob {
    /// A blob at (az, el).
    pub fn new(az: f32, el: f32, amplitude: f32, sigma_deg: f32) -> Self {
        Self { az: wrap_deg(az), el, amplitude, sigma_deg, cos_el: el.to_radians().cos() }
    }

    /// Its value at (az, el).
    pub fn value(&self, az: f32, el: f32) -> f32 {
        let d2 = dist2(az, el, self);
        let s2 = self.sigma_deg * self.sigma_deg;
        if d2 > 16.0 * s2 {
            0.0 // beyond 4 sigma: below 3.4e-4 of the peak
        } else {
            self.amplitude * (-0.5 * d2 / s2).exp()
        }
    }
}

/// A decaying sum of blobs (habituation, inhibition of return).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BlobField {
    /// The blobs.
    pub blobs: Vec<Blob>,
}

impl BlobField {
    /// Amplitude below which a blob is forgotten.
    pub const FORGET_BELOW: f32 = 1e-3;

    /// Value at (az, el): the sum of the blobs.
    pub fn value(&self, az: f32, el: f32) -> f32 {
        self.blobs.iter().map(|b| b.value(az, el)).sum()
    }

    /// Multiplies every amplitude by `factor` and forgets faint blobs.
    pub fn decay(&mut self, factor: f32) {
        self.blobs.iter_mut().for_each(|b| b.amplitude *= factor);
        self.blobs.retain(|b| b.amplitude >= Self::FORGET_BELOW);
    }

    /// Adds `amount` at (az, el): to an existing blob within `merge_deg` (so that dwelling on a
    /// place grows one blob), else as a new blob of `sigma_deg`.
    pub fn add(&mut self, az: f32, el: f32, amount: f32, sigma_deg: f32, merge_deg: f32) {
        if let Some(b) = self.blobs.iter_mut().find(|b| dist2(az, el, b) <= merge_deg * merge_deg) {
            b.amplitude += amount;
        } else {
            self.blobs.push(Blob::new(az, el, amount, sigma_deg));
        }
    }

    /// Removes the blobs centred within `radius_deg` of (az, el).
    pub fn clear_near(&mut self, az: f32, el: f32, radius_deg: f32) {
        self.blobs.retain(|b| dist2(az, el, b) > radius_deg * radius_deg);
    }
}

/// The saliency mosaic: a grid over azimuth x elevation holding the most recent saliency seen
/// in each direction.
#[derive(Clone, Debug)]
pub struct Egosphere {
    deg_per_cell: f32,
    mosaic: Plane<f32>,
}

impl Egosphere {
    /// A sphere of `deg_per_cell` degrees per cell (360 / deg_per_cell columns from azimuth
    /// -180, 180 / deg_per_cell rows from elevation -90).
    pub fn new(deg_per_cell: f32) -> Result<Self> {
        if !(deg_per_cell.is_finite() && (0.05..=30.0).contains(&deg_per_cell)) {
            return Err(AttentionError::InvalidConfig(format!("egosphere cell of {deg_per_cell} degrees")));
        }
        let (w, h) = ((360.0 / deg_per_cell).round() as usize, (180.0 / deg_per_cell).round() as usize);
        Ok(Self { deg_per_cell, mosaic: Plane::new(w, h) })
    }

    /// The mosaic (columns: azimuth from -180; rows: elevation from -90).
    pub fn mosaic(&self) -> &Plane<f32> {
        &self.mosaic
    }

    /// Degrees per cell.
    pub fn deg_per_cell(&self) -> f32 {
        self.deg_per_cell
    }

    /// The cell holding direction (az, el).
    pub fn cell(&self, az: f32, el: f32) -> (usize, usize) {
        let (w, h) = self.mosaic.size();
        let x = ((wrap_deg(az) + 180.0) / self.deg_per_cell) as usize % w;
        let y = (((el + 90.0) / self.deg_per_cell) as usize).min(h - 1);
        (x, y)
    }

    /// Direction of the centre of cell (x, y).
    pub fn cell_direction(&self, x: usize, y: usize) -> (f32, f32) {
        let d = self.deg_per_cell;
        (wrap_deg(-180.0 + (x as f32 + 0.5) * d), -90.0 + (y as f32 + 0.5) * d)
    }

    /// Writes a saliency map (any size, covering the view) into the cells the view sees:
    /// every cell whose centre is in view takes the map value there (nearest map pixel).
    pub fn splat(&mut self, map: &Plane<f32>, view: &ViewGeometry, pan_deg: f32, tilt_deg: f32) {
        if map.is_empty() {
            return;
        }
        let (sx, sy) = (map.width() as f32 / view.width as f32, map.height() as f32 / view.height as f32);
        let (w, h) = self.mosaic.size();
        // Only the cells within the view's angular box.
        let half_w = view.width as f32 * view.deg_per_px / 2.0 + self.deg_per_cell;
        let half_h = view.height as f32 * view.deg_per_px / 2.0 + self.deg_per_cell;
        let (y0, y1) = (self.cell(0.0, tilt_deg - half_h).1, self.cell(0.0, tilt_deg + half_h).1);
        let n_cols = ((2.0 * half_w / self.deg_per_cell).ceil() as usize + 1).min(w);
        let x_start = self.cell(pan_deg - half_w, 0.0).0;
        let (cx, cy) = ((view.width as f32 - 1.0) / 2.0, (view.height as f32 - 1.0) / 2.0);
        for y in y0..=y1 {
            let el = self.cell_direction(0, y).1;
            let py = (el - tilt_deg) / view.deg_per_px + cy;
            if py <= -0.5 || py >= view.height as f32 - 0.5 {
                continue;
            }
            let map_row = map.row((((py + 0.5) * sy) as usize).min(map.height() - 1));
            let out = self.mosaic.row_mut(y);
            // Image column of the first cell; each further cell is deg_per_cell further right.
            let az0 = -180.0 + (x_start as f32 + 0.5) * self.deg_per_cell;
            let px0 = wrap_deg(az0 - pan_deg) / view.deg_per_px + cx;
            let step = self.deg_per_cell / view.deg_per_px;
            let (lo, hi) = (-0.5, view.width as f32 - 0.5);
            for i in 0..n_cols {
                let px = px0 + i as f32 * step;
                if px > lo && px < hi {
                    out[(x_start + i) % w] = map_row[(((px + 0.5) * sx) as usize).min(map_row.len() - 1)];
                }
            }
        }
        debug_assert!(y1 < h);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pixel_and_direction_are_inverse_and_wrap() {
        let v = ViewGeometry { width: 640, height: 480, deg_per_px: 0.1 };
        let (az, el) = v.direction(100.0, 50.0, 170.0, -5.0);
        // 170 + (100 - 319.5) * 0.1 = 148.05; -5 + (50 - 239.5) * 0.1 = -23.95
        assert!((az - 148.05).abs() < 1e-3 && (el + 23.95).abs() < 1e-3);
        let (x, y) = v.pixel(az, el, 170.0, -5.0).unwrap();
        assert!((x - 100.0).abs() < 1e-3 && (y - 50.0).abs() < 1e-3);
        // Across the +-180 seam.
        let (az, _) = v.direction(639.0, 0.0, 175.0, 0.0);
        // 175 + 319.5 * 0.1 = 206.95 -> -153.05
        assert!((az - (-153.05)).abs() < 1e-3, "{az}");
        assert!(v.pixel(az, 0.0, 175.0, 0.0).is_some());
        assert!(v.pixel(0.0, 0.0, 175.0, 0.0).is_none(), "behind the camera");
    }

    #[test]
    fn blobs_add_merge_decay_and_clear() {
        let mut f = BlobField::default();
        f.add(10.0, 0.0, 0.5, 2.0, 1.0);
        f.add(10.5, 0.0, 0.5, 2.0, 1.0); // merges
        assert_eq!(f.blobs.len(), 1);
        assert!((f.value(10.0, 0.0) - 1.0).abs() < 1e-6);
        // One sigma away: exp(-1/2).
        assert!((f.value(12.0, 0.0) - (-0.5f32).exp()).abs() < 1e-5);
        f.add(179.0, 0.0, 1.0, 2.0, 1.0);
        assert!(f.value(-179.0, 0.0) > 0.6, "wraps around the seam");
        f.decay(0.5);
        assert!((f.value(10.0, 0.0) - 0.5).abs() < 1e-6);
        f.clear_near(10.0, 0.0, 1.0);
        assert_eq!(f.blobs.len(), 1);
        f.decay(1e-4);
        assert!(f.blobs.is_empty());
    }

    #[test]
    fn mosaic_keeps_what_left_the_view() {
        let v = ViewGeometry { width: 64, height: 48, deg_per_px: 0.5 };
        let mut e = Egosphere::new(1.0).unwrap();
        let map = Plane::from_fn(4, 3, |x, y| (x + 10 * y) as f32 + 1.0);
        e.splat(&map, &v, 0.0, 0.0);
        // The view spans azimuth -16..16: the cell at azimuth -15 shows map column 0.
        let (cx, cy) = e.cell(-15.0, 0.0);
        assert_eq!(e.mosaic().get(cx, cy), map.get(0, 1));
        e.splat(&Plane::new(4, 3), &v, 90.0, 0.0);
        assert_eq!(e.mosaic().get(cx, cy), map.get(0, 1), "out of view: remembered");
        let (qx, qy) = e.cell(90.0, 0.0);
        assert_eq!(e.mosaic().get(qx, qy), 0.0);
        assert!(Egosphere::new(0.0).is_err());
    }
}
