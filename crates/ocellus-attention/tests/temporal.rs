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

/// Saccades over a panning sequence, in world angles: (frame, azimuth, elevation, the world
/// inhibition at the target when it was chosen). `use_pan = false` feeds the attention a still
/// camera although it pans (the control without an ego-sphere). Inhibition is recomputed in
/// the world frame from the inhibition-of-return events of the run, identically for both.
fn pan_scanpath(use_pan: bool) -> (Vec<(usize, f32, f32, f32)>, usize) {
    use ocellus_attention::attention::{Attention, AttentionConfig};
    use ocellus_attention::egosphere::{separation_deg, ViewGeometry};
    let world: Vec<_> = ["coffee.png", "rocket.jpg", "astronaut.png"]
        .iter()
        .map(|n| ocellus_io::read_image(data_file(n)).unwrap())
        .collect();
    let object = ocellus_io::read_image(data_file("chelsea.png")).unwrap();
    let cfg = SceneConfig { frames: 90, pan_px_per_frame: 4.0, ..SceneConfig::new(Scenario::Pan) };
    let g = SceneGenerator::new(cfg, &world, &object).unwrap();
    let mut engine = SaliencyEngine::new(SaliencyConfig::ace2009(), 640, 480).unwrap();
    let view = ViewGeometry { width: 640, height: 480, deg_per_px: g.config().deg_per_px };
    let acfg = AttentionConfig::default();
    let (tau, sigma) = (acfg.ior_tau_frames, acfg.ior_sigma_deg);
    let mut a = Attention::new(acfg, view).unwrap();
    let mut saccades = Vec::new();
    // Longest stay of the gaze within 2.5 degrees of one world point, frames.
    let (mut dwell_start, mut dwell, mut longest) = ((f32::NAN, f32::NAN), 0usize, 0usize);
    // Inhibition-of-return events in world angles: (frame, azimuth, elevation, amount).
    let mut events: Vec<(usize, f32, f32, f32)> = Vec::new();
    let world_ior = |events: &[(usize, f32, f32, f32)], k: usize, az: f32, el: f32| -> f32 {
        let v: f32 = events
            .iter()
            .map(|&(j, eaz, eel, amt)| {
                let d = separation_deg((az, el), (eaz, eel));
                amt * (-((k - j) as f32) / tau).exp() * (-0.5 * d * d / (sigma * sigma)).exp()
            })
            .sum();
        v.min(1.0)
    };
    for k in 0..g.len() {
        let (frame, truth) = g.frame(k).unwrap();
        let s = engine.process(&frame).unwrap();
        let pan = if use_pan { truth.pan_deg } else { 0.0 };
        let shift = truth.pan_deg - pan; // camera-frame angles + shift = world angles
        let before: f32 = a.inhibition_of_return().blobs.iter().map(|b| b.amplitude).sum();
        let f = a.step(s, None, pan, 0.0).unwrap().unwrap();
        let (az, el) = (f.azimuth_deg + shift, f.elevation_deg);
        if f.saccade {
            saccades.push((k, az, el, world_ior(&events, k, az, el)));
        }
        if separation_deg((az, el), dwell_start) <= 2.5 {
            dwell += 1;
        } else {
            (dwell_start, dwell) = ((az, el), 1);
        }
        longest = longest.max(dwell);
        let after: f32 = a.inhibition_of_return().blobs.iter().map(|b| b.amplitude).sum();
        let decayed = before * (-1.0 / tau).exp();
        if after > decayed + 0.5 {
            events.push((k, az, el, after - decayed));
        }
    }
    (saccades, longest)
}

