//! Every subcommand that reports a location uses the one pixel convention of
//! `ocellus_image` (pixel centres at integers): a small bright blob centred on an integer
//! pixel is reported there exactly by what works at pixel level (the log-polar gaze point),
//! and within half a map cell by what works on a coarse map (saliency, surprise, attend).
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

mod common;
use common::{ocellus, run, tmpdir};
use ocellus_image::Plane;
use std::path::Path;

/// The blob's centre: a pixel whose map cell (16 px at level 4) is not centred on it.
const BLOB: (usize, usize) = (203, 117);
const SIZE: (usize, usize) = (384, 288);
/// Half a level-4 cell, pixels.
const HALF_CELL: f64 = 8.0;

/// A dark frame with faint texture and, if `blob`, a Gaussian blob (sigma 1.5 px) at `at`.
fn frame(at: (usize, usize), blob: bool) -> Plane<[u8; 3]> {
    Plane::from_fn(SIZE.0, SIZE.1, |x, y| {
        let texture = 20.0 + 6.0 * (((x * 7 + y * 13) % 17) as f64 / 17.0);
        let (dx, dy) = (x as f64 - at.0 as f64, y as f64 - at.1 as f64);
        let b = if blob { 230.0 * (-(dx * dx + dy * dy) / (2.0 * 1.5 * 1.5)).exp() } else { 0.0 };
        [(texture + b).min(255.0) as u8; 3]
    })
}

fn write(p: &Path, img: &Plane<[u8; 3]>) {
    ocellus_io::write_png(p, img).unwrap();
}

fn near(x: f64, y: f64, what: &str) {
    let (ex, ey) = (x - BLOB.0 as f64, y - BLOB.1 as f64);
    assert!(ex.abs() <= HALF_CELL && ey.abs() <= HALF_CELL, "{what} at ({x}, {y}), blob at {BLOB:?}");
}

/// A sequence: blob-free frames, then the blob from frame 6 on.
fn sequence(dir: &Path) {
    std::fs::create_dir_all(dir).unwrap();
    for k in 0..10 {
        write(&dir.join(format!("{k:03}.png")), &frame(BLOB, k >= 6));
    }
}

#[test]
fn saliency_reports_the_blob_within_half_a_cell() {
    let d = tmpdir("loc-sal");
    write(&d.join("blob.png"), &frame(BLOB, true));
    let s = run(ocellus().args(["saliency", "--out"]).arg(d.join("out")).arg(d.join("blob.png")));
    let at = s.split("most salient at (").nth(1).and_then(|r| r.split(')').next()).expect("peak printed");
    let v: Vec<f64> = at.split(',').map(|t| t.trim().parse().unwrap()).collect();
    near(v[0], v[1], "saliency peak");
}

#[test]
fn surprise_and_attend_report_the_blob_within_half_a_cell() {
    let d = tmpdir("loc-seq");
    sequence(&d.join("frames"));
    run(ocellus().args(["surprise", "--out"]).arg(d.join("s")).arg(d.join("frames")));
    let csv = std::fs::read_to_string(d.join("s/surprise.csv")).unwrap();
    let row: Vec<&str> = csv.lines().find(|l| l.starts_with("6,")).expect("frame 6").split(',').collect();
    near(row[2].parse().unwrap(), row[3].parse().unwrap(), "surprise peak at the blob's onset");

    run(ocellus().args(["attend", "--out"]).arg(d.join("a")).arg(d.join("frames")));
    let ctx = std::fs::read_to_string(d.join("a/context.csv")).unwrap();
    let row: Vec<&str> = ctx.lines().find(|l| l.starts_with("9,")).expect("frame 9").split(',').collect();
    near(row[4].parse().unwrap(), row[5].parse().unwrap(), "fixation once the blob is there");
}

/// The log-polar map centred on the blob's pixel sees it symmetrically: its innermost ring
/// is nearly the same in every sector. Half a pixel off (the other convention), it is lopsided.
#[test]
fn logpolar_gaze_is_the_blobs_pixel_exactly() {
    let d = tmpdir("loc-lp");
    write(&d.join("blob.png"), &frame(BLOB, true));
    let spread = |fx: f64, name: &str| {
        let out = d.join(name);
        run(ocellus()
            .args(["logpolar", "--sectors", "16", "--fovea-radius", "3", "--fovea"])
            .arg(format!("{fx},{}", BLOB.1))
            .arg("--out")
            .arg(&out)
            .arg(d.join("blob.png")));
        let cortex = ocellus_io::read_image(out.join("cortex.png")).unwrap().to_u8();
        let ring: Vec<f64> = (0..cortex.width()).map(|x| cortex.get(x, 0)[0] as f64).collect();
        let (lo, hi) = ring.iter().fold((f64::MAX, f64::MIN), |(a, b), &v| (a.min(v), b.max(v)));
        hi - lo
    };
    let exact = spread(BLOB.0 as f64, "exact");
    let half_off = spread(BLOB.0 as f64 + 0.5, "half");
    // Bilinear reads of a round blob are not perfectly round: a few grey levels remain (7
    // when this was written, against 50 half a pixel off).
    assert!(exact <= 12.0, "innermost ring varies by {exact} grey levels around the blob's pixel");
    assert!(half_off > 4.0 * exact.max(1.0), "half a pixel off: {half_off} vs {exact}");
}
