//! The model and its cost (SPEC 8.2).
//!
//! - observations `o = S i`, S: R receptive fields x N pixels;
//! - motor activations `a = M q`, M: K motor fields x Q motor cells;
//! - the predictor of an action `P^q = sum_k a_k P_k`, each P_k: R x R;
//! - the predicted next image `i1_hat = S^T P^q S i0`.
//!
//! The cost over T triplets is `C = sum_t ||i1_hat_t - i1_t||^2 / (T N)` (the mean squared
//! error per pixel) plus the simplicity term `lambda (mean(S) + mean(P) + mean(M))` over
//! the blocks being learned. Every entry is kept >= 0 (the seed's constraint, which with the
//! L1 term makes the fields sparse and local, as in non-negative matrix factorization); the
//! L1 term also fixes the scale that the product leaves free (S -> cS, P -> P / c^2 predict
//! the same).
//!
//! The gradient, with `e_t = i1_hat_t - i1_t`, `y_t = P^t o0_t`, `g_t = 2 S e_t`,
//! `h_t = P^tT g_t` (all over T N):
//! `dC/dS = sum_t (2 y_t e_t^T + h_t i0_t^T)`, `dC/dP_k = sum_t a_tk g_t o0_t^T`,
//! `dC/da_tk = g_t . (P_k o0_t)`, `dC/dM = sum_t (dC/da_t) q_t^T`.
//!
//! Triplets are processed in fixed chunks of [`CHUNK`] rows, in parallel; each chunk's
//! products are dense matrix products (`matrixmultiply`), and its partial gradient is summed
//! in chunk order, so the result is the same bit for bit on any number of threads.

use crate::experience::Experience;
use crate::gemm::{gemm, View};
use crate::{Real, Result, RetinaError};
use ocellus_image::rng::SplitMix64;
use rayon::prelude::*;

/// Triplets per chunk of the batched products.
pub const CHUNK: usize = 256;

/// The sizes of a model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Shape {
    /// Pixels N.
    pub pixels: usize,
    /// Receptive fields R.
    pub fields: usize,
    /// Motor fields K.
    pub motor_fields: usize,
    /// Motor cells Q.
    pub motor_cells: usize,
}

impl Shape {
    /// Checks every size is positive and the model fits in memory (under 2^31 entries).
    pub fn validate(&self) -> Result<()> {
        let Shape { pixels, fields, motor_fields, motor_cells } = *self;
        for (name, v) in [
            ("pixels", pixels),
            ("receptive fields", fields),
            ("motor fields", motor_fields),
            ("motor cells", motor_cells),
        ] {
            if v == 0 {
                return Err(RetinaError::Invalid(format!("a retina needs at least one of its {name}, not 0")));
            }
        }
        let total = (fields as u128) * (pixels as u128)
            + (motor_fields as u128) * (motor_cells as u128)
            + (motor_fields as u128) * (fields as u128) * (fields as u128);
        if total > (1u128 << 31) {
            return Err(RetinaError::Invalid(format!("{total} model entries is too many")));
        }
        Ok(())
    }

    /// Entries of S, M and P.
    pub fn sizes(&self) -> [usize; 3] {
        [self.fields * self.pixels, self.motor_fields * self.motor_cells, self.motor_fields * self.fields * self.fields]
    }
}

/// Which blocks are learned (the others stay as initialized).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Free {
    /// Receptive fields S.
    pub s: bool,
    /// Motor fields M.
    pub m: bool,
    /// Canonical predictors P.
    pub p: bool,
}

impl Free {
    /// As an array in block order (S, M, P).
    pub fn blocks(&self) -> [bool; 3] {
        [self.s, self.m, self.p]
    }
}

/// The parameters, row-major: `s` (R x N), `m` (K x Q), `p` (K x R x R, P_k row-major).
#[derive(Clone, Debug, PartialEq)]
pub struct Params<T> {
    /// Sizes.
    pub shape: Shape,
    /// Receptive fields, R x N.
    pub s: Vec<T>,
    /// Motor fields, K x Q.
    pub m: Vec<T>,
    /// Canonical predictors, K x R x R.
    pub p: Vec<T>,
}

impl<T: Real> Params<T> {
    /// All zeros.
    pub fn zeros(shape: Shape) -> Self {
        let [a, b, c] = shape.sizes();
        Self { shape, s: vec![T::default(); a], m: vec![T::default(); b], p: vec![T::default(); c] }
    }

