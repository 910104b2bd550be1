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
    // The winning cell and its centre in image pixels (pixel centres at integers).
    let peak = ocellus_image::location::peak(&map, (w, h)).ok_or("the saliency map is empty")?;
    let ((cx, cy), [px, py]) = (peak.cell, peak.pixel);
    println!("{}: {w}x{h}, map {mw}x{mh}", path.display());
    println!("most salient cell ({cx}, {cy}) = {:.4}, centred at ({px:.1}, {py:.1}) px in the image", peak.value);
    for (label, conspicuity) in engine.conspicuity_maps() {
        println!("  {label:<12} {:.4} at the peak", conspicuity.get(cx, cy));
    }
    let stages: Vec<String> =
        engine.timings().stages().iter().map(|(n, d)| format!("{n} {:.2}", d.as_secs_f64() * 1e3)).collect();
    println!("stage times, ms: {}", stages.join(", "));
    Ok(())
}
