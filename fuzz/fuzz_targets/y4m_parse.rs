//! Fuzz target: `cargo fuzz run y4m_parse` (from `fuzz/`). Any input must give frames or an error, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(mut r) = ocellus_io::y4m::Y4mReader::new(data, Path::new("fuzz.y4m")) {
        // Bounded: a header may promise huge frames, the data is what it is.
        for _ in 0..4 {
            match r.next_frame() {
                Ok(Some(_)) => {}
                _ => break,
            }
        }
    }
});
