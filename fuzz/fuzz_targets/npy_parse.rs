//! Fuzz target: `cargo fuzz run npy_parse` (from `fuzz/`). Any input must give Ok or Err, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let _ = ocellus_io::npy::parse(data, Path::new("fuzz.npy"));
});
