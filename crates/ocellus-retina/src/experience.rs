//! Sensorimotor experience (SPEC 8.1): triplets (i0, i1, q) rendered from real images.
//!
//! Each triplet picks a source image and a gaze point uniformly (seeded), samples the disc
//! there (i0), applies the action to the sampling positions and samples again (i1, see
//! [`crate::action::Action::map`]): i1 is rendered from the source image, not from the patch,
//! so nothing enters from a border. Sampling is bilinear (`ocellus_image`'s pixel-centre
//! convention); gaze points keep every sample at least one pixel inside the image.

use crate::action::{Action, MotorCode};
use crate::disc::Disc;
use crate::{Real, Result, RetinaError};
use ocellus_image::resample::sample_bilinear;
use ocellus_image::rng::SplitMix64;
use ocellus_image::Plane;

/// A set of triplets as matrices: row t of `x0`, `x1` is triplet t's patch before and after
/// its action (grey, [0, 1]), row t of `q` its motor code.
#[derive(Clone, Debug, PartialEq)]
pub struct Experience<T> {
    /// Pixels per patch (N).
    pub pixels: usize,
    /// Motor cells (Q).
    pub motor_cells: usize,
    /// Patches before the action, T x N row-major.
    pub x0: Vec<T>,
    /// Patches after it, T x N.
    pub x1: Vec<T>,
    /// Motor codes, T x Q.
    pub q: Vec<T>,
    /// The actions, one per triplet.
    pub actions: Vec<Action>,
}

impl<T: Real> Experience<T> {
    /// Number of triplets.
    pub fn len(&self) -> usize {
        self.actions.len()
    }

    /// True when there are no triplets.
    pub fn is_empty(&self) -> bool {
        self.actions.is_empty()
    }

    /// The same triplets in another float type.
    pub fn convert<U: Real>(&self) -> Experience<U> {
        let c = |v: &[T]| v.iter().map(|x| U::from_f64(x.to_f64())).collect();
        Experience {
            pixels: self.pixels,
            motor_cells: self.motor_cells,
            x0: c(&self.x0),
            x1: c(&self.x1),
            q: c(&self.q),
            actions: self.actions.clone(),
        }
    }

    /// Mean squared error per pixel of the identity predictor, i1_hat = i0.
    pub fn identity_mse(&self) -> f64 {
        let s: f64 = self.x0.iter().zip(&self.x1).map(|(a, b)| (a.to_f64() - b.to_f64()).powi(2)).sum();
        s / (self.x0.len().max(1)) as f64
    }

    /// Checks that every value is finite (a user may build an experience by hand).
    pub fn validate(&self) -> Result<()> {
        let t = self.len();
        if t == 0 || self.pixels == 0 || self.motor_cells == 0 {
            return Err(RetinaError::Invalid("an experience needs triplets, pixels and motor cells".into()));
        }
        if self.x0.len() != t * self.pixels || self.x1.len() != t * self.pixels || self.q.len() != t * self.motor_cells
        {
            return Err(RetinaError::Invalid("experience matrices do not match its triplet count".into()));
        }
        if !self.x0.iter().chain(&self.x1).chain(&self.q).all(|v| v.to_f64().is_finite()) {
            return Err(RetinaError::Invalid("experience holds a value that is not finite".into()));
        }
        Ok(())
    }
}

