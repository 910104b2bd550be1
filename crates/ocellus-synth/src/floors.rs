//! Floors that are hard for visual odometry, made from the real texture photos (SPEC 6; the
//! low-contrast, fine-grained and repetitive floors on which a tracker of image windows
//! loses its footing).
//!
//! Each takes one `TILE` x `TILE` grey photo in [0, 1] and returns another:
//! - [`low_contrast`]: the photo smoothed (Gaussian, sigma [`LOW_CONTRAST_BLUR_PX`]) and its
//!   contrast cut to a standard deviation of [`LOW_CONTRAST_STD`] about a dim mean of
//!   [`LOW_CONTRAST_MEAN`]: about 8 grey levels of texture on an 8-bit frame, as a dim concrete
//!   or regolith surface gives, not much above the hard variant's noise (sigma 5);
//! - [`fine_grained`]: the photo shrunk by [`FINE_GRAIN_FACTOR`] (area average, so no
//!   aliasing is baked in) and tiled mirrored, so that its grains are a few pixels across, near
//!   the scale a pixel integrates over;
//! - [`repetitive`]: a [`REPEAT_PERIOD_PX`]-pixel square cut from the photo (shrunk by 4)
//!   repeated over the tile: the floor is periodic with the side of the seed's search window,
//!   so that a window's match has twins one period away.

use crate::ground::TILE;
use crate::{Result, SynthError};
use ocellus_image::{Backend, Plane};

/// Blur of the low-contrast floor, pixels (sigma).
pub const LOW_CONTRAST_BLUR_PX: f32 = 1.5;
/// Mean grey level of the low-contrast floor, in [0, 1].
pub const LOW_CONTRAST_MEAN: f32 = 0.25;
/// Standard deviation of the low-contrast floor's grey levels, in [0, 1] units (0.03 is 7.7
/// grey levels of 255).
pub const LOW_CONTRAST_STD: f32 = 0.03;
/// Shrink factor of the fine-grained floor.
pub const FINE_GRAIN_FACTOR: usize = 4;
/// Period of the repetitive floor, pixels (the seed's 20-pixel search window).
pub const REPEAT_PERIOD_PX: usize = 20;

fn check(photo: &Plane<f32>) -> Result<()> {
    if photo.size() != (TILE, TILE) {
        return Err(SynthError::InvalidConfig(format!(
            "a floor photo must be {TILE}x{TILE}, not {}x{}",
            photo.width(),
            photo.height()
        )));
    }
    Ok(())
}

/// The mean of each `k` x `k` block of `p` (sides that do not divide drop their remainder).
fn shrink(p: &Plane<f32>, k: usize) -> Plane<f32> {
    let (w, h) = (p.width() / k, p.height() / k);
    Plane::from_fn(w, h, |x, y| {
        let mut s = 0.0;
        for yy in y * k..(y + 1) * k {
            s += p.row(yy)[x * k..(x + 1) * k].iter().sum::<f32>();
        }
        s / (k * k) as f32
    })
}

/// The low-contrast floor of `photo` (see the module doc).
pub fn low_contrast(photo: &Plane<f32>) -> Result<Plane<f32>> {
    check(photo)?;
    let smooth = ocellus_image::filter::gaussian_blur(Backend::Auto, photo, LOW_CONTRAST_BLUR_PX)
        .map_err(|e| SynthError::InvalidConfig(format!("smoothing the floor photo: {e}")))?;
    let n = (TILE * TILE) as f64;
    let mean = smooth.rows().flatten().map(|&v| f64::from(v)).sum::<f64>() / n;
    let var = smooth.rows().flatten().map(|&v| (f64::from(v) - mean).powi(2)).sum::<f64>() / n;
    if var <= 0.0 {
        return Err(SynthError::InvalidConfig("the floor photo has no texture to keep".into()));
    }
    let gain = f64::from(LOW_CONTRAST_STD) / var.sqrt();
    Ok(smooth.map(|v| (f64::from(LOW_CONTRAST_MEAN) + gain * (f64::from(v) - mean)).clamp(0.0, 1.0) as f32))
}

/// The fine-grained floor of `photo` (see the module doc).
pub fn fine_grained(photo: &Plane<f32>) -> Result<Plane<f32>> {
    check(photo)?;
    let small = shrink(photo, FINE_GRAIN_FACTOR);
    let n = small.width();
    // Mirrored tiling: the copies meet without a seam.
    let fold = |i: usize| {
        let j = i % (2 * n);
        if j < n {
            j
        } else {
            2 * n - 1 - j
        }
    };
    Ok(Plane::from_fn(TILE, TILE, |x, y| small.get(fold(x), fold(y))))
}

