//! Saliency configuration from a preset name plus an optional TOML file of overrides.

use anyhow::{Context, Result};
use ocellus_attention::{overrides, SaliencyConfig};
use std::path::Path;

/// The preset `preset`, with the fields given in the TOML file `file` replaced.
///
/// The file uses the field names of `SaliencyConfig` (see `ocellus saliency --print-config`),
/// e.g. `map_level = 3` or `[gabor]\nsize = 15`. `[[channels]]` entries add to the preset's
/// channels (an entry of a kind the preset has replaces that one); with
/// `replace_channels = true` at the top of the file they replace the whole list
/// (`ocellus_attention::overrides`, the rule the Python package's `config=` follows too).
pub fn load(preset: &str, file: Option<&Path>) -> Result<SaliencyConfig> {
    let Some(file) = file else { return Ok(SaliencyConfig::preset(preset)?) };
    let text = std::fs::read_to_string(file).with_context(|| format!("cannot read config file {}", file.display()))?;
    let over: toml::Value = toml::from_str(&text).with_context(|| format!("{} is not valid TOML", file.display()))?;
    let over = serde_json::to_value(over).with_context(|| format!("{}: cannot read its values", file.display()))?;
    overrides::saliency_config(preset, over)
        .with_context(|| format!("{}: invalid saliency configuration", file.display()))
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

    /// The README's example adds a skin channel and keeps the preset's three; an entry of an
    /// existing kind changes that channel; `replace_channels` replaces the list.
    #[test]
    fn channels_add_unless_replaced_and_kernels_normalize() {
        use ocellus_attention::config::ChannelKind;
        let dir = std::env::temp_dir().join(format!("ocellus-cfg-ch-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("c.toml");
        let kinds = |c: &SaliencyConfig| c.channels.iter().map(|c| c.kind.clone()).collect::<Vec<_>>();
        let preset = SaliencyConfig::ace2009();
        std::fs::write(&f, "map_level = 4\n[gabor]\nsize = 15\n\n[[channels]]\nkind = \"skin\"\nweight = 0.5\n")
            .unwrap();
        let c = load("ace2009", Some(&f)).unwrap();
        let mut want = kinds(&preset);
        want.push(ChannelKind::Skin);
        assert_eq!(kinds(&c), want);
        assert_eq!(c.channels.last().unwrap().weight, 0.5);
        std::fs::write(&f, "[[channels]]\nkind = \"intensity\"\nweight = 2.0\n").unwrap();
        let c = load("ace2009", Some(&f)).unwrap();
        assert_eq!(kinds(&c), kinds(&preset));
        assert_eq!(c.channels.iter().find(|c| c.kind == ChannelKind::Intensity).unwrap().weight, 2.0);
        std::fs::write(&f, "replace_channels = true\n[[channels]]\nkind = \"skin\"\nweight = 1.0\n").unwrap();
        assert_eq!(kinds(&load("ace2009", Some(&f)).unwrap()), vec![ChannelKind::Skin]);
        std::fs::write(&f, "replace_channels = 3\n").unwrap();
        assert!(load("ace2009", Some(&f)).is_err());
        // Kernels from a file are normalized (the seed's integers), and at most 16 taps.
        std::fs::write(&f, "[pyramid]\ntaps = [1.0, 5.0, 10.0, 10.0, 5.0, 1.0]\norigin = 2\n").unwrap();
        assert_eq!(load("ace2009", Some(&f)).unwrap().pyramid, preset.pyramid);
        std::fs::write(&f, format!("[pyramid]\ntaps = [{}]\norigin = 8\n", vec!["1.0"; 17].join(", "))).unwrap();
        assert!(format!("{:#}", load("ace2009", Some(&f)).unwrap_err()).contains("16"));
        std::fs::write(&f, "[pyramid]\ntaps = [0.0, 0.0]\norigin = 0\n").unwrap();
        assert!(load("ace2009", Some(&f)).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
