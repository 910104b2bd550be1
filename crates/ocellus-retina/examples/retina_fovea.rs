//! Does a fovea emerge? Experiment 1 of the self-organizing retina at a reduced size (481
//! pixels, 16 receptive fields, 20 motor fields as 5 x 4 cells of the motor space x 24
//! triplets) on the built-in photographs
//! and textures, once with translations and once with rotations + dilations, from the same
//! random start: the fovea index (correlation of field size with eccentricity) and the
//! held-out prediction error against the identity predictor.
use ocellus_retina::action::ActionKinds;
use ocellus_retina::experiment::{setup, start, ExperimentConfig, Init};
use ocellus_retina::layout::measure;
use ocellus_retina::model::Objective;
use ocellus_retina::solver::{solve, SolverConfig, SolverState};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let names = ["astronaut.png", "chelsea.png", "coffee.png", "rocket.jpg", "brick.png", "gravel.png", "grass.png"];
    let mut sources = Vec::new();
    for n in names {
        sources.push(ocellus_io::read_image(ocellus_testdata::asset(n))?.to_grey());
    }
    for actions in [ActionKinds::Translation, ActionKinds::RotationDilation] {
        let cfg = ExperimentConfig::sensor_design_small(actions);
        let su = setup::<f32>(&cfg, &sources)?;
        let mut p = start(&su, Init::Blobs, cfg.seed)?;
        let obj = Objective { data: &su.train, free: cfg.free(), simplicity: cfg.simplicity, smoothness: None };
        let mut state = SolverState::new();
        let stop = solve(&obj, &SolverConfig::default(), &mut p, &mut state, |_, _| true)?;
        let layout = measure(&su.disc, &p.s, cfg.fields)?;
        let held = Objective { data: &su.heldout, ..obj }.evaluate(&p, false).mse;
        println!(
            "{:<18} {:?} after {} iterations: fovea index {:+.2}, field area centre {:.0} / periphery {:.0} px, held-out mse {:.5} (identity {:.5})",
            actions.name(),
            stop,
            state.iteration,
            layout.fovea_index,
            layout.mean_area_centre_px,
            layout.mean_area_periphery_px,
            held,
            su.heldout.identity_mse()
        );
    }
    Ok(())
}
