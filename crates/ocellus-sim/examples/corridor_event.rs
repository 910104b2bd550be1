//! The seed's corridor experiment (SPEC 2.6): where the planner points the camera, step by
//! step, with and without a person appearing at step 5.
//!
//! `cargo run --release -p ocellus-sim --example corridor_event`

use ocellus_sim::corridor_experiment::{corridor, run, CorridorImages, RunConfig};
use ocellus_sim::SimError;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let images = CorridorImages::load(|n| ocellus_io::read_image(ocellus_testdata::asset(n)))?;
    let world = corridor(&images)?;
    let cfg = RunConfig { steps: 8, event: true, ..RunConfig::default() };
    let calm = run(&RunConfig { event: false, ..cfg.clone() }, &world, |_, _| Ok::<(), SimError>(()))?;
    let event = run(&cfg, &world, |r, _| {
        println!(
            "step {} at x = {:.1} m: chaos {:.3} bits, v = {}, camera {:>4.0} deg -> next {:>4.0} deg{}",
            r.step,
            r.true_xy.0,
            r.chaos,
            r.decision.v,
            r.pan_deg,
            r.decision.pan_deg,
            if r.person_visible {
                format!(" (person in view at {:.0} deg)", r.person_bearing_deg)
            } else {
                String::new()
            }
        );
        Ok::<(), SimError>(())
    })?;
    let k = cfg.event_step;
    println!(
        "at the event step the gaze goes to {:.0} deg (the person is at {:.0} deg from the next position); without the event: {:.0} deg",
        event[k].decision.pan_deg, event[k].person_bearing_next_deg, calm[k].decision.pan_deg
    );
    Ok(())
}
