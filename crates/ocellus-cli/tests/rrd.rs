//! `--rrd`: the Rerun logs of `attend`, `odometry` and `track`, read back with Rerun's own
//! decoder (feature `rerun`); without the feature the option is refused with advice.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

mod common;
use common::{ocellus, tmpdir};

#[cfg(not(feature = "rerun"))]
#[test]
fn without_the_feature_rrd_is_refused_with_advice() {
    let dir = tmpdir("rrd-off");
    let o = ocellus()
        .args(["attend", "/no/such/frames", "--out"])
        .arg(dir.join("out"))
        .arg("--rrd")
        .arg(dir.join("a.rrd"))
        .output()
        .unwrap();
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("--features rerun"), "{e}");
}

#[cfg(feature = "rerun")]
mod with_rerun {
    use super::*;
    use common::run;
    use std::collections::BTreeMap;
    use std::path::Path;

    /// Rows logged per entity path (a row: one log call at one time point), read back from
    /// the file with Rerun's decoder, and the number of recordings started.
    fn read_back(path: &Path) -> (BTreeMap<String, usize>, usize) {
        use rerun::external::re_log_types::LogMsg;
        let f = std::io::BufReader::new(std::fs::File::open(path).unwrap());
        let mut rows = BTreeMap::new();
        let mut stores = 0;
        for msg in re_log_encoding::DecoderApp::decode_eager(f).unwrap() {
            match msg.unwrap() {
                LogMsg::ArrowMsg(_, m) => {
                    let schema = m.batch.schema();
                    let entity = schema.metadata().get("rerun:entity_path").cloned().unwrap_or_default();
                    *rows.entry(entity).or_insert(0) += m.batch.num_rows();
                }
                LogMsg::SetStoreInfo(_) => stores += 1,
                LogMsg::BlueprintActivationCommand(_) => {}
            }
        }
        (rows, stores)
    }

    fn rows(log: &BTreeMap<String, usize>, entity: &str) -> usize {
        log.get(entity).copied().unwrap_or_else(|| panic!("{entity} not in the log: {:?}", log.keys()))
    }

    #[test]
    fn attend_logs_frames_maps_fixations_and_context() {
        let dir = tmpdir("rrd-attend");
        let seq = dir.join("seq");
        run(ocellus()
            .args(["generate", "attention", "--scenario", "sudden", "--frames", "12", "--event-frame", "8", "--out"])
            .arg(&seq));
        let rrd = dir.join("logs/attend.rrd");
        let s = run(ocellus()
            .arg("attend")
            .arg(seq.join("frames"))
            .args(["--no-overlays", "--no-video", "--out"])
            .arg(dir.join("out"))
            .arg("--rrd")
            .arg(&rrd));
        assert!(s.contains("attend.rrd"), "{s}");
        let (log, stores) = read_back(&rrd);
        assert_eq!(stores, 1);
        for e in ["/frame", "/maps/saliency", "/maps/surprise_bits", "/maps/inhibition", "/context/surprise_max_bits"] {
            assert_eq!(rows(&log, e), 12, "{e}: one row per frame");
        }
        // The chaos degree needs three frames.
        assert_eq!(rows(&log, "/context/chaos_bits"), 10);
        assert!(rows(&log, "/frame/fixation") >= 1 && rows(&log, "/frame/scanpath") >= 1);
    }

    #[test]
    fn odometry_logs_frames_flow_poses_and_drift() {
        let dir = tmpdir("rrd-odometry");
        let seq = dir.join("seq");
        run(ocellus().args(["synth", "ground", "--texture", "gravel", "--frames", "15", "--y4m", "--out"]).arg(&seq));
        let rrd = dir.join("odo.rrd");
        run(ocellus()
            .arg("odometry")
            .arg(seq.join("sequence.y4m"))
            .arg("--camera")
            .arg(seq.join("camera.toml"))
            .arg("--truth")
            .arg(seq.join("groundtruth.tum"))
            .arg("--out")
            .arg(dir.join("out"))
            .arg("--rrd")
            .arg(&rrd));
        let (log, _) = read_back(&rrd);
        for e in ["/camera", "/camera/flow_x5", "/world/estimate", "/world/truth"] {
            assert_eq!(rows(&log, e), 15, "{e}");
        }
        // The drift once the true path is 1 cm long; both whole paths, once.
        let drift = rows(&log, "/error/drift_percent");
        assert!((1..15).contains(&drift), "{drift}");
        assert_eq!(rows(&log, "/world/estimate/path"), 1);
        assert_eq!(rows(&log, "/world/truth/path"), 1);
    }

    #[test]
    fn track_logs_frames_particles_estimate_truth_and_errors() {
        let dir = tmpdir("rrd-track");
        let ball = dir.join("ball");
        run(ocellus()
            .args(["generate", "ball", "--trajectory", "throw", "--occlusion", "none", "--frames", "8", "--out"])
            .arg(&ball));
        let truth = std::fs::read_to_string(ball.join("truth.csv")).unwrap();
        let first: Vec<f64> = truth.lines().nth(1).unwrap().split(',').map(|v| v.parse().unwrap()).collect();
        let rrd = dir.join("track.rrd");
        run(ocellus()
            .arg("track")
            .arg(ball.join("frames"))
            .arg("--camera")
            .arg(ball.join("camera.toml"))
            .args(["--radius-m", "0.05", "--particles", "500", "--patch"])
            .arg(format!("{},{},{}", first[8], first[9], 0.8 * first[10]))
            .arg("--truth")
            .arg(ball.join("truth.csv"))
            .args(["--no-overlays", "--out"])
            .arg(dir.join("out"))
            .arg("--rrd")
            .arg(&rrd));
        let (log, _) = read_back(&rrd);
        for e in [
            "/frame",
            "/frame/particles",
            "/world/particles",
            "/frame/estimate",
            "/world/estimate",
            "/world/truth",
            "/filter/ess",
            "/filter/score",
            "/error/3d_m",
        ] {
            assert_eq!(rows(&log, e), 8, "{e}");
        }
    }

    #[test]
    fn an_unwritable_log_is_a_clear_error() {
        let dir = tmpdir("rrd-unwritable");
        let o = ocellus()
            .args(["attend", "/no/such/frames", "--rrd", "/proc/no/such.rrd", "--out"])
            .arg(dir.join("out"))
            .output()
            .unwrap();
        assert!(!o.status.success());
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(e.contains("/proc/no"), "{e}");
    }
}
