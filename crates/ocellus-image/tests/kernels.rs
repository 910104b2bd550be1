//! Every fast kernel against a slow, direct implementation written here, and every
//! available backend against the portable one.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

use ocellus_image::filter::{
    correlate_2d_direct, filter_cols, filter_rows, gaussian_kernel, sep_filter, sep_filter_u8, Border, FilterScratch,
};
use ocellus_image::preserving::PreservingFilter;
use ocellus_image::pyramid::{level_sizes, pyr_down, pyr_down_rgb8, PyrScratch, PyramidKernel};
use ocellus_image::resample::{resize, ResampleMethod};
use ocellus_image::{Backend, Plane};
use proptest::prelude::*;

/// Deterministic pseudo-random plane in [0, 1).
fn noise(w: usize, h: usize, seed: u64) -> Plane<f32> {
    let mut s = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    Plane::from_fn(w, h, |_, _| {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((s >> 40) as f32) / (1u64 << 24) as f32
    })
}

fn max_abs_diff(a: &Plane<f32>, b: &Plane<f32>) -> f32 {
    assert_eq!(a.size(), b.size());
    a.rows().zip(b.rows()).flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| (p - q).abs())).fold(0.0, f32::max)
}

/// SPEC 1.2 written out directly: 2D sum over both kernels' taps, each axis truncated
/// at the border and renormalized, sampled at even positions.
fn pyr_down_direct(src: &Plane<f32>, taps: &[f64], origin: usize) -> Plane<f32> {
    let (w, h) = src.size();
    let axis = |j: usize, n: usize| -> Vec<(usize, f64)> {
        let v: Vec<(usize, f64)> = taps
            .iter()
            .enumerate()
            .filter_map(|(t, &k)| {
                let i = (2 * j + t) as isize - origin as isize;
                (i >= 0 && (i as usize) < n).then_some((i as usize, k))
            })
            .collect();
        let s: f64 = v.iter().map(|p| p.1).sum();
        v.into_iter().map(|(i, k)| (i, k / s)).collect()
    };
    Plane::from_fn(w / 2, h / 2, |x, y| {
        let mut acc = 0.0;
        for (yy, wy) in axis(y, h) {
            for &(xx, wx) in &axis(x, w) {
                acc += wy * wx * src.get(xx, yy) as f64;
            }
        }
        acc as f32
    })
}

#[test]
fn pyramid_matches_direct_definition_on_odd_sizes() {
    let itti = [1.0, 5.0, 10.0, 10.0, 5.0, 1.0];
    for (w, h) in [(37, 23), (640, 480), (101, 9), (2, 2), (5, 4), (8, 3)] {
        let src = noise(w, h, (w * h) as u64);
        for b in Backend::available() {
            let mut dst = Plane::default();
            pyr_down(b, &src, &mut dst, &PyramidKernel::itti(), &mut PyrScratch::default()).unwrap();
            assert_eq!(dst.size(), (w / 2, h / 2));
            let want = pyr_down_direct(&src, &itti, 2);
            assert!(max_abs_diff(&dst, &want) < 2e-6, "{w}x{h} {b:?}: {}", max_abs_diff(&dst, &want));
        }
    }
}

#[test]
fn seed_border_weights_are_reproduced() {
    // A unit impulse at column 0: output 0 takes weight 10/26 (seed: [10 10 5 1]/26 on the left).
    let mut src = Plane::<f32>::new(16, 16);
    for y in 0..16 {
        src.set(0, y, 1.0);
    }
    let out = ocellus_image::pyramid::pyr_down_alloc(Backend::Scalar, &src, &PyramidKernel::itti()).unwrap();
    assert!((out.get(0, 3) - 10.0 / 26.0).abs() < 1e-6);
    // and an interior impulse at column 8: outputs 3, 4, 5 see taps 1, 10, 5 of 32 (offsets +2, 0, -2 ... )
    let mut src = Plane::<f32>::new(16, 16);
    for y in 0..16 {
        src.set(8, y, 1.0);
    }
    let out = ocellus_image::pyramid::pyr_down_alloc(Backend::Scalar, &src, &PyramidKernel::itti()).unwrap();
    let row: Vec<f32> = out.row(4).to_vec();
    assert!(
        (row[3] - 5.0 / 32.0).abs() < 1e-6 && (row[4] - 10.0 / 32.0).abs() < 1e-6 && (row[5] - 1.0 / 32.0).abs() < 1e-6,
        "{row:?}"
    );
}

