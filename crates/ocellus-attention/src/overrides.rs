//! A configuration from a preset and a tree of overrides: what a TOML file (`ocellus saliency
//! --config`), a JSON document or a Python dict (`ocellus.saliency(config=...)`) changes, one
//! rule for all of them.

use crate::config::SaliencyConfig;
use crate::{AttentionError, Result};
use serde_json::Value;

/// Deep-merges `over` into `base`: objects merge key by key, any other value replaces.
pub fn merge(base: &mut Value, over: Value) {
    match (base, over) {
        (Value::Object(b), Value::Object(o)) => {
            for (k, v) in o {
                match b.get_mut(&k) {
                    Some(slot) if slot.is_object() && v.is_object() => merge(slot, v),
                    _ => {
                        b.insert(k, v);
                    }
                }
            }
        }
        (b, o) => *b = o,
    }
}

/// Moves the `channels` of `over` into `base`'s list: an entry of a kind the list has replaces
/// that channel (to change its weight), any other is appended.
fn merge_channels(base: &mut Value, over: &mut Value) {
    let Some(new) = over.as_object_mut().and_then(|t| t.remove("channels")) else { return };
    let Some(list) = base.get_mut("channels").and_then(Value::as_array_mut) else { return };
    for entry in new.as_array().cloned().unwrap_or_default() {
        match list.iter_mut().find(|c| c.get("kind").is_some() && c.get("kind") == entry.get("kind")) {
            Some(existing) => *existing = entry,
            None => list.push(entry),
        }
    }
}

/// The preset `preset` with the fields of `overrides` replaced (field names of
/// [`SaliencyConfig`], nested tables merged key by key). `channels` entries add to the preset's
/// channels, an entry of a kind the preset has replacing that one; with `replace_channels:
/// true` at the top they replace the whole list. The result is validated.
pub fn saliency_config(preset: &str, overrides: Value) -> Result<SaliencyConfig> {
    let base = SaliencyConfig::preset(preset)?;
    let mut over = overrides;
    if over.is_null() {
        return Ok(base);
    }
    if !over.is_object() {
        return Err(AttentionError::InvalidConfig(format!("overrides must be a table of fields, not {over}")));
    }
    let replace = match over.as_object_mut().and_then(|t| t.remove("replace_channels")) {
        None => false,
        Some(Value::Bool(b)) => b,
        Some(v) => {
            return Err(AttentionError::InvalidConfig(format!("replace_channels must be true or false, not {v}")))
        }
    };
    let mut value = serde_json::to_value(&base).map_err(|e| AttentionError::InvalidConfig(e.to_string()))?;
    if !replace {
        merge_channels(&mut value, &mut over);
    }
    merge(&mut value, over);
    let cfg: SaliencyConfig =
        serde_json::from_value(value).map_err(|e| AttentionError::InvalidConfig(e.to_string()))?;
    cfg.validate()?;
    Ok(cfg)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::ChannelKind;
    use serde_json::json;

    #[test]
    fn fields_merge_channels_add_and_bad_overrides_are_named() {
        let c = saliency_config("stb", json!({"map_level": 3, "gabor": {"size": 15}})).unwrap();
        assert_eq!((c.map_level, c.gabor.size), (3, 15));
        assert_eq!(c.gabor.sigma_px, SaliencyConfig::stb().gabor.sigma_px);
        assert_eq!(saliency_config("ace2009", Value::Null).unwrap(), SaliencyConfig::ace2009());
        // A skin channel adds to the three; the intensity entry changes that channel's weight.
        let over = json!({"channels": [{"kind": "skin", "weight": 0.5}, {"kind": "intensity", "weight": 2.0}]});
        let c = saliency_config("ace2009", over.clone()).unwrap();
        assert_eq!(c.channels.len(), 4);
        assert_eq!(c.channels[0].weight, 2.0);
        assert_eq!(c.channels[3].kind, ChannelKind::Skin);
        let mut replaced = over;
        replaced["replace_channels"] = json!(true);
        assert_eq!(saliency_config("ace2009", replaced).unwrap().channels.len(), 2);
        for (bad, named) in [
            (json!({"map_levle": 3}), "map_levle"),
            (json!({"gabor": {"siz": 15}}), "siz"),
            (json!({"gabor": {"size": 16}}), "size"),
            (json!({"replace_channels": 1}), "replace_channels"),
            (json!([1, 2]), "table"),
        ] {
            let e = saliency_config("ace2009", bad).unwrap_err().to_string();
            assert!(e.contains(named), "{e}");
        }
        assert!(saliency_config("nope", Value::Null).is_err());
    }
}
