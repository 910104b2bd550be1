//! Fuzz target: `cargo fuzz run points_parse` (from `fuzz/`). Any input must give Ok or Err, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(points) = ocellus_io::points::parse(data, Path::new("fuzz.csv")) {
        let _ = ocellus_io::points::to_pixels(&points, 64, 48);
    }
});
