//! Fuzz target: `cargo fuzz run csv_rows` (from `fuzz/`). The first byte picks the column
//! count (1..=16); any input must give rows of exactly that many finite numbers, or an error.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Some((&first, rest)) = data.split_first() else { return };
    let columns = usize::from(first % 16) + 1;
    if let Ok(rows) = ocellus_io::csv::parse_rows(rest, Path::new("fuzz.csv"), columns, "numbers") {
        assert!(rows.iter().all(|r| r.len() == columns && r.iter().all(|v| v.is_finite())));
    }
});