    /// The three blocks, in order S, M, P.
    pub fn blocks(&self) -> [&[T]; 3] {
        [&self.s, &self.m, &self.p]
    }

    /// The three blocks, mutable.
    pub fn blocks_mut(&mut self) -> [&mut Vec<T>; 3] {
        [&mut self.s, &mut self.m, &mut self.p]
    }

    /// Random non-negative parameters, seeded: S uniform in [0, 2/N) (fields that average
    /// their pixels), P uniform in [0, 1), and M either the identity (one fixed motor field
    /// per motor cell, experiment 1; needs K = Q) or uniform in [0, 1). The predictors are
    /// then scaled so that the mean prediction fits the mean next image
    /// (see [`fit_scale`]).
    pub fn random(shape: Shape, identity_m: bool, seed: u64) -> Result<Self> {
        shape.validate()?;
        if identity_m && shape.motor_fields != shape.motor_cells {
            return Err(RetinaError::Invalid(format!(
                "fixed motor fields one per motor cell need as many of each, not {} and {}",
                shape.motor_fields, shape.motor_cells
            )));
        }
        let mut rng = SplitMix64::new(seed);
        let mut p = Self::zeros(shape);
        let n = shape.pixels as f64;
        p.s.iter_mut().for_each(|v| *v = T::from_f64(2.0 * rng.unit() / n));
        if identity_m {
            for k in 0..shape.motor_fields {
                p.m[k * shape.motor_cells + k] = T::from_f64(1.0);
            }
        } else {
            p.m.iter_mut().for_each(|v| *v = T::from_f64(rng.unit()));
        }
        p.p.iter_mut().for_each(|v| *v = T::from_f64(rng.unit()));
        Ok(p)
    }

    /// Checks the shapes and that every entry is finite and >= 0.
    pub fn validate(&self) -> Result<()> {
        self.shape.validate()?;
        let sizes = self.shape.sizes();
        for (i, (b, &n)) in self.blocks().iter().zip(&sizes).enumerate() {
            let name = ["S", "M", "P"][i];
            if b.len() != n {
                return Err(RetinaError::Invalid(format!("{name} has {} entries, the shape needs {n}", b.len())));
            }
            if let Some(v) = b.iter().find(|v| !(v.to_f64().is_finite() && v.to_f64() >= 0.0)) {
                return Err(RetinaError::Invalid(format!("{name} holds {v:?}: entries must be finite and >= 0")));
            }
        }
        Ok(())
    }

    /// The same parameters in another float type.
    pub fn convert<U: Real>(&self) -> Params<U> {
        let c = |v: &[T]| v.iter().map(|x| U::from_f64(x.to_f64())).collect();
        Params { shape: self.shape, s: c(&self.s), m: c(&self.m), p: c(&self.p) }
    }
}

/// The learning problem: the experience, which blocks are free and the simplicity weight.
#[derive(Clone, Copy, Debug)]
pub struct Objective<'a, T> {
    /// The triplets.
    pub data: &'a Experience<T>,
    /// Which blocks are learned (the simplicity term covers those only).
    pub free: Free,
    /// Weight lambda of the simplicity term (>= 0).
    pub simplicity: f64,
    /// Smoothness of learned motor fields over a `cells` x `cells` motor grid: weight mu of
    /// the mean squared difference between 4-neighbouring cells of every motor field, added
    /// to the cost. Neighbouring cells code similar actions, but each sees only its own
    /// triplets; without it the learned fields stay as noisy as the start.
    pub smoothness: Option<MotorSmoothness>,
}

/// See [`Objective::smoothness`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MotorSmoothness {
    /// Cells per axis of the motor grid (cells^2 = motor cells).
    pub cells: usize,
    /// Weight mu (>= 0).
    pub weight: f64,
}

/// What one evaluation gives.
#[derive(Clone, Debug)]
pub struct Evaluation<T> {
    /// The cost C (mean squared error per pixel plus the simplicity term).
    pub cost: f64,
    /// The mean squared error per pixel alone.
    pub mse: f64,
    /// dC/d(S, M, P) when asked for (zero on blocks that are not free).
    pub grad: Option<Params<T>>,
}

/// One chunk's sums.
struct Partial<T> {
    sse: f64,
    grad: Option<Params<T>>,
}

