//! Chessboard corner detection with sub-pixel refinement, so that calibration runs from images.
//!
//! 1. **Saddle response.** On the image smoothed with a Gaussian, the Hessian determinant is
//!    negative at an X-junction (the intensity is locally like `x y`), so
//!    `I_xy^2 - I_xx I_yy` peaks there. Local maxima are candidates.
//! 2. **Ring test** (the idea of the ChESS detector, Bennett & Lasenby 2014): on a circle around
//!    an X-junction the intensity changes from dark to light exactly four times, and opposite
//!    points have the same colour. This rejects edges, L-corners of the board's border and
//!    most background texture. The four crossing angles give the two grid directions.
//! 3. **Sub-pixel refinement** (Förstner & Gülch 1987, as OpenCV's `cornerSubPix`): every
//!    gradient near the corner is perpendicular to the vector from the corner to where it is
//!    taken, so the corner `q` solves `sum g g^T (q - p) = 0` over a Gaussian-weighted window.
//! 4. **Grid growing.** From a seed corner and its neighbours along the two directions, the grid
//!    grows cell by cell: each new position is predicted by linear extrapolation along a row or
//!    column (or by completing a parallelogram), and the nearest candidate within a third of
//!    the local spacing is taken. Perspective and lens distortion only bend the prediction
//!    slightly from cell to cell.
//!
//! The result is ordered row by row (`cols` corners per row), with the first index along the
//! row increasing to the right of the second in the image (the board seen from its printed
//! side); of the two orderings that remain (the board turned by 180 degrees) the one starting
//! nearer the image's top-left corner is returned.

use crate::{GeometryError, Result};
use ocellus_image::filter::gaussian_blur;
use ocellus_image::resample::sample_bilinear as sample;
use ocellus_image::{Backend, Plane};
use std::collections::HashMap;

/// Detector settings. Board squares should be at least about 3 ring radii wide in the image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChessboardOptions {
    /// Gaussian smoothing before the saddle response, pixels.
    pub smoothing_sigma_px: f32,
    /// Radius of the ring test, pixels.
    pub ring_radius_px: f32,
    /// Half size of the sub-pixel refinement window, pixels.
    pub refine_half_window_px: usize,
    /// Least light-dark difference on the ring, as a fraction of the image's intensity range.
    pub min_contrast_frac: f32,
    /// Which build of the smoothing kernels runs (`Auto`: the fastest this CPU has).
    pub backend: Backend,
}

impl Default for ChessboardOptions {
    fn default() -> Self {
        Self {
            smoothing_sigma_px: 1.5,
            ring_radius_px: 5.0,
            refine_half_window_px: 5,
            min_contrast_frac: 0.15,
            backend: Backend::Auto,
        }
    }
}

/// A corner candidate: sub-pixel position and the two grid directions (unit vectors).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Saddle {
    /// Position, pixels (x, y).
    pub pos: [f64; 2],
    /// First edge direction through the corner.
    pub dir_a: [f64; 2],
    /// Second edge direction through the corner.
    pub dir_b: [f64; 2],
    /// Saddle response at the pixel maximum.
    pub response: f32,
}

