//! Resampling a plane to another size with precomputed index tables.

use crate::simd::Madd;
use crate::{dispatch_kernel, Backend, ImageError, Plane, Result};
use serde::{Deserialize, Serialize};

/// How samples are taken when changing size.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ResampleMethod {
    /// Bilinear, pixel centres aligned: destination x samples source
    /// `(x + 0.5) * src_w / dst_w - 0.5`, clamped to the image (GPU texture rule).
    Bilinear,
    /// Nearest neighbour: destination pixel x takes the source pixel that contains its
    /// centre, `floor((x + 0.5) * src_w / dst_w)` (MATLAB's and GNU Octave 7's
    /// `imresize(..., 'nearest')`, used by the SaliencyToolbox reference).
    Nearest,
}

/// Per-axis table: destination index -> (i0, i1, weight of i1).
type AxisTable = Vec<(usize, usize, f32)>;

/// Resamples planes of one size to another; build once, apply per frame without allocation.
#[derive(Clone, Debug)]
pub struct Resampler {
    src: (usize, usize),
    dst: (usize, usize),
    xs: AxisTable,
    ys: AxisTable,
    cols: Columns,
}

/// The x table split into columns of 32-bit indices and weights, the form vector gathers
/// read.
#[derive(Clone, Debug, Default)]
struct Columns {
    i0: Vec<i32>,
    i1: Vec<i32>,
    w: Vec<f32>,
    /// The largest index of either column (the row must be longer).
    max_index: usize,
    /// Both columns never decrease and `i0 <= i1` (true of every table built here): the
    /// samples of a run of outputs then lie between its first `i0` and its last `i1`.
    monotonic: bool,
}

impl Columns {
    /// Empty (so unused) when an index does not fit 32 bits.
    fn new(xs: &AxisTable) -> Self {
        let max_index = xs.iter().map(|&(a, b, _)| a.max(b)).max().unwrap_or(0);
        if i32::try_from(max_index).is_err() {
            return Self::default();
        }
        let monotonic =
            xs.iter().all(|&(a, b, _)| a <= b) && xs.windows(2).all(|p| p[0].0 <= p[1].0 && p[0].1 <= p[1].1);
        Self {
            i0: xs.iter().map(|&(a, _, _)| a as i32).collect(),
            i1: xs.iter().map(|&(_, b, _)| b as i32).collect(),
            w: xs.iter().map(|&(_, _, w)| w).collect(),
            max_index,
            monotonic,
        }
    }
}

fn bilinear_axis(n_in: usize, n_out: usize) -> AxisTable {
    (0..n_out)
        .map(|o| {
            let u = ((o as f64 + 0.5) * n_in as f64 / n_out as f64 - 0.5).clamp(0.0, (n_in - 1) as f64);
            let i0 = u.floor() as usize;
            let i1 = (i0 + 1).min(n_in - 1);
            (i0, i1, (u - i0 as f64) as f32)
        })
        .collect()
}

fn nearest_axis(n_in: usize, n_out: usize) -> AxisTable {
    (0..n_out)
        .map(|o| {
            // floor((o + 0.5) * n_in / n_out), in exact integer arithmetic.
            let i = ((2 * o + 1) * n_in / (2 * n_out)).min(n_in - 1);
            (i, i, 0.0)
        })
        .collect()
}

impl Resampler {
    /// Tables for resampling `src` (w, h) to `dst` (w, h) with `method`.
    pub fn new(method: ResampleMethod, src: (usize, usize), dst: (usize, usize)) -> Result<Self> {
        if src.0 == 0 || src.1 == 0 {
            return Err(ImageError::Empty { width: src.0, height: src.1 });
        }
        if dst.0 == 0 || dst.1 == 0 {
            return Err(ImageError::Empty { width: dst.0, height: dst.1 });
        }
        let (xs, ys) = match method {
            ResampleMethod::Bilinear => (bilinear_axis(src.0, dst.0), bilinear_axis(src.1, dst.1)),
            ResampleMethod::Nearest => (nearest_axis(src.0, dst.0), nearest_axis(src.1, dst.1)),
        };
        let cols = Columns::new(&xs);
        Ok(Self { src, dst, xs, ys, cols })
    }

