use crate::{ImageError, Result};

/// A 2D array of pixels stored row-major with a row stride (in elements, >= width).
///
/// `T` is the pixel type: `f32` for feature maps, `u8` for grey images, `[u8; 3]` for
/// interleaved RGB. Row `y` occupies `data[y * stride .. y * stride + width]`.
#[derive(Debug, PartialEq)]
pub struct Plane<T> {
    width: usize,
    height: usize,
    stride: usize,
    data: Vec<T>,
}

impl<T: Clone> Clone for Plane<T> {
    fn clone(&self) -> Self {
        Self { width: self.width, height: self.height, stride: self.stride, data: self.data.clone() }
    }

    /// Copies `source` into this plane's buffer, which is reused when it is large enough (a
    /// stream that keeps its previous frame then allocates nothing per frame).
    fn clone_from(&mut self, source: &Self) {
        (self.width, self.height, self.stride) = (source.width, source.height, source.stride);
        self.data.clone_from(&source.data);
    }
}

impl<T: Copy + Default> Default for Plane<T> {
    fn default() -> Self {
        Self::new(0, 0)
    }
}

impl<T: Copy + Default> Plane<T> {
    /// A `width` x `height` plane filled with `T::default()` (zero), stride = width.
    pub fn new(width: usize, height: usize) -> Self {
        Self { width, height, stride: width, data: vec![T::default(); width * height] }
    }

    /// A plane whose pixel (x, y) is `f(x, y)`.
    pub fn from_fn(width: usize, height: usize, mut f: impl FnMut(usize, usize) -> T) -> Self {
        let mut data = Vec::with_capacity(width * height);
        for y in 0..height {
            for x in 0..width {
                data.push(f(x, y));
            }
        }
        Self { width, height, stride: width, data }
    }

    /// Wraps a row-major buffer with stride = width.
    pub fn from_vec(width: usize, height: usize, data: Vec<T>) -> Result<Self> {
        Self::from_vec_with_stride(width, height, width, data)
    }

    /// Wraps a row-major buffer whose rows are `stride` elements apart.
    pub fn from_vec_with_stride(width: usize, height: usize, stride: usize, data: Vec<T>) -> Result<Self> {
        let needed = if height == 0 { 0 } else { (height - 1) * stride + width };
        if stride < width || data.len() < needed {
            return Err(ImageError::BufferSize { len: data.len(), width, height, stride });
        }
        Ok(Self { width, height, stride, data })
    }

    /// Width in pixels (columns).
    #[inline]
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in pixels (rows).
    #[inline]
    pub fn height(&self) -> usize {
        self.height
    }

    /// Distance between the starts of two consecutive rows, in elements.
    #[inline]
    pub fn stride(&self) -> usize {
        self.stride
    }

