//! Back from the cortex to the image: the inverse map for display, and the cortical
//! coordinates of an image point.

use super::LogPolarMap;
use crate::Result;
use ocellus_image::Plane;
use std::f64::consts::TAU;

impl LogPolarMap {
    /// Back to a `width` x `height` Cartesian image for display: each pixel reads the
    /// cortical image bilinearly (cyclic across sectors) at its own (ring, sector)
    /// coordinates; pixels beyond rho_max (or inside an unsampled fovea) are 0.
    pub fn inverse(&self, cortex: &Plane<f32>) -> Result<Plane<f32>> {
        ocellus_image::check::same_size("cortical image", cortex.size(), (self.cfg.sectors, self.rows))?;
        let mut out = Plane::new(self.width, self.height);
        for y in 0..self.height {
            for x in 0..self.width {
                if let Some((row, col)) = self.cortical_coordinates(x as f64, y as f64) {
                    out.set(x, y, self.read_cortex(cortex, row, col));
                }
            }
        }
        Ok(out)
    }

    /// Fractional cortical coordinates (row, column) of image point (x, y), cell centres at
    /// integers; `None` outside rho_max or in an unsampled fovea.
    pub fn cortical_coordinates(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        let (dx, dy) = (x - self.cfg.centre[0], y - self.cfg.centre[1]);
        let r = dx.hypot(dy);
        let (f, rho0) = (self.cfg.fovea_rings, self.cfg.fovea_radius);
        if r >= self.cfg.max_radius {
            return None;
        }
        let row = if r < rho0 {
            if f == 0 {
                return None;
            }
            r / rho0 * f as f64 - 0.5
        } else {
            f as f64 + (r / rho0).ln() / self.cfg.ring_ratio().ln() - 0.5
        };
        let col = dy.atan2(dx).rem_euclid(TAU) / TAU * self.cfg.sectors as f64 - 0.5;
        Some((row, col))
    }

    fn read_cortex(&self, cortex: &Plane<f32>, row: f64, col: f64) -> f32 {
        let s = self.cfg.sectors as i64;
        let r = row.clamp(0.0, (self.rows - 1) as f64);
        let (r0, c0) = (r.floor(), col.floor());
        let (fr, fc) = ((r - r0) as f32, (col - c0) as f32);
        let r0 = r0 as usize;
        let r1 = (r0 + 1).min(self.rows - 1);
        let c0i = (c0 as i64).rem_euclid(s) as usize;
        let c1i = (c0 as i64 + 1).rem_euclid(s) as usize;
        let top = cortex.get(c0i, r0) + fc * (cortex.get(c1i, r0) - cortex.get(c0i, r0));
        let bot = cortex.get(c0i, r1) + fc * (cortex.get(c1i, r1) - cortex.get(c0i, r1));
        top + fr * (bot - top)
    }
}
