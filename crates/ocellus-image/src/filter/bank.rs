//! A bank of row filters on one input: [`filter_rows_bank`].

use super::{check_kernel, filter_rows, symmetry, Border, FilterScratch, Symmetry};
use crate::{Backend, ImageError, Plane, Result};

/// Correlates every row of `src` with each kernel of `kernels` (centred) into the plane of
/// `dsts` at the same index (each resized to `src`): the same values as [`filter_rows`] per
/// kernel, bit for bit. With AVX-512 or AVX2 and 2 to 8 symmetric kernels (even or odd) of
/// one length up to 33 taps, the row is padded once and the shifted vectors are formed once
/// for all of them (the Gabor bank's six row passes take about the time of two with
/// AVX-512); otherwise it is [`filter_rows`] per kernel.
pub fn filter_rows_bank(
    backend: Backend,
    src: &Plane<f32>,
    kernels: &[&[f32]],
    dsts: &mut [Plane<f32>],
    border: Border,
    scratch: &mut FilterScratch,
) -> Result<()> {
    if kernels.len() != dsts.len() {
        return Err(ImageError::InvalidParameter(format!(
            "{} kernels for {} output planes",
            kernels.len(),
            dsts.len()
        )));
    }
    for k in kernels {
        check_kernel(k, "horizontal")?;
    }
    #[cfg(target_arch = "x86_64")]
    if backend.has_avx2() && (2..=super::x86::BANK_MAX).contains(&kernels.len()) {
        // Indices of the even and the odd kernels, on the stack: this runs per level and frame.
        let (mut even, mut odd) = ([0usize; super::x86::BANK_MAX], [0usize; super::x86::BANK_MAX]);
        let (mut ne, mut no) = (0, 0);
        for (i, k) in kernels.iter().enumerate() {
            match symmetry(k) {
                Symmetry::Even => {
                    even[ne] = i;
                    ne += 1;
                }
                Symmetry::Odd => {
                    odd[no] = i;
                    no += 1;
                }
                Symmetry::None => {}
            }
        }
        if ne + no == kernels.len() {
            for d in dsts.iter_mut() {
                d.resize(src.width(), src.height());
            }
            let p = &mut scratch.padded;
            let wide = backend.resolve() == Backend::Avx512;
            // SAFETY: `has_avx2()` holds only on CPUs with AVX2 and FMA, and `resolve()`
            // returns Avx512 only on CPUs with AVX-512 F/BW/VL/DQ besides.
            if unsafe { bank_dispatch(wide, src, kernels, (&even[..ne], &odd[..no]), dsts, border, p) } {
                return Ok(());
            }
        }
    }
    for (k, d) in kernels.iter().zip(dsts.iter_mut()) {
        filter_rows(backend, src, d, k, border, scratch)?;
    }
    Ok(())
}

/// [`super::x86::bank_rows_avx512`] (`wide`) or [`super::x86::bank_rows_avx2`] for the even
/// kernels at `even` and the odd ones at `odd` (false for counts it was not instantiated for).
///
/// # Safety
/// The CPU must have AVX2 and FMA, and AVX-512 F for `wide`.
#[cfg(target_arch = "x86_64")]
unsafe fn bank_dispatch(
    wide: bool,
    src: &Plane<f32>,
    ks: &[&[f32]],
    (even, odd): (&[usize], &[usize]),
    ds: &mut [Plane<f32>],
    border: Border,
    p: &mut Vec<f32>,
) -> bool {
    use super::x86::{bank_rows_avx2, bank_rows_avx512};
    macro_rules! arms {
        ($(($e:literal, $o:literal)),*) => {
            match (even.len(), odd.len()) {
                // SAFETY: the caller's promise.
                $(($e, $o) if wide => unsafe { bank_rows_avx512::<$e, $o>(src, ks, (even, odd), ds, border, p) },)*
                // SAFETY: the caller's promise.
                $(($e, $o) => unsafe { bank_rows_avx2::<$e, $o>(src, ks, (even, odd), ds, border, p) },)*
                _ => false,
            }
        };
    }
    // Every split of 2 to 8 kernels.
    arms!(
        (2, 0),
        (1, 1),
        (0, 2),
        (3, 0),
        (2, 1),
        (1, 2),
        (0, 3),
        (4, 0),
        (3, 1),
        (2, 2),
        (1, 3),
        (0, 4),
        (5, 0),
        (4, 1),
        (3, 2),
        (2, 3),
        (1, 4),
        (0, 5),
        (6, 0),
        (5, 1),
        (4, 2),
        (3, 3),
        (2, 4),
        (1, 5),
        (0, 6),
        (7, 0),
        (6, 1),
        (5, 2),
        (4, 3),
        (3, 4),
        (2, 5),
        (1, 6),
        (0, 7),
        (8, 0),
        (7, 1),
        (6, 2),
        (5, 3),
        (4, 4),
        (3, 5),
        (2, 6),
        (1, 7),
        (0, 8)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bank gives each kernel's own row pass bit for bit: even and odd kernels mixed,
    /// both borders, widths around the vector length, every backend this CPU has.
    #[test]
    fn bank_equals_one_kernel_at_a_time_bit_for_bit() {
        let mut rng = crate::rng::SplitMix64::new(9);
        let g = |i: usize, h: usize| (-((i as f32 - h as f32).powi(2)) / 9.0).exp();
        for h in [1usize, 4, 9, 16] {
            let n = 2 * h + 1;
            let even: Vec<f32> = (0..n).map(|i| g(i, h) * (1.0 + 0.1 * (i as f32 - h as f32).abs())).collect();
            let odd: Vec<f32> = (0..n).map(|i| g(i, h) * (i as f32 - h as f32)).collect();
            let ones = vec![1.0f32; n];
            let bank: Vec<&[f32]> = vec![&ones, &even, &odd, &even, &odd, &ones];
            for (w, hh) in [(3, 2), (8, 3), (15, 4), (16, 2), (17, 3), (40, 5), (160, 3)] {
                let src = Plane::from_fn(w, hh, |_, _| rng.unit() as f32);
                for border in [Border::Zero, Border::Clamp] {
                    for b in Backend::available() {
                        for kn in [2, 3, 6] {
                            let ks = &bank[..kn];
                            let mut s = FilterScratch::default();
                            let mut got: Vec<Plane<f32>> = (0..kn).map(|_| Plane::default()).collect();
                            filter_rows_bank(b, &src, ks, &mut got, border, &mut s).unwrap_or_else(|e| panic!("{e}"));
                            for (k, g) in ks.iter().zip(&got) {
                                let mut want = Plane::default();
                                filter_rows(b, &src, &mut want, k, border, &mut s).unwrap_or_else(|e| panic!("{e}"));
                                let same = want
                                    .rows()
                                    .zip(g.rows())
                                    .all(|(p, q)| p.iter().zip(q).all(|(x, y)| x.to_bits() == y.to_bits()));
                                assert!(same, "{w}x{hh}, {n} taps, {border:?}, {b:?}, {kn} kernels");
                            }
                        }
                    }
                }
            }
        }
        let src = Plane::from_fn(4, 4, |_, _| 0.5);
        let mut one = vec![Plane::default()];
        assert!(filter_rows_bank(
            Backend::Auto,
            &src,
            &[&[1.0], &[1.0]],
            &mut one,
            Border::Zero,
            &mut FilterScratch::default()
        )
        .is_err());
        assert!(filter_rows_bank(
            Backend::Auto,
            &src,
            &[&[1.0, 1.0]],
            &mut one,
            Border::Zero,
            &mut FilterScratch::default()
        )
        .is_err());
    }
}
