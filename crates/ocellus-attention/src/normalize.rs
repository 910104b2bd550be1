//! The competition operator N(.) (SPEC 1.6): iterative difference of Gaussians
//! (Itti & Koch 2001), the local-maxima rule of Itti et al. 1998, or none.

use crate::config::{GlobalInhibition, Normalization};
use crate::Result;
use ocellus_image::preserving::{dog_step_lanes, Lanes, PreservingFilter};
use ocellus_image::simd::Madd;
use ocellus_image::{dispatch_kernel, Backend, Plane};

#[cfg(target_arch = "x86_64")]
mod x86;

/// One competition step: `M <- max(0, M + E - I - c)`.
#[inline(always)]
#[allow(clippy::extra_unused_type_parameters)] // dispatch_kernel! instantiates every kernel with a Madd
fn compete_generic<M: Madd>(map: &mut Plane<f32>, excit: &Plane<f32>, inhib: &Plane<f32>, c: f32) {
    for y in 0..map.height() {
        let (e, i) = (excit.row(y), inhib.row(y));
        let m = map.row_mut(y);
        let n = m.len().min(e.len()).min(i.len());
        for ((v, &ev), &iv) in m[..n].iter_mut().zip(&e[..n]).zip(&i[..n]) {
            *v = (*v + ev - iv - c).max(0.0);
        }
    }
}

dispatch_kernel!(fn compete => compete_generic(map: &mut Plane<f32>, excit: &Plane<f32>, inhib: &Plane<f32>, c: f32));

/// 1D Gaussian `peak * exp(-i^2 / (2 sigma^2))` for `i = -hw..=hw`, with `hw` where it falls
/// below 1 % of the peak: `floor(sigma * sqrt(-2 ln 0.01))` (seed eq. 18), capped at `max_hw`
/// when `max_hw > 0`.
pub fn gaussian_kernel(peak: f32, sigma: f32, max_hw: usize) -> Vec<f32> {
    let mut hw = (sigma as f64 * (-2.0 * 0.01f64.ln()).sqrt()).floor() as usize;
    if max_hw > 0 && hw > max_hw {
        hw = max_hw;
    }
    let s2 = 2.0 * (sigma as f64) * (sigma as f64);
    (-(hw as isize)..=hw as isize).map(|i| (peak as f64 * (-((i * i) as f64) / s2).exp()) as f32).collect()
}

/// Linearly maps the map's [min, max] to [0, range]; a flat map (max - min <= `flat_tolerance`)
/// becomes `range / 2` everywhere (SaliencyToolbox `normalizeImage`).
pub fn scale_to_range(map: &mut Plane<f32>, range: f32, flat_tolerance: f32) {
    let (mn, mx) = map.min_max();
    for y in 0..map.height() {
        let row = map.row_mut(y);
        if mx - mn > flat_tolerance {
            let s = range / (mx - mn);
            row.iter_mut().for_each(|v| *v = (*v - mn) * s);
        } else {
            row.fill(0.5 * range);
        }
    }
}

fn clamp_negative(map: &mut Plane<f32>) {
    for y in 0..map.height() {
        map.row_mut(y).iter_mut().for_each(|v| *v = v.max(0.0));
    }
}

/// N(.) for maps of one size; owns its filters and buffers.
#[derive(Debug, Clone)]
pub struct Normalizer {
    kind: Normalization,
    excitation: Option<PreservingFilter>,
    inhibition: Option<PreservingFilter>,
    excit: Plane<f32>,
    inhib: Plane<f32>,
    flat_tolerance: f32,
    excit_lanes: Plane<Lanes>,
    inhib_lanes: Plane<Lanes>,
    one: Plane<f32>,
}

impl Normalizer {
    /// Builds N(.) for `width` x `height` maps.
    /// `flat_tolerance`: maps whose range is at most this are treated as flat before scaling.
    pub fn new(kind: &Normalization, width: usize, height: usize, flat_tolerance: f32) -> Result<Self> {
        let (mut excitation, mut inhibition) = (None, None);
        if let Normalization::Iterative {
            excitation_sigma_frac,
            inhibition_sigma_frac,
            c_excitation,
            c_inhibition,
            ..
        } = kind
        {
            let sz = width.max(height) as f32;
            let max_hw = (width.min(height) / 2).saturating_sub(1);
            let (es, is) = (sz * excitation_sigma_frac, sz * inhibition_sigma_frac);
            let root = (2.0 * std::f32::consts::PI).sqrt();
            excitation =
                Some(PreservingFilter::new(&gaussian_kernel(c_excitation / (es * root), es, max_hw), width, height)?);
            inhibition =
                Some(PreservingFilter::new(&gaussian_kernel(c_inhibition / (is * root), is, max_hw), width, height)?);
        }
        Ok(Self {
            kind: kind.clone(),
            excitation,
            inhibition,
            excit: Plane::new(width, height),
            inhib: Plane::new(width, height),
            flat_tolerance,
            excit_lanes: Plane::new(width, height),
            inhib_lanes: Plane::new(width, height),
            one: Plane::new(width, height),
        })
    }

