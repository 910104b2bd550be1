//! The 3D ball tracker on generated sequences (`ocellus-synth::ball_world`): a ball thrown in
//! front of a real photograph through a distorted camera, with sensor noise; the estimate
//! is scored against the known trajectory (`ocellus-eval::tracking`).
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

use ocellus_eval::tracking::{score, EstimateFrame, TrackingScores, TruthFrame};
use ocellus_image::Plane;
use ocellus_synth::ball_world::{BallWorld, BallWorldConfig, Occlusion, Trajectory, GRAVITY};
use ocellus_tracking::colour::{Circle, ColourModel};
use ocellus_tracking::motion::Floor;
use ocellus_tracking::tracker::{BallTracker, TrackerConfig};

fn photo(name: &str) -> Plane<[f32; 3]> {
    ocellus_io::read_image(ocellus_testdata::data_file(name)).unwrap().to_u8().map(|p| p.map(f32::from))
}

/// Tracks `world` from a colour patch of the first frame; returns the scores.
fn track(world: &BallWorld, boost: f64, seed: u64) -> TrackingScores {
    let (f0, t0) = world.frame(0).unwrap();
    let [x, y, r] = t0.circle.unwrap();
    let colour = ColourModel::from_patch(&f0, Circle { x, y, r: 0.8 * r }).unwrap();
    let mut cfg = TrackerConfig::at_fps(world.config().fps);
    cfg.motion.gravity = [0.0, GRAVITY, 0.0];
    // The robot knows its floor, not the ball's restitution.
    cfg.motion.floor = world.config().trajectory.floor().map(|(y, _)| Floor::below(y, world.config().radius_m, 0.8));
    cfg.boost = boost;
    cfg.filter.seed = seed;
    let cam = *world.camera();
    let mut tracker = BallTracker::new(cfg, cam, world.config().distortion, world.config().radius_m, colour).unwrap();
    let (mut truth, mut est) = (Vec::new(), Vec::new());
    for k in 0..world.len() {
        let (f, t) = world.frame(k).unwrap();
        let e = tracker.process(&f).unwrap();
        truth.push(TruthFrame { position: t.position, circle: t.circle, visible_fraction: t.visible_fraction });
        est.push(EstimateFrame { position: e.position, centre_px: e.circle.map(|c| [c.x, c.y]), lost: e.lost });
    }
    score(&truth, &est).unwrap()
}

#[test]
fn a_thrown_ball_is_tracked_in_3d() {
    let cfg = BallWorldConfig { frames: 40, ..BallWorldConfig::new(Trajectory::Throw, 2) };
    let world = BallWorld::new(cfg, &photo("rocket.jpg"), &photo("gravel.png")).unwrap();
    let s = track(&world, 0.2, 2);
    println!("{s:?}");
    assert!(s.median_centre_error_px <= 2.0, "{s:?}");
    assert_eq!(s.lost_frames, 0, "{s:?}");
    // 3D: the depth comes from a radius of 10-12 px (1 px is about 9 % of the depth): 1.7 %
    // here (issue 16 asks for 2 %; 3.5 % before the guard band and the rim term of
    // `ocellus_tracking::colour`, 9.7 % before the silhouette circle and the floor).
    assert!(s.rmse_3d_percent_of_depth <= 3.0, "{s:?}");
}

#[test]
fn the_boosted_filter_finds_the_ball_after_a_full_occlusion() {
    let cfg = BallWorldConfig { occlusion: Occlusion::Full, ..BallWorldConfig::new(Trajectory::Throw, 1) };
    let world = BallWorld::new(cfg, &photo("rocket.jpg"), &photo("gravel.png")).unwrap();
    let boosted = track(&world, 0.2, 1);
    let plain = track(&world, 0.0, 1);
    println!("boosted {boosted:?}\nplain {plain:?}");
    assert_eq!(boosted.reacquisition_delays.len(), 1);
    assert!(boosted.reacquisition_delays[0].is_some_and(|d| d <= 3), "{boosted:?}");
    // Hidden, the cloud coasts on the motion model instead of following wrong circles
    // (without that, 18 % of the depth on this run; 6.7 % with it).
    assert!(boosted.rmse_3d_percent_of_depth <= 10.0, "{boosted:?}");
    assert!(boosted.lost_frames <= plain.lost_frames, "boosted {boosted:?}\nplain {plain:?}");
}

/// The colour likelihood reads the depth without bias: on fully visible frames of a rendered
/// ball (Lambert-shaded, 2x2-supersampled edges, sensor noise), the circle of the true centre
/// moved along its line of sight scores best within 1.5 % of the true distance, and within
/// 0.75 % on average. Reading the rim 0.5 px on both sides of the edge, it peaked 1.3-3.3 %
/// too far (mean 2.3 %).
#[test]
fn the_likelihood_peaks_at_the_true_depth() {
    for trajectory in [Trajectory::Throw, Trajectory::Approach] {
        let world = BallWorld::new(
            BallWorldConfig { occlusion: Occlusion::None, ..BallWorldConfig::new(trajectory, 1) },
            &photo("rocket.jpg"),
            &photo("gravel.png"),
        )
        .unwrap();
        let (f0, t0) = world.frame(0).unwrap();
        let [x, y, r] = t0.circle.unwrap();
        let colour = ColourModel::from_patch(&f0, Circle { x, y, r: 0.8 * r }).unwrap();
        let cam = *world.camera();
        let centre = cam.centre();
        let mut biases = Vec::new();
        for k in [2, 10, 20, 50, 55] {
            let (f, t) = world.frame(k).unwrap();
            assert_eq!(t.visible_fraction, 1.0);
            let binned = ocellus_tracking::binning::BinnedFrame::new(&f);
            let p = nalgebra::Vector3::from(t.position);
            let best = (0..=40)
                .map(|i| 0.95 + 0.0025 * f64::from(i))
                .map(|s| {
                    let q = centre + (p - centre) * s;
                    let c = ocellus_tracking::ball::project_ball(
                        &cam,
                        &world.config().distortion,
                        &q,
                        world.config().radius_m,
                    )
                    .unwrap();
                    (colour.log_likelihood(&binned, c), s)
                })
                .fold((f64::NEG_INFINITY, 0.0), |a, b| if b.0 > a.0 { b } else { a })
                .1;
            assert!((best - 1.0).abs() <= 0.015, "{trajectory:?} frame {k}: peak at {best}");
            biases.push(best - 1.0);
        }
        let mean = biases.iter().sum::<f64>() / biases.len() as f64;
        assert!(mean.abs() <= 0.0075, "{trajectory:?}: mean bias {mean}");
    }
}
