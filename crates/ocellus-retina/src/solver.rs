//! Solvers for the retina's cost under the constraint that every entry is >= 0 (SPEC 8.2).
//!
//! - [`Method::Pgd`]: projected gradient descent with step-size control: the spectral
//!   projected gradient of Birgin, Martínez & Raydan (SIAM J. Optim. 10(4), 2000), with one
//!   Barzilai-Borwein step per block (S, M and P differ in scale by orders of magnitude) and
//!   their nonmonotone Armijo line search over the last 5 costs (sufficient decrease 1e-4).
//! - [`Method::Adam`]: Adam (Kingma & Ba, ICLR 2015; beta1 0.9, beta2 0.999) followed by the
//!   projection onto x >= 0 after each step: the lecture's "Challenge 2", a deep-learning
//!   solver. Its step is a share of each block's initial mean entry (the learning rate is
//!   relative, so one value suits S, M and P).
//!
//! Both stop when the cost improved by less than `tolerance` (relative) over the last
//! `window` iterations (converged), or at the iteration or time limit. Both are
//! deterministic: no randomness, and the cost and gradient are the same on any thread count.

use crate::model::{Objective, Params};
use crate::{Real, Result, RetinaError};
use std::time::Instant;

/// Which solver.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Spectral projected gradient descent with a line search.
    Pgd,
    /// Adam with projection.
    Adam,
}

impl std::str::FromStr for Method {
    type Err = RetinaError;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "pgd" => Ok(Self::Pgd),
            "adam" => Ok(Self::Adam),
            _ => Err(RetinaError::Invalid(format!("solver '{s}': use pgd or adam"))),
        }
    }
}

/// Solver settings.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SolverConfig {
    /// Which solver.
    pub method: Method,
    /// Most iterations in all (a resumed run counts the earlier ones).
    pub max_iterations: usize,
    /// Most seconds for this call.
    pub time_limit_s: f64,
    /// Converged when the cost fell by less than this share over `window` iterations.
    pub tolerance: f64,
    /// Iterations the convergence test looks back.
    pub window: usize,
    /// Adam: step as a share of each block's initial mean entry.
    pub learning_rate: f64,
}

impl Default for SolverConfig {
    fn default() -> Self {
        Self {
            method: Method::Pgd,
            max_iterations: 5000,
            time_limit_s: 600.0,
            tolerance: 1e-3,
            window: 50,
            learning_rate: 0.01,
        }
    }
}

impl SolverConfig {
    /// Checks the settings.
    pub fn validate(&self) -> Result<()> {
        if !(self.time_limit_s.is_finite() && self.time_limit_s > 0.0) {
            return Err(RetinaError::Invalid(format!(
                "time limit {} s must be finite and positive",
                self.time_limit_s
            )));
        }
        if !(self.tolerance.is_finite() && self.tolerance >= 0.0) {
            return Err(RetinaError::Invalid(format!("tolerance {} must be finite and >= 0", self.tolerance)));
        }
        if !(self.learning_rate.is_finite() && self.learning_rate > 0.0) {
            return Err(RetinaError::Invalid(format!(
                "learning rate {} must be finite and positive",
                self.learning_rate
            )));
        }
        if self.window == 0 {
            return Err(RetinaError::Invalid("the convergence window must be at least one iteration".into()));
        }
        Ok(())
    }
}

/// One iteration's record.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Record {
    /// Iteration number (1-based; 0 is the starting point).
    pub iteration: usize,
    /// Cost after it.
    pub cost: f64,
    /// Mean squared error per pixel after it.
    pub mse: f64,
    /// Cost and gradient evaluations so far.
    pub evaluations: usize,
    /// Seconds of solving so far (over resumed runs too).
    pub seconds: f64,
}

/// Why a run stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Stop {
    /// The cost stopped improving (the convergence test).
    Converged,
    /// The iteration limit.
    MaxIterations,
    /// The time limit.
    TimeLimit,
    /// The line search found no decrease (a stationary point, to round-off).
    Stalled,
    /// The observer asked to stop.
    Cancelled,
}

/// What a run keeps between iterations, enough to resume it.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SolverState {
    /// Iterations done.
    pub iteration: usize,
    /// Evaluations done.
    pub evaluations: usize,
    /// One record per iteration, the starting point first.
    pub history: Vec<Record>,
    /// PGD: the spectral step of each block (S, M, P); 0 before the first iteration.
    pub steps: [f64; 3],
    /// Adam: the step of each block (absolute), and the epsilon of each.
    pub adam_lr: [f64; 3],
    /// Adam: epsilon per block.
    pub adam_eps: [f64; 3],
    /// Adam: first moments, blocks S, M, P concatenated (empty before the first iteration).
    pub adam_m: Vec<f64>,
    /// Adam: second moments.
    pub adam_v: Vec<f64>,
}