#[test]
fn stb_size3_rule() {
    let src = Plane::from_fn(5, 3, |x, y| (x + 10 * y) as f32);
    let out = ocellus_image::pyramid::pyr_down_alloc(Backend::Scalar, &src, &PyramidKernel::stb()).unwrap();
    assert_eq!(out.size(), (2, 1));
    // rows 0, 1, 2 weighted 1/4, 1/2, 1/4 -> row value 10 plus the horizontal part
    let horiz: Vec<f64> = {
        let k = [1.0f64, 1.0, 5.0, 10.0, 10.0, 5.0, 1.0];
        (0..2)
            .map(|j| {
                let (mut a, mut s) = (0.0, 0.0);
                for (t, &kk) in k.iter().enumerate() {
                    let i = (2 * j + t) as isize - 3;
                    if (0..5).contains(&i) {
                        a += kk * i as f64;
                        s += kk;
                    }
                }
                a / s
            })
            .collect()
    };
    for j in 0..2 {
        assert!((out.get(j, 0) as f64 - (horiz[j] + 10.0)).abs() < 1e-5, "{} vs {}", out.get(j, 0), horiz[j] + 10.0);
    }
}

/// The seed's kernel takes the exact 16-bit integer path from bytes, a kernel with an
/// irrational tap the float path; both must equal the direct definition.
#[test]
fn fused_rgb8_level_equals_float_path() {
    let (w, h) = (333, 251);
    let mut s = 7u32;
    let rgb: Plane<[u8; 3]> = Plane::from_fn(w, h, |_, _| {
        s = s.wrapping_mul(1664525).wrapping_add(1013904223);
        [(s >> 24) as u8, (s >> 16) as u8, (s >> 8) as u8]
    });
    let itti = [1.0, 5.0, 10.0, 10.0, 5.0, 1.0];
    let irrational = [1.0, std::f64::consts::E, 1.7];
    for (taps, origin) in [(&itti[..], 2), (&irrational[..], 1)] {
        let taps32: Vec<f32> = taps.iter().map(|&t| t as f32).collect();
        let kernel = PyramidKernel::new(&taps32, origin, false);
        for b in Backend::available() {
            let (mut r, mut g, mut bl) = (Plane::default(), Plane::default(), Plane::default());
            pyr_down_rgb8(b, &rgb, [&mut r, &mut g, &mut bl], &kernel, &mut PyrScratch::default()).unwrap();
            for (c, got) in [r, g, bl].iter().enumerate() {
                let chan = rgb.map(|p| p[c] as f32 / 255.0);
                let want = pyr_down_direct(&chan, taps, origin);
                assert!(max_abs_diff(got, &want) < 2e-6, "channel {c} {b:?} taps {taps:?}");
            }
        }
    }
}

#[test]
fn separable_filters_match_direct_2d() {
    let src = noise(53, 41, 3);
    let kx = [0.1f32, -0.4, 0.7, 1.0, 0.3, -0.2, 0.05];
    let ky = [0.2f32, 0.5, 1.0, 0.5, 0.2];
    let k2: Vec<f32> = ky.iter().flat_map(|a| kx.iter().map(move |b| a * b)).collect();
    for border in [Border::Zero, Border::Clamp] {
        let want = correlate_2d_direct(&src, &k2, kx.len(), ky.len(), border);
        for b in Backend::available() {
            let mut dst = Plane::default();
            sep_filter(b, &src, &mut dst, &kx, &ky, border, &mut FilterScratch::default()).unwrap();
            assert!(max_abs_diff(&dst, &want) < 1e-5, "{border:?} {b:?}");
        }
    }
    // symmetric and antisymmetric kernels take the folded path
    for k in [[0.1f32, 0.3, 1.0, 0.3, 0.1], [-0.2f32, -0.5, 0.0, 0.5, 0.2]] {
        let want = correlate_2d_direct(&src, &k, 5, 1, Border::Clamp);
        let mut dst = Plane::default();
        filter_rows(Backend::Auto, &src, &mut dst, &k, Border::Clamp, &mut FilterScratch::default()).unwrap();
        assert!(max_abs_diff(&dst, &want) < 1e-5);
        let want = correlate_2d_direct(&src, &k, 1, 5, Border::Zero);
        filter_cols(Backend::Auto, &src, &mut dst, &k, Border::Zero, &mut FilterScratch::default()).unwrap();
        assert!(max_abs_diff(&dst, &want) < 1e-5);
    }
    let mut dst = Plane::default();
    assert!(sep_filter(
        Backend::Auto,
        &src,
        &mut dst,
        &[1.0, 1.0],
        &[1.0],
        Border::Zero,
        &mut FilterScratch::default()
    )
    .is_err());
}