    /// (width, height).
    #[inline]
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// True when the plane has no pixels.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.width == 0 || self.height == 0
    }

    /// Row `y` (`width` elements). Panics if `y >= height` (a programming error, not input).
    #[inline]
    pub fn row(&self, y: usize) -> &[T] {
        let s = y * self.stride;
        &self.data[s..s + self.width]
    }

    /// All pixels in storage order: pixel (x, y) is at `y * stride() + x` (the elements past
    /// `width` in each row, if the stride is wider, are padding).
    #[inline]
    pub fn as_slice(&self) -> &[T] {
        &self.data
    }

    /// Mutable row `y`.
    #[inline]
    pub fn row_mut(&mut self, y: usize) -> &mut [T] {
        let s = y * self.stride;
        &mut self.data[s..s + self.width]
    }

    /// Pixel (x, y).
    #[inline]
    pub fn get(&self, x: usize, y: usize) -> T {
        self.data[y * self.stride + x]
    }

    /// Sets pixel (x, y).
    #[inline]
    pub fn set(&mut self, x: usize, y: usize, v: T) {
        self.data[y * self.stride + x] = v;
    }

    /// Iterator over the rows.
    pub fn rows(&self) -> impl Iterator<Item = &[T]> {
        (0..self.height).map(move |y| self.row(y))
    }

    /// Sets every pixel to `v`.
    pub fn fill(&mut self, v: T) {
        for y in 0..self.height {
            self.row_mut(y).fill(v);
        }
    }

    /// Changes the size to `width` x `height` (stride = width), keeping the allocation when
    /// it is large enough. Pixel values are unspecified afterwards.
    pub fn resize(&mut self, width: usize, height: usize) {
        self.width = width;
        self.height = height;
        self.stride = width;
        let n = width * height;
        if self.data.len() < n {
            self.data.resize(n, T::default());
        }
    }

    /// The pixels as one contiguous slice, when stride = width.
    pub fn as_contiguous(&self) -> Option<&[T]> {
        (self.stride == self.width).then(|| &self.data[..self.width * self.height])
    }

    /// Mutable contiguous pixels, when stride = width.
    pub fn as_contiguous_mut(&mut self) -> Option<&mut [T]> {
        let n = self.width * self.height;
        (self.stride == self.width).then(|| &mut self.data[..n])
    }

    /// The pixels as a contiguous vector (row-major): the plane's own buffer when its rows
    /// are contiguous (no copy), else a compacted copy.
    pub fn into_vec(mut self) -> Vec<T> {
        if self.stride == self.width {
            self.data.truncate(self.width * self.height);
            return self.data;
        }
        self.to_vec()
    }

    /// Copies the pixels into a new contiguous vector (row-major).
    pub fn to_vec(&self) -> Vec<T> {
        self.rows().flat_map(|r| r.iter().copied()).collect()
    }

    /// Applies `f` to every pixel, producing a new plane.
    pub fn map<U: Copy + Default>(&self, mut f: impl FnMut(T) -> U) -> Plane<U> {
        Plane::from_fn(self.width, self.height, |x, y| f(self.get(x, y)))
    }
}

impl Plane<f32> {
    /// The first pixel (in row order) holding the largest value: `(x, y, value)`; `None` for
    /// an empty plane or one of only NaN.
    pub fn argmax(&self) -> Option<(usize, usize, f32)> {
        let mut best: Option<(usize, usize, f32)> = None;
        for (y, r) in self.rows().enumerate() {
            for (x, &v) in r.iter().enumerate() {
                if best.is_none_or(|b| v > b.2) && !v.is_nan() {
                    best = Some((x, y, v));
                }
            }
        }
        best
    }

    /// (min, max) over all pixels; (0, 0) for an empty plane. NaN pixels are ignored.
    pub fn min_max(&self) -> (f32, f32) {
        let mut mn = f32::INFINITY;
        let mut mx = f32::NEG_INFINITY;
        for r in self.rows() {
            for &v in r {
                mn = mn.min(v);
                mx = mx.max(v);
            }
        }
        if mn > mx {
            (0.0, 0.0)
        } else {
            (mn, mx)
        }
    }

    /// Sum of all pixels, accumulated in f64.
    pub fn sum(&self) -> f64 {
        self.rows().map(|r| r.iter().map(|&v| v as f64).sum::<f64>()).sum()
    }

    /// True when every pixel is finite.
    pub fn all_finite(&self) -> bool {
        self.rows().all(|r| r.iter().all(|v| v.is_finite()))
    }

    /// Copies `src` into `self`, resizing `self` to match.
    pub fn copy_from(&mut self, src: &Plane<f32>) {
        self.resize(src.width, src.height);
        for y in 0..src.height {
            self.row_mut(y).copy_from_slice(src.row(y));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn into_vec_gives_the_rows_in_order_strided_or_not() {
        let p = Plane::from_fn(3, 2, |x, y| (10 * y + x) as u32);
        assert_eq!(p.clone().into_vec(), vec![0, 1, 2, 10, 11, 12]);
        // Rows 5 apart in the buffer: compacted.
        let data = vec![0, 1, 2, 99, 99, 10, 11, 12, 99, 99];
        let s = Plane::from_vec_with_stride(3, 2, 5, data).unwrap();
        assert_eq!(s.into_vec(), p.to_vec());
    }
}
