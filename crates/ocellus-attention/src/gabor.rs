//! Orientation channel: Gabor energy `|I * G_0| + |I * G_{pi/2}|` (SPEC 1.4).
//!
//! With an isotropic envelope (gamma = 1) the complex Gabor factors into two complex 1D
//! filters: `g(x) e^{i k x cos t} * g(y) e^{i k y sin t}` with `g(u) = exp(-u^2 / 2 sigma^2)`
//! and `k = 2 pi / lambda`. Its real part is the even (psi = 0) kernel and its imaginary
//! part the odd one (psi = pi/2, up to sign). Removing a kernel's mean m is the same as
//! subtracting `m * (I * box)`, and the box filter is separable too, so the exact
//! mean-removed, unit-norm 2D filter of SPEC 1.4 is computed with 1D passes only:
//! about 13 passes of `size` taps per pixel for the four standard angles instead of
//! 2 x 4 x size^2 taps (angles t and 180 - t share all passes).

use crate::config::{GaborBorder, GaborConfig};
use crate::Result;
use ocellus_image::filter::{filter_cols, filter_rows_bank, Border, FilterScratch};
use ocellus_image::simd::Madd;
use ocellus_image::{dispatch_kernel, Backend, Plane};

/// 1D factors and 2D normalization constants of one orientation.
#[derive(Clone, Debug)]
struct AngleFilters {
    /// Horizontal real and imaginary parts (x factor), None when identically zero.
    hr: Vec<f32>,
    hi: Option<Vec<f32>>,
    /// Vertical real and imaginary parts (y factor).
    vr: Vec<f32>,
    vi: Option<Vec<f32>>,
    /// Means of the even and odd 2D kernels.
    mean_even: f32,
    mean_odd: f32,
    /// 1 / L2 norm of the mean-removed even and odd kernels.
    inv_norm_even: f32,
    inv_norm_odd: f32,
    /// Index of an earlier angle with cos negated and sin equal (theta' = 180 - theta).
    mirror_of: Option<usize>,
}

/// The 2D Gabor kernel of SPEC 1.4 (mean removed, unit L2 norm), row-major `size` x `size`,
/// entry (row j, column i) at offset (x = i - size/2, y = j - size/2). Used as the
/// independent reference in tests and for display.
pub fn kernel_2d(cfg: &GaborConfig, angle_deg: f32, psi: f64) -> Vec<f32> {
    let n = cfg.size as isize;
    let hw = n / 2;
    let (s, c) = (angle_deg as f64).to_radians().sin_cos();
    let k = 2.0 * std::f64::consts::PI / cfg.wavelength_px as f64;
    let sig2 = 2.0 * (cfg.sigma_px as f64).powi(2);
    let gamma = cfg.gamma as f64;
    let mut v: Vec<f64> = Vec::with_capacity((n * n) as usize);
    for j in -hw..=hw {
        for i in -hw..=hw {
            let (x, y) = (i as f64, j as f64);
            let xp = x * c + y * s;
            let yp = -x * s + y * c;
            v.push((-(xp * xp + gamma * gamma * yp * yp) / sig2).exp() * (k * xp + psi).cos());
        }
    }
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    v.iter_mut().for_each(|a| *a -= mean);
    let norm = v.iter().map(|a| a * a).sum::<f64>().sqrt();
    v.iter().map(|a| if norm > 0.0 { (a / norm) as f32 } else { 0.0 }).collect()
}

fn factor(n: usize, sigma: f64, k: f64, dir: f64) -> (Vec<f64>, Vec<f64>) {
    let hw = (n / 2) as isize;
    let mut re = Vec::with_capacity(n);
    let mut im = Vec::with_capacity(n);
    for u in -hw..=hw {
        let u = u as f64;
        let g = (-(u * u) / (2.0 * sigma * sigma)).exp();
        re.push(g * (k * u * dir).cos());
        im.push(g * (k * u * dir).sin());
    }
    (re, im)
}

fn to_f32_or_none(v: &[f64]) -> Option<Vec<f32>> {
    let peak = v.iter().fold(0.0f64, |m, a| m.max(a.abs()));
    (peak > 1e-9).then(|| v.iter().map(|&a| a as f32).collect())
}

