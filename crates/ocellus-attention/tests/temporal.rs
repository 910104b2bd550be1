//! Surprise and context chaos on generated sequences built from real images, with ground truth.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

use ocellus_attention::chaos::{ChaosConfig, ChaosDegree};
use ocellus_attention::config::{ChannelConfig, ChannelKind};
use ocellus_attention::saliency::Source;
use ocellus_attention::surprise::{Surprise, SurpriseConfig};
use ocellus_attention::{SaliencyConfig, SaliencyEngine};
use ocellus_synth::attention_scenes::{Scenario, SceneConfig, SceneGenerator};
use ocellus_testdata::data_file;

struct FrameResult {
    chaos: Option<f64>,
    surprise_max: f32,
    surprise_at: (usize, usize),
}

fn run(scenario: Scenario) -> (Vec<FrameResult>, SceneGenerator) {
    let world: Vec<_> = ["coffee.png", "rocket.jpg", "astronaut.png"]
        .iter()
        .map(|n| ocellus_io::read_image(data_file(n)).unwrap())
        .collect();
    let object = ocellus_io::read_image(data_file("chelsea.png")).unwrap();
    let cfg = SceneConfig { frames: 24, event_frame: 12, ..SceneConfig::new(scenario) };
    let g = SceneGenerator::new(cfg, &world, &object).unwrap();
    let mut sal_cfg = SaliencyConfig::ace2009();
    sal_cfg.channels.push(ChannelConfig { kind: ChannelKind::Flicker, weight: 1.0 });
    let mut engine = SaliencyEngine::new(sal_cfg, 640, 480).unwrap();
    let (mw, mh) = engine.map_size();
    let mut surprise = Surprise::new(SurpriseConfig::default(), mw, mh).unwrap();
    let mut chaos = ChaosDegree::new(ChaosConfig::default()).unwrap();
    let mut out = Vec::new();
    for k in 0..g.len() {
        let (frame, _) = g.frame(k).unwrap();
        let s = engine.process(&frame).unwrap().clone();
        let c = chaos.update(engine.level(Source::Intensity, 2).unwrap()).unwrap();
        let m = surprise.update(&s).unwrap();
        let mut best = (f32::MIN, (0, 0));
        for y in 0..mh {
            for x in 0..mw {
                if m.get(x, y) > best.0 {
                    best = (m.get(x, y), (x, y));
                }
            }
        }
        out.push(FrameResult { chaos: c, surprise_max: best.0, surprise_at: best.1 });
    }
    (out, g)
}

#[test]
fn chaos_degree_separates_familiar_from_surprising_contexts() {
    let s_threshold = ChaosConfig::default().threshold;
    let (still, _) = run(Scenario::Static);
    let (pan, _) = run(Scenario::Pan);
    let (event, g) = run(Scenario::SuddenObject);
    let max = |r: &[FrameResult]| r.iter().filter_map(|f| f.chaos).fold(0.0f64, f64::max);
    let ev = g.config().event_frame;
    println!("chaos degree (bits): static max {:.4}, pan max {:.4}, sudden object at frame {ev}: {:.4} (seed: static 0.0526, crowd 0.0473, fast car 1.1761)",
        max(&still), max(&pan), event[ev].chaos.unwrap());
    assert!(still.iter().filter_map(|f| f.chaos).all(|s| s < s_threshold), "static scene stays familiar");
    assert!(pan.iter().filter_map(|f| f.chaos).all(|s| s < s_threshold), "steady pan stays familiar");
    assert!(event[ev].chaos.unwrap() > s_threshold, "the sudden object is unfamiliar");
    assert!(event
        .iter()
        .enumerate()
        .filter(|(k, _)| *k != ev && *k != ev + 1)
        .all(|(_, f)| f.chaos.unwrap_or(0.0) < s_threshold));
}

#[test]
fn surprise_peaks_where_and_when_the_object_appears() {
    let (still, _) = run(Scenario::Static);
    let (event, g) = run(Scenario::SuddenObject);
    let ev = g.config().event_frame;
    let r = g.truth(ev).unwrap().object.unwrap();
    let (cx, cy) = r.center();
    let (sx, sy) = event[ev].surprise_at;
    let (px, py) = ((sx as f32 + 0.5) * 16.0, (sy as f32 + 0.5) * 16.0);
    let static_max = still.iter().skip(1).map(|f| f.surprise_max).fold(0.0f32, f32::max);
    println!(
        "surprise max (bits): static {static_max:.4}, event frame {:.4} at ({px}, {py}) px; object centre ({cx}, {cy})",
        event[ev].surprise_max
    );
    assert!(
        px >= r.x as f32 - 16.0
            && px <= (r.x + r.w) as f32 + 16.0
            && py >= r.y as f32 - 16.0
            && py <= (r.y + r.h) as f32 + 16.0,
        "surprise peak at ({px}, {py}) px, object {r:?}"
    );
    assert!(event[ev].surprise_max > 10.0 * static_max, "event {} vs static {static_max}", event[ev].surprise_max);
}
