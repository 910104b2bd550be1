//! `Backend::Gpu` (feature `gpu`) against the scalar reference on real photos: every level
//! the GPU front end computes, and the saliency map built from them, within
//! `ocellus_gpu::TOLERANCE` of the CPU's.
//!
//! These tests need a GPU adapter; `scripts/setup.sh` installs Mesa's software Vulkan driver
//! (lavapipe) and `scripts/test.sh` points `VK_DRIVER_FILES` at it.
#![cfg(feature = "gpu")]
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

use ocellus_attention::saliency::Source;
use ocellus_attention::{AttentionError, SaliencyConfig, SaliencyEngine};
use ocellus_gpu::TOLERANCE;
use ocellus_image::convert::RgbImage;
use ocellus_image::{Backend, Plane};

fn photo(name: &str, w: usize, h: usize) -> RgbImage {
    let p = ocellus_io::read_image(ocellus_testdata::data_file(name)).unwrap().to_u8();
    let (pw, ph) = p.size();
    RgbImage::U8(Plane::from_fn(w, h, |x, y| p.get(x * pw / w, y * ph / h)))
}

fn with_backend(mut cfg: SaliencyConfig, backend: Backend) -> SaliencyConfig {
    cfg.backend = backend;
    cfg
}

fn peak(p: &Plane<f32>) -> f32 {
    p.as_slice().iter().fold(0.0f32, |m, v| m.max(v.abs()))
}

/// max |gpu - cpu| / scale.
fn rel_err(gpu: &Plane<f32>, cpu: &Plane<f32>, scale: f32) -> f32 {
    assert_eq!(gpu.size(), cpu.size());
    let diff = gpu.as_slice().iter().zip(cpu.as_slice()).fold(0.0f32, |m, (a, b)| m.max((a - b).abs()));
    diff / scale.max(1e-12)
}

fn compare(cfg: &SaliencyConfig, name: &str, w: usize, h: usize) {
    let frame = photo(name, w, h);
    let mut cpu = SaliencyEngine::new(with_backend(cfg.clone(), Backend::Scalar), w, h).unwrap();
    let cpu_map = cpu.process(&frame).unwrap().clone();
    let mut gpu = SaliencyEngine::new(with_backend(cfg.clone(), Backend::Gpu), w, h).unwrap();
    assert!(gpu.on_gpu() && !cpu.on_gpu());
    let gpu_map = gpu.process(&frame).unwrap().clone();
    let n_angles = cfg.gabor.angles_deg.len();
    for &l in cpu.used_levels() {
        for src in [Source::Intensity, Source::RedGreen, Source::BlueYellow] {
            let c = cpu.level(src, l).unwrap();
            let e = rel_err(gpu.level(src, l).unwrap(), c, peak(c));
            assert!(e <= TOLERANCE, "{name} {w}x{h} level {l} {src:?}: {e}");
        }
        // The energies of one level on one scale, at least the level's intensity peak: at the
        // top levels (2x1, 1x1) an angle across a single row or pixel responds with rounding
        // noise only, and its own peak would measure that noise, not agreement.
        let scale = (0..n_angles)
            .map(|a| peak(cpu.level(Source::Orientation(a), l).unwrap()))
            .fold(peak(cpu.level(Source::Intensity, l).unwrap()), f32::max);
        for a in 0..n_angles {
            let src = Source::Orientation(a);
            let e = rel_err(gpu.level(src, l).unwrap(), cpu.level(src, l).unwrap(), scale);
            assert!(e <= TOLERANCE, "{name} {w}x{h} level {l} angle {a}: {e}");
        }
    }
    compare_maps(&cpu, &gpu, &format!("{name} {w}x{h}"));
    let e = rel_err(&gpu_map, &cpu_map, peak(&cpu_map));
    assert!(e <= TOLERANCE, "{name} {w}x{h} saliency: {e}");
    // The same winner, so a robot looks at the same place whichever backend it runs.
    assert_eq!(gpu_map.argmax().map(|m| (m.0, m.1)), cpu_map.argmax().map(|m| (m.0, m.1)), "{name}");
}

