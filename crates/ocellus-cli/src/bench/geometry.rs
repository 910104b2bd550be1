//! `ocellus bench geometry`: DLT and Zhang calibration, triangulation, block matching and
//! semi-global matching, one thread.

use super::timing::median;
use anyhow::Result;
use nalgebra::{Rotation3, Vector3};
use ocellus_geometry::block_matching::{block_match, BlockMatching};
use ocellus_geometry::camera::{Intrinsics, PinholeCamera};
use ocellus_geometry::distortion::Distortion;
use ocellus_geometry::dlt::dlt;
use ocellus_geometry::sgm::{Sgm, SgmMatcher, SgmPaths};
use ocellus_geometry::triangulate::{n_view, two_view_seed};
use ocellus_geometry::zhang::{calibrate, project_view, PlanarView, Pose, ZhangOptions};
use ocellus_image::rng::SplitMix64;
use ocellus_image::{Backend, Plane};
use serde_json::json;
use std::time::Instant;

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Runs the benchmark; `reps` repetitions of each timing (median reported).
pub fn run(json_out: bool, backend: Backend, reps: usize) -> Result<()> {
    let k = Intrinsics { fx: 810.0, fy: 790.0, cx: 322.0, cy: 236.0, skew: 0.0 };
    let c1 = PinholeCamera {
        k,
        r: *Rotation3::from_euler_angles(0.2, -0.3, 0.1).matrix(),
        t: Vector3::new(0.05, -0.1, 2.0),
    };
    let c2 = PinholeCamera {
        k,
        r: *Rotation3::from_euler_angles(0.2, -0.1, 0.1).matrix(),
        t: Vector3::new(-0.4, -0.1, 2.0),
    };
    let mut rng = SplitMix64::new(9);
    let mut pts = Vec::new();
    while pts.len() < 100_000 {
        let x = Vector3::new(rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5) * 0.8;
        if let (Ok((a, _)), Ok((b, _))) = (c1.project(&x), c2.project(&x)) {
            pts.push((x, [a.x + 0.5 * rng.normal(), a.y + 0.5 * rng.normal()], [b.x, b.y]));
        }
    }
    let p3: Vec<[f64; 3]> = pts[..100].iter().map(|p| [p.0.x, p.0.y, p.0.z]).collect();
    let p2: Vec<[f64; 2]> = pts[..100].iter().map(|p| p.1).collect();
    let mut t_dlt: Vec<f64> = (0..reps.max(20) * 10)
        .map(|_| {
            let t = Instant::now();
            let _ = dlt(&p3, &p2);
            ms(t)
        })
        .collect();
    let (m1, m2) = (c1.projection_matrix(), c2.projection_matrix());
    let mut t_seed = Vec::new();
    let mut t_nview = Vec::new();
    for _ in 0..reps.clamp(3, 10) {
        let t = Instant::now();
        let ok = pts.iter().filter(|p| two_view_seed(&m1, p.1, &m2, p.2).is_ok()).count();
        t_seed.push(ms(t));
        let t = Instant::now();
        let ok2 = pts.iter().filter(|p| n_view(&[(&m1, p.1), (&m2, p.2)]).is_ok()).count();
        t_nview.push(ms(t));
        debug_assert_eq!(ok, ok2);
    }
    // Block matching on a 741x500 random-texture pair with two depths (the motorcycle size).
    let (w, h) = (741, 500);
    let tex: Vec<u8> = (0..(w + 80) * h).map(|_| (rng.next_u64() & 255) as u8).collect();
    let left = Plane::from_fn(w, h, |x, y| tex[y * (w + 80) + x + 40]);
    let right = Plane::from_fn(w, h, |x, y| tex[y * (w + 80) + x + 40 + if x > w / 2 { 30 } else { 10 }]);
    let mut t_bm: Vec<f64> = (0..reps.clamp(3, 10))
        .map(|_| {
            let t = Instant::now();
            let _ = block_match(&left, &right, &BlockMatching { backend, ..BlockMatching::default() });
            ms(t)
        })
        .collect();
    // SGM, steady state (the matcher's buffers reused), on the same pair.
    let mut t_sgm = Vec::new();
    for paths in [SgmPaths::Eight, SgmPaths::Four] {
        let mut m = SgmMatcher::new(Sgm { paths, backend, ..Sgm::default() }, w, h)?;
        m.compute(&left, &right)?;
        let mut t: Vec<f64> = (0..reps.clamp(3, 10))
            .map(|_| {
                let t = Instant::now();
                let _ = m.compute(&left, &right);
                ms(t)
            })
            .collect();
        t_sgm.push(median(&mut t));
    }
    let mut t_zhang = zhang_times(reps, &mut rng);
    let v = json!({
        "backend": backend.name(),
        "ms_dlt_100_points": median(&mut t_dlt),
        "ms_triangulate_100k_two_view_seed": median(&mut t_seed),
        "ms_triangulate_100k_two_view_svd": median(&mut t_nview),
        "ms_block_matching_741x500_64disp": median(&mut t_bm),
        "ms_sgm_8_paths_741x500_64disp": t_sgm[0],
        "ms_sgm_4_paths_741x500_64disp": t_sgm[1],
        "ms_zhang_10_views_9x6": median(&mut t_zhang),
    });
    if json_out {
        outln!("{v}");
    } else {
        outln!("geometry benchmark, one thread, medians:");
        for (k, val) in v.as_object().into_iter().flatten() {
            outln!("  {k:<36} {:.4} ms", val.as_f64().unwrap_or(f64::NAN));
        }
    }
    Ok(())
}

/// Times Zhang calibration (closed form + Levenberg-Marquardt with k1, k2, p1, p2, k3) on 10
/// views of a 9x6 board with 0.5 px noise.
fn zhang_times(reps: usize, rng: &mut SplitMix64) -> Vec<f64> {
    let k = Intrinsics { fx: 812.0, fy: 806.0, cx: 318.0, cy: 243.0, skew: 0.0 };
    let d = Distortion { k1: -0.25, k2: 0.08, k3: 0.0, p1: 0.001, p2: -0.0008 };
    let object: Vec<[f64; 2]> = (0..6).flat_map(|r| (0..9).map(move |c| [c as f64 * 25.0, r as f64 * 25.0])).collect();
    let mut views = Vec::new();
    while views.len() < 10 {
        let r =
            Rotation3::from_euler_angles((rng.unit() - 0.5) * 1.0, (rng.unit() - 0.5) * 1.0, (rng.unit() - 0.5) * 0.6);
        let t = Vector3::new((rng.unit() - 0.5) * 80.0, (rng.unit() - 0.5) * 60.0, 350.0 + 200.0 * rng.unit())
            - r * Vector3::new(100.0, 62.5, 0.0);
        let Some(img) = project_view(&k, &d, &Pose { r: *r.matrix(), t }, &object) else { continue };
        if img.iter().all(|p| p[0] >= 0.0 && p[1] >= 0.0 && p[0] <= 639.0 && p[1] <= 479.0) {
            let image = img.iter().map(|p| [p[0] + 0.5 * rng.normal(), p[1] + 0.5 * rng.normal()]).collect();
            views.push(PlanarView { object: object.clone(), image });
        }
    }
    (0..reps.max(20))
        .map(|_| {
            let t = Instant::now();
            let _ = calibrate(&views, &ZhangOptions::default());
            ms(t)
        })
        .collect()
}
