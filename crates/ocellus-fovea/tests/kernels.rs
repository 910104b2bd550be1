//! Conformance of the log-polar kernels (box-sum pyramid rows, RGB split, AVX2 quad
//! gathers): every backend this CPU has samples a real photograph like the scalar build, for
//! grey and RGB input, both field shapes, centred and off-centre gaze points.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

use ocellus_fovea::logpolar::{Fields, LogPolarConfig, LogPolarMap, Scratch};
use ocellus_image::{Backend, Plane};

fn close(a: &Plane<f32>, b: &Plane<f32>, what: &str) {
    assert_eq!(a.size(), b.size(), "{what}");
    let worst = a.rows().flatten().zip(b.rows().flatten()).map(|(x, y)| (x - y).abs()).fold(0.0f32, f32::max);
    // Grey levels 0..255; the u16 sums are exact, only the bilinear weights round.
    assert!(worst < 1e-3, "{what}: differs from the scalar build by {worst} grey levels");
}

#[test]
fn every_backend_samples_like_the_scalar_build() {
    let img = ocellus_io::read_image(ocellus_testdata::data_file("chelsea.png")).unwrap();
    let (rgb, grey) = (img.to_u8(), img.to_luma8());
    let (w, h) = rgb.size();
    for fields in [Fields::Pyramid, Fields::Area] {
        for centre in [[(w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0], [40.0, 250.0], [w as f64 + 30.0, 10.0]] {
            let cfg = |backend| LogPolarConfig { centre, fields, backend, ..LogPolarConfig::for_image(w, h) };
            let reference = LogPolarMap::new(&cfg(Backend::Scalar), w, h).unwrap();
            let (want_grey, want_rgb) = (reference.sample_grey(&grey).unwrap(), reference.sample_rgb(&rgb).unwrap());
            for b in Backend::available() {
                let map = LogPolarMap::new(&cfg(b), w, h).unwrap();
                let what = format!("{fields:?} at {centre:?}, {b:?}");
                let mut scratch = Scratch::default();
                let mut out = Plane::default();
                // Twice through one scratch: reused buffers must not carry anything over.
                for _ in 0..2 {
                    map.sample_grey_into(&grey, &mut scratch, &mut out).unwrap();
                    close(&out, &want_grey, &format!("grey, {what}"));
                    let mut planes = <[Plane<f32>; 3]>::default();
                    map.sample_rgb_into(&rgb, &mut scratch, &mut planes).unwrap();
                    for c in 0..3 {
                        close(&planes[c], &want_rgb[c], &format!("rgb channel {c}, {what}"));
                    }
                }
            }
        }
    }
}
