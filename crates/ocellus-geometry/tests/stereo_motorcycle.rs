//! Block matching on the real Middlebury 2014 "Motorcycle" pair (quarter size) against its
//! ground truth.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

use ocellus_geometry::block_matching::{bad_pixels, block_match, BlockMatching};
use ocellus_image::Plane;
use ocellus_testdata::data_file;

fn grey(name: &str) -> Plane<u8> {
    ocellus_io::read_image(data_file(name)).unwrap().to_luma8()
}

#[test]
fn motorcycle_bad2_and_density() {
    let (l, r) = (grey("motorcycle_left.png"), grey("motorcycle_right.png"));
    let truth = ocellus_io::pfm::read(data_file("motorcycle_disp.pfm")).unwrap();
    assert_eq!(truth.size(), l.size());
    let p = BlockMatching::default();
    let t = std::time::Instant::now();
    let est = block_match(&l, &r, &p).unwrap();
    let ms = t.elapsed().as_secs_f64() * 1e3;
    let (bad, density) = bad_pixels(&est, &truth, 2.0).unwrap();
    println!(
        "motorcycle BM ({}x{}, {} disparities, block {}): bad-2.0 {:.1} %, density {:.1} %, {ms:.1} ms (test build)",
        l.width(),
        l.height(),
        p.max_disparity,
        p.block,
        bad * 100.0,
        density * 100.0
    );
    // cv2.StereoBM (block 15) scores 27.0 % here (issue 6); ours must not be worse.
    assert!(bad < 0.27, "bad-2.0 {bad}");
    assert!(density > 0.6, "density {density}");
}

#[test]
fn motorcycle_sgm_bad2_and_density() {
    use ocellus_geometry::sgm::{sgm, Sgm, SgmPaths};
    let (l, r) = (grey("motorcycle_left.png"), grey("motorcycle_right.png"));
    let truth = ocellus_io::pfm::read(data_file("motorcycle_disp.pfm")).unwrap();
    for (paths, median) in [(SgmPaths::Eight, true), (SgmPaths::Four, true), (SgmPaths::Eight, false)] {
        let p = Sgm { paths, median, ..Sgm::default() };
        let t = std::time::Instant::now();
        let est = sgm(&l, &r, &p).unwrap();
        let ms = t.elapsed().as_secs_f64() * 1e3;
        let (bad, density) = bad_pixels(&est, &truth, 2.0).unwrap();
        println!(
            "motorcycle SGM {paths:?} paths, median {median}: bad-2.0 {:.2} %, density {:.1} %, {ms:.1} ms (test build)",
            bad * 100.0,
            density * 100.0
        );
        // cv2.StereoSGBM (block 3) scores 18.1 % here (issue 6); the target is 15 %.
        assert!(bad < 0.15, "{paths:?}: bad-2.0 {bad}");
    }
}
