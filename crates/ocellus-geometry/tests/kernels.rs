//! Conformance of the stereo kernels: SGM and block matching on the real Motorcycle pair
//! with every backend this CPU has give the scalar build's disparities (the same invalid
//! pixels; sub-pixel values within float rounding).
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

use ocellus_geometry::block_matching::{block_match, BlockMatching};
use ocellus_geometry::sgm::{sgm, Sgm};
use ocellus_image::{Backend, Plane};
use ocellus_testdata::data_file;

fn grey(name: &str) -> Plane<u8> {
    ocellus_io::read_image(data_file(name)).unwrap().to_luma8()
}

fn same(a: &Plane<f32>, b: &Plane<f32>, what: &str) {
    assert_eq!(a.size(), b.size());
    for (i, (x, y)) in a.rows().flatten().zip(b.rows().flatten()).enumerate() {
        assert!(x.is_nan() == y.is_nan() && (x.is_nan() || (x - y).abs() < 1e-4), "{what}: pixel {i}: {x} vs {y}");
    }
}

#[test]
fn sgm_and_block_matching_agree_on_every_backend() {
    let (l, r) = (grey("motorcycle_left.png"), grey("motorcycle_right.png"));
    let sgm_ref = sgm(&l, &r, &Sgm { backend: Backend::Scalar, ..Default::default() }).unwrap();
    let bm_ref = block_match(&l, &r, &BlockMatching { backend: Backend::Scalar, ..Default::default() }).unwrap();
    for b in Backend::available() {
        same(&sgm(&l, &r, &Sgm { backend: b, ..Default::default() }).unwrap(), &sgm_ref, &format!("sgm {b:?}"));
        let bm = block_match(&l, &r, &BlockMatching { backend: b, ..Default::default() }).unwrap();
        same(&bm, &bm_ref, &format!("block matching {b:?}"));
    }
}