    /// Source size (w, h).
    pub fn src_size(&self) -> (usize, usize) {
        self.src
    }

    /// Destination size (w, h).
    pub fn dst_size(&self) -> (usize, usize) {
        self.dst
    }

    /// The per-axis tables, x then y: for each destination index, the two source indices
    /// (i0, i1) and the weight of i1; a destination pixel is the lerp by the y weight of rows
    /// i0 and i1 (row i0 alone when the weight is 0), then by the x weight of those columns
    /// (what a GPU shader needs to give the same values).
    pub fn tables(&self) -> [&[(usize, usize, f32)]; 2] {
        [&self.xs, &self.ys]
    }

    /// Resamples `src` into `dst` (resized to the destination size); `row` is scratch space
    /// (one source row), kept by the caller so that steady state allocates nothing;
    /// `backend` chooses the kernel's build.
    pub fn apply_with(
        &self,
        backend: Backend,
        src: &Plane<f32>,
        dst: &mut Plane<f32>,
        row: &mut Vec<f32>,
    ) -> Result<()> {
        crate::check::same_size("resampler input", src.size(), self.src)?;
        dst.resize(self.dst.0, self.dst.1);
        resample_kernel(backend, &self.xs, &self.cols, &self.ys, src, dst, row);
        Ok(())
    }

    /// Like [`apply_with`](Self::apply_with) with a temporary row buffer (allocates).
    pub fn apply(&self, backend: Backend, src: &Plane<f32>, dst: &mut Plane<f32>) -> Result<()> {
        self.apply_with(backend, src, dst, &mut Vec::new())
    }
}