/// Precomputed filters for all configured angles, plus work buffers.
#[derive(Clone, Debug)]
pub struct GaborBank {
    cfg: GaborConfig,
    angles: Vec<AngleFilters>,
    ones: Vec<f32>,
    scratch: FilterScratch,
    box_: Plane<f32>,
    /// The kernels of the row pass, applied to the input together: the box's ones, then per
    /// angle that is not a mirror its `hr` and (when not zero) its `hi`.
    row_kernels: Vec<Vec<f32>>,
    /// Per angle: the indices in `row_kernels` (and `rows`) of its `hr` and `hi` (a mirror
    /// angle's are its original's).
    row_index: Vec<(usize, Option<usize>)>,
    /// The row pass's outputs, one per row kernel.
    rows: Vec<Plane<f32>>,
    /// Per angle: [Hr*vr, Hi*vi, Hr*vi, Hi*vr] of the last level (mirror angles read their
    /// original's).
    parts: Vec<[Plane<f32>; 4]>,
    /// Per angle: whether each part is known to be all zero (a part whose factors vanish
    /// for that angle is zeroed once, not for every level of every frame).
    zeroed: Vec<[bool; 4]>,
}

impl GaborBank {
    /// Builds the 1D factors for `cfg` (which must be validated).
    pub fn new(cfg: &GaborConfig) -> Self {
        let n = cfg.size;
        let k = 2.0 * std::f64::consts::PI / cfg.wavelength_px as f64;
        let sigma = cfg.sigma_px as f64;
        let mut angles: Vec<AngleFilters> = Vec::new();
        let mut dirs: Vec<(f64, f64)> = Vec::new();
        for &a in &cfg.angles_deg {
            let (s, c) = (a as f64).to_radians().sin_cos();
            let (c, s) = (if c.abs() < 1e-12 { 0.0 } else { c }, if s.abs() < 1e-12 { 0.0 } else { s });
            let (hr, hi) = factor(n, sigma, k, c);
            let (vr, vi) = factor(n, sigma, k, s);
            // 2D kernels from the factors, to get means and norms exactly as kernel_2d does.
            let (mut se, mut so, mut see, mut soo) = (0.0, 0.0, 0.0, 0.0);
            let mut even = Vec::with_capacity(n * n);
            let mut odd = Vec::with_capacity(n * n);
            for j in 0..n {
                for i in 0..n {
                    let e = hr[i] * vr[j] - hi[i] * vi[j];
                    let o = hr[i] * vi[j] + hi[i] * vr[j];
                    even.push(e);
                    odd.push(o);
                    se += e;
                    so += o;
                }
            }
            let cnt = (n * n) as f64;
            let (me, mo) = (se / cnt, so / cnt);
            for (e, o) in even.iter().zip(&odd) {
                see += (e - me) * (e - me);
                soo += (o - mo) * (o - mo);
            }
            let inv = |s: f64| if s > 0.0 { (1.0 / s.sqrt()) as f32 } else { 0.0 };
            let mirror_of =
                dirs.iter().position(|&(pc, ps)| (pc + c).abs() < 1e-9 && (ps - s).abs() < 1e-9 && c != 0.0);
            dirs.push((c, s));
            angles.push(AngleFilters {
                hr: hr.iter().map(|&v| v as f32).collect(),
                hi: to_f32_or_none(&hi),
                vr: vr.iter().map(|&v| v as f32).collect(),
                vi: to_f32_or_none(&vi),
                mean_even: me as f32,
                mean_odd: mo as f32,
                inv_norm_even: inv(see),
                inv_norm_odd: inv(soo),
                mirror_of,
            });
        }
        let parts = (0..angles.len()).map(|_| Default::default()).collect();
        let mut row_kernels = vec![vec![1.0; n]];
        let mut row_index: Vec<(usize, Option<usize>)> = Vec::with_capacity(angles.len());
        for f in &angles {
            let idx = match f.mirror_of {
                Some(m) => row_index[m],
                None => {
                    row_kernels.push(f.hr.clone());
                    let hr = row_kernels.len() - 1;
                    let hi = f.hi.as_ref().map(|hi| {
                        row_kernels.push(hi.clone());
                        row_kernels.len() - 1
                    });
                    (hr, hi)
                }
            };
            row_index.push(idx);
        }
        let rows = row_kernels.iter().map(|_| Plane::default()).collect();
        let zeroed = vec![[false; 4]; angles.len()];
        Self {
            cfg: cfg.clone(),
            angles,
            ones: vec![1.0; n],
            scratch: FilterScratch::default(),
            box_: Plane::default(),
            row_kernels,
            row_index,
            rows,
            parts,
            zeroed,
        }
    }

