//! Fuzz target: `cargo fuzz run saliency_config` (from `fuzz/`). A `--config` TOML file:
//! parsing and validation give Ok or Err, never a panic; an accepted configuration survives
//! a round trip through its own TOML.
#![no_main]
use libfuzzer_sys::fuzz_target;
use ocellus_attention::SaliencyConfig;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let Ok(cfg) = toml::from_str::<SaliencyConfig>(text) else { return };
    if cfg.validate().is_ok() {
        if let Ok(back) = toml::to_string(&cfg) {
            let again: SaliencyConfig = toml::from_str(&back).expect("a written configuration reads back");
            assert!(again.validate().is_ok());
        }
    }
});
