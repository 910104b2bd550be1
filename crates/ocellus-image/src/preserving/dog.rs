//! One step of the iterative difference of Gaussians (Itti & Koch 2001) on eight
//! interleaved maps: the competition of N(.) (SPEC 1.6), `M <- max(0, M + E - I - c)`.

use super::{Lanes, PreservingFilter};
use crate::simd::Madd;
use crate::{dispatch_kernel, Backend, Plane, Result};

#[cfg(target_arch = "x86_64")]
mod x86;

/// `maps <- max(0, maps + E - I - c)` per lane, with `E` and `I` the maps through
/// `excitation` and `inhibition` (both built for the maps' size; `excit` and `inhib` are
/// scratch planes). The same values as [`PreservingFilter::apply_lanes`] with each filter
/// followed by the competition; with AVX-512 or AVX2 the three run as one pass (the row
/// prepared once for both filters, both sums taken from registers), bit-identical.
pub fn dog_step_lanes(
    backend: Backend,
    excitation: &mut PreservingFilter,
    inhibition: &mut PreservingFilter,
    maps: &mut Plane<Lanes>,
    (excit, inhib): (&mut Plane<Lanes>, &mut Plane<Lanes>),
    c: Lanes,
) -> Result<()> {
    crate::check::same_size("maps", maps.size(), (excitation.width, excitation.height))?;
    crate::check::same_size("maps", maps.size(), (inhibition.width, inhibition.height))?;
    #[cfg(target_arch = "x86_64")]
    {
        let (e, i) = (&mut *excitation, &mut *inhibition);
        let (ex, inh) = ((&e.k[..], &e.rows[..], &mut e.wide), (&i.k[..], &i.rows[..], &mut i.wide));
        // SAFETY: `resolve()` returns Avx512 only on CPUs with AVX-512 F/BW/VL/DQ, AVX2 and
        // FMA, and Avx2 only on CPUs with AVX2 and FMA.
        let done = match backend.resolve() {
            Backend::Avx512 => unsafe { x86::dog_step_avx512(ex, inh, maps, &c) },
            Backend::Avx2 => unsafe { x86::dog_step_avx2(ex, inh, maps, &c) },
            _ => false,
        };
        if done {
            return Ok(());
        }
    }
    excitation_then_inhibition(backend, excitation, inhibition, maps, excit, inhib, c)
}

/// The unfused step: each filter, then the competition.
fn excitation_then_inhibition(
    backend: Backend,
    excitation: &mut PreservingFilter,
    inhibition: &mut PreservingFilter,
    maps: &mut Plane<Lanes>,
    excit: &mut Plane<Lanes>,
    inhib: &mut Plane<Lanes>,
    c: Lanes,
) -> Result<()> {
    excitation.apply_lanes(backend, maps, excit)?;
    inhibition.apply_lanes(backend, maps, inhib)?;
    compete_lanes(backend, maps, excit, inhib, c);
    Ok(())
}

/// One competition step per lane: `M <- max(0, M + E - I - c)`.
#[inline(always)]
#[allow(clippy::extra_unused_type_parameters)] // dispatch_kernel! instantiates every kernel with a Madd
fn compete_lanes_generic<M: Madd>(maps: &mut Plane<Lanes>, excit: &Plane<Lanes>, inhib: &Plane<Lanes>, c: Lanes) {
    for y in 0..maps.height() {
        let (e, i) = (excit.row(y), inhib.row(y));
        for ((p, ev), iv) in maps.row_mut(y).iter_mut().zip(e).zip(i) {
            for l in 0..8 {
                p[l] = (p[l] + ev[l] - iv[l] - c[l]).max(0.0);
            }
        }
    }
}

dispatch_kernel!(fn compete_lanes => compete_lanes_generic(maps: &mut Plane<Lanes>, excit: &Plane<Lanes>, inhib: &Plane<Lanes>, c: Lanes));

#[cfg(test)]
mod tests {
    use super::*;

    fn bits(p: &Plane<Lanes>) -> Vec<u32> {
        p.rows().flat_map(|r| r.as_flattened().iter().map(|v| v.to_bits())).collect()
    }

    /// With every backend, the step (fused with AVX-512 and AVX2) gives that backend's filters and
    /// competition run one after the other, bit for bit: widths odd and even (the last block
    /// then overlaps the one before), odd and even row counts, short and long kernels.
    #[test]
    fn fused_step_equals_filters_then_competition_bit_for_bit() {
        let mut rng = crate::rng::SplitMix64::new(21);
        for (te, ti) in [(1usize, 1usize), (5, 29), (3, 9), (5, 5), (9, 3)] {
            let g = |n: usize, s: f32| -> Vec<f32> {
                (0..n).map(|i| (-((i as f32 - (n / 2) as f32).powi(2)) / (2.0 * s * s)).exp() * 0.3).collect()
            };
            let (ke, ki) = (g(te, 0.8), g(ti, 10.0));
            for (w, h) in [(2, 1), (3, 2), (7, 5), (16, 4), (17, 9), (40, 30), (41, 31)] {
                let src: Plane<Lanes> = Plane::from_fn(w, h, |_, _| std::array::from_fn(|_| rng.unit() as f32 * 3.0));
                let c: Lanes = std::array::from_fn(|l| 0.05 * l as f32);
                let mk = |k: &[f32]| PreservingFilter::new(k, w, h).unwrap_or_else(|e| panic!("{e}"));
                let (mut ex, mut inh) = (mk(&ke), mk(&ki));
                let (mut e, mut i) = (Plane::default(), Plane::default());
                for b in Backend::available() {
                    let mut want = src.clone();
                    excitation_then_inhibition(b, &mut ex, &mut inh, &mut want, &mut e, &mut i, c)
                        .unwrap_or_else(|err| panic!("{err}"));
                    let mut got = src.clone();
                    dog_step_lanes(b, &mut ex, &mut inh, &mut got, (&mut e, &mut i), c)
                        .unwrap_or_else(|err| panic!("{err}"));
                    assert_eq!(bits(&want), bits(&got), "{te}/{ti} taps, {w}x{h}, {b:?}");
                }
            }
        }
    }
}
