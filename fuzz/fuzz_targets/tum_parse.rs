#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = ocellus_io::tum::parse(data, std::path::Path::new("fuzz.tum"));
});
