//! Experiment 1 reduced to CI size (481 pixels, 16 fields, 20 motor fields x 24 triplets)
//! on the built-in photographs and textures: from the same random start, rotation and
//! dilation actions grow the fields with eccentricity (a positive fovea index) while
//! translations do not, and the learned predictor beats the identity on held-out triplets;
//! with the motor fields as cells of the motor space (the default) and as exact values.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

use ocellus_retina::action::ActionKinds;
use ocellus_retina::experiment::{setup, start, ExperimentConfig, Init, MotorSpace};
use ocellus_retina::layout::measure;
use ocellus_retina::model::Objective;
use ocellus_retina::solver::{solve, SolverConfig, SolverState};

fn sources() -> Vec<ocellus_image::Plane<f32>> {
    ["astronaut.png", "chelsea.png", "coffee.png", "rocket.jpg", "brick.png", "gravel.png", "grass.png"]
        .iter()
        .map(|n| ocellus_io::read_image(ocellus_testdata::asset(n)).unwrap().to_grey())
        .collect()
}

/// (fovea index at the start, after learning, held-out mse learned, identity).
fn run(actions: ActionKinds, motor_space: MotorSpace, seed: u64) -> (f64, f64, f64, f64) {
    let mut cfg = ExperimentConfig { seed, motor_space, ..ExperimentConfig::sensor_design_small(actions) };
    if motor_space == MotorSpace::Values {
        // Exact values keep the ranges of the first build.
        cfg.action_scale = 1.0;
    }
    let su = setup::<f32>(&cfg, &sources()).unwrap();
    let mut p = start(&su, Init::Blobs, seed).unwrap();
    let before = measure(&su.disc, &p.s, cfg.fields).unwrap().fovea_index;
    let obj = Objective { data: &su.train, free: cfg.free(), simplicity: cfg.simplicity, smoothness: None };
    solve(&obj, &SolverConfig::default(), &mut p, &mut SolverState::new(), |_, _| true).unwrap();
    let after = measure(&su.disc, &p.s, cfg.fields).unwrap().fovea_index;
    let held =
        Objective { data: &su.heldout, free: cfg.free(), simplicity: 0.0, smoothness: None }.evaluate(&p, false).mse;
    (before, after, held, su.heldout.identity_mse())
}

#[test]
fn rotation_and_dilation_grow_a_fovea_and_translation_does_not() {
    // Motor fields as cells, at experiment 1's default action ranges (factor 5 for rotations
    // and dilations, 1.5 for shifts): over seeds 1-6 the index was +0.30 to +0.65 with
    // rotations and dilations, -0.41 to +0.06 with translations (-0.76 to -0.40 with shifts
    // at factor 5, where the rim cut the fields small); the held-out error against the
    // identity's 0.41-0.53 and 0.44-0.52. Seeds 1-3 here.
    for seed in [1, 2, 3] {
        let (b_rd, rd, held_rd, id_rd) = run(ActionKinds::RotationDilation, MotorSpace::Cells, seed);
        let (b_tr, tr, held_tr, id_tr) = run(ActionKinds::Translation, MotorSpace::Cells, seed);
        // The same start for both action sets.
        assert_eq!(b_rd, b_tr);
        assert!(rd > 0.15, "seed {seed}: rotation + dilation fovea index {rd} (start {b_rd})");
        assert!(rd - tr > 0.15, "seed {seed}: {rd} against {tr}");
        assert!(
            held_rd < 0.6 * id_rd && held_tr < 0.6 * id_tr,
            "seed {seed}: {held_rd} / {id_rd}, {held_tr} / {id_tr}"
        );
    }
    // Motor fields as exact values (seed 1: +0.31 against -0.23).
    let (_, rd, held_rd, id_rd) = run(ActionKinds::RotationDilation, MotorSpace::Values, 1);
    let (_, tr, held_tr, id_tr) = run(ActionKinds::Translation, MotorSpace::Values, 1);
    assert!(rd > 0.15 && tr < 0.05, "values: {rd} against {tr}");
    assert!(held_rd < id_rd && held_tr < 0.8 * id_tr, "values: {held_rd} / {id_rd}, {held_tr} / {id_tr}");
}
