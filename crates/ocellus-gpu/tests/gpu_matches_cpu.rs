#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up
//! The GPU front end against the CPU engine on real photos: every level it computes, and the
//! saliency map built from them, within `ocellus_gpu::TOLERANCE` of the CPU's.
//!
//! These tests need a GPU adapter; `scripts/setup.sh` installs Mesa's software Vulkan driver
//! (lavapipe), so they run on any CI machine.

use ocellus_attention::saliency::Source;
use ocellus_attention::{SaliencyConfig, SaliencyEngine};
use ocellus_gpu::{GpuContext, GpuError, GpuSaliencyEngine, TOLERANCE};
use ocellus_image::convert::RgbImage;
use ocellus_image::Plane;
use std::sync::OnceLock;

fn context() -> &'static GpuContext {
    static CTX: OnceLock<GpuContext> = OnceLock::new();
    CTX.get_or_init(|| GpuContext::new().expect("a GPU adapter (scripts/setup.sh installs lavapipe)"))
}

fn photo(name: &str, w: usize, h: usize) -> Plane<[u8; 3]> {
    let p = ocellus_io::read_image(ocellus_testdata::data_file(name)).unwrap().to_u8();
    let (pw, ph) = p.size();
    Plane::from_fn(w, h, |x, y| p.get(x * pw / w, y * ph / h))
}

fn peak(p: &Plane<f32>) -> f32 {
    p.as_slice().iter().fold(0.0f32, |m, v| m.max(v.abs()))
}

/// max |gpu - cpu| / max |cpu|.
fn rel_err(gpu: &Plane<f32>, cpu: &Plane<f32>) -> f32 {
    rel_err_to(gpu, cpu, peak(cpu))
}

/// max |gpu - cpu| / scale.
fn rel_err_to(gpu: &Plane<f32>, cpu: &Plane<f32>, scale: f32) -> f32 {
    assert_eq!(gpu.size(), cpu.size());
    let scale = scale.max(1e-12);
    let diff = gpu.as_slice().iter().zip(cpu.as_slice()).fold(0.0f32, |m, (a, b)| m.max((a - b).abs()));
    diff / scale
}

fn compare(name: &str, w: usize, h: usize) {
    let frame = photo(name, w, h);
    let mut cpu = SaliencyEngine::new(SaliencyConfig::ace2009(), w, h).unwrap();
    let cpu_map = cpu.process(&RgbImage::U8(frame.clone())).unwrap().clone();
    let mut gpu = GpuSaliencyEngine::new(context(), SaliencyConfig::ace2009(), w, h).unwrap();
    let gpu_map = gpu.process(&frame).unwrap().clone();
    let front = gpu.front_end();
    for &l in cpu.used_levels() {
        for (k, src) in [Source::Intensity, Source::RedGreen, Source::BlueYellow].into_iter().enumerate() {
            let e = rel_err(&front.opponency[k][l], cpu.level(src, l).unwrap());
            assert!(e <= TOLERANCE, "{name} {w}x{h} level {l} {src:?}: {e}");
        }
        // The energies of one level on one scale, at least the level's intensity peak: at the
        // top levels (2x1, 1x1) an angle across a single row or pixel responds with rounding
        // noise only, and its own peak would measure that noise, not agreement.
        let scale = (0..4)
            .map(|a| peak(cpu.level(Source::Orientation(a), l).unwrap()))
            .fold(peak(cpu.level(Source::Intensity, l).unwrap()), f32::max);
        for a in 0..4 {
            let e = rel_err_to(&front.orientation[l][a], cpu.level(Source::Orientation(a), l).unwrap(), scale);
            assert!(e <= TOLERANCE, "{name} {w}x{h} level {l} angle {a}: {e}");
        }
    }
    let e = rel_err(&gpu_map, &cpu_map);
    assert!(e <= TOLERANCE, "{name} {w}x{h} saliency: {e}");
    // The same winner, so a robot looks at the same place whichever backend it runs.
    assert_eq!(gpu_map.argmax().map(|m| (m.0, m.1)), cpu_map.argmax().map(|m| (m.0, m.1)), "{name}");
}

#[test]
fn the_gpu_front_end_matches_the_cpu_at_640x480() {
    for name in ["astronaut.png", "chelsea.png", "coffee.png"] {
        compare(name, 640, 480);
    }
}

#[test]
fn odd_sizes_match_too() {
    // Odd sides exercise the truncated, renormalized border taps at every level.
    compare("camera.png", 517, 389);
    compare("chelsea.png", 256, 256);
}

#[test]
fn every_frame_is_computed_afresh() {
    let (w, h) = (384, 288);
    let mut gpu = GpuSaliencyEngine::new(context(), SaliencyConfig::ace2009(), w, h).unwrap();
    let mut cpu = SaliencyEngine::new(SaliencyConfig::ace2009(), w, h).unwrap();
    for name in ["coffee.png", "astronaut.png", "coffee.png"] {
        let frame = photo(name, w, h);
        let g = gpu.process(&frame).unwrap().clone();
        let c = cpu.process(&RgbImage::U8(frame)).unwrap();
        assert!(rel_err(&g, c) <= TOLERANCE, "{name}");
    }
}

#[test]
fn bad_input_gets_a_clear_error() {
    let mut gpu = GpuSaliencyEngine::new(context(), SaliencyConfig::ace2009(), 384, 288).unwrap();
    let e = gpu.process(&Plane::new(385, 288)).unwrap_err();
    assert!(matches!(e, GpuError::InvalidInput(_)) && e.to_string().contains("385x288"), "{e}");
    // The stb preset computes opponency at the input: not what the GPU front end does.
    let e = GpuSaliencyEngine::new(context(), SaliencyConfig::stb(), 384, 288).unwrap_err();
    assert!(matches!(e, GpuError::Unsupported(_)), "{e}");
    // Too small for the pyramid: the CPU engine's own error.
    let e = GpuSaliencyEngine::new(context(), SaliencyConfig::ace2009(), 100, 80).unwrap_err();
    assert!(matches!(e, GpuError::Attention(_)), "{e}");
}
