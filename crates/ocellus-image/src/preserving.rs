//! The energy-preserving separable filter of the iterative normalization: zero border,
//! kernel truncated at the border and renormalized (Walther & Koch 2006,
//! `sepConv2PreserveEnergy`), for one map or for eight maps interleaved in SIMD lanes.

use crate::filter::{
    accumulate_rows_generic, check_kernel, correlate_any_generic, symmetry, vertical_taps, Border, Symmetry,
};
use crate::simd::Madd;
use crate::{dispatch_kernel, Backend, ImageError, Plane, Result};

/// The energy-preserving factor of each pixel of an axis of `n` pixels for the 1D kernel `k`
/// (odd length, centred): `sum(k) / sum(taps of k that fall inside the axis)`, 1 away from
/// the borders. [`PreservingFilter`] scales each pass by it; a GPU port reads the same table.
pub fn preserving_factors(k: &[f32], n: usize) -> Vec<f32> {
    let total: f32 = k.iter().sum();
    let hw = (k.len().max(1) - 1) / 2;
    (0..n)
        .map(|i| {
            let inside: f32 = k
                .iter()
                .enumerate()
                .filter(|(t, _)| {
                    let p = i as isize + *t as isize - hw as isize;
                    p >= 0 && p < n as isize
                })
                .map(|(_, &v)| v)
                .sum();
            total / inside
        })
        .collect()
}

/// Separable correlation with a zero border whose result at each pixel is rescaled by
/// `sum(kernel) / sum(kernel taps inside the image)`, per axis: the kernel is truncated
/// at the border and renormalized, so a border does not lower the response
/// (Walther & Koch 2006, `sepConv2PreserveEnergy`).
///
/// Built once for a map size; [`PreservingFilter::apply`] allocates nothing.
#[derive(Debug, Clone)]
pub struct PreservingFilter {
    k: Vec<f32>,
    sym: Symmetry,
    width: usize,
    height: usize,
    fx: Vec<f32>,
    rows: Vec<Vec<(usize, f32)>>,
    padded: Vec<f32>,
    tmp: Plane<f32>,
    padded_lanes: Vec<Lanes>,
    tmp_lanes: Plane<Lanes>,
    wide: WideScratch,
}

/// Two pixels of eight interleaved maps, 64-byte aligned: one 512-bit register, one cache
/// line (the AVX-512 kernel's unit).
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
struct Pair([f32; 16]);

/// The hand-written lanes kernels' aligned buffers (see `preserving/x86.rs`): the padded row
/// as pairs from even pixels (`even`, pixel x of the map at `x + off`) and, for the AVX-512
/// kernel, from odd ones (`odd`), the horizontal pass's output (`tmp`, rows of `ceil(w / 2)`
/// pairs) and its border factors in pairs. Empty off x86-64.
#[derive(Clone, Debug, Default)]
struct WideScratch {
    off: usize,
    /// One past the highest row any vertical tap of the filter's `rows` reads (0 without
    /// taps), found when both were built: the rows never change after that, and the kernels
    /// take this scratch only with the rows of the filter that owns it.
    taps_below: usize,
    even: Vec<Pair>,
    odd: Vec<Pair>,
    tmp: Vec<Pair>,
    fx_pairs: Vec<Pair>,
}

/// Eight maps interleaved: pixel (x, y) holds the value at (x, y) of each of eight maps, so
/// one 256-bit operation processes one pixel of all of them.
pub type Lanes = [f32; 8];

impl PreservingFilter {
    /// The same 1D kernel `k` (odd length, positive sum) on both axes of a `width` x `height` map.
    pub fn new(k: &[f32], width: usize, height: usize) -> Result<Self> {
        check_kernel(k, "energy-preserving")?;
        let total: f32 = k.iter().sum();
        if total <= 0.0 {
            return Err(ImageError::InvalidParameter("energy-preserving kernel must have a positive sum".into()));
        }
        let hw = (k.len() - 1) / 2;
        let fx = preserving_factors(k, width);
        let fy = preserving_factors(k, height);
        let rows = (0..height)
            .map(|y| {
                let f = fy[y];
                let mut r = Vec::new();
                vertical_taps(y, height, k, Border::Zero, &mut r);
                r.iter_mut().for_each(|(_, w)| *w *= f);
                r
            })
            .collect::<Vec<Vec<(usize, f32)>>>();
        #[cfg(target_arch = "x86_64")]
        let wide = WideScratch::new(width, height, hw, &fx, &rows);
        #[cfg(not(target_arch = "x86_64"))]
        let wide = WideScratch::default();
        Ok(Self {
            k: k.to_vec(),
            sym: symmetry(k),
            width,
            height,
            fx,
            rows,
            padded: vec![0.0; width + 2 * hw],
            tmp: Plane::new(width, height),
            padded_lanes: vec![[0.0; 8]; width + 2 * hw],
            tmp_lanes: Plane::new(width, height),
            wide,
        })
    }

    /// The 1D kernel (the same on both axes).
    pub fn kernel(&self) -> &[f32] {
        &self.k
    }

