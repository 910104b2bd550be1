//! `ocellus retina learn` as a user runs it: the outputs, and a run stopped and resumed from
//! its checkpoint.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

mod common;
use common::{ocellus, tmpdir};

fn figures(dir: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("retina.json")).unwrap()).unwrap()
}

#[test]
fn learn_writes_the_model_the_pictures_and_the_figures_and_resumes() {
    let out = tmpdir("retina");
    let run = |extra: &[&str]| {
        let o = ocellus()
            .args(["retina", "learn", "--experiment", "1", "--small", "--baseline", "false", "--tolerance", "0"])
            .args(extra)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        assert!(o.status.success(), "{} {}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    };
    run(&["--iterations", "30", "--checkpoint-every", "10"]);
    for f in ["S.npy", "M.npy", "P.npy", "disc.npy", "fields.png", "layout.png", "predictors.png", "cost.png"] {
        assert!(out.join(f).is_file(), "{f}");
    }
    assert!(out.join("flow_zoom_out.png").is_file() && out.join("flow_rotate_right.png").is_file());
    let s = ocellus_io::npy::read(out.join("S.npy")).unwrap();
    assert_eq!(s.shape, vec![16, 481]);
    assert!(s.data.iter().all(|&v| v >= 0.0 && v.is_finite()));
    let j = figures(&out);
    assert_eq!(j["runs"][0]["iterations"], 30);
    let cost30 = j["runs"][0]["cost"].as_f64().unwrap();
    // Resumed to 60 iterations in all: the cost goes on falling from where it stopped.
    run(&["--iterations", "60", "--resume"]);
    let j = figures(&out);
    assert_eq!(j["runs"][0]["iterations"], 60);
    assert!(j["runs"][0]["cost"].as_f64().unwrap() < cost30);
    // The same run twice pools to its own index, over twice its fields, with an interval
    // that narrows as 1 / sqrt(n - 3) in Fisher's z.
    let o = ocellus().args(["retina", "summary", "--json"]).arg(&out).arg(&out).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let sum: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let (r, n) = (j["layout"]["fovea_index"].as_f64().unwrap(), j["layout"]["fields"].as_array().unwrap().len());
    let pooled = &sum["pooled"][0]["fovea_index"];
    assert_eq!(sum["pooled"].as_array().unwrap().len(), 1);
    assert!((pooled["r"].as_f64().unwrap() - r).abs() < 1e-9);
    assert_eq!(pooled["pairs"].as_u64().unwrap() as usize, 2 * n);
    let half = |ci: &serde_json::Value| {
        let (lo, hi) = (ci[0].as_f64().unwrap(), ci[1].as_f64().unwrap());
        (hi.atanh() - lo.atanh()) / 2.0
    };
    let one = half(&j["layout"]["fovea_index_ci95"]);
    assert!((one - 1.959964 / ((n - 3) as f64).sqrt()).abs() < 1e-5, "{one}");
    assert!((half(&pooled["ci95"]) - one / 2f64.sqrt()).abs() < 1e-5);
    // Another experiment's checkpoint is refused.
    let o = ocellus()
        .args(["retina", "learn", "--experiment", "1", "--small", "--actions", "translation", "--resume", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("another run"), "{}", String::from_utf8_lossy(&o.stderr));
}
