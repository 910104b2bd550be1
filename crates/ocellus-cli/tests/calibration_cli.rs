//! `ocellus generate chessboard`, `calibrate chessboard|planar` and `undistort` as a user runs them.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

mod common;
use common::{ocellus, run, tmpdir};

use ocellus_geometry::chessboard::{find_chessboard, ChessboardOptions};
use std::path::Path;

fn camera(path: &Path) -> toml::Value {
    toml::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn grey(path: &Path) -> ocellus_image::Plane<f32> {
    ocellus_io::read_image(path).unwrap().to_grey()
}

/// Largest distance of the corners of any board row from their least-squares line, pixels.
fn worst_row_bend(corners: &[[f64; 2]], cols: usize) -> f64 {
    corners
        .chunks(cols)
        .map(|row| {
            let n = row.len() as f64;
            let (mx, my) = (row.iter().map(|p| p[0]).sum::<f64>() / n, row.iter().map(|p| p[1]).sum::<f64>() / n);
            let (sxx, sxy, syy) = row.iter().fold((0.0, 0.0, 0.0), |(a, b, c), p| {
                let (dx, dy) = (p[0] - mx, p[1] - my);
                (a + dx * dx, b + dx * dy, c + dy * dy)
            });
            // Direction of the line: main eigenvector of the scatter.
            let theta = 0.5 * (2.0 * sxy).atan2(sxx - syy);
            let (nx, ny) = (-theta.sin(), theta.cos());
            row.iter().map(|p| ((p[0] - mx) * nx + (p[1] - my) * ny).abs()).fold(0.0, f64::max)
        })
        .fold(0.0, f64::max)
}

#[test]
fn calibrate_chessboard_recovers_the_rendering_camera_and_undistort_straightens_rows() {
    let dir = tmpdir("board");
    let views = dir.join("views");
    run(ocellus().args(["generate", "chessboard", "--views", "8", "--seed", "4", "--out"]).arg(&views));
    let cal = dir.join("cal");
    let stdout = run(ocellus().args(["calibrate", "chessboard"]).arg(&views).arg("--out").arg(&cal));
    assert!(stdout.contains("views 8"), "{stdout}");
    for f in ["camera.toml", "calibration.json", "per_view_error.png", "corners/view_00.png"] {
        assert!(cal.join(f).is_file(), "{f} missing");
    }
    let (truth, est) = (camera(&views.join("camera_truth.toml")), camera(&cal.join("camera.toml")));
    for key in ["fx", "fy"] {
        let (t, e) = (truth["intrinsics"][key].as_float().unwrap(), est["intrinsics"][key].as_float().unwrap());
        assert!((t - e).abs() / t < 0.005, "{key}: truth {t}, calibrated {e}");
    }
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(cal.join("calibration.json")).unwrap()).unwrap();
    assert!(report["rms_px"].as_f64().unwrap() < 0.2, "{}", report["rms_px"]);
    assert!(report["std_dev"]["fx"].as_f64().unwrap() > 0.0);

    // Two calibrated views rebuild the board: their undistorted corners side by side,
    // triangulated with their projection matrices, land on the board's own grid (25 mm).
    let corners = |v: &str| std::fs::read_to_string(cal.join("views").join(format!("{v}.csv"))).unwrap();
    let (a, b) = (corners("view_00"), corners("view_05"));
    let matches: String = a.lines().zip(b.lines()).map(|(x, y)| format!("{x},{y}\n")).collect();
    std::fs::write(dir.join("matches.csv"), matches).unwrap();
    let board = std::fs::read_to_string(cal.join("board.csv")).unwrap();
    assert_eq!(board.lines().count(), 55, "a header and 9 x 6 corners");
    assert!(board.lines().nth(2).unwrap().starts_with("25,0,0"), "{board}");
    let t = run(ocellus()
        .arg("triangulate")
        .arg("--camera")
        .arg(cal.join("views/view_00.json"))
        .arg("--camera")
        .arg(cal.join("views/view_05.json"))
        .arg(dir.join("matches.csv"))
        .arg("--truth")
        .arg(cal.join("board.csv"))
        .arg("--out")
        .arg(dir.join("board_points.csv")));
    let rms: f64 = t.split("against the truth: ").nth(1).unwrap().split_whitespace().next().unwrap().parse().unwrap();
    assert!(rms < 0.5, "board rebuilt within {rms} mm: {t}");

    // The exact corners through `calibrate planar` give the camera exactly.
    let planar = dir.join("planar");
    run(ocellus().args(["calibrate", "planar"]).arg(views.join("corners_truth.csv")).arg("--out").arg(&planar));
    let exact = camera(&planar.join("camera.toml"));
    assert!((exact["distortion"]["k1"].as_float().unwrap() + 0.22).abs() < 1e-6, "{exact}");

    // Undistortion with the calibrated camera makes the board's rows straight.
    let und = dir.join("und");
    run(ocellus()
        .arg("undistort")
        .arg(views.join("view_00.png"))
        .arg("--camera")
        .arg(cal.join("camera.toml"))
        .arg("--out")
        .arg(&und));
    let opts = ChessboardOptions::default();
    let before = find_chessboard(&grey(&views.join("view_00.png")), 9, 6, &opts).unwrap();
    let after = find_chessboard(&grey(&und.join("view_00.png")), 9, 6, &opts).unwrap();
    let (b, a) = (worst_row_bend(&before, 9), worst_row_bend(&after, 9));
    println!("row bend: distorted {b:.3} px, undistorted {a:.3} px");
    assert!(a < 0.3 && b > 3.0 * a, "row bend before {b}, after {a}");
}

#[test]
fn calibration_errors_are_clear() {
    let dir = tmpdir("errors");
    let views = dir.join("views");
    run(ocellus().args(["generate", "chessboard", "--views", "2", "--out"]).arg(&views));
    let o = ocellus().args(["calibrate", "chessboard"]).arg(&views).arg("--out").arg(dir.join("c")).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("at least 3"), "{err}");
    // A board of the wrong size is not found, and says so per image.
    let o = ocellus()
        .args(["calibrate", "chessboard", "--board", "7x5"])
        .arg(&views)
        .arg("--out")
        .arg(dir.join("c"))
        .output()
        .unwrap();
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stdout).contains("not found"));
    let o = ocellus().args(["calibrate", "chessboard", "--square", "25 furlongs"]).arg(&views).output().unwrap();
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("length"));
    let o = ocellus()
        .args(["undistort", "--camera"])
        .arg(views.join("missing.toml"))
        .arg(views.join("view_00.png"))
        .output()
        .unwrap();
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("missing.toml"));
}