    /// Filters `src` (which must be `width` x `height`) into `dst`.
    pub fn apply(&mut self, backend: Backend, src: &Plane<f32>, dst: &mut Plane<f32>) -> Result<()> {
        crate::check::same_size("map", src.size(), (self.width, self.height))?;
        dst.resize(self.width, self.height);
        preserving_kernel(backend, &self.k, self.sym, &self.fx, &self.rows, &mut self.padded, &mut self.tmp, src, dst);
        Ok(())
    }
}

impl PreservingFilter {
    /// [`apply`](Self::apply) on eight interleaved maps at once (same result per lane).
    pub fn apply_lanes(&mut self, backend: Backend, src: &Plane<Lanes>, dst: &mut Plane<Lanes>) -> Result<()> {
        crate::check::same_size("maps", src.size(), (self.width, self.height))?;
        dst.resize(self.width, self.height);
        preserving_lanes_kernel(
            backend,
            &self.k,
            &self.fx,
            &self.rows,
            &mut self.padded_lanes,
            &mut self.tmp_lanes,
            &mut self.wide,
            src,
            dst,
        );
        Ok(())
    }
}

/// `B` pixels of eight lanes: `sum_i w(i) * s(i)[j]` for j in 0..B.
#[inline(always)]
fn lanes_block<'a, M: Madd, const B: usize>(
    n: usize,
    w: impl Fn(usize) -> f32,
    s: impl Fn(usize) -> &'a [Lanes; B],
) -> [Lanes; B] {
    let mut acc = [[0f32; 8]; B];
    for i in 0..n {
        let (wi, si) = (w(i), s(i));
        for j in 0..B {
            for l in 0..8 {
                acc[j][l] = M::madd(wi, si[j][l], acc[j][l]);
            }
        }
    }
    acc
}

#[inline(always)]
fn preserving_lanes_generic<M: Madd>(
    k: &[f32],
    fx: &[f32],
    rows: &[Vec<(usize, f32)>],
    padded: &mut [Lanes],
    tmp: &mut Plane<Lanes>,
    wide: &mut WideScratch,
    src: &Plane<Lanes>,
    dst: &mut Plane<Lanes>,
) {
    #[cfg(target_arch = "x86_64")]
    if M::AVX512 {
        // SAFETY: `M::AVX512` is true only inside kernels compiled for AVX-512, which
        // `dispatch_kernel!` calls only on CPUs that have it.
        if unsafe { x86::preserving_lanes_avx512(k, rows, wide, src, dst) } {
            return;
        }
    }
    #[cfg(target_arch = "x86_64")]
    if M::AVX2 {
        // SAFETY: `M::AVX2` is true only inside kernels compiled for AVX2 and FMA, which
        // `dispatch_kernel!` calls only on CPUs that have both.
        if unsafe { x86::preserving_lanes_avx2(k, rows, wide, src, dst) } {
            return;
        }
    }
    const Z: [Lanes; 8] = [[0.0; 8]; 8];
    let hw = (k.len() - 1) / 2;
    let (w, h) = src.size();
    tmp.resize(w, h);
    for y in 0..h {
        // The ends of `padded` stay zero: only the middle is ever written.
        padded[hw..hw + w].copy_from_slice(src.row(y));
        let out = tmp.row_mut(y);
        let mut x = 0;
        while x < w && w >= 8 {
            let x0 = if x + 8 <= w { x } else { w - 8 };
            let acc = lanes_block::<M, 8>(k.len(), |t| k[t], |t| padded[x0 + t..x0 + t + 8].try_into().unwrap_or(&Z));
            for j in 0..8 {
                let f = fx[x0 + j];
                out[x0 + j] = acc[j].map(|v| v * f);
            }
            x = x0 + 8;
        }
        while x < w {
            let mut a = [0f32; 8];
            for (t, &kt) in k.iter().enumerate() {
                for l in 0..8 {
                    a[l] = M::madd(kt, padded[x + t][l], a[l]);
                }
            }
            out[x] = a.map(|v| v * fx[x]);
            x += 1;
        }
    }
    // Vertical pass in strips of 8 columns: a strip of all rows (8 px x 32 B x h) stays in
    // L1, whereas whole rows (29 taps x 40 px x 32 B) would stream from L2 for every output row.
    let mut x = 0;
    while x < w && w >= 8 {
        let x0 = if x + 8 <= w { x } else { w - 8 };
        for (y, r) in rows.iter().enumerate() {
            let acc =
                lanes_block::<M, 8>(r.len(), |i| r[i].1, |i| tmp.row(r[i].0)[x0..x0 + 8].try_into().unwrap_or(&Z));
            dst.row_mut(y)[x0..x0 + 8].copy_from_slice(&acc);
        }
        x = x0 + 8;
    }
    for (y, r) in rows.iter().enumerate() {
        for xx in x..w {
            let mut a = [0f32; 8];
            for &(ry, wt) in r {
                for l in 0..8 {
                    a[l] = M::madd(wt, tmp.row(ry)[xx][l], a[l]);
                }
            }
            dst.row_mut(y)[xx] = a;
        }
    }
}

