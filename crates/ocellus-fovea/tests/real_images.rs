//! The log-polar map's properties, registration and vergence on the project's real images
//! (SPEC 4.2, 4.3). Run with `--nocapture` to see the figures.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use ocellus_fovea::logpolar::{Fields, LogPolarConfig, LogPolarMap};
use ocellus_fovea::register::{register, Mode, RegisterOptions};
use ocellus_fovea::vergence::{vergence, VergenceOptions};
use ocellus_image::resample::sample_bilinear;
use ocellus_image::Plane;

fn grey(name: &str) -> Plane<u8> {
    ocellus_io::read_image(ocellus_testdata::data_file(name)).unwrap().to_luma8()
}

fn rms(a: &Plane<f32>, b: &Plane<f32>, rows: std::ops::Range<usize>) -> f64 {
    let mut s = 0.0;
    let mut n = 0usize;
    for y in rows {
        for x in 0..a.width() {
            s += (a.get(x, y) as f64 - b.get(x, y) as f64).powi(2);
            n += 1;
        }
    }
    (s / n as f64).sqrt()
}

/// `img` rotated by `angle` rad and scaled by `scale` about its centre, each output pixel the
/// mean of 4x4 bilinear samples (so that shrinking does not alias).
fn warp(img: &Plane<f32>, angle: f64, scale: f64) -> Plane<f32> {
    let (w, h) = img.size();
    let (cx, cy) = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
    let (s, c) = angle.sin_cos();
    Plane::from_fn(w, h, |x, y| {
        let mut acc = 0.0;
        for j in 0..4 {
            for i in 0..4 {
                let (dx, dy) = (x as f64 + (i as f64 - 1.5) / 4.0 - cx, y as f64 + (j as f64 - 1.5) / 4.0 - cy);
                let (u, v) = ((c * dx + s * dy) / scale + cx, (-s * dx + c * dy) / scale + cy);
                if u >= 0.0 && v >= 0.0 && u <= (w - 1) as f64 && v <= (h - 1) as f64 {
                    acc += sample_bilinear(img, u as f32, v as f32);
                }
            }
        }
        acc / 16.0
    })
}

fn to_u8(p: &Plane<f32>) -> Plane<u8> {
    p.map(|v| v.round().clamp(0.0, 255.0) as u8)
}

#[test]
fn rotation_is_a_cyclic_shift_and_scaling_a_ring_shift() {
    let img = grey("camera.png"); // 512x512
    let (w, h) = img.size();
    let cfg = LogPolarConfig::for_image(w, h);
    let map = LogPolarMap::new(&cfg, w, h).unwrap();
    let (s, f, rows) = (map.sectors(), cfg.fovea_rings, map.rows());
    let base = map.sample_grey(&img).unwrap();
    println!(
        "camera.png {w}x{h} -> {rows} rows x {s} sectors: compression {:.2}, {} table entries ({:.1} per cell)",
        map.compression_ratio(),
        map.table_entries(),
        map.table_entries() as f64 / (rows * s) as f64
    );
    assert!((map.compression_ratio() - (w * h) as f64 / (rows * s) as f64).abs() < 1e-9);

    // A quarter turn about the centre ((n - 1) / 2) permutes the pixels exactly: the cortical
    // image shifts by S / 4 columns, to rounding of the table.
    let quarter = Plane::from_fn(w, h, |x, y| img.get(y, h - 1 - x)); // out(x, y) = in(y, n-1-x)
    let q = map.sample_grey(&quarter).unwrap();
    let rolled = |p: &Plane<f32>, k: usize| Plane::from_fn(s, rows, |x, y| p.get((x + s - k % s) % s, y));
    let e = rms(&q, &rolled(&base, s / 4), 0..rows);
    let e_none = rms(&q, &base, 0..rows);
    println!("quarter turn: rms vs shifted by S/4 {e:.4}, vs unshifted {e_none:.2} grey levels");
    assert!(e < 0.05, "{e}");

    // k sectors (not a multiple of 90 degrees): the input is resampled, so allow its blur.
    let f32img = img.map(|v| v as f32);
    for k in [5usize, 37] {
        let turned = to_u8(&warp(&f32img, k as f64 * std::f64::consts::TAU / s as f64, 1.0));
        let t = map.sample_grey(&turned).unwrap();
        // Outer rings lose corners of the rotated square to the black fill: compare inside.
        let inner = 0..rows - 4;
        let e = rms(&t, &rolled(&base, k), inner.clone());
        let e_off = rms(&t, &rolled(&base, k + 1), inner.clone());
        let e_none = rms(&t, &base, inner);
        println!("{k} sectors: rms vs shifted {e:.2}, vs shifted by {} {e_off:.2}, unshifted {e_none:.2}", k + 1);
        assert!(e < 0.25 * e_off && e < 0.15 * e_none, "{e} {e_off} {e_none}");
    }

    // Scaling by the ring ratio a: log ring i of the original is ring i + 1 of the scaled.
    let a = cfg.ring_ratio();
    let big = to_u8(&warp(&f32img, 0.0, a));
    let b = map.sample_grey(&big).unwrap();
    let log_rows = f + 2..rows - 2;
    let shifted = Plane::from_fn(s, rows, |x, y| if y >= 1 { base.get(x, y - 1) } else { 0.0 });
    let e = rms(&b, &shifted, log_rows.clone());
    let e_none = rms(&b, &base, log_rows.clone());
    let two = Plane::from_fn(s, rows, |x, y| if y >= 2 { base.get(x, y - 2) } else { 0.0 });
    let e_two = rms(&b, &two, log_rows);
    println!("scaled by a = {a:.5}: rms vs one ring out {e:.2}, vs none {e_none:.2}, vs two {e_two:.2}");
    assert!(e < 0.35 * e_none && e < 0.35 * e_two, "{e} {e_none} {e_two}");
}

