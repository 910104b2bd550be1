//! Portable Float Map, one channel (`Pf`), little-endian, rows stored bottom-up.

use crate::{read_bytes, write_bytes, IoError, Result};
use ocellus_image::Plane;
use std::path::Path;

/// Encodes a map as PFM bytes (scale -1.0: little-endian).
pub fn encode(plane: &Plane<f32>) -> Vec<u8> {
    let mut out = format!("Pf\n{} {}\n-1.0\n", plane.width(), plane.height()).into_bytes();
    for y in (0..plane.height()).rev() {
        for v in plane.row(y) {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
}

/// Writes a map as a PFM file.
pub fn write(path: impl AsRef<Path>, plane: &Plane<f32>) -> Result<()> {
    write_bytes(path.as_ref(), &encode(plane))
}

/// Parses PFM bytes (one channel); `path` is only used in error messages.
pub fn parse(bytes: &[u8], path: &Path) -> Result<Plane<f32>> {
    let bad = |r: &str| IoError::Invalid { path: path.into(), reason: format!("not a readable PFM file: {r}") };
    // Three whitespace-separated header tokens, then one whitespace byte, then data.
    let mut tokens = Vec::new();
    let mut i = 0;
    while tokens.len() < 4 && i < bytes.len() {
        while i < bytes.len() && bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        let s = i;
        while i < bytes.len() && !bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        tokens.push(std::str::from_utf8(&bytes[s..i]).map_err(|_| bad("header is not text"))?.to_string());
    }
    if tokens.len() < 4 || tokens[0] != "Pf" {
        return Err(bad("expected a 'Pf' header"));
    }
    let w: usize = tokens[1].parse().map_err(|_| bad("bad width"))?;
    let h: usize = tokens[2].parse().map_err(|_| bad("bad height"))?;
    let scale: f32 = tokens[3].parse().map_err(|_| bad("bad scale"))?;
    let start = i + 1;
    let end = w.checked_mul(h).and_then(|n| n.checked_mul(4)).and_then(|b| b.checked_add(start));
    let end = end.ok_or_else(|| bad("size overflows"))?;
    let body = bytes.get(start..end).ok_or_else(|| bad("truncated data"))?;
    let le = scale < 0.0;
    let mut p = Plane::new(w, h);
    for (k, c) in body.chunks_exact(4).enumerate() {
        let b: [u8; 4] = c.try_into().unwrap_or([0; 4]);
        let v = if le { f32::from_le_bytes(b) } else { f32::from_be_bytes(b) };
        p.set(k % w, h - 1 - k / w, v);
    }
    Ok(p)
}

/// Reads a one-channel PFM file.
pub fn read(path: impl AsRef<Path>) -> Result<Plane<f32>> {
    let path = path.as_ref();
    parse(&read_bytes(path)?, path)
}
