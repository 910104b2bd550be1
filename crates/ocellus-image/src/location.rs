//! Pixel locations and map cells, in the one convention of ocellus (see the crate doc):
//! pixel (x, y) has its centre at the integer point (x, y) and covers
//! [x - 0.5, x + 0.5) x [y - 0.5, y + 0.5), as in OpenCV and in the camera models of
//! `ocellus-geometry`.
//!
//! A coarse map (a saliency map at level 4, a surprise grid) of `m` cells across an image of
//! `n` pixels has cells of `n / m` pixels; cell i spans the pixel edges [i n/m, (i+1) n/m),
//! so its centre is the pixel coordinate `(i + 0.5) n / m - 0.5`. Every subcommand that
//! reports where something is converts through these functions, so that all of them agree.

use crate::Plane;

/// The centre of cell `i` of `cells` along an axis of `pixels` pixels, in pixel coordinates
/// (integer centres). `cells == pixels` gives `i` exactly.
pub fn cell_centre(i: usize, cells: usize, pixels: usize) -> f64 {
    if cells == 0 {
        return 0.0;
    }
    (i as f64 + 0.5) * pixels as f64 / cells as f64 - 0.5
}

/// The centre of map cell `(x, y)` of a `map` (width, height) laid over an `image` (width,
/// height), in image pixel coordinates `[x, y]` (integer centres).
pub fn cell_to_pixel(cell: (usize, usize), map: (usize, usize), image: (usize, usize)) -> [f64; 2] {
    [cell_centre(cell.0, map.0, image.0), cell_centre(cell.1, map.1, image.1)]
}

/// The cell of a `map` (width, height) laid over an `image` (width, height) that holds the
/// image point `p` (pixel coordinates, integer centres); `None` outside the image or for a
/// non-finite point.
pub fn pixel_to_cell(p: [f64; 2], map: (usize, usize), image: (usize, usize)) -> Option<(usize, usize)> {
    let axis = |v: f64, cells: usize, pixels: usize| -> Option<usize> {
        if !v.is_finite() || cells == 0 || pixels == 0 {
            return None;
        }
        // Pixel edges run from -0.5 to pixels - 0.5.
        let e = (v + 0.5) * cells as f64 / pixels as f64;
        (e >= 0.0 && e < cells as f64).then(|| (e.floor() as usize).min(cells - 1))
    };
    Some((axis(p[0], map.0, image.0)?, axis(p[1], map.1, image.1)?))
}

/// The largest value of a map laid over an image of `image` (width, height) pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Peak {
    /// The map cell `(x, y)` (the first in row order on ties).
    pub cell: (usize, usize),
    /// The cell's centre in image pixels `[x, y]` (integer centres).
    pub pixel: [f64; 2],
    /// The map's value there.
    pub value: f32,
}

/// The peak of `map` laid over an image of `image` (width, height) pixels; `None` for an empty
/// map or one of only NaN.
pub fn peak(map: &Plane<f32>, image: (usize, usize)) -> Option<Peak> {
    let (x, y, value) = map.argmax()?;
    Some(Peak { cell: (x, y), pixel: cell_to_pixel((x, y), map.size(), image), value })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn full_resolution_cells_are_pixels() {
        for i in 0..7 {
            assert_eq!(cell_centre(i, 7, 7), i as f64);
            assert_eq!(pixel_to_cell([i as f64, 3.0], (7, 5), (7, 5)), Some((i, 3)));
        }
    }

    #[test]
    fn coarse_cells_centre_on_their_pixel_blocks() {
        // 16 px cells: cell 0 covers pixels 0..=15, whose centres average 7.5.
        assert_eq!(cell_centre(0, 40, 640), 7.5);
        assert_eq!(cell_centre(39, 40, 640), 631.5);
        assert_eq!(pixel_to_cell([15.4, 0.0], (40, 30), (640, 480)), Some((0, 0)));
        assert_eq!(pixel_to_cell([15.6, 0.0], (40, 30), (640, 480)), Some((1, 0)));
        assert_eq!(pixel_to_cell([-0.6, 0.0], (40, 30), (640, 480)), None);
        assert_eq!(pixel_to_cell([639.49, 479.49], (40, 30), (640, 480)), Some((39, 29)));
        assert_eq!(pixel_to_cell([f64::NAN, 0.0], (40, 30), (640, 480)), None);
    }

    #[test]
    fn round_trip_through_cells() {
        for (m, n) in [(40usize, 640usize), (3, 10), (10, 3), (1, 1), (5, 5)] {
            for i in 0..m {
                let p = cell_centre(i, m, n);
                assert_eq!(pixel_to_cell([p, p], (m, m), (n, n)), Some((i, i)), "{m} cells over {n}");
            }
        }
    }

    #[test]
    fn peak_reports_the_first_maximum() {
        let mut map = Plane::new(4, 3);
        map.set(2, 1, 5.0);
        map.set(3, 2, 5.0);
        let p = peak(&map, (40, 30)).unwrap();
        assert_eq!((p.cell, p.pixel, p.value), ((2, 1), [24.5, 14.5], 5.0));
        assert!(peak(&Plane::new(0, 0), (1, 1)).is_none());
    }
}
