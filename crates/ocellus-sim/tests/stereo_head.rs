//! The active stereo head on a generated throw: after the first saccade the ball stays within
//! a few degrees of both foveas.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

use ocellus_sim::stereo_head::{run_head, saccade_count, HeadConfig};
use ocellus_synth::ball_world::{BallWorld, BallWorldConfig, Trajectory};

#[test]
fn the_head_keeps_a_thrown_ball_in_both_foveas() {
    let load =
        |n: &str| ocellus_io::read_image(ocellus_testdata::data_file(n)).unwrap().to_u8().map(|p| p.map(f32::from));
    let cfg = HeadConfig {
        tracker: ocellus_tracking::tracker::TrackerConfig { particles: 1000, ..HeadConfig::default().tracker },
        ..HeadConfig::default()
    };
    let wc = BallWorldConfig { fps: cfg.control_hz, frames: 60, ..BallWorldConfig::new(Trajectory::Throw, 1) };
    let world = BallWorld::new(wc, &load("rocket.jpg"), &load("gravel.png")).unwrap();
    let run = run_head(&world, &cfg, |_, _, _| Ok(())).unwrap();
    // The head starts looking straight ahead, 16 degrees from the ball: one saccade there.
    assert!(run.steps[0].left_error_deg > 10.0 || run.steps[0].saccade);
    assert!(saccade_count(&run.steps) >= 1);
    // From 0.2 s on, both eyes within 5 degrees at every step, and within 2 in most.
    let after: Vec<f64> = run.steps[12..].iter().map(|s| s.left_error_deg.max(s.right_error_deg)).collect();
    assert!(after.iter().all(|&e| e <= 5.0), "{after:?}");
    let within2 = after.iter().filter(|&&e| e <= 2.0).count() as f64 / after.len() as f64;
    assert!(within2 >= 0.9, "{within2}: {after:?}");
    // Vergence converged on the ball's distance (2.4-2.6 m: 1.5-1.6 degrees).
    let v = run.steps.last().unwrap().gaze.vergence.to_degrees();
    assert!((1.2..2.0).contains(&v), "vergence {v} deg");
}
