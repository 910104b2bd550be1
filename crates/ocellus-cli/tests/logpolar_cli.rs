//! `ocellus logpolar` as a user runs it.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

use std::process::Command;

fn ocellus() -> Command {
    Command::new(env!("CARGO_BIN_EXE_ocellus"))
}

#[test]
fn logpolar_writes_the_cortex_its_inverse_and_the_geometry() {
    let out = std::env::temp_dir().join(format!("ocellus-cli-{}-logpolar", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
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
