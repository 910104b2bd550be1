use super::*;
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]
    /// Any parameters: a clear error or a map whose outputs are finite and within the
    /// input's range (fields are weighted means), for both field kinds.
    #[test]
    fn any_parameters_give_an_error_or_bounded_means(
        w in 1usize..40, h in 1usize..40, rings in 0usize..20, sectors in 0usize..20, fovea_rings in 0usize..4,
        rho0 in -2.0f64..10.0, rho_max in -1.0f64..40.0, cx in -20.0f64..60.0, cy in -20.0f64..60.0,
        max_level in 0usize..6, area in any::<bool>(), seed in any::<u64>(),
    ) {
        let cfg = LogPolarConfig {
            rings, sectors, fovea_rings, fovea_radius: rho0, max_radius: rho_max, centre: [cx, cy], max_level,
            min_field_texels: 1.0, fields: if area { Fields::Area } else { Fields::Pyramid },
            backend: ocellus_image::Backend::Auto,
        };
        if let Ok(map) = LogPolarMap::new(&cfg, w, h) {
            let mut rng = ocellus_image::rng::SplitMix64::new(seed);
            let img = Plane::from_fn(w, h, |_, _| 50 + rng.below(100) as u8);
            let out = map.sample_grey(&img).unwrap();
            prop_assert_eq!(out.size(), (sectors, map.rows()));
            for (v, cov) in out.rows().flatten().zip(map.coverage()) {
                prop_assert!(v.is_finite());
                // Cells that read the image see only values in 50..150.
                if *cov > 0.0 {
                    prop_assert!((49.99..=150.01).contains(v), "{} (coverage {})", v, cov);
                }
            }
            let inv = map.inverse(&out).unwrap();
            prop_assert!(inv.all_finite());
        }
    }
}

#[test]
fn the_grey_fast_path_equals_the_general_one() {
    // Gaze points in the middle, near a corner (cells off the image, quads at the last
    // row and column) and outside the image.
    let (w, h) = (203, 157);
    let mut rng = ocellus_image::rng::SplitMix64::new(5);
    let img = Plane::from_fn(w, h, |_, _| rng.below(256) as u8);
    let f = img.map(|v| v as f32);
    for centre in [[101.0, 78.0], [199.5, 154.2], [3.0, 150.0], [-30.0, 40.0]] {
        let cfg = LogPolarConfig { centre, rings: 40, sectors: 37, ..LogPolarConfig::for_image(w, h) };
        let map = LogPolarMap::new(&cfg, w, h).unwrap();
        assert!(map.level_ranges.is_some());
        let (fast, general) = (map.sample_grey(&img).unwrap(), map.sample_f32(&f).unwrap());
        for (a, b) in fast.rows().flatten().zip(general.rows().flatten()) {
            assert!((a - b).abs() < 1e-3, "{centre:?}: {a} {b}");
        }
    }
}

#[test]
fn the_rgb_fast_path_equals_the_general_one_per_channel() {
    let (w, h) = (190, 141);
    let mut rng = ocellus_image::rng::SplitMix64::new(8);
    let img = Plane::from_fn(w, h, |_, _| [rng.below(256) as u8, rng.below(256) as u8, rng.below(256) as u8]);
    for centre in [[95.0, 70.0], [187.0, 2.5], [-10.0, 60.0]] {
        let cfg = LogPolarConfig { centre, rings: 33, sectors: 41, ..LogPolarConfig::for_image(w, h) };
        let map = LogPolarMap::new(&cfg, w, h).unwrap();
        let fast = map.sample_rgb(&img).unwrap();
        // Area fields go through the general interleaved path.
        let area = LogPolarMap::new(&LogPolarConfig { fields: Fields::Area, ..cfg }, w, h).unwrap();
        let area_rgb = area.sample_rgb(&img).unwrap();
        for c in 0..3 {
            let chan = img.map(|p| p[c] as f32);
            let general = map.sample_f32(&chan).unwrap();
            for (a, b) in fast[c].rows().flatten().zip(general.rows().flatten()) {
                assert!((a - b).abs() < 1e-3, "{centre:?} channel {c}: {a} {b}");
            }
            let area_general = area.sample_f32(&chan).unwrap();
            for (a, b) in area_rgb[c].rows().flatten().zip(area_general.rows().flatten()) {
                assert!((a - b).abs() < 1e-3, "{centre:?} area channel {c}: {a} {b}");
            }
        }
    }
}