impl SolverState {
    /// A fresh state.
    pub fn new() -> Self {
        Self {
            iteration: 0,
            evaluations: 0,
            history: Vec::new(),
            steps: [0.0; 3],
            adam_lr: [0.0; 3],
            adam_eps: [0.0; 3],
            adam_m: Vec::new(),
            adam_v: Vec::new(),
        }
    }

    /// True when the cost fell by less than `tolerance` over the last `window` iterations.
    pub fn converged(&self, tolerance: f64, window: usize) -> bool {
        let n = self.history.len();
        if n <= window {
            return false;
        }
        let (old, new) = (self.history[n - 1 - window].cost, self.history[n - 1].cost);
        (old - new) <= tolerance * new.abs()
    }
}

impl Default for SolverState {
    fn default() -> Self {
        Self::new()
    }
}

fn dot<T: Real>(a: &[T], b: &[T]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x.to_f64() * y.to_f64()).sum()
}

fn mean_abs<T: Real>(a: &[T]) -> f64 {
    a.iter().map(|v| v.to_f64().abs()).sum::<f64>() / a.len().max(1) as f64
}

/// Minimizes `obj` over `params` (updated in place) from `state`; `observe` sees every
/// iteration and returns false to stop.
pub fn solve<T: Real>(
    obj: &Objective<T>,
    cfg: &SolverConfig,
    params: &mut Params<T>,
    state: &mut SolverState,
    mut observe: impl FnMut(&Params<T>, &SolverState) -> bool,
) -> Result<Stop> {
    cfg.validate()?;
    obj.check(params)?;
    let start = Instant::now();
    let offset = state.history.last().map_or(0.0, |r| r.seconds);
    let free = obj.free.blocks();
    let mut ev = obj.evaluate(params, true);
    state.evaluations += 1;
    if state.history.is_empty() {
        state.history.push(Record {
            iteration: 0,
            cost: ev.cost,
            mse: ev.mse,
            evaluations: state.evaluations,
            seconds: 0.0,
        });
    }
    let mut grad = ev.grad.take().ok_or_else(|| RetinaError::Invalid("no gradient".into()))?;
    loop {
        if state.converged(cfg.tolerance, cfg.window) {
            return Ok(Stop::Converged);
        }
        if state.iteration >= cfg.max_iterations {
            return Ok(Stop::MaxIterations);
        }
        if start.elapsed().as_secs_f64() >= cfg.time_limit_s {
            return Ok(Stop::TimeLimit);
        }
        let cost = match cfg.method {
            Method::Pgd => match pgd_step(obj, params, &mut grad, ev.cost, state, free) {
                Some(next) => next,
                None => return Ok(Stop::Stalled),
            },
            Method::Adam => {
                adam_step(cfg, params, &grad, state, free);
                let e = obj.evaluate(params, true);
                state.evaluations += 1;
                grad = e.grad.clone().ok_or_else(|| RetinaError::Invalid("no gradient".into()))?;
                (e.cost, e.mse)
            }
        };
        ev.cost = cost.0;
        state.iteration += 1;
        state.history.push(Record {
            iteration: state.iteration,
            cost: cost.0,
            mse: cost.1,
            evaluations: state.evaluations,
            seconds: offset + start.elapsed().as_secs_f64(),
        });
        if !cost.0.is_finite() {
            return Err(RetinaError::Invalid(format!(
                "the cost became {} at iteration {}: lower the learning rate",
                cost.0, state.iteration
            )));
        }
        if !observe(params, state) {
            return Ok(Stop::Cancelled);
        }
    }
}

