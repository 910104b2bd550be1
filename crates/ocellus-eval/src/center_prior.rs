//! An evaluation-friendly saliency output: the map blurred and mixed with a centre prior.
//!
//! People look at image centres (Tatler 2007; Judd et al. 2009), so benchmark-winning models
//! blur their maps and add a centre bias. This is a separate output mode; the raw saliency map
//! of the saliency engine is unchanged.
//!
//! `out = (1 - w) * B(S) / max(B(S)) + w * G`, where B is a Gaussian blur of sigma
//! `blur_sigma_frac_width * width` and G a Gaussian centred on the image, peak 1, sigma
//! `center_sigma_frac * max(width, height)`.

use crate::{EvalError, Result};
use ocellus_image::filter::gaussian_blur;
use ocellus_image::resample::{ResampleMethod, Resampler};
use ocellus_image::{Backend, Plane};
use serde::{Deserialize, Serialize};

/// Blur and centre-prior parameters (fractions of the image size, so they apply to any size).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CenterPrior {
    /// Blur sigma as a fraction of the image width (0: no blur).
    pub blur_sigma_frac_width: f32,
    /// Weight w of the centre prior in [0, 1] (0: none).
    pub weight: f32,
    /// Sigma of the centre Gaussian as a fraction of the larger image side.
    pub center_sigma_frac: f32,
}

impl CenterPrior {
    /// Checks the ranges.
    pub fn validate(&self) -> Result<()> {
        use ocellus_image::check;
        (|| {
            check::within("blur (sigma, fraction of the width)", self.blur_sigma_frac_width, 0.0, 0.5)?;
            check::within("centre prior weight", self.weight, 0.0, 1.0)?;
            check::within("centre prior sigma (fraction of the larger side)", self.center_sigma_frac, 1e-6, 2.0)
        })()
        .map_err(EvalError::InvalidConfig)
    }

    /// Applies blur and prior to a map at the map level (`map`, any size) and returns it at
    /// `width` x `height`. The blur runs at the map level (its sigma scaled to map pixels),
    /// then the map is upsampled bilinearly: for the blurs of interest (several map pixels)
    /// that equals blurring the full-size map, at a fraction of the cost.
    /// `backend` runs the blur and resampling kernels.
    pub fn apply(&self, backend: Backend, map: &Plane<f32>, width: usize, height: usize) -> Result<Plane<f32>> {
        self.validate()?;
        if map.is_empty() || width == 0 || height == 0 {
            return Err(EvalError::InvalidConfig(format!(
                "cannot apply a centre prior to a {}x{} map at {width}x{height}",
                map.width(),
                map.height()
            )));
        }
        let sigma_map = self.blur_sigma_frac_width * map.width() as f32;
        let blurred = gaussian_blur(backend, map, sigma_map)?;
        let mut full = Plane::default();
        Resampler::new(ResampleMethod::Bilinear, blurred.size(), (width, height))?
            .apply(backend, &blurred, &mut full)?;
        let mx = full.min_max().1;
        let s = if mx > 0.0 { (1.0 - self.weight) / mx } else { 0.0 };
        let g = center_gaussian(width, height, self.center_sigma_frac * width.max(height) as f32);
        for y in 0..height {
            let gr = g.row(y);
            full.row_mut(y).iter_mut().zip(gr).for_each(|(v, q)| *v = *v * s + self.weight * q);
        }
        Ok(full)
    }
}

/// A Gaussian of peak 1 centred on the image, sigma in pixels. The centre is
/// ((width - 1) / 2, (height - 1) / 2) in the workspace's integer pixel centres.
pub fn center_gaussian(width: usize, height: usize, sigma: f32) -> Plane<f32> {
    let (cx, cy) = ((width as f32 - 1.0) / 2.0, (height as f32 - 1.0) / 2.0);
    let s2 = 2.0 * sigma * sigma;
    let gx: Vec<f32> = (0..width).map(|x| (-((x as f32 - cx).powi(2)) / s2).exp()).collect();
    let gy: Vec<f32> = (0..height).map(|y| (-((y as f32 - cy).powi(2)) / s2).exp()).collect();
    Plane::from_fn(width, height, |x, y| gx[x] * gy[y])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prior_alone_is_the_centre_gaussian() {
        let map = Plane::from_fn(8, 6, |x, _| x as f32);
        let p = CenterPrior { blur_sigma_frac_width: 0.0, weight: 1.0, center_sigma_frac: 0.25 };
        let out = p.apply(Backend::Scalar, &map, 64, 48).unwrap();
        let g = center_gaussian(64, 48, 16.0);
        assert_eq!(out, g);
        // peak at the centre, symmetric
        assert!((out.get(31, 23) - out.get(32, 24)).abs() < 1e-6);
        assert!(out.get(0, 0) < 0.1);
    }

    #[test]
    fn blur_keeps_mass_and_spreads_a_spike() {
        let mut m = Plane::<f32>::new(21, 21);
        m.set(10, 10, 1.0);
        let b = gaussian_blur(Backend::Scalar, &m, 2.0).unwrap();
        assert!((b.sum() - 1.0).abs() < 1e-4);
        assert!(b.get(10, 10) < 0.1 && b.get(12, 10) > 0.01);
        assert!(gaussian_blur(Backend::Scalar, &m, f32::NAN).is_err());
        let p = CenterPrior { blur_sigma_frac_width: 0.1, weight: 0.5, center_sigma_frac: 0.2 };
        let out = p.apply(Backend::Scalar, &m, 84, 84).unwrap();
        assert!(out.all_finite() && out.min_max().1 <= 1.0 + 1e-6);
        assert!(CenterPrior { weight: 1.5, ..p }.apply(Backend::Scalar, &m, 10, 10).is_err());
    }
}
