//! Attention over a generated sequence: an object appears suddenly in a still scene built from
//! real photographs; the stream engine (saliency with flicker, Bayesian surprise, context
//! chaos, winner-take-all with inhibition of return) turns the gaze to it.
//!
//! `cargo run --release -p ocellus-attention --example attend_sequence`

use ocellus_attention::stream::{StreamConfig, StreamEngine};
use ocellus_synth::attention_scenes::{Scenario, SceneConfig, SceneGenerator};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let read = |name: &str| ocellus_io::read_image(ocellus_testdata::asset(name));
    let world = [read("coffee.png")?, read("rocket.jpg")?, read("astronaut.png")?];
    let cfg = SceneConfig { frames: 24, event_frame: 12, ..SceneConfig::new(Scenario::SuddenObject) };
    let scene = SceneGenerator::new(cfg, &world, &read("chelsea.png")?)?;
    let (frame0, _) = scene.frame(0)?;
    let (w, h) = frame0.size();
    let mut engine = StreamEngine::new(StreamConfig::default(), w, h)?;
    for k in 0..scene.len() {
        let (frame, truth) = scene.frame(k)?;
        // A still camera: pan and tilt 0 degrees.
        let r = engine.process(&frame, 0.0, 0.0)?;
        let surprise = r.surprise.min_max().1;
        let chaos = r.chaos.map_or("-".to_string(), |c| format!("{c:.3}"));
        let gaze = match r.fixation {
            Some(f) if f.saccade => format!("saccade to ({:.0}, {:.0}), {}", f.x, f.y, f.reason.as_str()),
            _ => String::new(),
        };
        let object = truth.object.map_or(String::new(), |o| format!(" [object centre {:?}]", o.center()));
        println!("frame {k:2}: max surprise {surprise:6.2} bits, chaos {chaos:>6} bits {gaze}{object}");
    }
    Ok(())
}
