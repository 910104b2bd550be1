//! Saliency configuration from a preset name plus an optional TOML file of overrides.

use anyhow::{Context, Result};
use ocellus_attention::SaliencyConfig;
use std::path::Path;

/// Deep-merges `over` into `base` (tables merge key by key; other values replace).
fn merge(base: &mut toml::Value, over: toml::Value) {
    match (base, over) {
        (toml::Value::Table(b), toml::Value::Table(o)) => {
            for (k, v) in o {
                match b.get_mut(&k) {
                    Some(bv) if bv.is_table() && v.is_table() => merge(bv, v),
                    _ => {
                        b.insert(k, v);
                    }
                }
            }
        }
        (b, o) => *b = o,
    }
}

/// The preset `preset`, with the fields given in the TOML file `file` replaced.
///
/// The file uses the field names of `SaliencyConfig` (see `ocellus saliency --print-config`),
/// e.g. `map_level = 3` or `[gabor]\nsize = 15`.
pub fn load(preset: &str, file: Option<&Path>) -> Result<SaliencyConfig> {
    let base = SaliencyConfig::preset(preset)?;
    let Some(file) = file else { return Ok(base) };
    let text = std::fs::read_to_string(file).with_context(|| format!("cannot read config file {}", file.display()))?;
    let over: toml::Value = toml::from_str(&text).with_context(|| format!("{} is not valid TOML", file.display()))?;
    let mut value = toml::Value::try_from(&base).context("cannot serialize preset")?;
    merge(&mut value, over);
    let cfg: SaliencyConfig =
        value.try_into().with_context(|| format!("{}: invalid saliency configuration", file.display()))?;
    cfg.validate()?;
    Ok(cfg)
}

/// The configuration as TOML text.
pub fn to_toml(cfg: &SaliencyConfig) -> Result<String> {
    Ok(toml::to_string_pretty(cfg)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn toml_round_trip_and_override() {
        for p in SaliencyConfig::PRESETS {
            let c = SaliencyConfig::preset(p).unwrap();
            let back: SaliencyConfig = toml::from_str(&to_toml(&c).unwrap()).unwrap();
            assert_eq!(back, c);
        }
        let dir = std::env::temp_dir().join(format!("ocellus-cfg-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("o.toml");
        std::fs::write(&f, "map_level = 3\n[gabor]\nsize = 15\n").unwrap();
        let c = load("stb", Some(&f)).unwrap();
        assert_eq!(c.map_level, 3);
        assert_eq!(c.gabor.size, 15);
        assert_eq!(c.gabor.sigma_px, SaliencyConfig::stb().gabor.sigma_px);
        std::fs::write(&f, "[gabor]\nsize = 16\n").unwrap();
        assert!(load("stb", Some(&f)).is_err(), "even Gabor size must be rejected");
        std::fs::write(&f, "no_such_field = [").unwrap();
        assert!(load("stb", Some(&f)).is_err());
        // A misspelt key is named, at the top level and inside a table.
        for (text, key) in [
            ("map_levle = 3\n", "map_levle"),
            ("[gabor]\nsiz = 15\n", "siz"),
            ("[normalization]\nkind = \"iterative\"\niteratons = 2\n", "iteratons"),
        ] {
            std::fs::write(&f, text).unwrap();
            let e = format!("{:#}", load("ace2009", Some(&f)).unwrap_err());
            assert!(e.contains(key), "{text}: {e}");
        }
        assert!(load("nope", None).is_err());
    }
}
