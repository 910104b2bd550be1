//! Properties of the saliency pipeline against independent references and ground truth.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

use ocellus_attention::config::{ChannelConfig, ChannelKind, GaborBorder, SaliencyConfig};
use ocellus_attention::gabor::{kernel_2d, GaborBank};
use ocellus_attention::normalize::gaussian_kernel;
use ocellus_attention::{AttentionError, SaliencyEngine};
use ocellus_image::convert::RgbImage;
use ocellus_image::filter::{correlate_2d_direct, Border};
use ocellus_image::pyramid::pyr_down_alloc;
use ocellus_image::{Backend, ImageError, Plane};
use ocellus_testdata::data_file;
use proptest::prelude::*;

fn grey_level(name: &str, levels: usize) -> Plane<f32> {
    let img = ocellus_io::read_image(data_file(name)).unwrap();
    let (w, h) = img.size();
    let mut p = Plane::from_fn(w, h, |x, y| {
        let c = img.get_f32(x, y);
        (c[0] + c[1] + c[2]) / 3.0
    });
    for _ in 0..levels {
        p = pyr_down_alloc(Backend::Scalar, &p, &ocellus_image::pyramid::PyramidKernel::itti()).unwrap();
    }
    p
}

fn argmax(p: &Plane<f32>) -> (usize, usize) {
    let (x, y, _) = p.argmax().expect("a non-empty map");
    (x, y)
}

#[test]
fn gabor_matches_direct_2d_convolution() {
    // Levels 2 and 5 of a real image: a large map and one smaller than the 19x19 kernel's reach.
    for (levels, size, border, gb) in [
        (2, 19, Border::Clamp, GaborBorder::Clamp),
        (5, 19, Border::Clamp, GaborBorder::Clamp),
        (2, 9, Border::Zero, GaborBorder::Zero),
        (6, 9, Border::Zero, GaborBorder::Zero),
    ] {
        let src = grey_level("camera.png", levels);
        let mut cfg = SaliencyConfig::ace2009().gabor;
        cfg.size = size;
        cfg.border = gb;
        cfg.angles_deg = vec![0.0, 45.0, 90.0, 135.0, 30.0];
        let mut bank = GaborBank::new(&cfg);
        let mut out = vec![Plane::default(); cfg.angles_deg.len()];
        for b in Backend::available() {
            bank.filter(b, &src, &mut out).unwrap();
            for (a, &deg) in cfg.angles_deg.iter().enumerate() {
                let even = correlate_2d_direct(&src, &kernel_2d(&cfg, deg, 0.0), size, size, border);
                let odd =
                    correlate_2d_direct(&src, &kernel_2d(&cfg, deg, std::f64::consts::FRAC_PI_2), size, size, border);
                let (mut max_diff, mut max_ref) = (0f32, 0f32);
                for y in 0..src.height() {
                    for x in 0..src.width() {
                        let want = even.get(x, y).abs() + odd.get(x, y).abs();
                        max_diff = max_diff.max((out[a].get(x, y) - want).abs());
                        max_ref = max_ref.max(want);
                    }
                }
                let rel = max_diff / max_ref;
                assert!(rel < 1e-4, "level {levels} size {size} angle {deg} {b:?}: relative error {rel:e}");
            }
        }
    }
}

#[test]
fn normalization_kernels_have_the_seeds_sizes() {
    // At 40x30: sigma_ex = 0.8 -> 5 taps, sigma_inh = 10 -> 2 floor(30.35) + 1 capped at 2*14 + 1.
    assert_eq!(gaussian_kernel(1.0, 0.8, 14).len(), 5);
    assert_eq!(gaussian_kernel(1.0, 10.0, 14).len(), 29);
    assert_eq!(gaussian_kernel(1.0, 10.0, 0).len(), 61);
}

#[test]
fn size_limits_give_clear_errors() {
    assert!(SaliencyEngine::new(SaliencyConfig::ace2009(), 256, 256).is_ok());
    for (w, h) in [(255, 300), (0, 0), (1, 1), (300, 100)] {
        let e = SaliencyEngine::new(SaliencyConfig::ace2009(), w, h).unwrap_err();
        assert!(matches!(e, AttentionError::TooSmall { .. }), "{e}");
        assert!(e.to_string().contains(&format!("{w}x{h}")), "{e}");
    }
    // Fewer levels allow smaller images.
    let mut cfg = SaliencyConfig::ace2009();
    cfg.center_levels = vec![1, 2];
    cfg.deltas = vec![1, 2];
    cfg.map_level = 2;
    let mut e = SaliencyEngine::new(cfg, 16, 16).unwrap();
    let img = RgbImage::U8(Plane::from_fn(16, 16, |x, y| [(x * 16) as u8, (y * 16) as u8, 0]));
    assert!(e.process(&img).unwrap().all_finite());
    let mut e = SaliencyEngine::new(SaliencyConfig::ace2009(), 256, 256).unwrap();
    let wrong = RgbImage::U8(Plane::new(300, 256));
    assert!(matches!(e.process(&wrong), Err(AttentionError::Image(ImageError::SizeMismatch { .. }))));
}

