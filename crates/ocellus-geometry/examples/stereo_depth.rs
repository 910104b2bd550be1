//! Dense depth of the Middlebury motorcycle pair: semi-global matching, the error against the
//! ground-truth disparity, and the depth at a few pixels with the pair's calibration.
//!
//! `cargo run --release -p ocellus-geometry --example stereo_depth`

use ocellus_geometry::block_matching::bad_pixels;
use ocellus_geometry::sgm::{sgm, Sgm};
use ocellus_geometry::stereo::ParallelStereo;
use ocellus_testdata::data_file;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let left = ocellus_io::read_image(data_file("motorcycle_left.png"))?.to_luma8();
    let right = ocellus_io::read_image(data_file("motorcycle_right.png"))?.to_luma8();
    let truth = ocellus_io::pfm::read(data_file("motorcycle_disp.pfm"))?;
    // Census 9x7 costs along 8 paths, disparities 0..64, left-right checked; NaN where invalid.
    let t = std::time::Instant::now();
    let disparity = sgm(&left, &right, &Sgm::default())?;
    let ms = t.elapsed().as_secs_f64() * 1e3;
    let (bad, density) = bad_pixels(&disparity, &truth, 2.0)?;
    println!(
        "SGM {}x{}: {ms:.0} ms, bad-2.0 {:.1} %, density {:.1} %",
        left.width(),
        left.height(),
        bad * 100.0,
        density * 100.0
    );
    // The pair's calibration (testdata/LICENSES.md): Z = b f / (d + doffs), millimetres.
    let rig = ParallelStereo { baseline: 193.001, focal_px: 994.978 };
    let (cx, cy, doffs) = (311.193, 254.877, 31.086);
    for (x, y) in [(150, 250), (400, 250), (600, 120)] {
        let d = disparity.get(x, y);
        if d.is_nan() {
            println!("({x}, {y}): no disparity (occluded or not unique)");
            continue;
        }
        let p = rig.point(x as f64, y as f64, d as f64 + doffs, cx, cy)?;
        println!("({x}, {y}): disparity {d:.2} px, point ({:.0}, {:.0}, {:.0}) mm", p[0], p[1], p[2]);
    }
    Ok(())
}