mod dog;
pub use dog::dog_step_lanes;

#[cfg(target_arch = "x86_64")]
mod x86;

dispatch_kernel!(fn preserving_lanes_kernel => preserving_lanes_generic(
    k: &[f32], fx: &[f32], rows: &[Vec<(usize, f32)>], padded: &mut [Lanes], tmp: &mut Plane<Lanes>, wide: &mut WideScratch,
    src: &Plane<Lanes>, dst: &mut Plane<Lanes>
));

#[inline(always)]
fn preserving_generic<M: Madd>(
    k: &[f32],
    sym: Symmetry,
    fx: &[f32],
    rows: &[Vec<(usize, f32)>],
    padded: &mut [f32],
    tmp: &mut Plane<f32>,
    src: &Plane<f32>,
    dst: &mut Plane<f32>,
) {
    let hw = (k.len() - 1) / 2;
    let w = src.width();
    for y in 0..src.height() {
        padded[hw..hw + w].copy_from_slice(src.row(y));
        let out = tmp.row_mut(y);
        correlate_any_generic::<M>(padded, k, sym, out);
        for (o, f) in out.iter_mut().zip(fx) {
            *o *= f;
        }
    }
    for (y, r) in rows.iter().enumerate() {
        // The generic kernels: on 40-pixel rows the hand-written ones were slower (13 -> 17 us
        // for one normalization), their set-up and tails weighing more than their gain.
        accumulate_rows_generic::<M>(tmp, r, dst.row_mut(y));
    }
}

dispatch_kernel!(fn preserving_kernel => preserving_generic(
    k: &[f32], sym: Symmetry, fx: &[f32], rows: &[Vec<(usize, f32)>], padded: &mut [f32], tmp: &mut Plane<f32>, src: &Plane<f32>, dst: &mut Plane<f32>
));
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn preserving_factors_renormalize_the_truncated_kernel() {
        let k = [1.0, 2.0, 4.0, 2.0, 1.0];
        let f = preserving_factors(&k, 6);
        // At the first pixel the taps -2 and -1 fall outside: 10 / 7.
        assert!((f[0] - 10.0 / 7.0).abs() < 1e-6);
        assert!((f[1] - 10.0 / 9.0).abs() < 1e-6);
        assert_eq!(f[2], 1.0);
        assert_eq!(f[3], 1.0);
        assert!((f[5] - 10.0 / 7.0).abs() < 1e-6);
    }

    /// The hand-written AVX2 and AVX-512 kernels give the generic kernel's results bit for
    /// bit (the same fused multiply-add chain per output), over widths around their block
    /// sizes and a short and a long kernel.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn hand_written_lanes_kernels_equal_the_generic_kernel_bit_for_bit() {
        if !crate::simd::avx2_available() {
            return;
        }
        let same = |a: &Plane<Lanes>, b: &Plane<Lanes>| {
            a.rows()
                .zip(b.rows())
                .all(|(a, b)| a.as_flattened().iter().zip(b.as_flattened()).all(|(p, q)| p.to_bits() == q.to_bits()))
        };
        let mut rng = crate::rng::SplitMix64::new(5);
        for taps in [1usize, 5, 29] {
            let k: Vec<f32> = (0..taps).map(|_| rng.unit() as f32 + 0.1).collect();
            for (w, h) in
                [(1, 3), (2, 1), (3, 4), (7, 5), (8, 3), (15, 7), (16, 30), (17, 9), (40, 30), (41, 31), (77, 3)]
            {
                let src: Plane<Lanes> = Plane::from_fn(w, h, |_, _| std::array::from_fn(|_| rng.unit() as f32));
                let f = PreservingFilter::new(&k, w, h).unwrap_or_else(|e| panic!("{e}"));
                let (mut pad, mut tmp) = (f.padded_lanes.clone(), Plane::default());
                let mut want = Plane::new(w, h);
                // Empty buffers: the hand-written kernels refuse them, so this is the generic loop.
                let mut unused = WideScratch::default();
                preserving_lanes_generic::<crate::simd::Fused>(
                    &k,
                    &f.fx,
                    &f.rows,
                    &mut pad,
                    &mut tmp,
                    &mut unused,
                    &src,
                    &mut want,
                );
                let mut got = Plane::from_fn(w, h, |_, _| [f32::NAN; 8]);
                // SAFETY: AVX2 and FMA were checked above.
                let ran = unsafe { x86::preserving_lanes_avx2(&k, &f.rows, &mut f.wide.clone(), &src, &mut got) };
                assert!(ran && same(&want, &got), "{taps} taps, {w}x{h} (256)");
                if crate::simd::avx512_available() && w >= 2 {
                    let mut got = Plane::from_fn(w, h, |_, _| [f32::NAN; 8]);
                    // SAFETY: AVX-512 was checked just above.
                    let ran = unsafe { x86::preserving_lanes_avx512(&k, &f.rows, &mut f.wide.clone(), &src, &mut got) };
                    assert!(ran && same(&want, &got), "{taps} taps, {w}x{h} (512)");
                }
            }
        }
    }
}
