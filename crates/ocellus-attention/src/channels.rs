//! Colour conversion and the colour-derived channels (SPEC 1.1, 1.3, 1.8).
//!
//! - intensity `I = w_r r + w_g g + w_b b`;
//! - opponency (Walther & Koch 2006): `RG = (r - g) / max(r, g, b)`,
//!   `BY = (b - min(r, g)) / max(r, g, b)`, both 0 where `max(r, g, b) < threshold`;
//! - skin: a Gaussian likelihood in (r, g) chromaticity.
//!
//! Channel values are in [0, 1] for r, g, b, I; RG and BY are in [-1, 1].

use ocellus_image::convert::RgbImage;
use ocellus_image::simd::Madd;
use ocellus_image::{dispatch_kernel, Backend, Plane};

/// Intensity and opponency of one pixel: (I, RG, BY).
#[inline(always)]
pub fn opponency(rgb: [f32; 3], weights: [f32; 3], threshold: f32) -> (f32, f32, f32) {
    let [r, g, b] = rgb;
    let i = weights[0] * r + weights[1] * g + weights[2] * b;
    let mx = r.max(g).max(b);
    if mx < threshold || mx <= 0.0 {
        (i, 0.0, 0.0)
    } else {
        (i, (r - g) / mx, (b - r.min(g)) / mx)
    }
}

/// Skin chromaticity model of the SaliencyToolbox (`skinHueParams`, Walther 2006 thesis
/// appendix A.4, from 3947 faces): mean (r, g) = (0.434904, 0.301983) in chromaticity
/// coordinates r = R / (R + G + B), g = G / (R + G + B), standard deviations 0.053375 and
/// 0.024349, correlation 0.5852.
pub const SKIN_MODEL: [f32; 5] = [0.434_904, 0.301_983, 0.053_375, 0.024_349, 0.5852];

/// Skin likelihood in [0, 1] of one pixel: `exp(-q / 2)` with q the Mahalanobis distance
/// of its chromaticity under [`SKIN_MODEL`]; 0 for pixels darker than `threshold` (max
/// channel), where chromaticity is noise.
#[inline(always)]
pub fn skin_likelihood(rgb: [f32; 3], threshold: f32) -> f32 {
    let [r, g, b] = rgb;
    let sum = r + g + b;
    if r.max(g).max(b) < threshold || sum <= 0.0 {
        return 0.0;
    }
    let [mr, mg, sr, sg, rho] = SKIN_MODEL;
    let dr = (r / sum - mr) / sr;
    let dg = (g / sum - mg) / sg;
    let q = (dr * dr - 2.0 * rho * dr * dg + dg * dg) / (1.0 - rho * rho);
    (-0.5 * q).exp()
}

#[inline(always)]
fn px_u8(p: [u8; 3]) -> [f32; 3] {
    const S: f32 = 1.0 / 255.0;
    [p[0] as f32 * S, p[1] as f32 * S, p[2] as f32 * S]
}

#[inline(always)]
fn split_rows<P: Copy + Default>(src: &Plane<P>, to: impl Fn(P) -> [f32; 3], out: [&mut Plane<f32>; 3]) {
    let [a, b, c] = out;
    for y in 0..src.height() {
        let (ra, rb, rc) = (a.row_mut(y), b.row_mut(y), c.row_mut(y));
        for (x, &p) in src.row(y).iter().enumerate() {
            let v = to(p);
            ra[x] = v[0];
            rb[x] = v[1];
            rc[x] = v[2];
        }
    }
}

#[inline(always)]
fn opponent_rows<P: Copy + Default>(
    src: &Plane<P>,
    to: impl Fn(P) -> [f32; 3],
    w: [f32; 3],
    thr: f32,
    out: [&mut Plane<f32>; 3],
) {
    split_rows(
        src,
        |p| {
            let (i, rg, by) = opponency(to(p), w, thr);
            [i, rg, by]
        },
        out,
    )
}

#[inline(always)]
#[allow(clippy::extra_unused_type_parameters)] // dispatch_kernel! instantiates every kernel with a Madd
fn split_u8_generic<M: Madd>(src: &Plane<[u8; 3]>, out: [&mut Plane<f32>; 3]) {
    split_rows(src, px_u8, out)
}

dispatch_kernel!(fn split_u8 => split_u8_generic(src: &Plane<[u8; 3]>, out: [&mut Plane<f32>; 3]));

#[inline(always)]
#[allow(clippy::extra_unused_type_parameters)] // dispatch_kernel! instantiates every kernel with a Madd
fn opponent_u8_generic<M: Madd>(src: &Plane<[u8; 3]>, w: [f32; 3], thr: f32, out: [&mut Plane<f32>; 3]) {
    opponent_rows(src, px_u8, w, thr, out)
}