/// Renders triplets: `actions[t]` applied at a random gaze point of a random source.
pub fn render<T: Real>(
    sources: &[Plane<f32>],
    disc: &Disc,
    actions: &[Action],
    code: &MotorCode,
    seed: u64,
) -> Result<Experience<T>> {
    if sources.is_empty() {
        return Err(RetinaError::Invalid("no source images for the experience".into()));
    }
    if actions.is_empty() {
        return Err(RetinaError::Invalid("no actions for the experience".into()));
    }
    let radius = disc.radius();
    let reach = actions.iter().map(|a| a.reach(radius)).fold(radius, f64::max);
    if !reach.is_finite() {
        return Err(RetinaError::Invalid("an action's reach is not finite".into()));
    }
    // A gaze point c with every sample inside [1, size - 2]: c in [m, size - 1 - m].
    let m = reach.ceil() + 1.0;
    let usable: Vec<&Plane<f32>> =
        sources.iter().filter(|p| p.width() as f64 > 2.0 * m + 1.0 && p.height() as f64 > 2.0 * m + 1.0).collect();
    if usable.is_empty() {
        let (w, h) = sources.iter().map(|p| p.size()).max().unwrap_or((0, 0));
        return Err(RetinaError::TooSmall(format!(
            "the patch of radius {radius:.1} px with actions reaching {reach:.1} px needs images larger than {0}x{0} px; the largest is {w}x{h}",
            (2.0 * m + 2.0) as usize
        )));
    }
    if !usable.iter().all(|p| p.all_finite()) {
        return Err(RetinaError::Invalid("a source image holds a value that is not finite".into()));
    }
    let (n, qn, t) = (disc.len(), code.len(), actions.len());
    let mut exp = Experience {
        pixels: n,
        motor_cells: qn,
        x0: vec![T::default(); t * n],
        x1: vec![T::default(); t * n],
        q: vec![T::default(); t * qn],
        actions: actions.to_vec(),
    };
    let mut rng = SplitMix64::new(seed);
    let mut qv = vec![0.0; qn];
    for (i, a) in actions.iter().enumerate() {
        let src = usable[rng.below(usable.len())];
        let cx = m + rng.unit() * (src.width() as f64 - 1.0 - 2.0 * m);
        let cy = m + rng.unit() * (src.height() as f64 - 1.0 - 2.0 * m);
        for (j, &[dx, dy]) in disc.offsets().iter().enumerate() {
            let p = [dx as f64, dy as f64];
            exp.x0[i * n + j] = T::from_f64(sample_bilinear(src, (cx + p[0]) as f32, (cy + p[1]) as f32) as f64);
            let s = a.map(p);
            exp.x1[i * n + j] = T::from_f64(sample_bilinear(src, (cx + s[0]) as f32, (cy + s[1]) as f32) as f64);
        }
        code.encode(a, &mut qv)?;
        for (o, &v) in exp.q[i * qn..(i + 1) * qn].iter_mut().zip(&qv) {
            *o = T::from_f64(v);
        }
    }
    Ok(exp)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shift_by_whole_pixels_is_the_same_image_moved() {
        let src = Plane::from_fn(80, 60, |x, y| ((x * 13 + y * 7) % 31) as f32 / 31.0);
        let disc = Disc::with_pixels(45).unwrap();
        let a = Action::Shift { dx: 2.0, dy: -1.0 };
        let e: Experience<f64> = render(&[src], &disc, &[a], &MotorCode::OneHot(vec![a]), 3).unwrap();
        // i1 at offset p is i0 at offset p + (2, -1), wherever both lie on the disc.
        let idx = |x: i32, y: i32| disc.offsets().iter().position(|&o| o == [x, y]);
        let mut checked = 0;
        for (j, &[dx, dy]) in disc.offsets().iter().enumerate() {
            if let Some(k) = idx(dx + 2, dy - 1) {
                assert!((e.x1[j] - e.x0[k]).abs() < 1e-6);
                checked += 1;
            }
        }
        assert!(checked > 20);
        assert_eq!(e.q, vec![1.0]);
    }

    #[test]
    fn too_small_images_and_empty_inputs_are_refused() {
        let src = Plane::from_fn(20, 20, |_, _| 0.5f32);
        let disc = Disc::with_pixels(481).unwrap();
        let a = Action::Shift { dx: 1.0, dy: 0.0 };
        let code = MotorCode::OneHot(vec![a]);
        assert!(matches!(
            render::<f32>(std::slice::from_ref(&src), &disc, &[a], &code, 1),
            Err(RetinaError::TooSmall(_))
        ));
        assert!(render::<f32>(&[], &disc, &[a], &code, 1).is_err());
        assert!(render::<f32>(&[src], &disc, &[], &code, 1).is_err());
    }
}