/// The map-level outputs the GPU computes on the device: every feature map (center-surround,
/// before N(.)) and every conspicuity map, each within the tolerance of its own peak.
fn compare_maps(cpu: &SaliencyEngine, gpu: &SaliencyEngine, what: &str) {
    assert_eq!(cpu.feature_maps().len(), gpu.feature_maps().len());
    for (c, g) in cpu.feature_maps().iter().zip(gpu.feature_maps()) {
        assert_eq!((c.subfeature, c.center, c.surround), (g.subfeature, g.center, g.surround));
        let e = rel_err(&g.map, &c.map, peak(&c.map));
        assert!(e <= TOLERANCE, "{what} feature map {} {}-{}: {e}", c.subfeature, c.center, c.surround);
    }
    for i in 0..cpu.config().channels.len() {
        let (c, g) = (cpu.conspicuity(i).unwrap(), gpu.conspicuity(i).unwrap());
        let e = rel_err(g, c, peak(c));
        assert!(e <= TOLERANCE, "{what} conspicuity {i}: {e}");
    }
}

/// ace2009 with centre levels 1-2 and surround deltas 2-3: levels up to 5, so that 160x120
/// frames (too small for the 9 levels of the full preset) run the same machinery.
fn small() -> SaliencyConfig {
    let mut cfg = SaliencyConfig::ace2009();
    cfg.center_levels = vec![1, 2];
    cfg.deltas = vec![2, 3];
    cfg.map_level = 2;
    cfg
}

#[test]
fn the_gpu_matches_the_scalar_reference_at_640x480() {
    for name in ["astronaut.png", "chelsea.png", "coffee.png"] {
        compare(&SaliencyConfig::ace2009(), name, 640, 480);
    }
}

#[test]
fn the_gpu_matches_the_scalar_reference_at_160x120_and_odd_sizes() {
    for name in ["astronaut.png", "chelsea.png"] {
        compare(&small(), name, 160, 120);
    }
    // Odd sides exercise the truncated, renormalized border taps at every level.
    compare(&SaliencyConfig::ace2009(), "camera.png", 517, 389);
    compare(&small(), "coffee.png", 97, 75);
}

#[test]
fn every_frame_is_computed_afresh() {
    let (w, h) = (384, 288);
    let mut gpu = SaliencyEngine::new(with_backend(SaliencyConfig::ace2009(), Backend::Gpu), w, h).unwrap();
    let mut cpu = SaliencyEngine::new(SaliencyConfig::ace2009(), w, h).unwrap();
    for name in ["coffee.png", "astronaut.png", "coffee.png"] {
        let frame = photo(name, w, h);
        let g = gpu.process(&frame).unwrap().clone();
        let c = cpu.process(&frame).unwrap();
        assert!(rel_err(&g, c, peak(c)) <= TOLERANCE, "{name}");
    }
}

#[test]
fn what_the_gpu_does_not_do_gets_a_clear_error() {
    // The stb preset computes opponency at the input: refused by name.
    let e = SaliencyEngine::new(with_backend(SaliencyConfig::stb(), Backend::Gpu), 384, 288).unwrap_err();
    assert!(matches!(e, AttentionError::Gpu(_)) && e.to_string().contains("opponency"), "{e}");
    let mut cfg = with_backend(SaliencyConfig::ace2009(), Backend::Gpu);
    cfg.channels.push(ocellus_attention::config::ChannelConfig {
        kind: ocellus_attention::config::ChannelKind::Flicker,
        weight: 1.0,
    });
    let e = SaliencyEngine::new(cfg, 384, 288).unwrap_err();
    assert!(e.to_string().contains("Flicker"), "{e}");
    // A frame of the wrong size: the engine's own check, before the GPU.
    let mut gpu = SaliencyEngine::new(with_backend(SaliencyConfig::ace2009(), Backend::Gpu), 384, 288).unwrap();
    assert!(gpu.process(&RgbImage::U8(Plane::new(385, 288))).is_err());
}