impl<'a, T: Real> Objective<'a, T> {
    /// Checks the experience and the parameters fit together.
    pub fn check(&self, params: &Params<T>) -> Result<()> {
        params.validate()?;
        let sh = params.shape;
        if self.data.pixels != sh.pixels || self.data.motor_cells != sh.motor_cells {
            return Err(RetinaError::Invalid(format!(
                "the experience has {} pixels and {} motor cells, the model {} and {}",
                self.data.pixels, self.data.motor_cells, sh.pixels, sh.motor_cells
            )));
        }
        if !(self.simplicity.is_finite() && self.simplicity >= 0.0) {
            return Err(RetinaError::Invalid(format!("simplicity weight {} must be finite and >= 0", self.simplicity)));
        }
        if let Some(m) = self.smoothness {
            if m.cells < 2 || m.cells * m.cells != sh.motor_cells || !(m.weight.is_finite() && m.weight >= 0.0) {
                return Err(RetinaError::Invalid(format!(
                    "motor smoothness over {0}x{0} cells with weight {1} does not fit {2} motor cells",
                    m.cells, m.weight, sh.motor_cells
                )));
            }
        }
        self.data.validate()
    }

    /// The cost, and its gradient when `grad` is true. The caller has run [`check`](Self::check).
    pub fn evaluate(&self, params: &Params<T>, grad: bool) -> Evaluation<T> {
        let t = self.data.len();
        let chunks: Vec<Partial<T>> = (0..t.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| chunk(self.data, params, c * CHUNK, ((c + 1) * CHUNK).min(t), grad.then_some(self.free)))
            .collect();
        let denom = (t * params.shape.pixels) as f64;
        let sse: f64 = chunks.iter().map(|c| c.sse).sum();
        let mse = sse / denom;
        let free = self.free.blocks();
        let sizes = params.shape.sizes();
        let mut cost = mse;
        for (b, block) in params.blocks().iter().enumerate() {
            if free[b] {
                let sum: f64 = block.iter().map(|v| v.to_f64()).sum();
                cost += self.simplicity * sum / sizes[b] as f64;
            }
        }
        // The smoothness of the motor fields: mu times the mean squared difference of
        // 4-neighbouring cells, and its gradient.
        let mut smooth_grad = Vec::new();
        if let (Some(ms), true) = (self.smoothness, free[1]) {
            let (n, q) = (ms.cells, params.shape.motor_cells);
            let pairs = (params.shape.motor_fields * 2 * n * (n - 1)) as f64;
            let scale = ms.weight / pairs;
            if grad {
                smooth_grad = vec![0.0f64; params.m.len()];
            }
            let mut sum = 0.0;
            for k in 0..params.shape.motor_fields {
                let row = &params.m[k * q..(k + 1) * q];
                for y in 0..n {
                    for x in 0..n {
                        let here = row[y * n + x].to_f64();
                        for (nx, ny) in [(x + 1, y), (x, y + 1)] {
                            if nx < n && ny < n {
                                let d = here - row[ny * n + nx].to_f64();
                                sum += d * d;
                                if grad {
                                    smooth_grad[k * q + y * n + x] += 2.0 * scale * d;
                                    smooth_grad[k * q + ny * n + nx] -= 2.0 * scale * d;
                                }
                            }
                        }
                    }
                }
            }
            cost += scale * sum;
        }
        let grad = grad.then(|| {
            let mut g = Params::zeros(params.shape);
            for part in chunks.iter().filter_map(|c| c.grad.as_ref()) {
                for (dst, src) in g.blocks_mut().into_iter().zip(part.blocks()) {
                    dst.iter_mut().zip(src).for_each(|(d, &s)| *d += s);
                }
            }
            let inv = T::from_f64(1.0 / denom);
            for (b, dst) in g.blocks_mut().into_iter().enumerate() {
                if free[b] {
                    let l1 = T::from_f64(self.simplicity / sizes[b] as f64);
                    dst.iter_mut().for_each(|d| *d = *d * inv + l1);
                } else {
                    dst.iter_mut().for_each(|d| *d = T::default());
                }
            }
            for (d, &v) in g.m.iter_mut().zip(&smooth_grad) {
                *d += T::from_f64(v);
            }
            g
        });
        Evaluation { cost, mse, grad }
    }

    /// The predicted next patches, T x N row-major.
    pub fn predict(&self, params: &Params<T>) -> Vec<T> {
        let (t, n) = (self.data.len(), params.shape.pixels);
        let mut out = vec![T::default(); t * n];
        out.par_chunks_mut(CHUNK * n).enumerate().for_each(|(c, o)| {
            let (r0, r1) = (c * CHUNK, ((c + 1) * CHUNK).min(t));
            let f = forward(self.data, params, r0, r1);
            // e = y S - x1, so the prediction is e + x1.
            for (i, v) in o.iter_mut().enumerate() {
                *v = f.e[i] + self.data.x1[r0 * n + i];
            }
        });
        out
    }
}

