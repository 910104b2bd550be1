//! Conversions between `image` crate buffers and ocellus planes.
//!
//! Every input kind (grey, grey+alpha, RGB, RGBA, 8 or 16 bits, float) becomes an RGB
//! image; alpha is dropped (not composited), grey is replicated to R = G = B.

use crate::{ImageError, Plane, Result};
use image::DynamicImage;

/// An RGB image as given to the attention pipeline.
#[derive(Clone, Debug, PartialEq)]
pub enum RgbImage {
    /// 8 bits per channel, interleaved.
    U8(Plane<[u8; 3]>),
    /// Float channels in [0, 1], interleaved (from 16-bit or float inputs).
    F32(Plane<[f32; 3]>),
}

impl RgbImage {
    /// (width, height).
    pub fn size(&self) -> (usize, usize) {
        match self {
            RgbImage::U8(p) => p.size(),
            RgbImage::F32(p) => p.size(),
        }
    }

    /// Pixel (x, y) as floats in [0, 1].
    pub fn get_f32(&self, x: usize, y: usize) -> [f32; 3] {
        match self {
            RgbImage::U8(p) => p.get(x, y).map(|v| v as f32 / 255.0),
            RgbImage::F32(p) => p.get(x, y),
        }
    }

    /// 8-bit copy (rounded, saturated), e.g. for overlays.
    pub fn to_u8(&self) -> Plane<[u8; 3]> {
        match self {
            RgbImage::U8(p) => p.clone(),
            RgbImage::F32(p) => p.map(|c| c.map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)),
        }
    }

    /// Grey in [0, 1]: BT.601 luma (0.299 R + 0.587 G + 0.114 B), the workspace's one grey
    /// conversion, unrounded.
    pub fn to_grey(&self) -> Plane<f32> {
        let (w, h) = self.size();
        Plane::from_fn(w, h, |x, y| luma(self.get_f32(x, y)))
    }

    /// 8-bit luma: [`RgbImage::to_grey`] times 255, rounded and saturated.
    pub fn to_luma8(&self) -> Plane<u8> {
        let (w, h) = self.size();
        Plane::from_fn(w, h, |x, y| (luma(self.get_f32(x, y)) * 255.0).round().clamp(0.0, 255.0) as u8)
    }
}

/// BT.601 luma of an RGB triple, in the triple's units.
pub fn luma([r, g, b]: [f32; 3]) -> f32 {
    0.299 * r + 0.587 * g + 0.114 * b
}

/// The three channels of an 8-bit RGB image as float planes (grey levels 0..=255, the units
/// of the bytes), for linear operators that keep units (resampling, remapping, log-polar).
pub fn split_rgb8(p: &Plane<[u8; 3]>) -> [Plane<f32>; 3] {
    std::array::from_fn(|c| p.map(|v| v[c] as f32))
}

/// 8-bit RGB from three float planes of grey levels 0..=255 (rounded, saturated): the
/// inverse of [`split_rgb8`]. The planes must have the same size; the first one's is used.
pub fn merge_rgb8(p: [&Plane<f32>; 3]) -> Plane<[u8; 3]> {
    let (w, h) = p[0].size();
    let at = |c: &Plane<f32>, x: usize, y: usize| if x < c.width() && y < c.height() { c.get(x, y) } else { 0.0 };
    Plane::from_fn(w, h, |x, y| p.map(|c| at(c, x, y).round().clamp(0.0, 255.0) as u8))
}

/// Converts any decoded image to RGB, keeping 16-bit and float precision.
pub fn from_dynamic(img: &DynamicImage) -> Result<RgbImage> {
    let (w, h) = (img.width() as usize, img.height() as usize);
    if w == 0 || h == 0 {
        return Err(ImageError::Empty { width: w, height: h });
    }
    let high_precision = matches!(
        img,
        DynamicImage::ImageLuma16(_)
            | DynamicImage::ImageLumaA16(_)
            | DynamicImage::ImageRgb16(_)
            | DynamicImage::ImageRgba16(_)
            | DynamicImage::ImageRgb32F(_)
            | DynamicImage::ImageRgba32F(_)
    );
    if high_precision {
        let buf = img.to_rgb32f();
        let data = buf.pixels().map(|p| p.0.map(|v| if v.is_finite() { v.clamp(0.0, 1.0) } else { 0.0 })).collect();
        Ok(RgbImage::F32(Plane::from_vec(w, h, data)?))
    } else {
        let buf = img.to_rgb8();
        let data = buf.pixels().map(|p| p.0).collect();
        Ok(RgbImage::U8(Plane::from_vec(w, h, data)?))
    }
}