/// The repetitive floor of `photo` (see the module doc).
pub fn repetitive(photo: &Plane<f32>) -> Result<Plane<f32>> {
    check(photo)?;
    let p = REPEAT_PERIOD_PX;
    // A square of 4 periods from the photo's centre, shrunk by 4: one period of real texture.
    let c = TILE / 2 - 2 * p;
    let cut = Plane::from_fn(4 * p, 4 * p, |x, y| photo.get(c + x, c + y));
    let motif = shrink(&cut, 4);
    Ok(Plane::from_fn(TILE, TILE, |x, y| motif.get(x % p, y % p)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn photo() -> Plane<f32> {
        ocellus_io::read_image(ocellus_testdata::asset("gravel.png")).unwrap().to_grey()
    }

    fn mean_std(p: &Plane<f32>) -> (f64, f64) {
        let n = (p.width() * p.height()) as f64;
        let m = p.rows().flatten().map(|&v| f64::from(v)).sum::<f64>() / n;
        (m, (p.rows().flatten().map(|&v| (f64::from(v) - m).powi(2)).sum::<f64>() / n).sqrt())
    }

    /// Mean absolute difference of neighbouring pixels along x: the fine structure.
    fn roughness(p: &Plane<f32>) -> f64 {
        let mut s = 0.0;
        for y in 0..p.height() {
            let r = p.row(y);
            s += r.windows(2).map(|w| f64::from((w[1] - w[0]).abs())).sum::<f64>();
        }
        s / (p.height() * (p.width() - 1)) as f64
    }

    #[test]
    fn the_low_contrast_floor_is_dim_smooth_and_flat() {
        let src = photo();
        let low = low_contrast(&src).unwrap();
        let (m, s) = mean_std(&low);
        assert!((m - f64::from(LOW_CONTRAST_MEAN)).abs() < 1e-3, "{m}");
        assert!((s - f64::from(LOW_CONTRAST_STD)).abs() < 1e-3, "{s}");
        // Smoothed: relative to its spread, less pixel-to-pixel change than the photo.
        assert!(roughness(&low) / s < 0.7 * roughness(&src) / mean_std(&src).1);
    }

    #[test]
    fn the_fine_grained_floor_changes_faster_and_has_no_seam() {
        let src = photo();
        let fine = fine_grained(&src).unwrap();
        assert!(roughness(&fine) > 1.5 * roughness(&src), "{} vs {}", roughness(&fine), roughness(&src));
        // The mirrored copies meet without a jump: across the fold the difference is as
        // small as anywhere.
        let n = TILE / FINE_GRAIN_FACTOR;
        let jump: f64 = (0..TILE).map(|y| f64::from((fine.get(n, y) - fine.get(n - 1, y)).abs())).sum::<f64>();
        assert_eq!(jump, 0.0, "the fold repeats the edge column");
        let (m0, _) = mean_std(&src);
        let (m1, _) = mean_std(&fine);
        assert!((m0 - m1).abs() < 0.02, "area averaging keeps the mean: {m0} vs {m1}");
    }

    #[test]
    fn the_repetitive_floor_has_the_period_and_real_texture() {
        let rep = repetitive(&photo()).unwrap();
        let p = REPEAT_PERIOD_PX;
        for (x, y) in [(0, 0), (7, 3), (100, 250), (480, 490)] {
            assert_eq!(rep.get(x, y), rep.get(x + p, y));
            assert_eq!(rep.get(x, y), rep.get(x, y + p));
        }
        // Not periodic at half the period: the motif is texture, not a pattern of its own.
        let half = (0..TILE - p)
            .flat_map(|y| (0..TILE - p).map(move |x| (x, y)))
            .map(|(x, y)| f64::from((rep.get(x, y) - rep.get(x + p / 2, y)).abs()))
            .sum::<f64>();
        assert!(half > 0.01 * ((TILE - p) * (TILE - p)) as f64, "{half}");
    }

    #[test]
    fn wrong_sizes_and_flat_photos_are_refused() {
        let small = Plane::from_fn(64, 64, |x, _| x as f32 / 64.0);
        assert!(low_contrast(&small).is_err());
        assert!(fine_grained(&small).is_err());
        assert!(repetitive(&small).is_err());
        let flat = Plane::from_fn(TILE, TILE, |_, _| 0.5f32);
        assert!(low_contrast(&flat).is_err());
    }
}