    /// The 1D excitatory and inhibitory kernels of the iterative rule (peaks `c / (sigma
    /// sqrt(2 pi))`, cut and capped as [`gaussian_kernel`]); `None` for the other rules.
    pub fn kernels(&self) -> Option<[&[f32]; 2]> {
        Some([self.excitation.as_ref()?.kernel(), self.inhibition.as_ref()?.kernel()])
    }

    /// Applies N(.) in place: clamp at 0, scale to `[0, range]` when `range` is given, then
    /// compete. The result is finite and non-negative for any finite input.
    pub fn apply(&mut self, backend: Backend, map: &mut Plane<f32>, range: Option<f32>) -> Result<()> {
        clamp_negative(map);
        if let Some(r) = range {
            scale_to_range(map, r, self.flat_tolerance);
        }
        match &self.kind {
            Normalization::None => Ok(()),
            Normalization::LocalMax => {
                local_max(map, range);
                Ok(())
            }
            Normalization::Iterative { iterations, global_inhibition, .. } => {
                let (Some(ex), Some(inh)) = (self.excitation.as_mut(), self.inhibition.as_mut()) else {
                    return Ok(());
                };
                for _ in 0..*iterations {
                    ex.apply(backend, map, &mut self.excit)?;
                    inh.apply(backend, map, &mut self.inhib)?;
                    let c = match *global_inhibition {
                        GlobalInhibition::Constant(c) => c,
                        GlobalInhibition::RelativeToMax(f) => f * map.min_max().1,
                    };
                    compete(backend, map, &self.excit, &self.inhib, c);
                }
                Ok(())
            }
        }
    }
}

impl Normalizer {
    /// [`apply`](Self::apply) on eight interleaved maps at once; each lane gets exactly the
    /// treatment of `apply` (its own range scaling and global inhibition).
    pub fn apply_lanes(&mut self, backend: Backend, maps: &mut Plane<Lanes>, range: Option<f32>) -> Result<()> {
        let Normalization::Iterative { iterations, global_inhibition, .. } = self.kind.clone() else {
            // The other rules are cheap: one lane at a time.
            for l in 0..8 {
                self.one.resize(maps.width(), maps.height());
                for y in 0..maps.height() {
                    let (src, dst) = (maps.row(y), self.one.row_mut(y));
                    dst.iter_mut().zip(src).for_each(|(d, s)| *d = s[l]);
                }
                let mut one = std::mem::take(&mut self.one);
                let r = self.apply(backend, &mut one, range);
                for y in 0..maps.height() {
                    maps.row_mut(y).iter_mut().zip(one.row(y)).for_each(|(d, s)| d[l] = *s);
                }
                self.one = one;
                r?;
            }
            return Ok(());
        };
        let (mut mn, mut mx) = lanes_min_max(backend, maps);
        if let Some(r) = range {
            // Clamp at 0, then scale each lane to [0, r] (flat lanes to r / 2).
            mn = mn.map(|v| v.max(0.0));
            mx = mx.map(|v| v.max(0.0));
            let flat: [bool; 8] = std::array::from_fn(|l| mx[l] - mn[l] <= self.flat_tolerance);
            let scale: Lanes = std::array::from_fn(|l| if flat[l] { 0.0 } else { r / (mx[l] - mn[l]) });
            let offset: Lanes = std::array::from_fn(|l| if flat[l] { 0.5 * r } else { -mn[l] * scale[l] });
            lanes_affine(backend, maps, scale, offset);
        } else {
            lanes_affine(backend, maps, [1.0; 8], [0.0; 8]);
        }
        let (Some(ex), Some(inh)) = (self.excitation.as_mut(), self.inhibition.as_mut()) else { return Ok(()) };
        for _ in 0..iterations {
            // The filters leave `maps` as it is, so its maximum may be taken first.
            let c: Lanes = match global_inhibition {
                GlobalInhibition::Constant(c) => [c; 8],
                GlobalInhibition::RelativeToMax(f) => lanes_min_max(backend, maps).1.map(|m| f * m),
            };
            dog_step_lanes(backend, ex, inh, maps, (&mut self.excit_lanes, &mut self.inhib_lanes), c)?;
        }
        Ok(())
    }
}

