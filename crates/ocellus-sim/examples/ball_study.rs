//! A ball thrown across a real photo, hidden behind a panel for 10 frames, tracked in 3D by
//! the plain SIR filter and by the boosted filter (particles drawn from colour blobs too);
//! prints each one's 3D RMSE, image-centre error, lost frames and re-acquisition delay.
//! `ocellus track study` runs the full study (3 trajectories x 3 seeds).
//!
//! `cargo run --release -p ocellus-sim --example ball_study`

use ocellus_sim::ball_tracking::{score_run, study_world_config, track_world, tracker_config, StudyScene};
use ocellus_synth::ball_world::{BallWorld, Trajectory};
use ocellus_tracking::tracker::TrackerConfig;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let load = |n: &str| -> Result<_, Box<dyn std::error::Error>> {
        Ok(ocellus_io::read_image(ocellus_testdata::asset(n))?.to_u8().map(|p| p.map(f32::from)))
    };
    let wc = study_world_config(Trajectory::Throw, 1, StudyScene::default());
    let world = BallWorld::new(wc, &load("rocket.jpg")?, &load("gravel.png")?)?;
    for boost in [0.0, 0.2] {
        let mut cfg = tracker_config(&wc, TrackerConfig::at_fps(wc.fps));
        cfg.boost = boost;
        cfg.particles = 1500;
        let (truth, estimates) = track_world(&world, cfg, |_, _, _, _| Ok(()))?;
        let s = score_run(&truth, &estimates)?;
        println!(
            "boost {boost}: 3D RMSE {:.1} % of the depth, median centre error {:.2} px, lost {} of {} frames, re-acquired after {:?}",
            s.rmse_3d_percent_of_depth, s.median_centre_error_px, s.lost_frames, s.scored_frames, s.reacquisition_delays
        );
    }
    Ok(())
}
