//! One step of the iterative difference of Gaussians (Itti & Koch 2001) on eight
//! interleaved maps: the competition of N(.) (SPEC 1.6), `M <- max(0, M + E - I - c)`.

use super::{Lanes, PreservingFilter};

#[cfg(target_arch = "x86_64")]
mod x86;
use crate::simd::Madd;
use crate::{dispatch_kernel, Backend, Plane, Result};

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
    if backend.resolve() == Backend::Avx512 {
        let (e, i) = (&mut *excitation, &mut *inhibition);
        // SAFETY: `resolve()` returns Avx512 only on CPUs with AVX-512 F/BW/VL/DQ, AVX2 and FMA.
        let done =
            unsafe { x86::dog_step_avx512((&e.k, &e.rows, &mut e.wide), (&i.k, &i.rows, &mut i.wide), maps, &c) };
        if done {
            return Ok(());
        }
    }
    #[cfg(target_arch = "x86_64")]
    if backend.resolve() == Backend::Avx2 {
        let (e, i) = (&mut *excitation, &mut *inhibition);
        // SAFETY: `resolve()` returns Avx2 only on CPUs with AVX2 and FMA.
        let done = unsafe { x86::dog_step_avx2((&e.k, &e.rows, &mut e.wide), (&i.k, &i.rows, &mut i.wide), maps, &c) };
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
    #[cfg(target_arch = "x86_64")]
    if M::AVX512 {
        // SAFETY: `M::AVX512` is true only inside kernels compiled for AVX-512, which
        // `dispatch_kernel!` calls only on CPUs that have it.
        return unsafe { x86::compete_lanes(maps, excit, inhib, &c) };
    }
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

    /// With every backend, the step (fused with AVX-512) gives that backend's filters and
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

    /// The AVX-512 competition gives the generic one's results bit for bit.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx512_competition_equals_the_generic_one_bit_for_bit() {
        if !crate::simd::avx512_available() {
            return;
        }
        let mut rng = crate::rng::SplitMix64::new(11);
        for (w, h) in [(1, 1), (2, 3), (7, 5), (40, 30), (41, 31)] {
            let mut map = || -> Plane<Lanes> {
                Plane::from_fn(w, h, |_, _| std::array::from_fn(|_| rng.unit() as f32 * 4.0 - 1.0))
            };
            let (m, e, i) = (map(), map(), map());
            let c: Lanes = std::array::from_fn(|l| 0.1 * l as f32);
            let (mut a, mut b) = (m.clone(), m.clone());
            compete_lanes_generic::<crate::simd::Fused>(&mut a, &e, &i, c);
            // SAFETY: AVX-512 was checked above.
            unsafe { super::x86::compete_lanes(&mut b, &e, &i, &c) };
            assert_eq!(bits(&a), bits(&b), "{w}x{h}");
        }
    }
}