/// Per output row: the vertical lerp of two source rows (whole rows, vectorized), then the
/// horizontal lerp at the table's columns.
#[inline(always)]
fn resample_generic<M: Madd>(
    xs: &AxisTable,
    cols: &Columns,
    ys: &AxisTable,
    src: &Plane<f32>,
    dst: &mut Plane<f32>,
    row: &mut Vec<f32>,
) {
    row.resize(src.width(), 0.0);
    for (y, &(y0, y1, fy)) in ys.iter().enumerate() {
        let (r0, r1) = (src.row(y0), src.row(y1));
        if fy == 0.0 {
            row.copy_from_slice(r0);
        } else {
            for ((o, &a), &b) in row.iter_mut().zip(r0).zip(r1) {
                *o = M::madd(fy, b - a, a);
            }
        }
        let out = dst.row_mut(y);
        #[cfg(target_arch = "x86_64")]
        if M::AVX2 && cols.max_index < row.len() && cols.i0.len() >= out.len() {
            // SAFETY: `M::AVX2` (`M::AVX512`) is true only inside kernels compiled for AVX2
            // and FMA (AVX-512 F/BW/VL/DQ), which `dispatch_kernel!` calls only on CPUs that
            // have them; the bounds are checked just above.
            unsafe {
                if !(M::AVX512 && x86::columns_permute_avx512(cols, row, out)) {
                    x86::columns_avx2(cols, row, out);
                }
            }
            continue;
        }
        let _ = cols;
        for (o, &(x0, x1, fx)) in out.iter_mut().zip(xs) {
            *o = M::madd(fx, row[x1] - row[x0], row[x0]);
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod x86;

dispatch_kernel!(fn resample_kernel => resample_generic(
    xs: &AxisTable, cols: &Columns, ys: &AxisTable, src: &Plane<f32>, dst: &mut Plane<f32>, row: &mut Vec<f32>
));

/// Bilinear sample of `img` at (x, y), pixel centres at integers; positions outside the image
/// are clamped to its border (a non-empty image is assumed).
#[inline]
pub fn sample_bilinear(img: &Plane<f32>, x: f32, y: f32) -> f32 {
    let (w, h) = (img.width() as f32, img.height() as f32);
    let (x, y) = (x.clamp(0.0, w - 1.0), y.clamp(0.0, h - 1.0));
    let (x0, y0) = (x.floor() as usize, y.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(img.width() - 1), (y0 + 1).min(img.height() - 1));
    let (ax, ay) = (x - x0 as f32, y - y0 as f32);
    let top = img.get(x0, y0) + ax * (img.get(x1, y0) - img.get(x0, y0));
    let bot = img.get(x0, y1) + ax * (img.get(x1, y1) - img.get(x0, y1));
    top + ay * (bot - top)
}

/// Allocating convenience: resample `src` to `w` x `h` with `backend`'s kernel.
pub fn resize(backend: Backend, src: &Plane<f32>, w: usize, h: usize, method: ResampleMethod) -> Result<Plane<f32>> {
    let r = Resampler::new(method, src.size(), (w, h))?;
    let mut dst = Plane::default();
    r.apply(backend, src, &mut dst)?;
    Ok(dst)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The gathering and permuting kernels give the generic kernel's results bit for bit,
    /// downsampling and upsampling, on widths around their vector lengths.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn gathering_kernels_equal_the_generic_kernel_bit_for_bit() {
        if !crate::simd::avx2_available() {
            return;
        }
        let mut rng = crate::rng::SplitMix64::new(3);
        // Windows of 16 outputs within 32 and 64 samples, and wider (1280 -> 40: gathers), rows
        // ending inside the last window, and the nearest-neighbour tables.
        for (sw, sh, dw, dh) in [
            (160, 120, 40, 30),
            (80, 60, 40, 30),
            (20, 15, 40, 30),
            (5, 3, 40, 30),
            (2, 1, 7, 3),
            (33, 9, 17, 5),
            (1280, 4, 40, 3),
            (1, 2, 19, 2),
            (47, 3, 61, 2),
        ] {
            let src = Plane::from_fn(sw, sh, |_, _| rng.unit() as f32);
            let r = Resampler::new(ResampleMethod::Bilinear, (sw, sh), (dw, dh)).unwrap_or_else(|e| panic!("{e}"));
            let mut want = Plane::new(dw, dh);
            // Empty columns: the generic loop.
            resample_generic::<crate::simd::Fused>(&r.xs, &Columns::default(), &r.ys, &src, &mut want, &mut Vec::new());
            let mut row = vec![0.0; sw];
            for y in 0..dh {
                let (y0, y1, fy) = r.ys[y];
                for (x, o) in row.iter_mut().enumerate() {
                    let (a, b) = (src.get(x, y0), src.get(x, y1));
                    *o = if fy == 0.0 { a } else { fy.mul_add(b - a, a) };
                }
                let mut out = vec![f32::NAN; dw];
                // SAFETY: AVX2 was checked above; the columns index a row of the source's width.
                unsafe { x86::columns_avx2(&r.cols, &row, &mut out) };
                let same = out.iter().zip(want.row(y)).all(|(a, b)| a.to_bits() == b.to_bits());
                assert!(same, "{sw}x{sh} -> {dw}x{dh}, row {y}");
                if crate::simd::avx512_available() {
                    let mut out = vec![f32::NAN; dw];
                    // SAFETY: AVX-512 was checked just above; the same bounds.
                    let ran = unsafe { x86::columns_permute_avx512(&r.cols, &row, &mut out) };
                    assert_eq!(ran, dw >= 16, "{sw}x{sh} -> {dw}x{dh}");
                    let same = !ran || out.iter().zip(want.row(y)).all(|(a, b)| a.to_bits() == b.to_bits());
                    assert!(same, "{sw}x{sh} -> {dw}x{dh}, row {y} (permutes)");
                }
                // The same columns in reverse order: not monotonic, so every block gathers.
                let rev = |v: &[i32]| v.iter().rev().copied().collect::<Vec<i32>>();
                let w: Vec<f32> = r.cols.w.iter().rev().copied().collect();
                let back = Columns {
                    i0: rev(&r.cols.i0),
                    i1: rev(&r.cols.i1),
                    w,
                    max_index: r.cols.max_index,
                    monotonic: false,
                };
                let mut out = vec![f32::NAN; dw];
                // SAFETY: AVX2 was checked above; the same bounds.
                unsafe { x86::columns_avx2(&back, &row, &mut out) };
                let same = out.iter().rev().zip(want.row(y)).all(|(a, b)| a.to_bits() == b.to_bits());
                assert!(same, "{sw}x{sh} -> {dw}x{dh}, row {y} (reversed columns)");
            }
        }
    }
}