#[test]
fn egosphere_keeps_attended_world_points_inhibited_during_a_pan() {
    let ((with, dwell_with), (without, dwell_without)) = (pan_scanpath(true), pan_scanpath(false));
    let fmt = |v: &[(usize, f32, f32, f32)]| {
        v.iter().map(|s| format!("f{} ({:.1},{:.1}) ior {:.2}", s.0, s.1, s.2, s.3)).collect::<Vec<_>>().join("; ")
    };
    println!("with ego-sphere (longest dwell {dwell_with} frames): {}", fmt(&with));
    println!("without (longest dwell {dwell_without} frames): {}", fmt(&without));
    assert!(with.len() >= 4, "the gaze moves on: {}", fmt(&with));
    // A fresh inhibition blob is 1 and decays with tau = 90 frames; 0.75 means inhibited
    // within the last 26 frames. (Older, weaker inhibition can lose to a strong stimulus.)
    let worst = with.iter().map(|s| s.3).fold(0.0f32, f32::max);
    assert!(worst < 0.75, "a saccade went to a world point still inhibited at {worst}");
    // Habituation moves the gaze on after about 14 frames on one place; without the
    // ego-sphere the inhibition slides away with the image and the gaze stays on one world point.
    assert!(dwell_with <= 30, "with ego-sphere the gaze dwelt {dwell_with} frames on one place");
    assert!(dwell_without > 2 * dwell_with, "control dwelt {dwell_without} frames");
}

/// Everything a frame's outputs hold, by value.
fn snapshot(r: &ocellus_attention::stream::StreamFrame) -> (usize, Vec<f32>, Vec<f32>, Option<f64>, String, Vec<f32>) {
    (r.frame, r.saliency.to_vec(), r.surprise.to_vec(), r.chaos, format!("{:?}", r.fixation), r.inhibition.to_vec())
}

#[test]
fn workers_on_any_frames_give_the_sequential_stream_bit_for_bit() {
    use ocellus_attention::stream::{StreamConfig, StreamEngine, StreamWorker};
    use ocellus_io::pipeline::{run_ordered, PipelineConfig};
    use std::sync::Arc;
    let world: Vec<_> =
        ["coffee.png", "rocket.jpg"].iter().map(|n| ocellus_io::read_image(data_file(n)).unwrap()).collect();
    let object = ocellus_io::read_image(data_file("chelsea.png")).unwrap();
    let cfg = SceneConfig { frames: 14, event_frame: 7, ..SceneConfig::new(Scenario::SuddenObject) };
    let g = SceneGenerator::new(cfg, &world, &object).unwrap();
    let frames: Vec<Arc<_>> = (0..g.len()).map(|k| Arc::new(g.frame(k).unwrap().0)).collect();
    let (w, h) = frames[0].size();
    let scfg = StreamConfig::default();
    let mut seq = StreamEngine::new(scfg.clone(), w, h).unwrap();
    let want: Vec<_> = frames.iter().map(|f| snapshot(&seq.process(f, 0.0, 0.0).unwrap())).collect();
    // Each worker count through the pipeline: workers see interleaved frames and prime
    // their flicker from the previous frame.
    for workers in [1, 2, 3] {
        let mut engine = StreamEngine::new(scfg.clone(), w, h).unwrap();
        let mut k = 0;
        let mut got = Vec::new();
        run_ordered(
            PipelineConfig { workers, depth: workers + 2 },
            || -> Result<_, ocellus_attention::AttentionError> {
                k += 1;
                Ok((k <= frames.len()).then(|| (k.checked_sub(2).map(|p| frames[p].clone()), frames[k - 1].clone())))
            },
            || StreamWorker::new(&scfg, w, h),
            |wk, i, (prev, cur)| wk.process(i, &cur, prev.as_deref()),
            |_, maps| {
                got.push(snapshot(&engine.process_maps(maps, 0.0, 0.0)?));
                Ok(())
            },
        )
        .unwrap();
        assert_eq!(got.len(), want.len());
        for (a, b) in got.iter().zip(&want) {
            assert!(a == b, "{workers} workers: frame {} differs", b.0);
        }
    }
    // Maps out of turn, and a worker without the previous frame, are errors.
    let mut wk = StreamWorker::new(&scfg, w, h).unwrap();
    assert!(wk.process(3, &frames[3], None).is_err());
    let maps = wk.process(3, &frames[3], Some(&frames[2])).unwrap();
    assert!(StreamEngine::new(scfg, w, h).unwrap().process_maps(maps, 0.0, 0.0).is_err());
}