/// The forward products of rows r0..r1.
struct Forward<T> {
    /// a = Q M^T, c x K.
    a: Vec<T>,
    /// o0 = X0 S^T, c x R.
    o0: Vec<T>,
    /// W_k = O0 P_k^T on the rows where a_k != 0, c x K x R (zero elsewhere).
    w: Vec<T>,
    /// y = sum_k a_k W_k, c x R.
    y: Vec<T>,
    /// e = y S - X1, c x N.
    e: Vec<T>,
    /// Rows (chunk-relative) with a_tk != 0, per k.
    rows: Vec<Vec<usize>>,
}

fn forward<T: Real>(data: &Experience<T>, p: &Params<T>, r0: usize, r1: usize) -> Forward<T> {
    let Shape { pixels: n, fields: r, motor_fields: k, motor_cells: qn } = p.shape;
    let c = r1 - r0;
    let x0 = View::rm(&data.x0[r0 * n..r1 * n], c, n);
    let q = View::rm(&data.q[r0 * qn..r1 * qn], c, qn);
    let (one, zero) = (T::from_f64(1.0), T::default());
    let mut a = vec![zero; c * k];
    gemm(one, q, View::rm(&p.m, k, qn).t(), zero, &mut a);
    let mut o0 = vec![zero; c * r];
    gemm(one, x0, View::rm(&p.s, r, n).t(), zero, &mut o0);
    // Experiment 1's motor code is one-hot: each row uses one predictor, so each P_k is
    // applied to its own rows only (gathered, one product, scattered) instead of to all.
    let rows: Vec<Vec<usize>> = (0..k).map(|kk| (0..c).filter(|&t| a[t * k + kk] != zero).collect()).collect();
    let mut w = vec![zero; c * k * r];
    let mut y = vec![zero; c * r];
    let mut gathered = Vec::new();
    let mut wk = Vec::new();
    for kk in 0..k {
        let rk = &rows[kk];
        if rk.is_empty() {
            continue;
        }
        gathered.clear();
        rk.iter().for_each(|&t| gathered.extend_from_slice(&o0[t * r..(t + 1) * r]));
        wk.clear();
        wk.resize(rk.len() * r, zero);
        gemm(
            one,
            View::rm(&gathered, rk.len(), r),
            View::rm(&p.p[kk * r * r..(kk + 1) * r * r], r, r).t(),
            zero,
            &mut wk,
        );
        for (j, &t) in rk.iter().enumerate() {
            let src = &wk[j * r..(j + 1) * r];
            w[(t * k + kk) * r..(t * k + kk + 1) * r].copy_from_slice(src);
            let at = a[t * k + kk];
            for (yy, &s) in y[t * r..(t + 1) * r].iter_mut().zip(src) {
                *yy += at * s;
            }
        }
    }
    let mut e: Vec<T> = data.x1[r0 * n..r1 * n].iter().map(|&v| zero - v).collect();
    gemm(one, View::rm(&y, c, r), View::rm(&p.s, r, n), one, &mut e);
    Forward { a, o0, w, y, e, rows }
}