#[test]
fn filtering_an_8_bit_rectangle_equals_converting_it_first() {
    let img = Plane::from_fn(67, 45, |x, y| ((x * 37 + y * 11 + x * y) % 256) as u8);
    let k = gaussian_kernel(1.5).unwrap();
    let skew = [0.1f32, -0.4, 0.7, 1.0, 0.3];
    for rect in [[0, 0, 67, 45], [5, 3, 60, 41], [20, 10, 29, 12]] {
        let [x0, y0, x1, y1] = rect;
        let grey = Plane::from_fn(x1 - x0, y1 - y0, |x, y| f32::from(img.get(x0 + x, y0 + y)));
        for b in Backend::available() {
            for (kx, border) in [(&k[..], Border::Clamp), (&skew[..], Border::Zero)] {
                let (mut want, mut got) = (Plane::default(), Plane::default());
                sep_filter(b, &grey, &mut want, kx, &k, border, &mut FilterScratch::default()).unwrap();
                sep_filter_u8(b, &img, rect, &mut got, kx, &k, border, &mut FilterScratch::default()).unwrap();
                assert_eq!(got, want, "{rect:?} {b:?} {border:?}");
            }
        }
    }
    let mut dst = Plane::default();
    for bad in [[0, 0, 68, 45], [10, 5, 10, 9], [3, 40, 9, 30]] {
        let r = sep_filter_u8(Backend::Auto, &img, bad, &mut dst, &k, &k, Border::Clamp, &mut FilterScratch::default());
        assert!(r.is_err(), "{bad:?}");
    }
    let even = [0.5f32, 0.5];
    let r = sep_filter_u8(
        Backend::Auto,
        &img,
        [0, 0, 9, 9],
        &mut dst,
        &even,
        &k,
        Border::Clamp,
        &mut FilterScratch::default(),
    );
    assert!(r.is_err());
}

#[test]
fn preserving_filter_matches_direct_renormalized_sum() {
    let g: Vec<f32> = (-14i32..=14).map(|i| (-(i * i) as f32 / 200.0).exp()).collect();
    let total: f64 = g.iter().map(|&v| v as f64).sum();
    for (w, h) in [(40, 30), (20, 15), (7, 3)] {
        let src = noise(w, h, 11);
        let want = Plane::from_fn(w, h, |x, y| {
            let (mut acc, mut sx, mut sy) = (0.0f64, 0.0f64, 0.0f64);
            for (j, &ky) in g.iter().enumerate() {
                let yy = y as isize + j as isize - 14;
                if yy >= 0 && yy < h as isize {
                    sy += ky as f64;
                }
            }
            for (i, &kx) in g.iter().enumerate() {
                let xx = x as isize + i as isize - 14;
                if xx >= 0 && xx < w as isize {
                    sx += kx as f64;
                }
            }
            for (j, &ky) in g.iter().enumerate() {
                for (i, &kx) in g.iter().enumerate() {
                    let (xx, yy) = (x as isize + i as isize - 14, y as isize + j as isize - 14);
                    if xx >= 0 && yy >= 0 && xx < w as isize && yy < h as isize {
                        acc += (kx * ky) as f64 * src.get(xx as usize, yy as usize) as f64;
                    }
                }
            }
            (acc * (total / sx) * (total / sy)) as f32
        });
        for b in Backend::available() {
            let mut f = PreservingFilter::new(&g, w, h).unwrap();
            let mut dst = Plane::default();
            f.apply(b, &src, &mut dst).unwrap();
            assert!(max_abs_diff(&dst, &want) < 1e-4, "{w}x{h} {b:?} {}", max_abs_diff(&dst, &want));
        }
        // A constant map stays constant: the border creates no false maxima.
        let c = Plane::from_fn(w, h, |_, _| 3.0f32);
        let mut f = PreservingFilter::new(&g, w, h).unwrap();
        let mut dst = Plane::default();
        f.apply(Backend::Auto, &c, &mut dst).unwrap();
        let (mn, mx) = dst.min_max();
        assert!((mx - mn) < 1e-4 * mx, "{w}x{h}: {mn}..{mx}");
    }
}

