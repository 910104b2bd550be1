//! Tests of SGM: census bits against a direct count, one path step against the recurrence,
//! random-dot and smooth pairs of known shift, every backend against the scalar build, bad input.

use super::*;
use crate::block_matching::bad_pixels;
use ocellus_image::rng::SplitMix64;

#[test]
fn census_bits_match_a_direct_count() {
    let mut rng = SplitMix64::new(2);
    let img = Plane::from_fn(23, 17, |_, _| (rng.next_u64() & 255) as u8);
    let c = census(Backend::Scalar, &img, 5, 3);
    for (x, y) in [(0usize, 0usize), (11, 8), (22, 16), (3, 1)] {
        let mut want = 0u64;
        let mut bit = 0;
        for dy in -1isize..=1 {
            for dx in -2isize..=2 {
                if dx == 0 && dy == 0 {
                    continue;
                }
                let xx = (x as isize + dx).clamp(0, 22) as usize;
                let yy = (y as isize + dy).clamp(0, 16) as usize;
                want |= u64::from(img.get(xx, yy) < img.get(x, y)) << bit;
                bit += 1;
            }
        }
        assert_eq!(c.get(x, y), want, "({x}, {y})");
    }
}

#[test]
fn path_step_matches_the_recurrence() {
    let cost = [5u8, 0, 9, 3];
    let mut prev = vec![PAD, 4, 20, 1, 30, PAD];
    prev[0] = PAD;
    let mut cur = vec![0u16; 6];
    let m = path_step(&cost, &prev, 1, &mut cur, 2, 10);
    // d = 0: min(4, min(PAD, 20) + 2, 1 + 10) = 4 -> 5 + 4 - 1 = 8;
    // d = 1: min(20, min(4, 1) + 2, 11) = 3 -> 0 + 3 - 1 = 2;
    // d = 2: min(1, min(20, 30) + 2, 11) = 1 -> 9; d = 3: min(30, 1 + 2, 11) = 3 -> 5.
    assert_eq!(&cur[1..5], &[8, 2, 9, 5]);
    assert_eq!(m, 2);
}

#[test]
fn random_dot_pair_with_known_shift() {
    let mut rng = SplitMix64::new(5);
    let tex: Vec<u8> = (0..200 * 120).map(|_| (rng.next_u64() & 255) as u8).collect();
    let left = Plane::from_fn(160, 100, |x, y| tex[y * 200 + x + 20]);
    let right = Plane::from_fn(160, 100, |x, y| {
        let near = (60 - 12..100 - 12).contains(&x) && (30..70).contains(&y);
        let d = if near { 12 } else { 7 };
        tex[y * 200 + (x + d).min(199) + 20]
    });
    let truth = Plane::from_fn(160, 100, |x, y| {
        if x < 20 {
            f32::INFINITY
        } else if (60..100).contains(&x) && (30..70).contains(&y) {
            12.0f32
        } else {
            7.0
        }
    });
    for paths in [SgmPaths::Four, SgmPaths::Eight] {
        let est = sgm(&left, &right, &Sgm { max_disparity: 20, paths, ..Default::default() }).unwrap();
        let (bad, density) = bad_pixels(&est, &truth, 0.5).unwrap();
        assert!(bad < 0.06 && density > 0.94, "{paths:?}: bad {bad}, density {density}");
        // Per-pixel random dots have no sub-pixel structure: check the integer part.
        for (x, y, want) in [(30usize, 50usize, 7.0f32), (80, 50, 12.0), (130, 15, 7.0)] {
            assert!((est.get(x, y) - want).abs() < 0.5, "({x}, {y}): {}", est.get(x, y));
        }
    }
}

#[test]
fn sub_pixel_shift_of_a_smooth_texture() {
    // A band-limited texture (sum of sinusoids) shifted by 7.3 px: sub-pixel estimates
    // must beat integer ones (whose error would be 0.3 px everywhere).
    let mut rng = SplitMix64::new(3);
    let waves: Vec<(f64, f64, f64)> = (0..12)
        .map(|_| (0.05 + 0.5 * rng.unit(), 0.05 + 0.5 * rng.unit(), rng.unit() * std::f64::consts::TAU))
        .collect();
    let f = |x: f64, y: f64| {
        let v: f64 = waves.iter().map(|(a, b, p)| (a * x + b * y + p).sin()).sum();
        (128.0 + 9.0 * v).clamp(0.0, 255.0) as u8
    };
    let left = Plane::from_fn(160, 80, |x, y| f(x as f64, y as f64));
    let right = Plane::from_fn(160, 80, |x, y| f(x as f64 + 7.3, y as f64));
    let est = sgm(&left, &right, &Sgm { max_disparity: 16, ..Default::default() }).unwrap();
    let mut v: Vec<f32> = (10..70)
        .flat_map(|y| (30..150).map(move |x| (x, y)))
        .map(|(x, y)| est.get(x, y))
        .filter(|v| v.is_finite())
        .collect();
    assert!(v.len() > 5000, "{} valid", v.len());
    v.sort_by(f32::total_cmp);
    let med = v[v.len() / 2];
    let mean_abs = v.iter().map(|e| (e - 7.3).abs()).sum::<f32>() / v.len() as f32;
    println!("sub-pixel: median {med:.3}, mean |error| {mean_abs:.3} px");
    assert!((med - 7.3).abs() < 0.2 && mean_abs < 0.22, "median {med}, mean |error| {mean_abs}");
}

#[test]
fn scalar_and_simd_builds_agree() {
    let mut rng = SplitMix64::new(8);
    let a = Plane::from_fn(64, 40, |_, _| (rng.next_u64() & 255) as u8);
    let b = Plane::from_fn(64, 40, |x, y| a.get((x + 3).min(63), y));
    let p = Sgm { max_disparity: 16, ..Default::default() };
    let (cl, cr) = (census(Backend::Scalar, &a, 9, 7), census(Backend::Scalar, &b, 9, 7));
    let mut sums = Vec::new();
    for backend in Backend::available() {
        let mut cost = vec![0u8; 64 * 40 * 16];
        costs_kernel(backend, &cl, &cr, &mut cost, 16);
        let mut sum = vec![0u16; 64 * 40 * 16];
        pass_kernel(backend, &cost, &mut sum, 64, 40, 16, p.p1, p.p2, true, true);
        pass_kernel(backend, &cost, &mut sum, 64, 40, 16, p.p1, p.p2, true, false);
        sums.push(sum);
    }
    assert!(sums.windows(2).all(|s| s[0] == s[1]));
}

#[test]
fn bad_inputs_are_errors() {
    let a = Plane::new(20, 20);
    assert!(sgm(&a, &Plane::new(21, 20), &Sgm::default()).is_err());
    assert!(sgm(&a, &a, &Sgm { census_width: 8, ..Default::default() }).is_err());
    assert!(sgm(&a, &a, &Sgm { census_width: 11, census_height: 7, ..Default::default() }).is_err());
    assert!(sgm(&a, &a, &Sgm { p1: 20, p2: 10, ..Default::default() }).is_err());
    assert!(sgm(&Plane::new(4, 4), &Plane::new(4, 4), &Sgm::default()).is_err());
    // A flat pair is ambiguous everywhere: all invalid, no panic.
    let flat = sgm(&a, &a, &Sgm { max_disparity: 8, ..Default::default() }).unwrap();
    assert!(flat.to_vec().iter().all(|v| v.is_nan()));
}
