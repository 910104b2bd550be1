//! Fuzz target: `cargo fuzz run camera_file` (from `fuzz/`). Camera files as TOML and as
//! JSON: Ok or Err, never a panic; an accepted camera has finite values and positive focals.
#![no_main]
use libfuzzer_sys::fuzz_target;
use ocellus_geometry::camera_file::{parse_json, parse_toml};
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    for cam in [parse_toml(text, Path::new("fuzz.toml")), parse_json(text, Path::new("fuzz.json"))].into_iter().flatten() {
        let k = cam.intrinsics;
        assert!(k.fx > 0.0 && k.fy > 0.0 && k.cx.is_finite() && k.cy.is_finite());
    }
});