/// The ring test: the two edge directions if the ring around (x, y) crosses its mean four
/// times with opposite points alike.
fn ring_directions(img: &Plane<f32>, x: f32, y: f32, radius: f32, min_contrast: f32) -> Option<([f64; 2], [f64; 2])> {
    const N: usize = 32;
    let v: [f32; N] = std::array::from_fn(|k| {
        let a = k as f32 * std::f32::consts::TAU / N as f32;
        sample(img, x + radius * a.cos(), y + radius * a.sin())
    });
    let (lo, hi) = v.iter().fold((f32::MAX, f32::MIN), |(a, b), &s| (a.min(s), b.max(s)));
    if hi - lo < min_contrast {
        return None;
    }
    let mean = v.iter().sum::<f32>() / N as f32;
    let opposite = (0..N / 2).map(|k| (v[k] - v[k + N / 2]).abs()).sum::<f32>() / (N / 2) as f32;
    if opposite > 0.25 * (hi - lo) {
        return None;
    }
    let mut crossings = Vec::with_capacity(4);
    for k in 0..N {
        let (a, b) = (v[k] - mean, v[(k + 1) % N] - mean);
        if (a < 0.0) != (b < 0.0) {
            if crossings.len() == 4 {
                return None;
            }
            let frac = a / (a - b);
            crossings.push((k as f32 + frac) * std::f32::consts::TAU / N as f32);
        }
    }
    if crossings.len() != 4 {
        return None;
    }
    // Crossings 0 and 2 lie on one edge line, 1 and 3 on the other.
    let dir = |a: f32, b: f32| {
        let (dx, dy) = (a.cos() - b.cos(), a.sin() - b.sin());
        let n = (dx * dx + dy * dy).sqrt().max(1e-6);
        [(dx / n) as f64, (dy / n) as f64]
    };
    Some((dir(crossings[0], crossings[2]), dir(crossings[1], crossings[3])))
}