#[test]
fn area_fields_are_closer_to_a_supersampled_reference_than_point_sampling() {
    // Gravel: fine, high-contrast texture everywhere.
    let img = grey("gravel.png");
    let (w, h) = img.size();
    let cfg = LogPolarConfig { rings: 64, sectors: 64, ..LogPolarConfig::for_image(w, h) };
    let map = LogPolarMap::new(&cfg, w, h).unwrap();
    let area =
        LogPolarMap::new(&LogPolarConfig { fields: Fields::Area, min_field_texels: 2.0, max_level: 3, ..cfg }, w, h)
            .unwrap();
    let exact = area.sample_grey(&img).unwrap();
    let ours = map.sample_grey(&img).unwrap();
    let nearest = map.sample_point_grey(&img, false).unwrap();
    let bilinear = map.sample_point_grey(&img, true).unwrap();
    // Reference: the mean over each cell of the bilinear image, 48 x 48 samples per cell
    // weighted by radius (the area element), independent of the table and the pyramid.
    let f = img.map(|v| v as f32);
    let reference = Plane::from_fn(map.sectors(), map.rows(), |sx, row| {
        let (r0, r1) = map.row_radii(row);
        let dt = std::f64::consts::TAU / map.sectors() as f64;
        let (mut acc, mut wsum) = (0.0, 0.0);
        for m in 0..48 {
            let r = r0 + (m as f64 + 0.5) * (r1 - r0) / 48.0;
            for n in 0..48 {
                let t = sx as f64 * dt + (n as f64 + 0.5) * dt / 48.0;
                let (x, y) = (cfg.centre[0] + r * t.cos(), cfg.centre[1] + r * t.sin());
                acc += r * sample_bilinear(&f, x as f32, y as f32) as f64;
                wsum += r;
            }
        }
        (acc / wsum) as f32
    });
    let all = 0..map.rows();
    let ea = rms(&exact, &reference, all.clone());
    let (eo, en, eb) =
        (rms(&ours, &reference, all.clone()), rms(&nearest, &reference, all.clone()), rms(&bilinear, &reference, all));
    // The periphery (outer half of the rings) is where point sampling aliases.
    let outer = map.rows() / 2..map.rows();
    let (po, pn, pb) = (
        rms(&ours, &reference, outer.clone()),
        rms(&nearest, &reference, outer.clone()),
        rms(&bilinear, &reference, outer),
    );
    println!(
        "rms vs supersampled reference, all rows: pyramid fields {eo:.2}, area fields {ea:.2}, nearest {en:.2}, bilinear {eb:.2} grey levels"
    );
    println!("outer half: pyramid fields {po:.2}, nearest {pn:.2}, bilinear {pb:.2}");
    assert!(ea < 0.2 * eb && eo < 0.5 * eb && eb < en, "{ea} {eo} {eb} {en}");
    assert!(po < 0.5 * pb, "{po} {pb}");
}

