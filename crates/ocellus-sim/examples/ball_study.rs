//! The tracking study on the built-in photos: three generated ball sequences (thrown,
//! bouncing, approaching; both occluders, noise) x three seeds, tracked by the plain SIR and
//! the boosted particle filter; prints the 3D RMSE, centre error, lost frames and the
//! re-acquisition delay after the 10-frame full occlusion.
//!
//! `cargo run --release -p ocellus-sim --example ball_study`

use ocellus_sim::ball_tracking::study;
use ocellus_synth::ball_world::Trajectory;
use ocellus_tracking::tracker::TrackerConfig;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let load = |n: &str| -> Result<_, Box<dyn std::error::Error>> {
        Ok(ocellus_io::read_image(ocellus_testdata::asset(n))?.to_u8().map(|p| p.map(f32::from)))
    };
    let (background, occluder) = (load("rocket.jpg")?, load("gravel.png")?);
    let seeds: Vec<u64> =
        std::env::args().nth(1).map_or(Ok(vec![1, 2, 3]), |s| s.split(',').map(str::parse).collect())?;
    let runs = study(
        &background,
        &occluder,
        &[Trajectory::Throw, Trajectory::Bounce, Trajectory::Approach],
        &seeds,
        &[0.0, 0.2],
        TrackerConfig::at_fps(30.0),
    )?;
    println!("trajectory  seed  boost  3D RMSE (% depth)  centre px  lost  re-acquired after");
    for r in &runs {
        let s = &r.scores;
        println!(
            "{:<10} {:>5} {:>6.2}  {:>8.4} m ({:>5.2} %)  {:>9.2}  {:>4}  {:?}",
            format!("{:?}", r.trajectory),
            r.seed,
            r.boost,
            s.rmse_3d_m,
            s.rmse_3d_percent_of_depth,
            s.median_centre_error_px,
            s.lost_frames,
            s.reacquisition_delays
        );
    }
    Ok(())
}