#[test]
fn grey_rgba_16bit_and_flat_inputs_give_finite_maps() {
    for preset in SaliencyConfig::PRESETS {
        let cfg = SaliencyConfig::preset(preset).unwrap();
        // grey (real photograph), via the file reader
        let grey = ocellus_io::read_image(data_file("camera.png")).unwrap();
        let mut e = SaliencyEngine::new(cfg.clone(), 512, 512).unwrap();
        let s = e.process(&grey).unwrap();
        assert!(s.all_finite() && s.min_max().1 > 0.0);
        // colour maps of a grey image are zero: RG = BY = 0
        let ci = cfg.channels.iter().position(|c| c.kind == ChannelKind::Color).unwrap();
        assert_eq!(e.conspicuity(ci).unwrap().min_max(), (0.0, 0.0));
        // 16-bit float input path
        let f = RgbImage::F32(Plane::from_fn(320, 256, |x, y| [x as f32 / 320.0, y as f32 / 256.0, 0.5]));
        let mut e = SaliencyEngine::new(cfg.clone(), 320, 256).unwrap();
        assert!(e.process(&f).unwrap().all_finite());
        // Flat images: finite, never NaN. With ace2009 (clamped Gabor border) the map is flat.
        // The SaliencyToolbox zero-pads its Gabor filters, so the frame edge itself is an
        // oriented edge: its map of a flat image is not flat (checked with the toolbox in
        // GNU Octave: max 2.91 for a 320x256 grey image); `stb` reproduces that, and only the
        // orientation channel may vary.
        for v in [0u8, 128, 255] {
            let flat = RgbImage::U8(Plane::from_fn(300, 260, |_, _| [v, v, v]));
            let mut e = SaliencyEngine::new(cfg.clone(), 300, 260).unwrap();
            let s = e.process(&flat).unwrap();
            assert!(s.all_finite(), "{preset} flat {v}");
            let flat_enough = |p: &Plane<f32>| {
                let (mn, mx) = p.min_max();
                mx - mn <= 1e-4 * mx.abs().max(1.0)
            };
            if *preset == "ace2009" {
                assert!(flat_enough(e.saliency()), "{preset} flat {v}: {:?}", e.saliency().min_max());
            }
            for (label, m) in e.conspicuity_maps() {
                assert!(m.all_finite());
                if label != "orientation" {
                    assert!(flat_enough(m), "{preset} flat {v} {label}: {:?}", m.min_max());
                }
            }
        }
    }
}

/// Real gravel texture with a colourful patch of a real photo pasted at a known place.
fn scene_with_patch() -> (RgbImage, (usize, usize)) {
    let bg = ocellus_io::read_image(data_file("gravel.png")).unwrap();
    let fg = ocellus_io::read_image(data_file("coffee.png")).unwrap();
    let (px, py, pw) = (340usize, 300usize, 64usize);
    let img = Plane::from_fn(512, 512, |x, y| {
        let c = if (px..px + pw).contains(&x) && (py..py + pw).contains(&y) {
            fg.get_f32(x - px + 250, y - py + 150)
        } else {
            bg.get_f32(x, y)
        };
        c.map(|v| (v * 255.0).round() as u8)
    });
    (RgbImage::U8(img), (px + pw / 2, py + pw / 2))
}

#[test]
fn pasted_object_is_the_most_salient_place() {
    let (img, (cx, cy)) = scene_with_patch();
    for preset in SaliencyConfig::PRESETS {
        let mut e = SaliencyEngine::new(SaliencyConfig::preset(preset).unwrap(), 512, 512).unwrap();
        let s = e.process(&img).unwrap();
        let (mx, my) = argmax(s);
        let (gx, gy) = ((mx as f32 + 0.5) * 16.0, (my as f32 + 0.5) * 16.0);
        let d = ((gx - cx as f32).powi(2) + (gy - cy as f32).powi(2)).sqrt();
        assert!(d < 48.0, "{preset}: peak at ({gx}, {gy}) px, object at ({cx}, {cy}), {d} px away");
    }
}