#[test]
fn rotation_and_scale_are_recovered_from_real_images() {
    let cases: [(f64, f64); 10] = [
        (0.0, 1.0),
        (12.5, 1.0),
        (33.0, 0.5),
        (45.0, 0.8),
        (90.0, 1.25),
        (123.4, 0.62),
        (150.0, 2.0),
        (180.0, 1.6),
        (7.7, 1.9),
        (66.6, 1.1),
    ];
    for name in ["camera.png", "astronaut.png"] {
        let a = grey(name).map(|v| v as f32);
        let (mut angle_err, mut scale_err) = (0.0, 0.0);
        for &(deg, s) in &cases {
            let b = warp(&a, deg.to_radians(), s);
            let r = register(&a, &b, &RegisterOptions::default()).unwrap();
            let de =
                (r.angle_deg - deg).abs().min((r.angle_deg - deg + 360.0).abs()).min((r.angle_deg - deg - 360.0).abs());
            let se = (r.scale / s - 1.0).abs();
            println!("{name}: {deg:6.1} deg x {s:.2} -> {:8.3} deg x {:.4} (peak {:.3})", r.angle_deg, r.scale, r.peak);
            angle_err += de;
            scale_err += se;
        }
        let n = cases.len() as f64;
        println!("{name}: mean angle error {:.3} deg, mean scale error {:.3} %", angle_err / n, 100.0 * scale_err / n);
        assert!(angle_err / n <= 0.5 && scale_err / n <= 0.01, "{} {}", angle_err / n, scale_err / n);
    }
}

#[test]
fn the_spectrum_mode_also_survives_a_translation() {
    let a = grey("astronaut.png").map(|v| v as f32);
    let (w, h) = a.size();
    for &(deg, s, tx, ty) in &[(20.0f64, 1.2f64, 9.0f64, -6.0f64), (140.0, 0.85, -12.0, 4.0)] {
        let rs = warp(&a, deg.to_radians(), s);
        let b = Plane::from_fn(w, h, |x, y| {
            let (u, v) = (x as f64 - tx, y as f64 - ty);
            if u < 0.0 || v < 0.0 || u > (w - 1) as f64 || v > (h - 1) as f64 {
                0.0
            } else {
                sample_bilinear(&rs, u as f32, v as f32)
            }
        });
        let r = register(&a, &b, &RegisterOptions { mode: Mode::Spectrum, ..Default::default() }).unwrap();
        println!("spectrum mode: {deg} deg x {s} + ({tx}, {ty}) -> {r:?}");
        let de = (r.angle_deg - deg).abs().min(360.0 - (r.angle_deg - deg).abs());
        assert!(de < 1.0 && (r.scale / s - 1.0).abs() < 0.02, "{r:?}");
        assert!((r.translation[0] - tx).abs() < 1.5 && (r.translation[1] - ty).abs() < 1.5, "{r:?}");
    }
}

#[test]
fn vergence_finds_the_motorcycle_disparity_at_the_fovea() {
    let left = grey("motorcycle_left.png");
    let right = grey("motorcycle_right.png");
    let truth = ocellus_io::pfm::read(ocellus_testdata::data_file("motorcycle_disp.pfm")).unwrap();
    let opts = VergenceOptions { max_disparity: 80, ..Default::default() };
    let (w, h) = left.size();
    let mut tested = 0;
    let mut worst: f64 = 0.0;
    // Gaze points on a grid, kept where the truth is known and smooth within 10 px and the
    // left image has texture there.
    for gy in (40..h - 40).step_by(40) {
        for gx in (110..w - 40).step_by(40) {
            let mut vals = Vec::new();
            for y in gy - 10..=gy + 10 {
                for x in gx - 10..=gx + 10 {
                    vals.push(truth.get(x, y) as f64);
                }
            }
            if vals.iter().any(|v| !v.is_finite()) {
                continue;
            }
            let (lo, hi) = vals.iter().fold((f64::MAX, f64::MIN), |(a, b), &v| (a.min(v), b.max(v)));
            let mean = vals.iter().sum::<f64>() / vals.len() as f64;
            let tex: Vec<f64> = (gx - 10..=gx + 10).map(|x| left.get(x, gy) as f64).collect();
            let tm = tex.iter().sum::<f64>() / tex.len() as f64;
            let tsd = (tex.iter().map(|v| (v - tm).powi(2)).sum::<f64>() / tex.len() as f64).sqrt();
            if hi - lo > 1.5 || tsd < 4.0 {
                continue;
            }
            let v = vergence(&left, &right, [gx as f64, gy as f64], &opts).unwrap();
            let t = truth.get(gx, gy) as f64;
            println!(
                "gaze ({gx}, {gy}): disparity {:.2} px, truth {t:.2} (window mean {mean:.2}), score {:.3}",
                v.disparity_px, v.score
            );
            worst = worst.max((v.disparity_px - t).abs());
            tested += 1;
        }
    }
    println!("{tested} gaze points, worst error {worst:.2} px");
    assert!(tested >= 10, "{tested}");
    assert!(worst <= 1.0, "{worst}");
}
