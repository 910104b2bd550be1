//! Fuzz target: `cargo fuzz run decode_image` (from `fuzz/`). Any input must give Ok or Err, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let _ = ocellus_io::decode_image(data, Path::new("fuzz.img"));
});