    /// Number of orientations.
    pub fn len(&self) -> usize {
        self.angles.len()
    }

    /// True when no angle is configured.
    pub fn is_empty(&self) -> bool {
        self.angles.is_empty()
    }

    /// Filters intensity `src` with every orientation; `out[a]` receives `M_theta` for angle `a`.
    pub fn filter(&mut self, backend: Backend, src: &Plane<f32>, out: &mut [Plane<f32>]) -> Result<()> {
        let border = match self.cfg.border {
            GaborBorder::Clamp => Border::Clamp,
            GaborBorder::Zero | GaborBorder::StbCompat => Border::Zero,
        };
        let s = &mut self.scratch;
        // Every row pass reads `src`: one bank (up to eight kernels at a time, from a list on
        // the stack, so that a frame allocates nothing).
        let n_rows = self.row_kernels.len();
        let mut start = 0;
        while start < n_rows {
            let end = (start + 8).min(n_rows);
            let mut ks: [&[f32]; 8] = [&[]; 8];
            for (slot, k) in ks.iter_mut().zip(&self.row_kernels[start..end]) {
                *slot = k;
            }
            filter_rows_bank(backend, src, &ks[..end - start], &mut self.rows[start..end], border, s)?;
            start = end;
        }
        filter_cols(backend, &self.rows[0], &mut self.box_, &self.ones, border, s)?;
        for a in 0..self.angles.len() {
            let f = &self.angles[a];
            // theta' = 180 - theta: Hi flips sign and v is shared, so a mirror angle reuses its
            // original's parts with the signs of B and D flipped (see energy_row).
            if f.mirror_of.is_none() {
                let (hr, hi) = self.row_index[a];
                let hr = &self.rows[hr];
                let hi = hi.map(|i| &self.rows[i]);
                let (p, z) = (&mut self.parts[a], &mut self.zeroed[a]);
                filter_cols(backend, hr, &mut p[0], &f.vr, border, s)?;
                match (hi, &f.vi) {
                    (Some(hi), Some(vi)) => {
                        filter_cols(backend, hi, &mut p[1], vi, border, s)?;
                        filter_cols(backend, hr, &mut p[2], vi, border, s)?;
                        filter_cols(backend, hi, &mut p[3], &f.vr, border, s)?;
                    }
                    (Some(hi), None) => {
                        zero_like(&mut p[1], src, &mut z[1]);
                        zero_like(&mut p[2], src, &mut z[2]);
                        filter_cols(backend, hi, &mut p[3], &f.vr, border, s)?;
                    }
                    (None, Some(vi)) => {
                        zero_like(&mut p[1], src, &mut z[1]);
                        filter_cols(backend, hr, &mut p[2], vi, border, s)?;
                        zero_like(&mut p[3], src, &mut z[3]);
                    }
                    (None, None) => {
                        zero_like(&mut p[1], src, &mut z[1]);
                        zero_like(&mut p[2], src, &mut z[2]);
                        zero_like(&mut p[3], src, &mut z[3]);
                    }
                }
            }
            let f = &self.angles[a];
            let (p, sgn) = match f.mirror_of {
                Some(m) => (&self.parts[m], -1.0),
                None => (&self.parts[a], 1.0),
            };
            let (w, h) = src.size();
            let o = &mut out[a];
            o.resize(w, h);
            let h2 = self.cfg.size / 2;
            let stb = self.cfg.border == GaborBorder::StbCompat && h2 > 0 && h2 <= h;
            let consts = [f.mean_even, f.inv_norm_even, f.mean_odd, f.inv_norm_odd, sgn];
            for y in 0..h {
                let rows = [p[0].row(y), p[1].row(y), p[2].row(y), p[3].row(y), self.box_.row(y)];
                let (fe, fo) = if stb { stb_row_factors(&self.cfg, f, y, h) } else { (1.0, 1.0) };
                let orow = o.row_mut(y);
                if (fe, fo) == (1.0, 1.0) {
                    energy_row(backend, rows, consts, [1.0, 1.0], orow);
                } else {
                    // The toolbox's factors apply to the interior columns only.
                    let (x0, x1) = (h2.min(w), w.saturating_sub(h2).max(h2.min(w)));
                    energy_row(backend, rows.map(|v| &v[..x0]), consts, [1.0, 1.0], &mut orow[..x0]);
                    energy_row(backend, rows.map(|v| &v[x0..x1]), consts, [fe, fo], &mut orow[x0..x1]);
                    energy_row(backend, rows.map(|v| &v[x1..]), consts, [1.0, 1.0], &mut orow[x1..]);
                }
            }
        }
        Ok(())
    }
}

