//! The saliency map of a photograph and where it peaks.
//!
//! `cargo run --release -p ocellus-attention --example saliency_peak [IMAGE]`
//! (default: the built-in astronaut). Prints the map size, the most salient point in input
//! pixels and each channel's share of the saliency there.

use ocellus_attention::{SaliencyConfig, SaliencyEngine};
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args().nth(1).map(PathBuf::from).unwrap_or_else(|| ocellus_testdata::asset("astronaut.png"));
    let image = ocellus_io::read_image(&path)?;
    let (w, h) = image.size();
    // The seed's parameters; `SaliencyConfig::stb()` gives the SaliencyToolbox's.
    let mut engine = SaliencyEngine::new(SaliencyConfig::ace2009(), w, h)?;
    let map = engine.process(&image)?.clone();
    let (mw, mh) = map.size();
    let (cx, cy, peak) = map.argmax().ok_or("the saliency map is empty")?;
    // A map cell covers w / mw x h / mh input pixels; report its centre.
    let (px, py) = ((cx as f32 + 0.5) * w as f32 / mw as f32, (cy as f32 + 0.5) * h as f32 / mh as f32);
    println!("{}: {w}x{h}, map {mw}x{mh}", path.display());
    println!("most salient cell ({cx}, {cy}) = {peak:.4}, about ({px:.0}, {py:.0}) px in the image");
    for (label, conspicuity) in engine.conspicuity_maps() {
        println!("  {label:<12} {:.4} at the peak", conspicuity.get(cx, cy));
    }
    let stages: Vec<String> =
        engine.timings().stages().iter().map(|(n, d)| format!("{n} {:.2}", d.as_secs_f64() * 1e3)).collect();
    println!("stage times, ms: {}", stages.join(", "));
    Ok(())
}