/// One chunk's squared error and, with `grad` (the free blocks), its gradient on those blocks.
fn chunk<T: Real>(data: &Experience<T>, p: &Params<T>, r0: usize, r1: usize, grad: Option<Free>) -> Partial<T> {
    let f = forward(data, p, r0, r1);
    let sse: f64 = f.e.iter().map(|v| v.to_f64() * v.to_f64()).sum();
    let Some(free) = grad else {
        return Partial { sse, grad: None };
    };
    let Shape { pixels: n, fields: r, motor_fields: k, motor_cells: qn } = p.shape;
    let c = r1 - r0;
    let (one, two, zero) = (T::from_f64(1.0), T::from_f64(2.0), T::default());
    let x0 = View::rm(&data.x0[r0 * n..r1 * n], c, n);
    let e = View::rm(&f.e, c, n);
    // g = 2 E S^T (c x R).
    let mut g = vec![zero; c * r];
    gemm(two, e, View::rm(&p.s, r, n).t(), zero, &mut g);
    let mut out = Params::zeros(p.shape);
    let mut h = vec![zero; c * r];
    let mut da = vec![zero; c * k];
    let (mut ga, mut og, mut hk) = (Vec::new(), Vec::new(), Vec::new());
    for kk in 0..k {
        let rk = &f.rows[kk];
        if rk.is_empty() {
            continue;
        }
        ga.clear();
        og.clear();
        for &t in rk {
            let at = f.a[t * k + kk];
            ga.extend(g[t * r..(t + 1) * r].iter().map(|&v| at * v));
            og.extend_from_slice(&f.o0[t * r..(t + 1) * r]);
            let wt = &f.w[(t * k + kk) * r..(t * k + kk + 1) * r];
            let mut d = zero;
            for (&gv, &wv) in g[t * r..(t + 1) * r].iter().zip(wt) {
                d += gv * wv;
            }
            da[t * k + kk] = d;
        }
        let pk = View::rm(&p.p[kk * r * r..(kk + 1) * r * r], r, r);
        let m = rk.len();
        // dP_k = (a_k g)^T O0 over its rows.
        gemm(one, View::rm(&ga, m, r).t(), View::rm(&og, m, r), zero, &mut out.p[kk * r * r..(kk + 1) * r * r]);
        // h += (a_k g) P_k over its rows.
        hk.clear();
        hk.resize(m * r, zero);
        gemm(one, View::rm(&ga, m, r), pk, zero, &mut hk);
        for (j, &t) in rk.iter().enumerate() {
            for (hh, &v) in h[t * r..(t + 1) * r].iter_mut().zip(&hk[j * r..(j + 1) * r]) {
                *hh += v;
            }
        }
    }
    // dS = 2 Y^T E + H^T X0: the two largest products, skipped when S is fixed (the
    // random-S baseline).
    if free.s {
        gemm(two, View::rm(&f.y, c, r).t(), e, zero, &mut out.s);
        gemm(one, View::rm(&h, c, r).t(), x0, one, &mut out.s);
    }
    // dM = dA^T Q.
    if free.m {
        gemm(one, View::rm(&da, c, k).t(), View::rm(&data.q[r0 * qn..r1 * qn], c, qn), zero, &mut out.m);
    }
    Partial { sse, grad: Some(out) }
}

