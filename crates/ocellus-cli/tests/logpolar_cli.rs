//! `ocellus logpolar` as a user runs it.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

mod common;
use common::{ocellus, tmpdir};

#[test]
fn logpolar_writes_the_cortex_its_inverse_and_the_geometry() {
    let out = tmpdir("logpolar");
    let img = ocellus_testdata::asset("chelsea.png");
    let o = ocellus()
        .arg("logpolar")
        .arg(&img)
        .args(["--rings", "64", "--sectors", "96", "--fovea", "200,140", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{stdout} {}", String::from_utf8_lossy(&o.stderr));
    let cortex = image::open(out.join("cortex.png")).unwrap();
    let info: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("logpolar.json")).unwrap()).unwrap();
    let rows = info["cortex_rows"].as_u64().unwrap() as u32;
    assert_eq!((cortex.width(), cortex.height()), (96, rows));
    assert_eq!(rows as u64, 64 + info["fovea_rows"].as_u64().unwrap());
    let inverse = image::open(out.join("inverse.png")).unwrap();
    assert_eq!((inverse.width(), inverse.height()), (451, 300));
    let ratio = info["compression_ratio"].as_f64().unwrap();
    assert!((ratio - 451.0 * 300.0 / (96.0 * rows as f64)).abs() < 1e-9, "{ratio}");

    // The same image registered with itself: no rotation, unit scale.
    let o = ocellus().args(["logpolar", "register"]).arg(&img).arg(&img).arg("--json").output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(r["angle_deg"].as_f64().unwrap().abs() < 0.01 && (r["scale"].as_f64().unwrap() - 1.0).abs() < 1e-3, "{r}");

    // Bad input: a clear error, not a panic.
    let o = ocellus().args(["logpolar", "/nonexistent.png"]).output().unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("error"), "{}", String::from_utf8_lossy(&o.stderr));
    let o = ocellus().arg("logpolar").arg(&img).args(["--sectors", "0"]).output().unwrap();
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("sectors"));
}

#[test]
fn logpolar_runs_every_frame_of_a_folder_through_one_map() {
    let base = tmpdir("logpolar-stream");
    let (frames, out) = (base.join("frames"), base.join("out"));
    std::fs::create_dir_all(&frames).unwrap();
    for k in 0..3 {
        std::fs::copy(ocellus_testdata::asset("chelsea.png"), frames.join(format!("f{k}.png"))).unwrap();
    }
    let o = ocellus()
        .arg("logpolar")
        .arg(&frames)
        .args(["--rings", "32", "--sectors", "48", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for k in 0..3 {
        let c = image::open(out.join(format!("cortex/{k:05}.png"))).unwrap();
        assert_eq!(c.width(), 48);
    }
    // The same picture gives the same cortical image in every frame.
    let (a, b) =
        (image::open(out.join("cortex/00000.png")).unwrap(), image::open(out.join("cortex/00002.png")).unwrap());
    assert_eq!(a.as_bytes(), b.as_bytes());
    let info: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("logpolar.json")).unwrap()).unwrap();
    assert_eq!(info["frames"].as_u64(), Some(3));
}
