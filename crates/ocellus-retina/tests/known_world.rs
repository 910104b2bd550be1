//! A world with a known answer: a ring of 8 pixels whose actions shift it cyclically by one
//! and by two pixels. The best predictor of each action is then the shift matrix itself,
//! with zero error; the learning must find it.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

use ocellus_image::rng::SplitMix64;
use ocellus_retina::action::Action;
use ocellus_retina::experience::Experience;
use ocellus_retina::model::{Free, Objective, Params, Shape};
use ocellus_retina::solver::{solve, Method, SolverConfig, SolverState};

const N: usize = 8;
const SHIFTS: [usize; 2] = [1, 2];

fn ring_world(t: usize, seed: u64) -> Experience<f64> {
    let mut rng = SplitMix64::new(seed);
    let mut e = Experience {
        pixels: N,
        motor_cells: 2,
        x0: vec![0.0; t * N],
        x1: vec![0.0; t * N],
        q: vec![0.0; t * 2],
        actions: vec![Action::Shift { dx: 0.0, dy: 0.0 }; t],
    };
    for i in 0..t {
        let k = i % 2;
        e.q[i * 2 + k] = 1.0;
        e.actions[i] = Action::Shift { dx: SHIFTS[k] as f64, dy: 0.0 };
        for j in 0..N {
            e.x0[i * N + j] = rng.unit();
        }
        for j in 0..N {
            // Pixel j after the action shows what pixel j + shift showed before.
            e.x1[i * N + j] = e.x0[i * N + (j + SHIFTS[k]) % N];
        }
    }
    e
}

/// S^T P_k S, the predictor of action k in pixel space.
fn pixel_predictor(p: &Params<f64>, k: usize) -> Vec<f64> {
    let r = p.shape.fields;
    let mut out = vec![0.0; N * N];
    for a in 0..N {
        for b in 0..N {
            let mut v = 0.0;
            for i in 0..r {
                for j in 0..r {
                    v += p.s[i * N + a] * p.p[(k * r + i) * r + j] * p.s[j * N + b];
                }
            }
            out[a * N + b] = v;
        }
    }
    out
}

fn shift_matrix(s: usize) -> Vec<f64> {
    (0..N * N).map(|i| if (i / N + s) % N == i % N { 1.0 } else { 0.0 }).collect()
}

#[test]
fn with_one_field_per_pixel_the_predictors_become_the_shift_matrices() {
    let data = ring_world(200, 1);
    let shape = Shape { pixels: N, fields: N, motor_fields: 2, motor_cells: 2 };
    let mut p = Params::random(shape, true, 4).unwrap();
    // S fixed at the identity: the problem in P is convex with the shifts as its unique
    // minimum.
    p.s = (0..N * N).map(|i| if i / N == i % N { 1.0 } else { 0.0 }).collect();
    let obj = Objective { data: &data, free: Free { s: false, m: false, p: true }, simplicity: 0.0, smoothness: None };
    let cfg = SolverConfig { method: Method::Pgd, max_iterations: 3000, tolerance: 1e-9, ..SolverConfig::default() };
    solve(&obj, &cfg, &mut p, &mut SolverState::new(), |_, _| true).unwrap();
    for (k, &s) in SHIFTS.iter().enumerate() {
        let want = shift_matrix(s);
        let got = &p.p[k * N * N..(k + 1) * N * N];
        let err = got.iter().zip(&want).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(err < 1e-3, "shift {s}: max error {err}");
    }
}

#[test]
fn learning_fields_and_predictors_together_recovers_the_shifts() {
    let data = ring_world(200, 2);
    let shape = Shape { pixels: N, fields: N, motor_fields: 2, motor_cells: 2 };
    let mut p = Params::random(shape, true, 5).unwrap();
    let obj = Objective { data: &data, free: Free { s: true, m: false, p: true }, simplicity: 0.0, smoothness: None };
    let cfg = SolverConfig { method: Method::Pgd, max_iterations: 20_000, tolerance: 1e-7, ..SolverConfig::default() };
    let mut st = SolverState::new();
    solve(&obj, &cfg, &mut p, &mut st, |_, _| true).unwrap();
    let mse = obj.evaluate(&p, false).mse;
    let identity = data.identity_mse();
    assert!(mse < 1e-4 * identity, "mse {mse} against the identity predictor's {identity}");
    for (k, &s) in SHIFTS.iter().enumerate() {
        let want = shift_matrix(s);
        let got = pixel_predictor(&p, k);
        let err = got.iter().zip(&want).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(err < 0.02, "shift {s}: S^T P S differs from the shift matrix by {err}");
    }
}