/// Scales the predictors so that the predictions best fit the next patches in least squares
/// (one factor for all of P; the prediction is linear in P). Leaves P alone when the
/// predictions are all zero.
pub fn fit_scale<T: Real>(data: &Experience<T>, params: &mut Params<T>) {
    let obj = Objective { data, free: Free { s: false, m: false, p: false }, simplicity: 0.0, smoothness: None };
    let pred = obj.predict(params);
    let (mut pp, mut py) = (0.0, 0.0);
    for (a, b) in pred.iter().zip(&data.x1) {
        pp += a.to_f64() * a.to_f64();
        py += a.to_f64() * b.to_f64();
    }
    if pp > 0.0 && py > 0.0 {
        let alpha = T::from_f64(py / pp);
        params.p.iter_mut().for_each(|v| *v = *v * alpha);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::action::{Action, MotorCode};

    /// A small random problem in f64: `t` triplets, dense or one-hot motor codes.
    fn problem(t: usize, one_hot: bool, seed: u64) -> (Experience<f64>, Params<f64>) {
        let shape = Shape { pixels: 13, fields: 4, motor_fields: 3, motor_cells: if one_hot { 3 } else { 4 } };
        let mut rng = SplitMix64::new(seed);
        let mut data = Experience {
            pixels: 13,
            motor_cells: shape.motor_cells,
            x0: (0..t * 13).map(|_| rng.unit()).collect(),
            x1: (0..t * 13).map(|_| rng.unit()).collect(),
            q: vec![0.0; t * shape.motor_cells],
            actions: vec![Action::Shift { dx: 0.0, dy: 0.0 }; t],
        };
        for i in 0..t {
            if one_hot {
                data.q[i * 3 + rng.below(3)] = 1.0;
            } else {
                for j in 0..4 {
                    data.q[i * 4 + j] = rng.unit();
                }
            }
        }
        let mut p = Params::random(shape, one_hot, seed + 1).unwrap();
        p.s.iter_mut().for_each(|v| *v += 0.05);
        (data, p)
    }

    /// The model evaluated directly, triplet by triplet, from the formula.
    fn direct_sse(data: &Experience<f64>, p: &Params<f64>) -> f64 {
        let Shape { pixels: n, fields: r, motor_fields: k, motor_cells: qn } = p.shape;
        let mut sse = 0.0;
        for t in 0..data.len() {
            let i0 = &data.x0[t * n..(t + 1) * n];
            let o: Vec<f64> = (0..r).map(|i| (0..n).map(|j| p.s[i * n + j] * i0[j]).sum()).collect();
            let a: Vec<f64> = (0..k).map(|kk| (0..qn).map(|j| p.m[kk * qn + j] * data.q[t * qn + j]).sum()).collect();
            let y: Vec<f64> = (0..r)
                .map(|i| (0..k).map(|kk| a[kk] * (0..r).map(|j| p.p[kk * r * r + i * r + j] * o[j]).sum::<f64>()).sum())
                .collect();
            for j in 0..n {
                let pred: f64 = (0..r).map(|i| p.s[i * n + j] * y[i]).sum();
                sse += (pred - data.x1[t * n + j]).powi(2);
            }
        }
        sse
    }

    #[test]
    fn the_batched_cost_is_the_formula() {
        for one_hot in [false, true] {
            // More than one chunk, the last one partial.
            let (data, p) = problem(CHUNK + 37, one_hot, 4);
            let obj = Objective {
                data: &data,
                free: Free { s: true, m: !one_hot, p: true },
                simplicity: 0.0,
                smoothness: None,
            };
            obj.check(&p).unwrap();
            let ev = obj.evaluate(&p, false);
            let want = direct_sse(&data, &p) / (data.len() * 13) as f64;
            assert!((ev.mse - want).abs() < 1e-12 * want.max(1.0), "{} vs {want}", ev.mse);
        }
    }

    #[test]
    fn the_gradient_matches_finite_differences() {
        for one_hot in [false, true] {
            let (data, p) = problem(40, one_hot, 9);
            // The dense codes form a 2 x 2 motor grid: the smoothness term is checked too.
            let smoothness = (!one_hot).then_some(MotorSmoothness { cells: 2, weight: 0.5 });
            let obj =
                Objective { data: &data, free: Free { s: true, m: !one_hot, p: true }, simplicity: 0.01, smoothness };
            let g = obj.evaluate(&p, true).grad.unwrap();
            let mut rng = SplitMix64::new(5);
            for b in 0..3 {
                if !obj.free.blocks()[b] {
                    assert!(g.blocks()[b].iter().all(|&v| v == 0.0));
                    continue;
                }
                for _ in 0..12 {
                    let i = rng.below(g.blocks()[b].len());
                    let h = 1e-5;
                    let (mut plus, mut minus) = (p.clone(), p.clone());
                    plus.blocks_mut()[b][i] += h;
                    minus.blocks_mut()[b][i] -= h;
                    let fd = (obj.evaluate(&plus, false).cost - obj.evaluate(&minus, false).cost) / (2.0 * h);
                    let an = g.blocks()[b][i];
                    let rel =
                        (fd - an).abs() / an.abs().max(1e-3 * g.blocks()[b].iter().fold(0.0f64, |m, v| m.max(v.abs())));
                    assert!(rel < 1e-4, "block {b} entry {i}: analytic {an}, finite difference {fd}, rel {rel}");
                }
            }
        }
    }

    #[test]
    fn results_do_not_depend_on_the_thread_count() {
        let (data, p) = problem(3 * CHUNK + 5, false, 11);
        let obj =
            Objective { data: &data, free: Free { s: true, m: true, p: true }, simplicity: 0.1, smoothness: None };
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| obj.evaluate(&p, true))
        };
        let (a, b) = (run(1), run(3));
        assert_eq!(a.cost.to_bits(), b.cost.to_bits());
        assert_eq!(a.grad, b.grad);
    }

    #[test]
    fn mismatched_or_bad_parameters_are_refused() {
        let (data, mut p) = problem(10, true, 2);
        let obj =
            Objective { data: &data, free: Free { s: true, m: false, p: true }, simplicity: 0.0, smoothness: None };
        p.s[3] = f64::NAN;
        assert!(obj.check(&p).is_err());
        p.s[3] = -1.0;
        assert!(obj.check(&p).is_err());
        let bad = Objective { simplicity: f64::NAN, ..obj };
        assert!(bad.check(&Params::random(p.shape, true, 1).unwrap()).is_err());
        let shape = Shape { fields: 0, ..p.shape };
        assert!(Params::<f32>::random(shape, false, 1).is_err());
        let other = Shape { pixels: 14, ..p.shape };
        assert!(obj.check(&Params::random(other, true, 1).unwrap()).is_err());
        let _ = MotorCode::OneHot(vec![]);
    }
}