/// One spectral projected gradient iteration; returns the new (cost, mse), or None when the
/// line search found no decrease. `grad` is replaced by the gradient at the new point.
fn pgd_step<T: Real>(
    obj: &Objective<T>,
    params: &mut Params<T>,
    grad: &mut Params<T>,
    cost: f64,
    state: &mut SolverState,
    free: [bool; 3],
) -> Option<(f64, f64)> {
    // First step of a block: move its entries by about 1 % of their mean size.
    for b in 0..3 {
        if free[b] && state.steps[b] <= 0.0 {
            let (x, g) = (mean_abs(params.blocks()[b]), mean_abs(grad.blocks()[b]));
            state.steps[b] = if g > 0.0 && x > 0.0 { 0.01 * x / g } else { 1e-3 };
        }
    }
    // d = P(x - step g) - x on the free blocks.
    let mut d = Params::zeros(params.shape);
    let mut gd = 0.0;
    for b in 0..3 {
        if !free[b] {
            continue;
        }
        let step = T::from_f64(state.steps[b]);
        let zero = T::default();
        let (x, g) = (params.blocks()[b], grad.blocks()[b]);
        for ((dd, &xv), &gv) in d.blocks_mut()[b].iter_mut().zip(x).zip(g) {
            let t = xv - step * gv;
            *dd = if t > zero { t } else { zero } - xv;
        }
        gd += dot(g, d.blocks()[b]);
    }
    if gd >= 0.0 {
        return None;
    }
    // The nonmonotone reference: the largest of the last 5 costs.
    let n = state.history.len();
    let reference = state.history[n.saturating_sub(5)..].iter().map(|r| r.cost).fold(cost, f64::max);
    let mut lambda = 1.0;
    for _ in 0..40 {
        let mut trial = params.clone();
        let l = T::from_f64(lambda);
        let zero = T::default();
        for b in 0..3 {
            if free[b] {
                for (xv, &dv) in trial.blocks_mut()[b].iter_mut().zip(d.blocks()[b]) {
                    // A convex combination of x >= 0 and P(...) >= 0; the max guards round-off.
                    let v = *xv + l * dv;
                    *xv = if v > zero { v } else { zero };
                }
            }
        }
        let e = obj.evaluate(&trial, true);
        state.evaluations += 1;
        if e.cost.is_finite() && e.cost <= reference + 1e-4 * lambda * gd {
            let g_new = e.grad?;
            // Barzilai-Borwein per block: s.s / s.y, kept when the curvature is not positive.
            for b in 0..3 {
                if !free[b] {
                    continue;
                }
                let (mut ss, mut sy) = (0.0, 0.0);
                for ((xn, xo), (gn, go)) in
                    trial.blocks()[b].iter().zip(params.blocks()[b]).zip(g_new.blocks()[b].iter().zip(grad.blocks()[b]))
                {
                    let s = xn.to_f64() - xo.to_f64();
                    ss += s * s;
                    sy += s * (gn.to_f64() - go.to_f64());
                }
                if sy > 0.0 && ss > 0.0 {
                    let old = state.steps[b];
                    state.steps[b] = (ss / sy).clamp(old * 1e-3, old * 1e3);
                }
            }
            *params = trial;
            *grad = g_new;
            return Some((e.cost, e.mse));
        }
        lambda *= 0.5;
        // Shrink the steps too, so that the next iteration starts nearer an acceptable one.
        if lambda < 0.01 {
            for s in state.steps.iter_mut() {
                *s *= 0.5;
            }
        }
    }
    None
}

