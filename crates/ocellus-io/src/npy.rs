//! NumPy `.npy` files (format version 1.0 and 2.0).
//!
//! Reads little-endian `f4`/`f8` arrays in C or Fortran order; returns the values in C
//! (row-major) order with the shape. Writes `<f4` arrays in C order.

use crate::{read_bytes, write_bytes, IoError, Result};
use std::path::Path;

/// An n-dimensional array in C order.
#[derive(Debug, Clone, PartialEq)]
pub struct NpyArray {
    /// Dimensions, outermost first.
    pub shape: Vec<usize>,
    /// Values in C order (last index fastest).
    pub data: Vec<f64>,
}

fn header_field<'a>(header: &'a str, key: &str) -> Option<&'a str> {
    let i = header.find(&format!("'{key}'"))?;
    let rest = &header[i + key.len() + 2..];
    let rest = rest.trim_start().strip_prefix(':')?.trim_start();
    Some(rest)
}

/// Parses `.npy` bytes; `path` is only used in error messages.
pub fn parse(bytes: &[u8], path: &Path) -> Result<NpyArray> {
    let bad =
        |reason: &str| IoError::Invalid { path: path.into(), reason: format!("not a readable .npy file: {reason}") };
    if bytes.len() < 10 || &bytes[..6] != b"\x93NUMPY" {
        return Err(bad("missing magic"));
    }
    let (hlen, hstart) = match bytes[6] {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        2 | 3 if bytes.len() >= 12 => (u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize, 12),
        v => return Err(bad(&format!("format version {v}"))),
    };
    let header = bytes.get(hstart..hstart + hlen).ok_or_else(|| bad("truncated header"))?;
    let header = std::str::from_utf8(header).map_err(|_| bad("header is not text"))?;
    let descr = header_field(header, "descr").ok_or_else(|| bad("no descr"))?;
    let (size, is_f8) = if descr.starts_with("'<f8'") {
        (8, true)
    } else if descr.starts_with("'<f4'") {
        (4, false)
    } else {
        return Err(bad(&format!("dtype {} (only <f4 and <f8)", descr.split(',').next().unwrap_or(""))));
    };
    let fortran = header_field(header, "fortran_order").ok_or_else(|| bad("no fortran_order"))?.starts_with("True");
    let shape_s = header_field(header, "shape").ok_or_else(|| bad("no shape"))?;
    let shape_s = shape_s.strip_prefix('(').and_then(|s| s.split(')').next()).ok_or_else(|| bad("bad shape"))?;
    let shape: Vec<usize> = shape_s
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.parse::<usize>().map_err(|_| bad("bad shape")))
        .collect::<Result<_>>()?;
    // A hostile header can promise more values than any file holds: count without overflow.
    let n = shape.iter().try_fold(1usize, |acc, &d| acc.checked_mul(d)).ok_or_else(|| bad("shape overflows"))?;
    let body = &bytes[hstart + hlen..];
    if n.checked_mul(size).is_none_or(|b| body.len() < b) {
        return Err(bad(&format!("{} data bytes for {n} values", body.len())));
    }
    let raw: Vec<f64> = (0..n)
        .map(|i| {
            let b = &body[i * size..(i + 1) * size];
            if is_f8 {
                f64::from_le_bytes(b.try_into().unwrap_or([0; 8]))
            } else {
                f32::from_le_bytes(b.try_into().unwrap_or([0; 4])) as f64
            }
        })
        .collect();
    let data = if fortran && shape.len() > 1 {
        // Fortran order: first index fastest. Reorder to C order.
        let mut out = vec![0.0; n];
        let nd = shape.len();
        let mut idx = vec![0usize; nd];
        for v in &raw {
            let mut c = 0;
            for d in 0..nd {
                c = c * shape[d] + idx[d];
            }
            out[c] = *v;
            for d in 0..nd {
                idx[d] += 1;
                if idx[d] < shape[d] {
                    break;
                }
                idx[d] = 0;
            }
        }
        out
    } else {
        raw
    };
    Ok(NpyArray { shape, data })
}

/// Reads a `.npy` file.
pub fn read(path: impl AsRef<Path>) -> Result<NpyArray> {
    let path = path.as_ref();
    parse(&read_bytes(path)?, path)
}

/// Encodes `data` (C order) with `shape` as `<f4` `.npy` bytes.
pub fn encode_f32(shape: &[usize], data: &[f32]) -> Vec<u8> {
    encode("<f4", shape, data.len() * 4, data.iter().flat_map(|v| v.to_le_bytes()))
}

/// Encodes `data` (C order) with `shape` as `<f8` `.npy` bytes (exact f64, for state that
/// must be restored bit for bit).
pub fn encode_f64(shape: &[usize], data: &[f64]) -> Vec<u8> {
    encode("<f8", shape, data.len() * 8, data.iter().flat_map(|v| v.to_le_bytes()))
}

/// Writes `data` (C order) with `shape` as an `<f4` `.npy` file.
pub fn write_f32(path: impl AsRef<Path>, shape: &[usize], data: &[f32]) -> Result<()> {
    write_bytes(path.as_ref(), &encode_f32(shape, data))
}

/// Writes `data` (C order) with `shape` as an `<f8` `.npy` file.
pub fn write_f64(path: impl AsRef<Path>, shape: &[usize], data: &[f64]) -> Result<()> {
    write_bytes(path.as_ref(), &encode_f64(shape, data))
}

fn encode(descr: &str, shape: &[usize], bytes: usize, data: impl Iterator<Item = u8>) -> Vec<u8> {
    let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
    let shape_s = if dims.len() == 1 { format!("({},)", dims[0]) } else { format!("({})", dims.join(", ")) };
    let mut header = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape_s}, }}");
    // Pad so that the data starts on a 64-byte boundary; the header ends with '\n'.
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut out = Vec::with_capacity(10 + header.len() + bytes);
    out.extend_from_slice(b"\x93NUMPY\x01\x00");
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    out.extend(data);
    out
}

/// Writes a 2D f32 map (rows x columns) as `.npy`.
pub fn write_plane(path: impl AsRef<Path>, plane: &ocellus_image::Plane<f32>) -> Result<()> {
    write_bytes(path.as_ref(), &encode_f32(&[plane.height(), plane.width()], &plane.to_vec()))
}
