//! Fuzz target: `cargo fuzz run decode_image` (from `fuzz/`). Any input must give Ok or Err, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    // A small pixel limit keeps the fuzzer's memory bounded; the limit itself is under test.
    if let Ok(img) = ocellus_io::decode_image_within(data, Path::new("fuzz.img"), 1 << 22) {
        let (w, h) = img.size();
        assert!(w * h <= 1 << 22 && w > 0 && h > 0);
    }
});