#[test]
fn every_rule_of_the_map_level_stages_matches_the_cpu() {
    use ocellus_attention::config::{Combination, GlobalInhibition, Normalization};
    use ocellus_image::resample::ResampleMethod;
    let base = SaliencyConfig::ace2009();
    let mut variants = Vec::new();
    // The SaliencyToolbox's rules on ace2009's front end: nearest across-scale, inhibition
    // relative to the maximum, weights per sub-feature, a final rescaling.
    let mut stb_rules = base.clone();
    stb_rules.across_scale = ResampleMethod::Nearest;
    if let Normalization::Iterative { global_inhibition, .. } = &mut stb_rules.normalization {
        *global_inhibition = GlobalInhibition::RelativeToMax(0.02);
    }
    stb_rules.combination = Combination::StbPerSubfeature;
    stb_rules.final_range = Some(2.0);
    variants.push(("stb rules", stb_rules));
    let mut local = base.clone();
    local.normalization = Normalization::LocalMax;
    variants.push(("local max", local));
    let mut none = base.clone();
    none.normalization = Normalization::None;
    variants.push(("none", none));
    let mut weighted = base.clone();
    weighted.channels[0].weight = 2.0;
    weighted.channels[2].weight = 0.5;
    weighted.border_ramp_frac = 0.0;
    variants.push(("weights, no ramp", weighted));
    for (what, cfg) in variants {
        let (w, h) = (512, 384);
        let frame = photo("chelsea.png", w, h);
        let mut cpu = SaliencyEngine::new(with_backend(cfg.clone(), Backend::Scalar), w, h).unwrap();
        let c = cpu.process(&frame).unwrap().clone();
        let mut gpu = SaliencyEngine::new(with_backend(cfg, Backend::Gpu), w, h).unwrap();
        let g = gpu.process(&frame).unwrap().clone();
        compare_maps(&cpu, &gpu, what);
        let e = rel_err(&g, &c, peak(&c));
        assert!(e <= TOLERANCE, "{what} saliency: {e}");
    }
}

#[test]
fn the_spatial_prior_and_the_level_readback_switch() {
    let (w, h) = (384, 288);
    let frame = photo("astronaut.png", w, h);
    let prior = Plane::from_fn(24, 18, |x, _| if x < 12 { 1.0 } else { 0.25 });
    let mut cpu = SaliencyEngine::new(SaliencyConfig::ace2009(), w, h).unwrap();
    cpu.set_spatial_prior(Some(&prior)).unwrap();
    let c = cpu.process(&frame).unwrap().clone();
    let mut gpu = SaliencyEngine::new(with_backend(SaliencyConfig::ace2009(), Backend::Gpu), w, h).unwrap();
    gpu.set_spatial_prior(Some(&prior)).unwrap();
    gpu.set_gpu_level_readback(false);
    let g = gpu.process(&frame).unwrap().clone();
    assert!(rel_err(&g, &c, peak(&c)) <= TOLERANCE);
    // Without the levels read back, the engine has none to show.
    assert!(gpu.level(Source::Intensity, 2).is_none());
    gpu.set_gpu_level_readback(true);
    gpu.process(&frame).unwrap();
    let e = rel_err(gpu.level(Source::Intensity, 2).unwrap(), cpu.level(Source::Intensity, 2).unwrap(), 1.0);
    assert!(e <= TOLERANCE, "{e}");
}

#[test]
fn a_batch_gives_each_frame_its_own_map() {
    let (w, h) = (320, 256);
    let names = ["coffee.png", "astronaut.png", "chelsea.png", "coffee.png", "camera.png"];
    let frames: Vec<RgbImage> = names.iter().map(|n| photo(n, w, h)).collect();
    let gpu_cfg = with_backend(SaliencyConfig::ace2009(), Backend::Gpu);
    let mut one = SaliencyEngine::new(gpu_cfg.clone(), w, h).unwrap();
    let singles: Vec<Plane<f32>> = frames.iter().map(|f| one.process(f).unwrap().clone()).collect();
    let mut batched = SaliencyEngine::new(gpu_cfg, w, h).unwrap();
    let mut out = Vec::new();
    // A batch of two, then one of five (the buffers grow), then of three (they are reused).
    for n in [2, 5, 3] {
        batched.process_batch(&frames[..n], &mut out).unwrap();
        assert_eq!(out.len(), n);
        for (k, m) in out.iter().enumerate() {
            // The same shaders on the same input: the same bits as one frame at a time.
            assert_eq!(m.as_slice(), singles[k].as_slice(), "batch of {n}, frame {k}");
        }
    }
    // The CPU's batch is frame by frame, and agrees within the tolerance.
    let mut cpu = SaliencyEngine::new(SaliencyConfig::ace2009(), w, h).unwrap();
    let mut cpu_out = Vec::new();
    cpu.process_batch(&frames, &mut cpu_out).unwrap();
    batched.process_batch(&frames, &mut out).unwrap();
    for (g, c) in out.iter().zip(&cpu_out) {
        assert!(rel_err(g, c, peak(c)) <= TOLERANCE);
    }
    // Frames of another size are refused before anything runs.
    let wrong = vec![photo("coffee.png", w, h), photo("coffee.png", w + 1, h)];
    assert!(batched.process_batch(&wrong, &mut out).is_err());
    batched.process_batch(&[], &mut out).unwrap();
    assert!(out.is_empty());
}