/// Gabor energy of one row: `|fe (Re - m_e B) / n_e| + |fo (Im - m_o B) / n_o|` with
/// `Re = p0 - s p1`, `Im = p2 + s p3`, B the box sum; `c = [m_e, 1/n_e, m_o, 1/n_o, s]`
/// (s = -1 for the mirror angle 180 - theta, whose Hi factor has the opposite sign).
#[inline(always)]
fn energy_row_generic<M: Madd>(r: [&[f32]; 5], c: [f32; 5], f: [f32; 2], out: &mut [f32]) {
    let n = out.len();
    let [a0, a1, a2, a3, bx] = r.map(|v| &v[..n]);
    let (se, so, sgn) = (c[1] * f[0], c[3] * f[1], c[4]);
    for x in 0..n {
        let even = M::madd(-c[0], bx[x], M::madd(-sgn, a1[x], a0[x])) * se;
        let odd = M::madd(-c[2], bx[x], M::madd(sgn, a3[x], a2[x])) * so;
        out[x] = even.abs() + odd.abs();
    }
}

dispatch_kernel!(fn energy_row => energy_row_generic(r: [&[f32]; 5], c: [f32; 5], f: [f32; 2], out: &mut [f32]));

/// Sizes `p` like `like`, all zero. A part that is zero for an angle is never written
/// otherwise, and a resize keeps or zero-extends the buffer, so after its first fill (`done`)
/// it stays zero at every size: filling it again per level and frame was 1.5 % of a frame.
fn zero_like(p: &mut Plane<f32>, like: &Plane<f32>, done: &mut bool) {
    p.resize(like.width(), like.height());
    if !*done {
        p.fill(0.0);
        *done = true;
    }
}

/// SaliencyToolbox's `conv2PreserveEnergy` multiplies the top and bottom `size/2` rows of
/// the interior columns by `sum(kernel) / (partial row sums)`. For a zero-mean Gabor that
/// is a ratio of rounding residues: about 1e-15 (so 0) for every default kernel except the
/// odd kernel whose rows sum to zero exactly (its 90 degree angle, our 0 degrees), where
/// the ratios are O(1). These are those ratios for the default 9x9 kernel (sigma 2.3333,
/// period 7), evaluated with GNU Octave 7.3: rows 1..4 from the top, and rows h-3..h.
const STB_ODD_TOP: [f32; 4] = [-1.708_333_3, -2.5625, 5.125, 3.416_666_7];
const STB_ODD_BOTTOM: [f32; 4] = [3.416_666_7, 5.125, 1.281_25, 2.05];

/// (even, odd) factors of row `y` of an `h`-row map under the SaliencyToolbox rule.
fn stb_row_factors(cfg: &GaborConfig, f: &AngleFilters, y: usize, h: usize) -> (f32, f32) {
    let h2 = cfg.size / 2;
    let known = cfg.size == 9 && (cfg.sigma_px - 2.3333).abs() < 1e-6 && (cfg.wavelength_px - 7.0).abs() < 1e-6;
    // The odd kernel of an angle with sin = 0 has rows that sum to exactly zero.
    let odd_rows_vanish = f.vi.is_none() && f.hi.is_some();
    let (mut fe, mut fo) = (1.0f32, 1.0f32);
    if y < h2 {
        fe = 0.0;
        fo = if known && odd_rows_vanish { STB_ODD_TOP[y] } else { 0.0 };
    }
    if y + h2 >= h {
        let k = y + h2 - h; // 0 for row h - h2
        fe = 0.0;
        fo *= if known && odd_rows_vanish && h2 == 4 { STB_ODD_BOTTOM[k] } else { 0.0 };
    }
    (fe, fo)
}