#[test]
fn intermediates_are_exposed() {
    let (img, _) = scene_with_patch();
    let mut e = SaliencyEngine::new(SaliencyConfig::ace2009(), 512, 512).unwrap();
    e.process(&img).unwrap();
    assert_eq!(e.feature_maps().len(), 42);
    let count = |k: ChannelKind| {
        e.feature_maps().iter().filter(|f| e.config().channels[e.subfeatures()[f.subfeature].channel].kind == k).count()
    };
    assert_eq!(
        (count(ChannelKind::Intensity), count(ChannelKind::Color), count(ChannelKind::Orientation)),
        (6, 12, 24)
    );
    assert_eq!(e.conspicuity_maps().count(), 3);
    assert_eq!(e.scale_pairs().len(), 6);
    assert_eq!(e.map_size(), (32, 32));
    let lvl = e.level(ocellus_attention::saliency::Source::Intensity, 2).unwrap();
    assert_eq!(lvl.size(), (128, 128));
    let mut full = Plane::default();
    e.saliency_full_size(&mut full).unwrap();
    assert_eq!(full.size(), (512, 512));
    let t = e.timings();
    assert!(t.total() > std::time::Duration::ZERO);
}

#[test]
fn deterministic_and_backends_agree() {
    let (img, _) = scene_with_patch();
    let mut outs = Vec::new();
    for b in Backend::available() {
        let mut cfg = SaliencyConfig::ace2009();
        cfg.backend = b;
        let mut e = SaliencyEngine::new(cfg, 512, 512).unwrap();
        let a = e.process(&img).unwrap().clone();
        let again = e.process(&img).unwrap().clone();
        assert_eq!(a, again, "same input, same output");
        outs.push(a);
    }
    for o in &outs[1..] {
        let mx = outs[0].min_max().1;
        let d = o
            .rows()
            .zip(outs[0].rows())
            .flat_map(|(p, q)| p.iter().zip(q).map(|(a, b)| (a - b).abs()))
            .fold(0.0, f32::max);
        assert!(d <= 1e-4 * mx, "backends differ by {d} (max {mx})");
    }
}

#[test]
fn external_map_spatial_prior_and_gains() {
    let flat = RgbImage::U8(Plane::from_fn(320, 320, |_, _| [90, 90, 90]));
    let mut cfg = SaliencyConfig::ace2009();
    cfg.channels.push(ChannelConfig { kind: ChannelKind::External("detector".into()), weight: 1.0 });
    let mut e = SaliencyEngine::new(cfg, 320, 320).unwrap();
    // The detector map has its own size (any size works) and one blob.
    let det = Plane::from_fn(64, 64, |x, y| if (40..48).contains(&x) && (10..18).contains(&y) { 1.0 } else { 0.0 });
    let s = e.process_with_maps(&flat, &[&det]).unwrap();
    let (mx, my) = argmax(s);
    let (gx, gy) = ((mx as f32 + 0.5) / 20.0 * 64.0, (my as f32 + 0.5) / 20.0 * 64.0);
    assert!((gx - 44.0).abs() < 6.0 && (gy - 14.0).abs() < 6.0, "peak at {gx},{gy} (detector coordinates)");
    assert!(e.process(&flat).is_err(), "missing external map is an error");

    let (img, _) = scene_with_patch();
    let mut e = SaliencyEngine::new(SaliencyConfig::ace2009(), 512, 512).unwrap();
    let prior = Plane::from_fn(2, 1, |x, _| x as f32);
    e.set_spatial_prior(Some(&prior)).unwrap();
    let s = e.process(&img).unwrap();
    assert!((0..32).all(|y| s.get(0, y) == 0.0), "prior is zero at the left edge");
    assert!(e.set_spatial_prior(Some(&Plane::from_fn(2, 2, |_, _| f32::NAN))).is_err());

    let mut cfg = SaliencyConfig::ace2009();
    cfg.channels[2].weight = 0.0;
    let mut e = SaliencyEngine::new(cfg, 512, 512).unwrap();
    e.process(&img).unwrap();
    assert_eq!(e.conspicuity(2).unwrap().min_max(), (0.0, 0.0));
}

