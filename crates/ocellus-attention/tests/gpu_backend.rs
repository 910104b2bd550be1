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
    let e = rel_err(&gpu_map, &cpu_map, peak(&cpu_map));
    assert!(e <= TOLERANCE, "{name} {w}x{h} saliency: {e}");
    // The same winner, so a robot looks at the same place whichever backend it runs.
    assert_eq!(gpu_map.argmax().map(|m| (m.0, m.1)), cpu_map.argmax().map(|m| (m.0, m.1)), "{name}");
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