/// One Adam step with projection.
fn adam_step<T: Real>(
    cfg: &SolverConfig,
    params: &mut Params<T>,
    grad: &Params<T>,
    state: &mut SolverState,
    free: [bool; 3],
) {
    let sizes = params.shape.sizes();
    let total: usize = sizes.iter().sum();
    if state.adam_m.len() != total {
        state.adam_m = vec![0.0; total];
        state.adam_v = vec![0.0; total];
        for b in 0..3 {
            let x = mean_abs(params.blocks()[b]);
            let g = (dot(grad.blocks()[b], grad.blocks()[b]) / sizes[b].max(1) as f64).sqrt();
            state.adam_lr[b] = cfg.learning_rate * if x > 0.0 { x } else { 1e-3 };
            state.adam_eps[b] = 1e-8 * if g > 0.0 { g } else { 1.0 };
        }
    }
    let (b1, b2) = (0.9f64, 0.999f64);
    let t = (state.iteration + 1) as i32;
    let (c1, c2) = (1.0 - b1.powi(t), 1.0 - b2.powi(t));
    let mut off = 0;
    for b in 0..3 {
        let n = sizes[b];
        if free[b] {
            let (lr, eps) = (state.adam_lr[b], state.adam_eps[b]);
            let m = &mut state.adam_m[off..off + n];
            let v = &mut state.adam_v[off..off + n];
            for (((x, &g), mm), vv) in params.blocks_mut()[b].iter_mut().zip(grad.blocks()[b]).zip(m).zip(v) {
                let g = g.to_f64();
                *mm = b1 * *mm + (1.0 - b1) * g;
                *vv = b2 * *vv + (1.0 - b2) * g * g;
                let step = lr * (*mm / c1) / ((*vv / c2).sqrt() + eps);
                *x = T::from_f64((x.to_f64() - step).max(0.0));
            }
        }
        off += n;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::action::Action;
    use crate::experience::Experience;
    use crate::model::{Free, Shape};
    use ocellus_image::rng::SplitMix64;

    fn problem() -> (Experience<f64>, Params<f64>) {
        let shape = Shape { pixels: 10, fields: 3, motor_fields: 2, motor_cells: 2 };
        let mut rng = SplitMix64::new(1);
        let t = 60;
        let x0: Vec<f64> = (0..t * 10).map(|_| rng.unit()).collect();
        // i1 = i0 shifted cyclically by one for action 0, by two for action 1.
        let mut x1 = vec![0.0; t * 10];
        let mut q = vec![0.0; t * 2];
        for i in 0..t {
            let k = i % 2;
            q[i * 2 + k] = 1.0;
            for j in 0..10 {
                x1[i * 10 + j] = x0[i * 10 + (j + 1 + k) % 10];
            }
        }
        let data =
            Experience { pixels: 10, motor_cells: 2, x0, x1, q, actions: vec![Action::Shift { dx: 0.0, dy: 0.0 }; t] };
        (data, Params::random(shape, true, 3).unwrap())
    }

    #[test]
    fn both_solvers_lower_the_cost_and_keep_every_entry_non_negative() {
        let (data, p0) = problem();
        let obj =
            Objective { data: &data, free: Free { s: true, m: false, p: true }, simplicity: 1e-3, smoothness: None };
        for method in [Method::Pgd, Method::Adam] {
            let mut p = p0.clone();
            let cfg = SolverConfig { method, max_iterations: 200, ..SolverConfig::default() };
            let mut st = SolverState::new();
            let mut all_non_negative = true;
            solve(&obj, &cfg, &mut p, &mut st, |p, _| {
                all_non_negative &= p.blocks().iter().all(|b| b.iter().all(|&v| v >= 0.0));
                true
            })
            .unwrap();
            assert!(all_non_negative, "{method:?}");
            let (first, last) = (st.history[0].cost, st.history.last().unwrap().cost);
            assert!(last < 0.5 * first, "{method:?}: {first} -> {last}");
            // The fixed block did not move.
            assert_eq!(p.m, p0.m);
        }
    }

    #[test]
    fn runs_are_deterministic_and_resume_where_they_stopped() {
        let (data, p0) = problem();
        let obj =
            Objective { data: &data, free: Free { s: true, m: false, p: true }, simplicity: 1e-3, smoothness: None };
        for method in [Method::Pgd, Method::Adam] {
            let cfg = SolverConfig { method, max_iterations: 40, tolerance: 0.0, ..SolverConfig::default() };
            let mut a = p0.clone();
            let mut sa = SolverState::new();
            solve(&obj, &cfg, &mut a, &mut sa, |_, _| true).unwrap();
            let mut b = p0.clone();
            let mut sb = SolverState::new();
            solve(&obj, &cfg, &mut b, &mut sb, |_, _| true).unwrap();
            assert_eq!(a, b);
            // Stopped at 20 and resumed from the state: the same as 40 straight for Adam
            // (its state is complete); PGD restarts its line-search memory, so only lower.
            let mut c = p0.clone();
            let mut sc = SolverState::new();
            solve(&obj, &SolverConfig { max_iterations: 20, ..cfg }, &mut c, &mut sc, |_, _| true).unwrap();
            solve(&obj, &cfg, &mut c, &mut sc, |_, _| true).unwrap();
            assert_eq!(sc.iteration, 40);
            if method == Method::Adam {
                assert_eq!(a, c);
            } else {
                assert!(sc.history.last().unwrap().cost < sc.history[20].cost);
            }
        }
    }

    #[test]
    fn bad_settings_are_refused() {
        let (data, mut p) = problem();
        let obj =
            Objective { data: &data, free: Free { s: true, m: false, p: true }, simplicity: 0.0, smoothness: None };
        let mut st = SolverState::new();
        for cfg in [
            SolverConfig { learning_rate: f64::NAN, ..SolverConfig::default() },
            SolverConfig { time_limit_s: 0.0, ..SolverConfig::default() },
            SolverConfig { window: 0, ..SolverConfig::default() },
        ] {
            assert!(solve(&obj, &cfg, &mut p, &mut st, |_, _| true).is_err());
        }
        assert!("sgd".parse::<Method>().is_err());
    }
}
