//! Trajectories in the TUM RGB-D format: one pose per line,
//! `timestamp tx ty tz qx qy qz qw` (seconds, metres, unit quaternion of the body-to-world
//! rotation), `#` comments allowed. Read by evo, rpg_trajectory_evaluation and the TUM tools.

use crate::csv::parse_rows;
use crate::{read_bytes, IoError, Result};
use std::io::Write;
use std::path::Path;

/// One timestamped pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TumPose {
    /// Time, seconds.
    pub time_s: f64,
    /// Position, metres.
    pub position: [f64; 3],
    /// Orientation quaternion (x, y, z, w), unit norm.
    pub quaternion: [f64; 4],
}

impl TumPose {
    /// A planar pose: position (x, y, 0) and a rotation by `yaw_rad` about +z.
    pub fn planar(time_s: f64, x: f64, y: f64, yaw_rad: f64) -> Self {
        let (s, c) = (0.5 * yaw_rad).sin_cos();
        Self { time_s, position: [x, y, 0.0], quaternion: [0.0, 0.0, s, c] }
    }

    /// The rotation angle about +z (radians, in (-pi, pi]) of the orientation, for planar
    /// trajectories.
    pub fn yaw(&self) -> f64 {
        let [x, y, z, w] = self.quaternion;
        (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z))
    }
}

/// Parses TUM text; `path` only names the source in errors.
pub fn parse(bytes: &[u8], path: &Path) -> Result<Vec<TumPose>> {
    let rows = parse_rows(bytes, path, 8, "'timestamp tx ty tz qx qy qz qw'")?;
    if rows.is_empty() {
        return Err(IoError::Invalid {
            path: path.into(),
            reason: "no poses (lines 'timestamp tx ty tz qx qy qz qw')".into(),
        });
    }
    // Evaluation pairs poses by time: a repeated or backward timestamp would silently drop
    // poses (and score what is left), so the order is part of the format here.
    for (i, w) in rows.windows(2).enumerate() {
        if w[1][0] <= w[0][0] {
            return Err(IoError::Invalid {
                path: path.into(),
                reason: format!(
                    "pose {}: timestamp {} does not increase (pose {} has {}); timestamps must be strictly increasing",
                    i + 2,
                    w[1][0],
                    i + 1,
                    w[0][0]
                ),
            });
        }
    }
    rows.iter()
        .enumerate()
        .map(|(i, r)| {
            let q = [r[4], r[5], r[6], r[7]];
            let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
            if !(n > 0.5 && n < 1.5) {
                return Err(IoError::Invalid {
                    path: path.into(),
                    reason: format!("pose {}: quaternion norm {n} is not 1", i + 1),
                });
            }
            Ok(TumPose { time_s: r[0], position: [r[1], r[2], r[3]], quaternion: q.map(|v| v / n) })
        })
        .collect()
}

/// Reads a TUM trajectory file.
pub fn read(path: impl AsRef<Path>) -> Result<Vec<TumPose>> {
    let path = path.as_ref();
    parse(&read_bytes(path)?, path)
}

/// Writes a TUM trajectory file (a comment line, then one pose per line).
pub fn write(path: impl AsRef<Path>, poses: &[TumPose]) -> Result<()> {
    let path = path.as_ref();
    let io = |e: std::io::Error| IoError::Io { path: path.into(), source: e };
    let mut f = std::io::BufWriter::new(std::fs::File::create(path).map_err(io)?);
    writeln!(f, "# timestamp tx ty tz qx qy qz qw").map_err(io)?;
    for p in poses {
        let [x, y, z] = p.position;
        let [qx, qy, qz, qw] = p.quaternion;
        writeln!(f, "{:.6} {x:.9} {y:.9} {z:.9} {qx:.9} {qy:.9} {qz:.9} {qw:.9}", p.time_s).map_err(io)?;
    }
    f.flush().map_err(io)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_yaw() {
        let dir = std::env::temp_dir().join(format!("ocellus-tum-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let poses: Vec<TumPose> =
            (0..5).map(|k| TumPose::planar(k as f64 * 0.005, 0.1 * k as f64, -0.02, 0.3 * k as f64 - 0.5)).collect();
        write(dir.join("t.tum"), &poses).unwrap();
        let back = read(dir.join("t.tum")).unwrap();
        for (a, b) in poses.iter().zip(&back) {
            assert!((a.yaw() - b.yaw()).abs() < 1e-8 && (a.position[0] - b.position[0]).abs() < 1e-9);
        }
        assert!((TumPose::planar(0.0, 0.0, 0.0, 3.0).yaw() - 3.0).abs() < 1e-12);
        assert!(parse(b"0 0 0 0 0 0 0 0\n", Path::new("x")).is_err());
        assert!(parse(b"0 1 2 3 0 0 0\n", Path::new("x")).is_err());
        // Repeated and backward timestamps are refused, naming the pose.
        let e = parse(b"0 0 0 0 0 0 0 1\n0.1 0 0 0 0 0 0 1\n0.1 1 0 0 0 0 0 1\n", Path::new("x")).unwrap_err();
        assert!(e.to_string().contains("pose 3"), "{e}");
        assert!(parse(b"1 0 0 0 0 0 0 1\n0.5 0 0 0 0 0 0 1\n", Path::new("x")).is_err());
    }
}