/// Per-lane (min, max).
#[inline(always)]
#[allow(clippy::extra_unused_type_parameters)] // dispatch_kernel! instantiates every kernel with a Madd
fn lanes_min_max_generic<M: Madd>(maps: &Plane<Lanes>) -> (Lanes, Lanes) {
    #[cfg(target_arch = "x86_64")]
    if M::AVX512 {
        // SAFETY: `M::AVX512` is true only inside kernels compiled for AVX-512, which
        // `dispatch_kernel!` calls only on CPUs that have it.
        return unsafe { x86::lanes_min_max(maps) };
    }
    let (mut mn, mut mx) = ([f32::INFINITY; 8], [f32::NEG_INFINITY; 8]);
    for r in maps.rows() {
        for p in r {
            for l in 0..8 {
                mn[l] = mn[l].min(p[l]);
                mx[l] = mx[l].max(p[l]);
            }
        }
    }
    (mn, mx)
}

dispatch_kernel!(fn lanes_min_max => lanes_min_max_generic(maps: &Plane<Lanes>) -> (Lanes, Lanes));

/// `v <- max(0, v) * scale + offset` per lane.
#[inline(always)]
fn lanes_affine_generic<M: Madd>(maps: &mut Plane<Lanes>, scale: Lanes, offset: Lanes) {
    #[cfg(target_arch = "x86_64")]
    if M::AVX512 {
        // SAFETY: as in `lanes_min_max_generic`.
        return unsafe { x86::lanes_affine(maps, &scale, &offset) };
    }
    for y in 0..maps.height() {
        for p in maps.row_mut(y) {
            for l in 0..8 {
                p[l] = M::madd(p[l].max(0.0), scale[l], offset[l]);
            }
        }
    }
}

dispatch_kernel!(fn lanes_affine => lanes_affine_generic(maps: &mut Plane<Lanes>, scale: Lanes, offset: Lanes));

/// Itti et al. 1998: multiply by `(M - mean of local maxima)^2`, M the range's top (or the
/// map maximum without a range). Local maxima: interior pixels not below their 4 neighbours
/// nor below a tenth of the range (SaliencyToolbox `maxNormalizeLocalMax`). With one maximum
/// the factor is `M^2`; with none the map is left as is.
fn local_max(map: &mut Plane<f32>, range: Option<f32>) {
    let (thresh, gmax) = match range {
        Some(r) => (r / 10.0, r),
        None => (1.0, map.min_max().1),
    };
    let (w, h) = map.size();
    let (mut n, mut sum) = (0usize, 0f64);
    for y in 1..h.saturating_sub(1) {
        for x in 1..w.saturating_sub(1) {
            let v = map.get(x, y);
            if v >= thresh
                && v >= map.get(x - 1, y)
                && v >= map.get(x + 1, y)
                && v >= map.get(x, y - 1)
                && v >= map.get(x, y + 1)
            {
                n += 1;
                sum += v as f64;
            }
        }
    }
    let f = match n {
        0 => 1.0,
        1 => gmax * gmax,
        _ => {
            let d = gmax - (sum / n as f64) as f32;
            d * d
        }
    };
    for y in 0..h {
        map.row_mut(y).iter_mut().for_each(|v| *v *= f);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The AVX-512 min/max and affine steps give the generic kernels' results bit for bit,
    /// on widths with and without an odd last pixel.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx512_lane_steps_equal_the_generic_ones_bit_for_bit() {
        if !ocellus_image::simd::avx512_available() {
            return;
        }
        use ocellus_image::simd::Fused;
        let bits = |p: &Plane<Lanes>| -> Vec<u32> {
            p.rows().flat_map(|r| r.as_flattened().iter().map(|v| v.to_bits())).collect()
        };
        let mut rng = ocellus_image::rng::SplitMix64::new(11);
        for (w, h) in [(1, 1), (2, 3), (7, 5), (40, 30), (41, 31)] {
            let mut map = || -> Plane<Lanes> {
                Plane::from_fn(w, h, |_, _| std::array::from_fn(|_| rng.unit() as f32 * 4.0 - 1.0))
            };
            let m = map();
            let c: Lanes = std::array::from_fn(|l| 0.1 * l as f32);
            let s: Lanes = std::array::from_fn(|l| 1.0 + 0.37 * l as f32);
            // SAFETY: AVX-512 was checked above.
            let got = unsafe { x86::lanes_min_max(&m) };
            assert_eq!(got, lanes_min_max_generic::<Fused>(&m), "{w}x{h} min/max");
            let (mut a, mut b) = (m.clone(), m.clone());
            lanes_affine_generic::<Fused>(&mut a, s, c);
            // SAFETY: as above.
            unsafe { x86::lanes_affine(&mut b, &s, &c) };
            assert_eq!(bits(&a), bits(&b), "{w}x{h} affine");
        }
    }
}
