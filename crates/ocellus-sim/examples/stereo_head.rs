//! The active stereo head keeping a ball in both foveas: a ball flying towards the head and
//! away, 1 s at 60 Hz; prints the share of steps with the ball within 2 and 5 degrees of both
//! foveas, the saccades, and the control rate on this machine.
//!
//! `cargo run --release -p ocellus-sim --example stereo_head`

use ocellus_sim::stereo_head::{run_head, HeadConfig};
use ocellus_synth::ball_world::{BallWorld, BallWorldConfig, Trajectory};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let load = |n: &str| -> Result<_, Box<dyn std::error::Error>> {
        Ok(ocellus_io::read_image(ocellus_testdata::asset(n))?.to_u8().map(|p| p.map(f32::from)))
    };
    let traj = match std::env::args().nth(1).as_deref() {
        Some("throw") => Trajectory::Throw,
        Some("bounce") => Trajectory::Bounce,
        _ => Trajectory::Approach,
    };
    let cfg = HeadConfig::default();
    let wc = BallWorldConfig { fps: cfg.control_hz, frames: 60, ..BallWorldConfig::new(traj, 1) };
    let world = BallWorld::new(wc, &load("rocket.jpg")?, &load("gravel.png")?)?;
    let s = run_head(&world, &cfg, |_, _, _| Ok(()))?.summary();
    println!(
        "{} steps: ball within 2 deg of both foveas {:.0} %, within 5 deg {:.0} %, median {:.2} deg; {} saccades; control loop {:.0} Hz (rendering excluded)",
        s.steps,
        100.0 * s.within_2deg,
        100.0 * s.within_5deg,
        s.median_error_deg,
        s.saccades,
        s.control_hz
    );
    Ok(())
}
