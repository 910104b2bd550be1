//! `cargo bench -p ocellus-attention`: the saliency pipeline at 640x480 and its hot kernels.
//! `ocellus bench saliency` prints the figures (median, all cores, per stage, memory).
#![allow(clippy::expect_used)] // a benchmark aborts on broken set-up

use ocellus_attention::{SaliencyConfig, SaliencyEngine};
use ocellus_image::convert::RgbImage;
use ocellus_image::preserving::PreservingFilter;
use ocellus_image::pyramid::{pyr_down_rgb8, PyrScratch, PyramidKernel};
use ocellus_image::{Backend, Plane};

fn main() {
    divan::main();
}

/// The shipped astronaut photo, resized (nearest) to 640x480.
fn frame() -> RgbImage {
    let img = ocellus_io::read_image(ocellus_testdata::asset("astronaut.png")).expect("assets/astronaut.png");
    let (w, h) = img.size();
    let src = img.to_u8();
    RgbImage::U8(Plane::from_fn(640, 480, |x, y| src.get(x * w / 640, y * h / 480)))
}

#[divan::bench(args = ["ace2009", "stb"])]
fn saliency_640x480(bencher: divan::Bencher, preset: &str) {
    let f = frame();
    let mut e = SaliencyEngine::new(SaliencyConfig::preset(preset).expect("preset"), 640, 480).expect("engine");
    bencher.bench_local(|| {
        e.process(divan::black_box(&f)).expect("process");
    });
}

#[divan::bench(args = [Backend::Scalar, Backend::Avx2, Backend::Avx512])]
fn first_pyramid_level_rgb8(bencher: divan::Bencher, backend: Backend) {
    let RgbImage::U8(p) = frame() else { return };
    let (mut a, mut b, mut c) = (Plane::default(), Plane::default(), Plane::default());
    let mut s = PyrScratch::default();
    bencher.bench_local(|| {
        pyr_down_rgb8(backend, &p, [&mut a, &mut b, &mut c], &PyramidKernel::itti(), &mut s).expect("pyr");
    });
}

#[divan::bench(args = [Backend::Scalar, Backend::Avx2, Backend::Avx512])]
fn inhibition_filter_40x30(bencher: divan::Bencher, backend: Backend) {
    let k: Vec<f32> = (-14i32..=14).map(|i| (-(i * i) as f32 / 200.0).exp()).collect();
    let mut f = PreservingFilter::new(&k, 40, 30).expect("filter");
    let m = Plane::from_fn(40, 30, |x, y| ((x * 7 + y * 3) % 11) as f32);
    let mut out = Plane::default();
    bencher.bench_local(|| {
        f.apply(backend, &m, &mut out).expect("apply");
    });
}
