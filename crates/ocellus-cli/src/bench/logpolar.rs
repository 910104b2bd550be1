//! `ocellus bench logpolar`: the log-polar map per 640x480 frame on one core.

use super::timing::median;
use anyhow::{Context, Result};
use ocellus_fovea::logpolar::{Fields, LogPolarConfig, LogPolarMap, Scratch};
use ocellus_fovea::register::{register, Mode, RegisterOptions};
use ocellus_fovea::vergence::{vergence, VergenceOptions, VergenceTracker};
use ocellus_image::{Backend, Plane};
use serde_json::json;
use std::time::Instant;

/// The built-in astronaut photo stretched to 640x480 (nearest pixel: the content only has
/// to be a real image; the timing does not depend on it).
fn frame() -> Result<Plane<[u8; 3]>> {
    let src = crate::assets::decode("astronaut.png")?.to_u8();
    let (w, h) = src.size();
    Ok(Plane::from_fn(640, 480, |x, y| src.get(x * w / 640, y * h / 480)))
}

/// Runs the benchmark: 128 log rings x 128 sectors (plus the fovea rings) about the centre.
pub fn run(json_out: bool, backend: Backend) -> Result<()> {
    let rgb = frame()?;
    let grey = rgb.map(|p| ((p[0] as u32 * 77 + p[1] as u32 * 150 + p[2] as u32 * 29 + 128) >> 8) as u8);
    let mut figures = serde_json::Map::new();
    figures.insert("backend".into(), json!(backend.name()));
    for (name, fields) in [("pyramid", Fields::Pyramid), ("area", Fields::Area)] {
        let cfg = LogPolarConfig { fields, backend, ..LogPolarConfig::for_image(640, 480) };
        let mut build = Vec::new();
        let mut map = None;
        for _ in 0..5 {
            let t = Instant::now();
            map = Some(LogPolarMap::new(&cfg, 640, 480)?);
            build.push(t.elapsed().as_secs_f64() * 1e3);
        }
        let map = map.context("no map")?;
        let mut scratch = Scratch::default();
        let (mut out, mut out_rgb) = (Plane::default(), <[Plane<f32>; 3]>::default());
        let (mut tg, mut tc) = (Vec::new(), Vec::new());
        for _ in 0..400 {
            let t = Instant::now();
            map.sample_grey_into(&grey, &mut scratch, &mut out)?;
            tg.push(t.elapsed().as_secs_f64() * 1e6);
            let t = Instant::now();
            map.sample_rgb_into(&rgb, &mut scratch, &mut out_rgb)?;
            tc.push(t.elapsed().as_secs_f64() * 1e6);
        }
        let suffix = if fields == Fields::Pyramid { String::new() } else { format!("_{name}") };
        figures.insert(format!("us_per_frame_grey_1thread{suffix}"), json!(median(&mut tg)));
        figures.insert(format!("us_per_frame_rgb_1thread{suffix}"), json!(median(&mut tc)));
        figures.insert(format!("ms_table_build{suffix}"), json!(median(&mut build)));
        figures.insert(format!("table_entries{suffix}"), json!(map.table_entries()));
        if fields == Fields::Pyramid {
            figures.insert("cells".into(), json!(map.rows() * map.sectors()));
            figures.insert("compression_ratio".into(), json!(map.compression_ratio()));
        }
    }
    // Registration of a 512x512 photo with a turned and scaled copy, and vergence over 65
    // disparities on a pair made by shifting it 20 px.
    let decoded = crate::assets::decode("astronaut.png")?;
    let (photo, a) = (decoded.to_luma8(), decoded.to_grey());
    let b = ocellus_fovea::register::warp_similarity(&a, 0.5, 1.3);
    for (key, mode) in [("ms_register_direct_512", Mode::Direct), ("ms_register_spectrum_512", Mode::Spectrum)] {
        let mut t = Vec::new();
        for _ in 0..5 {
            let s = Instant::now();
            register(&a, &b, &RegisterOptions { mode, ..Default::default() })?;
            t.push(s.elapsed().as_secs_f64() * 1e3);
        }
        figures.insert(key.into(), json!(median(&mut t)));
    }
    let (pw, ph) = photo.size();
    let right = Plane::from_fn(pw, ph, |x, y| photo.get((x + 20).min(pw - 1), y));
    let mut t = Vec::new();
    for _ in 0..20 {
        let s = Instant::now();
        vergence(&photo, &right, [300.0, 250.0], &VergenceOptions { backend, ..VergenceOptions::default() })?;
        t.push(s.elapsed().as_secs_f64() * 1e3);
    }
    figures.insert("ms_vergence_65_disparities".into(), json!(median(&mut t)));
    // Tracking: each frame searches 4 px around the last disparity (9 candidates).
    let mut tracker = VergenceTracker::new(VergenceOptions { backend, ..VergenceOptions::default() }, 4, 0.8)?;
    tracker.update(&photo, &right, [300.0, 250.0])?;
    let mut t = Vec::new();
    for _ in 0..20 {
        let s = Instant::now();
        tracker.update(&photo, &right, [300.0, 250.0])?;
        t.push(s.elapsed().as_secs_f64() * 1e3);
    }
    figures.insert("ms_vergence_tracked_frame".into(), json!(median(&mut t)));
    let v = serde_json::Value::Object(figures);
    if json_out {
        outln!("{v}");
    } else {
        outln!("log-polar benchmark, 640x480 -> 128 log rings (+ fovea) x 128 sectors, one thread, medians:");
        for (k, val) in v.as_object().into_iter().flatten() {
            outln!("  {k:<34} {:.4}", val.as_f64().unwrap_or(f64::NAN));
        }
    }
    Ok(())
}
