//! Applying a map to frames: grey, float and RGB images into cortical images, with reused
//! buffers, and the point-sampled comparison.

use super::{Fields, LogPolarMap, Scratch};
use crate::{FoveaError, Result};
use ocellus_image::Plane;

impl LogPolarMap {
    pub(super) fn check_size(&self, w: usize, h: usize) -> Result<()> {
        Ok(ocellus_image::check::same_size("image (against the map's)", (w, h), (self.width, self.height))?)
    }

    /// The cortical image of a grey image (grey levels as given: 0..255), `sectors` wide and
    /// `rows` high.
    pub fn sample_grey(&self, img: &Plane<u8>) -> Result<Plane<f32>> {
        let mut out = Plane::new(self.cfg.sectors, self.rows);
        self.sample_grey_into(img, &mut Scratch::default(), &mut out)?;
        Ok(out)
    }

    /// [`Self::sample_grey`] into reused buffers (`out` is resized).
    pub fn sample_grey_into(&self, img: &Plane<u8>, scratch: &mut Scratch, out: &mut Plane<f32>) -> Result<()> {
        self.check_size(img.width(), img.height())?;
        out.resize(self.cfg.sectors, self.rows);
        let src = contiguous(img);
        let o = out_slice(out);
        if self.cfg.fields != Fields::Pyramid || !self.apply_grey_pyramid(&src, scratch, o) {
            self.apply::<u8, 1>(&src, 0, scratch, o);
        }
        Ok(())
    }

    /// The cortical image of a float image (any units; e.g. a magnitude spectrum).
    pub fn sample_f32(&self, img: &Plane<f32>) -> Result<Plane<f32>> {
        self.check_size(img.width(), img.height())?;
        let mut out = Plane::new(self.cfg.sectors, self.rows);
        let src = contiguous(img);
        self.apply::<f32, 1>(&src, 0, &mut Scratch::default(), out_slice(&mut out));
        Ok(out)
    }

    /// The cortical image of an RGB image: three planes (r, g, b), grey levels 0..255.
    pub fn sample_rgb(&self, img: &Plane<[u8; 3]>) -> Result<[Plane<f32>; 3]> {
        let mut out = <[Plane<f32>; 3]>::default();
        self.sample_rgb_into(img, &mut Scratch::default(), &mut out)?;
        Ok(out)
    }

    /// [`Self::sample_rgb`] into reused planes (r, g, b), each resized to `sectors` x `rows`:
    /// steady state allocates nothing.
    pub fn sample_rgb_into(
        &self,
        img: &Plane<[u8; 3]>,
        scratch: &mut Scratch,
        out: &mut [Plane<f32>; 3],
    ) -> Result<()> {
        self.check_size(img.width(), img.height())?;
        let cells = self.rows * self.cfg.sectors;
        for o in out.iter_mut() {
            o.resize(self.cfg.sectors, self.rows);
        }
        let src = contiguous(img);
        let flat: &[u8] = src.as_flattened();
        let [r, g, b] = out;
        let mut o = [out_slice(r), out_slice(g), out_slice(b)];
        if o.iter().any(|s| s.len() < cells) {
            return Err(FoveaError::Invalid("cortical planes are not contiguous".into()));
        }
        if self.cfg.fields == Fields::Pyramid && self.apply_rgb_pyramid(flat, scratch, &mut o) {
            return Ok(());
        }
        let mut mixed = std::mem::take(&mut scratch.channels);
        mixed.resize(3 * cells, 0.0);
        self.apply::<u8, 3>(flat, 0, scratch, &mut mixed);
        for (c, v) in mixed.chunks_exact(3).enumerate() {
            (o[0][c], o[1][c], o[2][c]) = (v[0], v[1], v[2]);
        }
        scratch.channels = mixed;
        Ok(())
    }

    /// Point-sampled cortical image for comparison (what a plain remap such as OpenCV's
    /// `warpPolar` does): one nearest or bilinear sample at each cell's centre, no area.
    pub fn sample_point_grey(&self, img: &Plane<u8>, bilinear: bool) -> Result<Plane<f32>> {
        self.check_size(img.width(), img.height())?;
        let mut out = Plane::new(self.cfg.sectors, self.rows);
        let (w, h) = (self.width as f64, self.height as f64);
        for row in 0..self.rows {
            let (r0, r1) = self.row_radii(row);
            let r = 0.5 * (r0 + r1);
            for s in 0..self.cfg.sectors {
                let (sn, cs) = self.sector_angle(s).sin_cos();
                let (x, y) = (self.cfg.centre[0] + r * cs, self.cfg.centre[1] + r * sn);
                if x < -0.5 || y < -0.5 || x > w - 0.5 || y > h - 0.5 {
                    continue;
                }
                let v = if bilinear {
                    let xc = x.clamp(0.0, w - 1.0);
                    let yc = y.clamp(0.0, h - 1.0);
                    let (x0, y0) = (xc.floor() as usize, yc.floor() as usize);
                    let (x1, y1) = ((x0 + 1).min(self.width - 1), (y0 + 1).min(self.height - 1));
                    let (ax, ay) = ((xc - x0 as f64) as f32, (yc - y0 as f64) as f32);
                    let g = |xx: usize, yy: usize| img.get(xx, yy) as f32;
                    let top = g(x0, y0) + ax * (g(x1, y0) - g(x0, y0));
                    let bot = g(x0, y1) + ax * (g(x1, y1) - g(x0, y1));
                    top + ay * (bot - top)
                } else {
                    let (xi, yi) = (
                        (x.round().max(0.0) as usize).min(self.width - 1),
                        (y.round().max(0.0) as usize).min(self.height - 1),
                    );
                    img.get(xi, yi) as f32
                };
                out.set(s, row, v);
            }
        }
        Ok(out)
    }
}

/// The pixels as one row-major slice (copied only when the plane has padding).
pub(super) fn contiguous<T: Copy + Default>(img: &Plane<T>) -> std::borrow::Cow<'_, [T]> {
    match img.as_contiguous() {
        Some(s) => std::borrow::Cow::Borrowed(s),
        None => std::borrow::Cow::Owned(img.to_vec()),
    }
}

/// The plane's pixels as one mutable slice (empty when it has padding).
pub(super) fn out_slice(out: &mut Plane<f32>) -> &mut [f32] {
    out.as_contiguous_mut().unwrap_or_default()
}