#[test]
fn huge_or_degenerate_maps_are_refused_with_a_reason() {
    let base = LogPolarConfig::for_image(64, 64);
    for (cfg, why) in [
        (LogPolarConfig { rings: 60_000, sectors: 60_000, ..base }, "cells"),
        (LogPolarConfig { max_radius: 1.0, ..base }, "outer radius"),
        (LogPolarConfig { centre: [f64::NAN, 3.0], ..base }, "gaze"),
        (LogPolarConfig { max_level: 5, ..base }, "level"),
    ] {
        let e = LogPolarMap::new(&cfg, 64, 64).unwrap_err().to_string();
        assert!(e.contains(why), "{e}");
    }
    assert!(LogPolarMap::new(&base, 0, 64).is_err());
}

#[test]
fn a_shifted_map_equals_one_built_at_the_new_gaze_point() {
    let (w, h) = (120, 90);
    let img = Plane::from_fn(w, h, |x, y| ((x * 13 + y * 7 + x * y / 5) % 251) as u8);
    let cfg = LogPolarConfig {
        rings: 10,
        sectors: 24,
        fovea_rings: 2,
        fovea_radius: 2.0,
        max_radius: 20.0,
        centre: [60.0, 45.0],
        max_level: 0,
        min_field_texels: 1.0,
        fields: Fields::Area,
        backend: ocellus_image::Backend::Auto,
    };
    let map = LogPolarMap::new(&cfg, w, h).unwrap();
    let moved = map.shifted(-17, 9).unwrap();
    let fresh = LogPolarMap::new(&LogPolarConfig { centre: [43.0, 54.0], ..cfg }, w, h).unwrap();
    let (a, b) = (moved.sample_grey(&img).unwrap(), fresh.sample_grey(&img).unwrap());
    for (x, y) in a.rows().flatten().zip(b.rows().flatten()) {
        assert!((x - y).abs() < 1e-3, "{x} {y}");
    }
    // Reading the table at an offset gives the same, without a copy.
    let mut read = Plane::default();
    assert!(map.sample_grey_moved_into(&img, (-17, 9), &mut Scratch::default(), &mut read).unwrap());
    assert_eq!(read.to_vec(), a.to_vec());
    // Not when the fields would leave the image, nor for pyramid maps.
    assert!(map.shifted(-50, 0).is_none());
    assert!(!map.sample_grey_moved_into(&img, (-50, 0), &mut Scratch::default(), &mut read).unwrap());
    let pyr = LogPolarMap::new(&LogPolarConfig { max_level: 3, fields: Fields::Pyramid, ..cfg }, w, h).unwrap();
    assert!(pyr.shifted(1, 0).is_none());
}

#[test]
fn a_quarter_turn_is_a_shift_by_a_quarter_of_the_sectors() {
    // 32 = 2^5: the pyramid's texel grids are symmetric about the centre (15.5, 15.5) at
    // every level, so pyramid fields turn with the image too (for other sizes they do up
    // to the grid, as the 512x512 test on a real image shows).
    let n = 32;
    let img = Plane::from_fn(n, n, |x, y| ((x * 37 + y * 11 + x * y) % 200) as u8);
    let quarter = Plane::from_fn(n, n, |x, y| img.get(y, n - 1 - x));
    for fields in [Fields::Pyramid, Fields::Area] {
        let cfg = LogPolarConfig { rings: 12, sectors: 16, fields, ..LogPolarConfig::for_image(n, n) };
        let map = LogPolarMap::new(&cfg, n, n).unwrap();
        let (a, b) = (map.sample_grey(&img).unwrap(), map.sample_grey(&quarter).unwrap());
        for y in 0..map.rows() {
            for x in 0..16 {
                assert!((b.get((x + 4) % 16, y) - a.get(x, y)).abs() < 1e-2, "{fields:?} row {y} sector {x}");
            }
        }
    }
}
