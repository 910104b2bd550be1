//! Conformance of the block-search kernels: every backend this CPU has gives exactly the
//! scalar search's flows (integer SADs leave no room for rounding), on real floor texture
//! and on low-contrast noise where ties are common.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

use ocellus_image::rng::SplitMix64;
use ocellus_image::{Backend, Plane};
use ocellus_odometry::sad_flow::{window_flows, SadFlowConfig};

/// A 640x480 crop of a real texture and the same crop moved by (dx, dy).
fn real_pair(dx: usize, dy: usize) -> (Plane<u8>, Plane<u8>) {
    let photo = ocellus_io::read_image(ocellus_testdata::data_file("coffee.png")).unwrap().to_luma8();
    let crop = |ox: usize, oy: usize| Plane::from_fn(560, 380, |x, y| photo.get(x + ox, y + oy));
    (crop(10, 10), crop(10 + dx, 10 + dy))
}

fn check(prev: &Plane<u8>, cur: &Plane<u8>, cfg: SadFlowConfig, what: &str) {
    let want = window_flows(prev, cur, &SadFlowConfig { backend: Backend::Scalar, ..cfg }).unwrap();
    for b in Backend::available() {
        let got = window_flows(prev, cur, &SadFlowConfig { backend: b, ..cfg }).unwrap();
        assert_eq!(got, want, "{what}: {b:?} differs from the scalar search");
    }
}

#[test]
fn every_backend_matches_the_scalar_search() {
    let small = SadFlowConfig { region: 280, ..Default::default() };
    for (dx, dy) in [(0, 0), (3, 1), (5, 6)] {
        let (a, b) = real_pair(dx, dy);
        check(&a, &b, small, &format!("coffee moved by ({dx}, {dy})"));
    }
    let mut rng = SplitMix64::new(5);
    for levels in [2, 4, 256] {
        let a = Plane::from_fn(560, 380, |_, _| rng.below(levels) as u8);
        let b = Plane::from_fn(560, 380, |_, _| rng.below(levels) as u8);
        check(&a, &b, small, &format!("noise of {levels} levels"));
    }
    // A block size without a SIMD kernel runs the scalar search on every backend.
    let (a, b) = real_pair(2, 2);
    check(&a, &b, SadFlowConfig { region: 280, window: 20, block: 6, ..Default::default() }, "6x6 blocks");
}