#[test]
fn nearest_resize_reproduces_octave_indices() {
    // Indices (1-based) printed by GNU Octave 7.3 + image 2.14 `imresize(A, [30 40], 'nearest')`.
    let cases: [(usize, usize, Vec<usize>); 4] = [
        (7, 30, vec![1, 1, 1, 1, 2, 2, 2, 2, 2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 6, 6, 6, 6, 6, 7, 7, 7, 7]),
        (120, 30, (0..30).map(|k| 4 * k + 3).collect()),
        (15, 30, (0..30).map(|k| k / 2 + 1).collect()),
        (3, 30, (0..30).map(|k| k / 10 + 1).collect()),
    ];
    for (n_in, n_out, want) in cases {
        let src = Plane::from_fn(1, n_in, |_, y| (y + 1) as f32);
        let out = resize(Backend::Scalar, &src, 1, n_out, ResampleMethod::Nearest).unwrap();
        let got: Vec<usize> = (0..n_out).map(|y| out.get(0, y) as usize).collect();
        assert_eq!(got, want, "{n_in} -> {n_out}");
    }
    let src = Plane::from_fn(5, 1, |x, _| (x + 1) as f32);
    let out = resize(Backend::Scalar, &src, 40, 1, ResampleMethod::Nearest).unwrap();
    let got: Vec<usize> = (0..40).map(|x| out.get(x, 0) as usize).collect();
    assert_eq!(got, (0..40).map(|k| k / 8 + 1).collect::<Vec<_>>());
}

#[test]
fn bilinear_resize_properties() {
    let src = noise(17, 9, 5);
    assert_eq!(resize(Backend::Scalar, &src, 17, 9, ResampleMethod::Bilinear).unwrap(), src);
    // A linear ramp stays a ramp away from the clamped borders.
    let ramp = Plane::from_fn(10, 4, |x, _| x as f32);
    let up = resize(Backend::Scalar, &ramp, 40, 4, ResampleMethod::Bilinear).unwrap();
    for x in 4..36 {
        let want = (x as f32 + 0.5) * 10.0 / 40.0 - 0.5;
        assert!((up.get(x, 2) - want).abs() < 1e-5);
    }
    assert!(resize(Backend::Scalar, &src, 0, 3, ResampleMethod::Bilinear).is_err());
}

#[test]
fn level_sizes_follow_floor_halving() {
    let s = level_sizes(640, 480, 9);
    assert_eq!(s[4], (40, 30));
    assert_eq!(s[8], (2, 1));
    let mut dst = Plane::default();
    assert!(pyr_down(Backend::Auto, &Plane::new(1, 5), &mut dst, &PyramidKernel::itti(), &mut PyrScratch::default())
        .is_err());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn pyramid_never_panics_and_stays_in_range(w in 2usize..90, h in 2usize..90, seed in 0u64..1000) {
        let src = noise(w, h, seed);
        let mut dst = Plane::default();
        pyr_down(Backend::Auto, &src, &mut dst, &PyramidKernel::stb(), &mut PyrScratch::default()).unwrap();
        prop_assert_eq!(dst.size(), (w / 2, h / 2));
        let (mn, mx) = dst.min_max();
        prop_assert!(mn >= -1e-6 && mx <= 1.0 + 1e-6);
    }

    #[test]
    fn plane_from_vec_checks_length(w in 0usize..20, h in 0usize..20, extra in 0usize..3, short in proptest::bool::ANY) {
        let n = (w * h + extra).saturating_sub(if short && w * h > 0 { w * h } else { 0 });
        let r = Plane::from_vec(w, h, vec![0f32; n]);
        prop_assert_eq!(r.is_ok(), n >= w * h);
    }
}

#[test]
fn preserving_filter_on_lanes_equals_one_map_at_a_time() {
    // A symmetric kernel and a lopsided one.
    let g: Vec<f32> = (-14i32..=14).map(|i| (-(i * i) as f32 / 200.0).exp()).collect();
    let lopsided: Vec<f32> = (-3i32..=3).map(|i| (-((i - 1) * (i - 1)) as f32 / 4.0).exp()).collect();
    for ((w, h), g) in
        [(40, 30), (37, 25), (3, 2), (40, 30), (11, 9)].into_iter().zip([&g, &g, &g, &lopsided, &lopsided])
    {
        let maps: Vec<Plane<f32>> = (0..8).map(|m| noise(w, h, 100 + m)).collect();
        let lanes = Plane::from_fn(w, h, |x, y| std::array::from_fn(|l| maps[l].get(x, y)));
        for b in Backend::available() {
            let mut f = PreservingFilter::new(g, w, h).unwrap();
            let mut out = Plane::default();
            f.apply_lanes(b, &lanes, &mut out).unwrap();
            for (l, m) in maps.iter().enumerate() {
                let mut one = Plane::default();
                f.apply(b, m, &mut one).unwrap();
                let lane = out.map(|p| p[l]);
                let rel = max_abs_diff(&lane, &one) / one.min_max().1;
                assert!(rel < 1e-5, "{w}x{h} lane {l} {b:?}: relative difference {rel:e}");
            }
        }
    }
}