#[test]
fn skin_channel_finds_skin_coloured_region() {
    use ocellus_attention::channels::skin_likelihood;
    // The model's mean chromaticity scores 1.
    let [mr, mg, ..] = ocellus_attention::channels::SKIN_MODEL;
    assert!((skin_likelihood([mr, mg, 1.0 - mr - mg], 0.1) - 1.0).abs() < 1e-5);
    assert_eq!(skin_likelihood([0.02, 0.01, 0.01], 0.1), 0.0, "dark pixels are not skin");
    // A skin-coloured square in a real texture.
    let bg = ocellus_io::read_image(data_file("grass.png")).unwrap();
    let img = RgbImage::U8(Plane::from_fn(512, 512, |x, y| {
        if (100..160).contains(&x) && (380..440).contains(&y) {
            [224, 160, 130]
        } else {
            bg.get_f32(x, y).map(|v| (v * 200.0) as u8)
        }
    }));
    let mut cfg = SaliencyConfig::ace2009();
    cfg.channels = vec![ChannelConfig { kind: ChannelKind::Skin, weight: 1.0 }];
    let mut e = SaliencyEngine::new(cfg, 512, 512).unwrap();
    let s = e.process(&img).unwrap();
    let (mx, my) = argmax(s);
    assert!((4..=12).contains(&mx) && (22..=29).contains(&my), "skin peak at cell ({mx}, {my})");
}

#[test]
fn invalid_configs_are_rejected() {
    let mut c = SaliencyConfig::ace2009();
    c.gabor.size = 8;
    assert!(matches!(SaliencyEngine::new(c, 512, 512), Err(AttentionError::InvalidConfig(_))));
    let mut c = SaliencyConfig::ace2009();
    c.deltas = vec![0];
    assert!(SaliencyEngine::new(c, 512, 512).is_err());
    let mut c = SaliencyConfig::ace2009();
    c.channels.iter_mut().for_each(|ch| ch.weight = f32::NAN);
    assert!(SaliencyEngine::new(c, 512, 512).is_err());
    assert!(SaliencyConfig::preset("itti").is_err());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]
    #[test]
    fn any_size_and_levels_never_panic(w in 16usize..140, h in 16usize..140, c0 in 0usize..3, d in 1usize..3, seed in 0u32..100) {
        let mut cfg = SaliencyConfig::ace2009();
        cfg.center_levels = vec![c0, c0 + 1];
        cfg.deltas = vec![d, d + 1];
        cfg.map_level = c0 + 1;
        let mut s = seed;
        let img = RgbImage::U8(Plane::from_fn(w, h, |_, _| { s = s.wrapping_mul(1664525).wrapping_add(1013904223); [(s >> 24) as u8, (s >> 16) as u8, (s >> 8) as u8] }));
        match SaliencyEngine::new(cfg, w, h) {
            Ok(mut e) => { let m = e.process(&img).unwrap(); prop_assert!(m.all_finite()); }
            Err(err) => {
                let too_small = matches!(err, AttentionError::TooSmall { .. });
                prop_assert!(too_small, "unexpected error: {}", err);
            }
        }
    }
}

#[test]
fn flicker_channel_responds_only_to_change() {
    // Gravel alone, then gravel with a real patch pasted: the flicker channel alone must peak
    // at the patch; an unchanged frame (and the first frame) gives a flat, zero map.
    let bg = ocellus_io::read_image(data_file("gravel.png")).unwrap();
    let bg = RgbImage::U8(Plane::from_fn(512, 512, |x, y| bg.get_f32(x, y).map(|v| (v * 255.0).round() as u8)));
    let (with_patch, (cx, cy)) = scene_with_patch();
    let mut cfg = SaliencyConfig::ace2009();
    cfg.channels = vec![ChannelConfig { kind: ChannelKind::Flicker, weight: 1.0 }];
    let mut e = SaliencyEngine::new(cfg, 512, 512).unwrap();
    assert_eq!(e.process(&bg).unwrap().min_max(), (0.0, 0.0), "first frame: no flicker");
    assert_eq!(e.process(&bg).unwrap().min_max(), (0.0, 0.0), "same frame: no flicker");
    let s = e.process(&with_patch).unwrap();
    let (mx, my) = argmax(s);
    let (gx, gy) = ((mx as f32 + 0.5) * 16.0, (my as f32 + 0.5) * 16.0);
    let d = ((gx - cx as f32).powi(2) + (gy - cy as f32).powi(2)).sqrt();
    assert!(d < 48.0, "flicker peak at ({gx}, {gy}) px, change at ({cx}, {cy})");
    e.reset_temporal();
    assert_eq!(e.process(&with_patch).unwrap().min_max(), (0.0, 0.0), "after a reset: no flicker");
}
