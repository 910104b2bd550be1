//! The sensor: a disc of pixels about the gaze point.

use crate::{Result, RetinaError};

/// The integer pixel offsets (dx, dy) of a disc about the gaze point, nearest first (ties by
/// angle), so that `with_pixels(n)` is the n pixels nearest the centre. The seed's sizes are
/// whole discs: 2877 pixels are the offsets with dx^2 + dy^2 <= 914 (radius 30.23 px), 481
/// those with dx^2 + dy^2 <= 149 (radius 12.21 px).
#[derive(Clone, Debug, PartialEq)]
pub struct Disc {
    offsets: Vec<[i32; 2]>,
}

impl Disc {
    /// The `n` pixels nearest the centre (n >= 1, at most 10^6).
    pub fn with_pixels(n: usize) -> Result<Self> {
        if n == 0 || n > 1_000_000 {
            return Err(RetinaError::Invalid(format!("a retina needs 1 to 10^6 pixels, not {n}")));
        }
        // The disc of n pixels has radius about sqrt(n / pi); two more pixels of margin.
        let r = ((n as f64 / std::f64::consts::PI).sqrt().ceil() as i32) + 2;
        let mut all: Vec<[i32; 2]> = (-r..=r).flat_map(|y| (-r..=r).map(move |x| [x, y])).collect();
        all.sort_by(|a, b| {
            let (da, db) = (a[0] * a[0] + a[1] * a[1], b[0] * b[0] + b[1] * b[1]);
            da.cmp(&db).then_with(|| {
                let (ta, tb) = ((a[1] as f64).atan2(a[0] as f64), (b[1] as f64).atan2(b[0] as f64));
                ta.total_cmp(&tb)
            })
        });
        all.truncate(n);
        Ok(Self { offsets: all })
    }

    /// Number of pixels.
    pub fn len(&self) -> usize {
        self.offsets.len()
    }

    /// Always false (a disc has at least one pixel).
    pub fn is_empty(&self) -> bool {
        self.offsets.is_empty()
    }

    /// The offsets, pixels (x right, y down).
    pub fn offsets(&self) -> &[[i32; 2]] {
        &self.offsets
    }

    /// Distance of the farthest pixel centre from the gaze point, pixels.
    pub fn radius(&self) -> f64 {
        self.offsets.iter().map(|&[x, y]| ((x * x + y * y) as f64).sqrt()).fold(0.0, f64::max)
    }

    /// Half-width of the square that holds the disc: offsets lie in [-h, h].
    pub fn half_width(&self) -> usize {
        self.offsets.iter().map(|&[x, y]| x.unsigned_abs().max(y.unsigned_abs())).max().unwrap_or(0) as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_seed_sizes_are_whole_discs() {
        for (n, r2) in [(2877, 914), (481, 149)] {
            let d = Disc::with_pixels(n).unwrap();
            assert_eq!(d.len(), n);
            // Exactly the lattice points within the radius: none outside, all inside counted.
            assert!(d.offsets().iter().all(|&[x, y]| x * x + y * y <= r2));
            let r = (r2 as f64).sqrt().ceil() as i32;
            let inside = (-r..=r).flat_map(|y| (-r..=r).map(move |x| x * x + y * y)).filter(|&v| v <= r2).count();
            assert_eq!(inside, n);
        }
        assert!(Disc::with_pixels(0).is_err());
        assert_eq!(Disc::with_pixels(1).unwrap().offsets(), &[[0, 0]]);
    }
}
