//! The corridor experiment (SPEC 2.6) on the repository's CC0 photographs: without an event
//! the planned gaze serves localization better than looking forward; the sudden person turns
//! it.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

use ocellus_sim::corridor_experiment::{corridor, run, CorridorImages, RunConfig};

fn images() -> CorridorImages {
    CorridorImages::load(|n| ocellus_io::read_image(ocellus_testdata::asset(n))).unwrap()
}

/// The step callback's error type of these runs.
type Res = Result<(), ocellus_sim::SimError>;

#[test]
fn without_event_the_gaze_serves_localization() {
    let world = corridor(&images()).unwrap();
    let planned = run(&RunConfig::default(), &world, |_, _| -> Res { Ok(()) }).unwrap();
    let forward =
        run(&RunConfig { fixed_forward: true, ..Default::default() }, &world, |_, _| -> Res { Ok(()) }).unwrap();
    let angles: Vec<f64> = planned.iter().map(|r| r.decision.pan_deg).collect();
    println!("no event, chosen angles: {angles:?}");
    for r in &planned {
        let chosen = r.decision.candidates.iter().find(|c| c.pan_deg == r.decision.pan_deg).unwrap();
        assert!(chosen.landmarks_in_view >= 1, "step {}: {} sees no landmark", r.step, chosen.pan_deg);
        assert_eq!(r.decision.v, 1.0, "step {}: chaos {} in a static corridor", r.step, r.chaos);
    }
    let (a, b) = (planned.last().unwrap().cov_trace, forward.last().unwrap().cov_trace);
    println!("final covariance trace: planned {a:.5} m^2, fixed forward {b:.5} m^2");
    assert!(a < b, "planned {a} vs forward {b}");
}

#[test]
fn the_sudden_person_turns_the_gaze() {
    let world = corridor(&images()).unwrap();
    let cfg = RunConfig { event: true, steps: 7, ..Default::default() };
    let event = run(&cfg, &world, |_, _| -> Res { Ok(()) }).unwrap();
    let calm = run(&RunConfig { steps: 7, ..Default::default() }, &world, |_, _| -> Res { Ok(()) }).unwrap();
    let k = cfg.event_step;
    let r = &event[k];
    println!(
        "event step {k}: pan {} -> {}, chaos {:.3}, person at {:.1} deg (next {:.1}); without event: -> {}",
        r.pan_deg,
        r.decision.pan_deg,
        r.chaos,
        r.person_bearing_deg,
        r.person_bearing_next_deg,
        calm[k].decision.pan_deg
    );
    assert!(r.person_visible, "the person must be in the burst's view");
    assert!(r.chaos > 1.0, "chaos {}", r.chaos);
    assert_eq!(r.decision.v, 0.0);
    // The chosen pan is used at the next position: the person within 10 degrees of its centre.
    assert!((r.decision.pan_deg - r.person_bearing_next_deg).abs() <= 10.0);
    // Without the event the top-down choice stands at that step.
    let c = &calm[k].decision;
    let best_td = c.candidates.iter().fold(f64::MIN, |m, x| m.max(x.top_down_bits));
    let chosen = c.candidates.iter().find(|x| x.pan_deg == c.pan_deg).unwrap();
    assert_eq!(chosen.top_down_bits, best_td);
}