/// An 8-bit RGB plane as an `image` buffer.
pub fn to_image_rgb8(p: &Plane<[u8; 3]>) -> image::RgbImage {
    let (w, h) = p.size();
    image::RgbImage::from_fn(w as u32, h as u32, |x, y| image::Rgb(p.get(x as usize, y as usize)))
}

/// A float map as an 8-bit grey `image` buffer, linearly scaled so `lo..hi` maps to 0..255.
pub fn to_image_gray8(p: &Plane<f32>, lo: f32, hi: f32) -> image::GrayImage {
    let g = to_grey8(p, lo, hi);
    image::GrayImage::from_fn(g.width() as u32, g.height() as u32, |x, y| image::Luma([g.get(x as usize, y as usize)]))
}

/// A float map as 8-bit grey: `lo` to 0, `hi` to 255, clamped, rounded; NaN to 0.
pub fn to_grey8(p: &Plane<f32>, lo: f32, hi: f32) -> Plane<u8> {
    let span = if hi > lo { hi - lo } else { 1.0 };
    // `as u8` of NaN is 0: a NaN pixel comes out black.
    p.map(|v| (((v - lo) / span).clamp(0.0, 1.0) * 255.0).round() as u8)
}

/// A grey `image` buffer as a float plane in [0, 1].
pub fn from_image_gray8(img: &image::GrayImage) -> Plane<f32> {
    Plane::from_fn(img.width() as usize, img.height() as usize, |x, y| {
        img.get_pixel(x as u32, y as u32).0[0] as f32 / 255.0
    })
}

/// An 8-bit grey `image` buffer as a grey plane.
pub fn from_image_luma8(img: &image::GrayImage) -> Plane<u8> {
    Plane::from_fn(img.width() as usize, img.height() as usize, |x, y| img.get_pixel(x as u32, y as u32).0[0])
}

/// A grey plane as an 8-bit grey `image` buffer.
pub fn to_image_luma8(p: &Plane<u8>) -> image::GrayImage {
    let (w, h) = p.size();
    image::GrayImage::from_fn(w as u32, h as u32, |x, y| image::Luma([p.get(x as usize, y as usize)]))
}

/// An 8-bit RGB `image` buffer as an interleaved RGB plane.
pub fn from_image_rgb8(img: &image::RgbImage) -> Plane<[u8; 3]> {
    Plane::from_fn(img.width() as usize, img.height() as usize, |x, y| img.get_pixel(x as u32, y as u32).0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn image_crate_round_trips() {
        let g = Plane::from_fn(7, 5, |x, y| (x * 30 + y) as u8);
        assert_eq!(from_image_luma8(&to_image_luma8(&g)), g);
        let c = Plane::from_fn(6, 4, |x, y| [x as u8, y as u8, (x * y) as u8]);
        assert_eq!(from_image_rgb8(&to_image_rgb8(&c)), c);
        let f = Plane::from_fn(3, 2, |x, _| x as f32 / 2.0);
        let back = from_image_gray8(&to_image_gray8(&f, 0.0, 1.0));
        assert!(back
            .rows()
            .zip(f.rows())
            .all(|(a, b)| a.iter().zip(b).all(|(p, q)| (p - q).abs() <= 0.5 / 255.0 + 1e-6)));
        let dynamic = image::DynamicImage::ImageLuma8(to_image_luma8(&g));
        let rgb = from_dynamic(&dynamic).unwrap();
        assert_eq!(rgb.get_f32(2, 1), [61.0 / 255.0; 3]);
        assert!(from_dynamic(&image::DynamicImage::new_rgb8(0, 3)).is_err());
    }
}
