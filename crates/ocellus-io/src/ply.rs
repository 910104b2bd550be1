//! PLY point clouds (binary little-endian): x, y, z as float, red, green, blue as uchar.

use crate::{write_bytes, Result};
use std::path::Path;

/// Encodes coloured points as a binary PLY file.
pub fn encode(points: &[([f32; 3], [u8; 3])]) -> Vec<u8> {
    let header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment written by ocellus\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n",
        points.len()
    );
    let mut out = Vec::with_capacity(header.len() + points.len() * 15);
    out.extend_from_slice(header.as_bytes());
    for (p, c) in points {
        for v in p {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out.extend_from_slice(c);
    }
    out
}

/// Writes coloured points to a PLY file.
pub fn write(path: impl AsRef<Path>, points: &[([f32; 3], [u8; 3])]) -> Result<()> {
    write_bytes(path.as_ref(), &encode(points))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_and_payload() {
        let b = encode(&[([1.0, 2.0, 3.0], [4, 5, 6])]);
        let text = String::from_utf8_lossy(&b);
        assert!(text.starts_with("ply\nformat binary_little_endian 1.0\n") && text.contains("element vertex 1\n"));
        let body = &b[b.len() - 15..];
        assert_eq!(&body[..4], &1.0f32.to_le_bytes());
        assert_eq!(&body[12..], &[4, 5, 6]);
    }
}