/// Förstner refinement of a corner near `start` on gradients of `img`; `None` if it wanders
/// off by more than the window or the system is singular.
fn refine(img: &Plane<f32>, start: [f64; 2], half: usize) -> Option<[f64; 2]> {
    let (w, h) = (img.width() as i64, img.height() as i64);
    let hw = half as i64;
    let sigma2 = 2.0 * (half as f64 / 2.0).max(1.0).powi(2);
    let mut q = start;
    for _ in 0..20 {
        let (cx, cy) = (q[0].round() as i64, q[1].round() as i64);
        if cx - hw < 1 || cy - hw < 1 || cx + hw >= w - 1 || cy + hw >= h - 1 {
            return None;
        }
        let (mut a11, mut a12, mut a22, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for y in cy - hw..=cy + hw {
            for x in cx - hw..=cx + hw {
                let (xu, yu) = (x as usize, y as usize);
                let gx = 0.5 * (img.get(xu + 1, yu) - img.get(xu - 1, yu)) as f64;
                let gy = 0.5 * (img.get(xu, yu + 1) - img.get(xu, yu - 1)) as f64;
                let d2 = (x as f64 - q[0]).powi(2) + (y as f64 - q[1]).powi(2);
                let wt = (-d2 / sigma2).exp();
                let (gxx, gxy, gyy) = (wt * gx * gx, wt * gx * gy, wt * gy * gy);
                a11 += gxx;
                a12 += gxy;
                a22 += gyy;
                b1 += gxx * x as f64 + gxy * y as f64;
                b2 += gxy * x as f64 + gyy * y as f64;
            }
        }
        let det = a11 * a22 - a12 * a12;
        if det.is_nan() || det <= 1e-12 * (a11 + a22).powi(2) {
            return None;
        }
        let next = [(a22 * b1 - a12 * b2) / det, (a11 * b2 - a12 * b1) / det];
        let step = ((next[0] - q[0]).powi(2) + (next[1] - q[1]).powi(2)).sqrt();
        q = next;
        if ((q[0] - start[0]).powi(2) + (q[1] - start[1]).powi(2)).sqrt() > half as f64 {
            return None;
        }
        if step < 1e-3 {
            break;
        }
    }
    Some(q)
}

/// All X-junction candidates of an image (grey, any range), refined to sub-pixel accuracy.
pub fn saddles(img: &Plane<f32>, opts: &ChessboardOptions) -> Result<Vec<Saddle>> {
    let (w, h) = img.size();
    let margin = (opts.ring_radius_px.ceil() as usize + 2).max(opts.refine_half_window_px + 2);
    if w < 2 * margin + 3 || h < 2 * margin + 3 {
        return Err(GeometryError::Invalid(format!("image {w}x{h} is too small to find a chessboard in")));
    }
    if !img.all_finite() {
        return Err(GeometryError::Invalid("image has non-finite pixels".into()));
    }
    let smooth = gaussian_blur(opts.backend, img, opts.smoothing_sigma_px)?;
    let fine = gaussian_blur(opts.backend, img, 1.0)?;
    let (lo, hi) = smooth.min_max();
    let min_contrast = opts.min_contrast_frac * (hi - lo);
    let mut resp = Plane::<f32>::new(w, h);
    for y in 1..h - 1 {
        let (up, row, down) = (smooth.row(y - 1), smooth.row(y), smooth.row(y + 1));
        let out = resp.row_mut(y);
        for x in 1..w - 1 {
            let ixx = row[x + 1] - 2.0 * row[x] + row[x - 1];
            let iyy = down[x] - 2.0 * row[x] + up[x];
            let ixy = 0.25 * (down[x + 1] - down[x - 1] - up[x + 1] + up[x - 1]);
            out[x] = (ixy * ixy - ixx * iyy).max(0.0);
        }
    }
    let peak = resp.min_max().1;
    if peak <= 0.0 {
        return Ok(Vec::new());
    }
    let floor = 0.02 * peak;
    let nms = 3usize;
    let mut out = Vec::new();
    for y in margin..h - margin {
        for x in margin..w - margin {
            let r = resp.get(x, y);
            if r < floor {
                continue;
            }
            let is_max = (y - nms..=y + nms).all(|yy| {
                (x - nms..=x + nms).all(|xx| {
                    let o = resp.get(xx, yy);
                    o < r || (o == r && (yy, xx) >= (y, x))
                })
            });
            if !is_max {
                continue;
            }
            let Some((dir_a, dir_b)) = ring_directions(&smooth, x as f32, y as f32, opts.ring_radius_px, min_contrast)
            else {
                continue;
            };
            if let Some(pos) = refine(&fine, [x as f64, y as f64], opts.refine_half_window_px) {
                out.push(Saddle { pos, dir_a, dir_b, response: r });
            }
        }
    }
    Ok(out)
}

type Cell = (i32, i32);

/// Grows a grid from `seed` over the candidates; returns the cells found.
fn grow(cands: &[Saddle], seed: usize) -> HashMap<Cell, usize> {
    let mut grid: HashMap<Cell, usize> = HashMap::new();
    let mut used = vec![false; cands.len()];
    let p = |i: usize| cands[i].pos;
    let nearest_along = |from: [f64; 2], dir: [f64; 2], used: &[bool]| -> Option<usize> {
        let cos_tol = 20f64.to_radians().cos();
        (0..cands.len())
            .filter(|&i| !used[i])
            .filter_map(|i| {
                let (dx, dy) = (p(i)[0] - from[0], p(i)[1] - from[1]);
                let d = (dx * dx + dy * dy).sqrt();
                ((dx * dir[0] + dy * dir[1]).abs() > cos_tol * d && d > 0.0).then_some((i, d))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i)
    };
    grid.insert((0, 0), seed);
    used[seed] = true;
    let s = &cands[seed];
    let Some(a) = nearest_along(s.pos, s.dir_a, &used) else { return grid };
    grid.insert((1, 0), a);
    used[a] = true;
    let Some(b) = nearest_along(s.pos, s.dir_b, &used) else { return grid };
    grid.insert((0, 1), b);
    used[b] = true;
    loop {
        let mut added = false;
        let cells: Vec<Cell> = grid.keys().copied().collect();
        for cell in cells {
            for dir in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
                let next = (cell.0 + dir.0, cell.1 + dir.1);
                if grid.contains_key(&next) {
                    continue;
                }
                let here = p(grid[&cell]);
                let back = (cell.0 - dir.0, cell.1 - dir.1);
                let pred = if let Some(&bi) = grid.get(&back) {
                    let pb = p(bi);
                    Some([2.0 * here[0] - pb[0], 2.0 * here[1] - pb[1]])
                } else {
                    [(dir.1, dir.0), (-dir.1, -dir.0)].iter().find_map(|perp| {
                        let side = grid.get(&(cell.0 + perp.0, cell.1 + perp.1))?;
                        let diag = grid.get(&(next.0 + perp.0, next.1 + perp.1))?;
                        let (ps, pd) = (p(*side), p(*diag));
                        Some([here[0] + pd[0] - ps[0], here[1] + pd[1] - ps[1]])
                    })
                };
                let Some(pred) = pred else { continue };
                let spacing = ((pred[0] - here[0]).powi(2) + (pred[1] - here[1]).powi(2)).sqrt();
                let best = (0..cands.len())
                    .filter(|&i| !used[i])
                    .map(|i| (i, ((p(i)[0] - pred[0]).powi(2) + (p(i)[1] - pred[1]).powi(2)).sqrt()))
                    .min_by(|a, b| a.1.total_cmp(&b.1));
                if let Some((i, d)) = best {
                    if d < spacing / 3.0 {
                        grid.insert(next, i);
                        used[i] = true;
                        added = true;
                    }
                }
            }
        }
        if !added {
            return grid;
        }
    }
}

/// Finds the `cols` x `rows` inner corners of a chessboard (a board of (cols + 1) x (rows + 1)
/// squares) in a grey image; returns them row by row, sub-pixel, in pixels. An error says
/// what was found instead when the board is not found whole.
pub fn find_chessboard(img: &Plane<f32>, cols: usize, rows: usize, opts: &ChessboardOptions) -> Result<Vec<[f64; 2]>> {
    if cols < 2 || rows < 2 {
        return Err(GeometryError::Invalid(format!(
            "a {cols}x{rows} board: both counts of inner corners must be >= 2"
        )));
    }
    let cands = saddles(img, opts)?;
    let mut order: Vec<usize> = (0..cands.len()).collect();
    order.sort_by(|&a, &b| cands[b].response.total_cmp(&cands[a].response));
    let mut best_size = (0, 0);
    // Several seeds, strongest first: a background saddle as seed grows nothing useful.
    for &seed in order.iter().take(12) {
        let grid = grow(&cands, seed);
        let (i0, i1) = grid.keys().fold((i32::MAX, i32::MIN), |(a, b), k| (a.min(k.0), b.max(k.0)));
        let (j0, j1) = grid.keys().fold((i32::MAX, i32::MIN), |(a, b), k| (a.min(k.1), b.max(k.1)));
        let (nx, ny) = ((i1 - i0 + 1) as usize, (j1 - j0 + 1) as usize);
        if grid.len() > best_size.0 * best_size.1 {
            best_size = (nx, ny);
        }
        let full = grid.len() == nx * ny;
        if !full || !((nx, ny) == (cols, rows) || (nx, ny) == (rows, cols)) {
            continue;
        }
        let at = |i: usize, j: usize| cands[grid[&(i0 + i as i32, j0 + j as i32)]].pos;
        // Rows of `cols` corners.
        let mut rows_v: Vec<Vec<[f64; 2]>> = if nx == cols {
            (0..ny).map(|j| (0..nx).map(|i| at(i, j)).collect()).collect()
        } else {
            (0..nx).map(|i| (0..ny).map(|j| at(i, j)).collect()).collect()
        };
        let (o, a, b) = (rows_v[0][0], rows_v[0][1], rows_v[1][0]);
        let cross = (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
        if cross < 0.0 {
            rows_v.iter_mut().for_each(|r| r.reverse());
        }
        let mut flat: Vec<[f64; 2]> = rows_v.into_iter().flatten().collect();
        let (first, last) = (flat[0], flat[flat.len() - 1]);
        if last[0] + last[1] < first[0] + first[1] {
            flat.reverse();
        }
        return Ok(flat);
    }
    Err(GeometryError::NotFound(format!(
        "chessboard with {cols}x{rows} inner corners not found ({} corner candidates; largest grid {}x{})",
        cands.len(),
        best_size.0,
        best_size.1
    )))
}