dispatch_kernel!(fn opponent_u8 => opponent_u8_generic(src: &Plane<[u8; 3]>, w: [f32; 3], thr: f32, out: [&mut Plane<f32>; 3]));

fn resize3(out: &mut [&mut Plane<f32>; 3], w: usize, h: usize) {
    for p in out.iter_mut() {
        p.resize(w, h);
    }
}

/// Splits an RGB image into three float planes in [0, 1].
pub fn split_rgb(backend: Backend, img: &RgbImage, mut out: [&mut Plane<f32>; 3]) {
    let (w, h) = img.size();
    resize3(&mut out, w, h);
    match img {
        RgbImage::U8(p) => split_u8(backend, p, out),
        RgbImage::F32(p) => split_rows(p, |v| v, out),
    }
}

/// Intensity, RG and BY planes straight from an RGB image.
pub fn opponent_planes(
    backend: Backend,
    img: &RgbImage,
    weights: [f32; 3],
    threshold: f32,
    mut out: [&mut Plane<f32>; 3],
) {
    let (w, h) = img.size();
    resize3(&mut out, w, h);
    match img {
        RgbImage::U8(p) => opponent_u8(backend, p, weights, threshold, out),
        RgbImage::F32(p) => opponent_rows(p, |v| v, weights, threshold, out),
    }
}

#[inline(always)]
#[allow(clippy::extra_unused_type_parameters)] // dispatch_kernel! instantiates every kernel with a Madd
fn opponent_from_planes_generic<M: Madd>(
    rgb: [&Plane<f32>; 3],
    weights: [f32; 3],
    threshold: f32,
    out: [&mut Plane<f32>; 3],
) {
    let (w, h) = rgb[0].size();
    let [oi, org, oby] = out;
    oi.resize(w, h);
    org.resize(w, h);
    oby.resize(w, h);
    for y in 0..h {
        let (r, g, b) = (&rgb[0].row(y)[..w], &rgb[1].row(y)[..w], &rgb[2].row(y)[..w]);
        let (ri, rrg, rby) = (&mut oi.row_mut(y)[..w], &mut org.row_mut(y)[..w], &mut oby.row_mut(y)[..w]);
        for x in 0..w {
            let (i, rg, by) = opponency([r[x], g[x], b[x]], weights, threshold);
            ri[x] = i;
            rrg[x] = rg;
            rby[x] = by;
        }
    }
}

dispatch_kernel!(
    /// Intensity, RG and BY planes from R, G, B planes of one pyramid level (the same
    /// arithmetic as [`opponency`] on every backend: the wider builds only vectorize it).
    pub fn opponent_from_planes => opponent_from_planes_generic(rgb: [&Plane<f32>; 3], weights: [f32; 3], threshold: f32, out: [&mut Plane<f32>; 3])
);

/// Skin likelihood plane of an RGB image.
pub fn skin_plane(img: &RgbImage, threshold: f32, out: &mut Plane<f32>) {
    let (w, h) = img.size();
    out.resize(w, h);
    for y in 0..h {
        let row = out.row_mut(y);
        for (x, o) in row.iter_mut().enumerate() {
            *o = skin_likelihood(img.get_f32(x, y), threshold);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every build of the per-level opponency gives the pixel formula's values bit for bit,
    /// dark pixels (below the threshold, and black) included.
    #[test]
    fn opponent_from_planes_equals_the_pixel_formula_on_every_backend() {
        let mut rng = ocellus_image::rng::SplitMix64::new(3);
        let (w, h) = (37, 11);
        let mut plane = |dark: f64| Plane::from_fn(w, h, |_, _| (rng.unit() * dark) as f32);
        let rgb = [plane(1.0), plane(0.3), plane(0.05)];
        for weights in [[1.0 / 3.0; 3], [0.2989, 0.587, 0.114]] {
            for b in Backend::available() {
                let (mut i, mut rg, mut by) = (Plane::default(), Plane::default(), Plane::default());
                opponent_from_planes(b, [&rgb[0], &rgb[1], &rgb[2]], weights, 0.1, [&mut i, &mut rg, &mut by]);
                for y in 0..h {
                    for x in 0..w {
                        let want = opponency([rgb[0].get(x, y), rgb[1].get(x, y), rgb[2].get(x, y)], weights, 0.1);
                        let got = (i.get(x, y), rg.get(x, y), by.get(x, y));
                        assert_eq!(
                            [want.0.to_bits(), want.1.to_bits(), want.2.to_bits()],
                            [got.0.to_bits(), got.1.to_bits(), got.2.to_bits()],
                            "{b:?} at ({x}, {y})"
                        );
                    }
                }
            }
        }
    }
}
