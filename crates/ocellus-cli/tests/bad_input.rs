//! Bad input on every subcommand, as a careless or hostile user would give it (SPEC 10.5).
//!
//! Each case runs the binary and asserts: a non-zero exit (1 for ocellus's own errors, 2 for
//! command-line usage errors), no death by signal, a message on stderr that names the
//! problem, and that no file left in the case's output folder holds NaN or infinity. The
//! cases are a table; one test runs them all and reports every failure at once, with the
//! count of cases by outcome.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use common::{ocellus, tmpdir};
use std::os::unix::process::ExitStatusExt;
use std::path::{Path, PathBuf};
use std::process::Stdio;

/// What a case must give.
#[derive(Clone, Copy)]
enum Expect {
    /// A usage error from the argument parser (exit 2), its message containing every string.
    Usage(&'static [&'static str]),
    /// An error of ocellus itself (exit 1), its message containing every string.
    Error(&'static [&'static str]),
}

struct Case {
    /// Arguments; `{D}` is the fixture folder, `{O}` the case's own empty output folder.
    args: &'static str,
    expect: Expect,
}

use Expect::{Error, Usage};

const fn c(args: &'static str, expect: Expect) -> Case {
    Case { args, expect }
}

/// The table. Arguments are split on spaces.
const CASES: &[Case] = &[
    // ---- saliency
    c("saliency {D}/missing.png --out {O}", Error(&["missing.png", "no such file"])),
    c("saliency {D}/empty.png --out {O}", Error(&["empty.png", "empty"])),
    c("saliency {D}/corrupt.png --out {O}", Error(&["corrupt.png", "decode"])),
    c("saliency {D}/text.png --out {O}", Error(&["text.png", "unsupported"])),
    c("saliency {D}/notes.txt --out {O}", Error(&["notes.txt", "unsupported"])),
    c("saliency {D}/empty_dir --out {O}", Error(&["empty_dir", "no png"])),
    c("saliency {D}/trunc.jpg --out {O}", Error(&["trunc.jpg", "truncated jpeg"])),
    c("saliency {D}/huge.pgm --out {O}", Error(&["huge.pgm", "megapixels", "ocellus_max_memory_mb"])),
    c("saliency {D}/img.png --preset nope --out {O}", Error(&["nope"])),
    c("saliency {D}/img.png --config {D}/missing.toml --out {O}", Error(&["missing.toml"])),
    c("saliency {D}/img.png --config {D}/cfg_typo.toml --out {O}", Error(&["map_levle"])),
    c("saliency {D}/img.png --config {D}/cfg_gabor_typo.toml --out {O}", Error(&["siz"])),
    c("saliency {D}/img.png --config {D}/cfg_even.toml --out {O}", Error(&["gabor"])),
    c("saliency {D}/img.png --config {D}/cfg_syntax.toml --out {O}", Error(&["cfg_syntax.toml", "toml"])),
    c("saliency {D}/a/x.png {D}/b/x.png --out {O}", Error(&["x.*", "both write"])),
    c("saliency {D}/a --out {D}/a", Error(&["holds the input"])),
    c("saliency {D}/img.png --out {D}/img.png", Error(&["img.png"])),
    c("saliency", Usage(&["images"])),
    c("saliency --print-config {D}/img.png", Usage(&["--print-config"])),
    c("saliency {D}/img.png --no-such-flag", Usage(&["--no-such-flag"])),
    c("saliency {D}/img.png {D}/missing.png --out {O}", Error(&["missing.png", "1 of 2 images failed"])),
    // ---- eval
    c("eval --stimuli {D}/stim --fixations {D}/fix --blur -1", Usage(&["--blur", "range"])),
    c("eval --stimuli {D}/stim --fixations {D}/fix --blur 1e30", Usage(&["--blur", "range"])),
    c("eval --stimuli {D}/stim --fixations {D}/fix --blur NaN", Usage(&["--blur", "range"])),
    c("eval --stimuli {D}/stim --fixations {D}/fix --prior-weight 2", Usage(&["--prior-weight", "range"])),
    c("eval --stimuli {D}/stim --fixations {D}/fix --prior-sigma 0", Usage(&["--prior-sigma", "range"])),
    c("eval --stimuli {D}/stim --fixations {D}/fix --skin-weight -3", Usage(&["--skin-weight", "range"])),
    c("eval --stimuli {D}/stim --fixations {D}/fix --limit 0", Usage(&["--limit", "range"])),
    c("eval --stimuli {D}/stim --fixations {D}/fix --limit -5", Usage(&["--limit"])),
    c("eval --stimuli {D}/missing --fixations {D}/fix", Error(&["missing"])),
    c("eval --stimuli {D}/stim --fixations {D}/missing", Error(&["missing"])),
    c("eval --stimuli {D}/stim --fixations {D}/fix --model nonsense", Error(&["nonsense"])),
    c("eval --stimuli {D}/stim --fixations {D}/fix --model maps:{D}/missing", Error(&["missing"])),
    c("eval --stimuli {D}/stim --fixations {D}/fix --model centre --tune", Error(&["--tune"])),
    c("eval --stimuli {D}/stim --points {D}/points_extra", Error(&["got 3"])),
    c("eval --stimuli {D}/stim", Usage(&["--fixations"])),
    c("eval --stimuli {D}/stim --fixations {D}/fix --config {D}/cfg_typo.toml", Error(&["map_levle"])),
    // ---- attend
    c("attend {D}/frames --out {O} --fps 0", Usage(&["--fps", "range"])),
    c("attend {D}/frames --out {O} --fps 5000", Usage(&["--fps", "range"])),
    c("attend {D}/frames --out {O} --fps -3", Usage(&["--fps"])),
    c("attend {D}/frames --out {O} --deg-per-px 0", Usage(&["--deg-per-px", "range"])),
    c("attend {D}/frames --out {O} --deg-per-px NaN", Usage(&["--deg-per-px", "range"])),
    c("attend {D}/frames --out {O} --limit 0", Usage(&["--limit", "range"])),
    c("attend {D}/missing --out {O}", Error(&["missing"])),
    c("attend {D}/header.y4m --out {O}", Error(&["header.y4m", "no frames"])),
    c("attend {D}/empty_dir --out {O}", Error(&["empty_dir", "no png"])),
    c("attend {D}/frames --out {D}/frames", Error(&["input folder"])),
    c("attend {D}/frames --out {D}/mp4_is_dir", Error(&["overlays.mp4", "folder"])),
    c("attend {D}/frames --out {O} --pan-tilt {D}/missing.csv", Error(&["missing.csv"])),
    c("attend {D}/frames --out {O} --pan-tilt {D}/pts_extra.csv", Error(&["pts_extra.csv", "line"])),
    c("attend {D}/frames --out {O} --config {D}/cfg_typo.toml", Error(&["map_levle"])),
    c("attend {D}/frames --out {O} --preset nope", Error(&["nope"])),
    // ---- surprise
    c("surprise {D}/frames --out {O} --limit 0", Usage(&["--limit", "range"])),
    c("surprise {D}/missing --out {O}", Error(&["missing"])),
    c("surprise {D}/header.y4m --out {O}", Error(&["no frames"])),
    c("surprise {D}/frames --out {D}/frames", Error(&["input folder"])),
    c("surprise {D}/frames --out {O} --config {D}/cfg_even.toml", Error(&["gabor"])),
    c("surprise {D}/huge.pgm --out {O}", Error(&["huge.pgm"])),
    // ---- plan
    c("plan corridor --steps 0 --out {O}", Usage(&["--steps", "range"])),
    c("plan corridor --steps 20000 --out {O}", Usage(&["--steps", "range"])),
    c("plan corridor --steps 2.5 --out {O}", Usage(&["--steps"])),
    c("plan corridor --seed -1 --out {O}", Usage(&["--seed"])),
    c("plan hallway --out {O}", Usage(&["hallway"])),
    c("plan", Usage(&["usage"])),
    // ---- calibrate dlt
    c("calibrate dlt {D}/pts_few.csv --out {O}/c.json", Error(&["at least 6"])),
    c("calibrate dlt {D}/pts_planar.csv --out {O}/c.json", Error(&["degenerate"])),
    c("calibrate dlt {D}/pts_nan.csv --out {O}/c.json", Error(&["non-finite"])),
    c("calibrate dlt {D}/pts_extra.csv --out {O}/c.json", Error(&["line 1", "got 6"])),
    c("calibrate dlt {D}/pts_short.csv --out {O}/c.json", Error(&["line 1"])),
    c("calibrate dlt {D}/pts_affine.csv --out {O}/c.json", Error(&["perspective"])),
    c("calibrate dlt {D}/pts_affine.csv --linear --out {O}/c.json", Error(&["perspective"])),
    c("calibrate dlt {D}/missing.csv --out {O}/c.json", Error(&["missing.csv"])),
    c("calibrate dlt {D}/pts_good.csv --out {D}/no/such/dir/c.json", Error(&["c.json"])),
    c("calibrate dlt {D}/img.png --out {O}/c.json", Error(&["img.png"])),
    // ---- calibrate chessboard / planar
    c("calibrate chessboard {D}/img.png --board 0x0 --out {O}", Error(&["--board", "range"])),
    c("calibrate chessboard {D}/img.png --board 1x6 --out {O}", Error(&["--board", "range"])),
    c("calibrate chessboard {D}/img.png --board 100x100 --out {O}", Error(&["--board", "range"])),
    c("calibrate chessboard {D}/img.png --board 9by6 --out {O}", Error(&["--board"])),
    c("calibrate chessboard {D}/img.png --square 0mm --out {O}", Error(&["0mm", "range"])),
    c("calibrate chessboard {D}/img.png --square -5 --out {O}", Error(&["-5", "range"])),
    c("calibrate chessboard {D}/img.png --square NaNmm --out {O}", Error(&["nanmm"])),
    c("calibrate chessboard {D}/img.png --square 25furlong --out {O}", Error(&["25furlong"])),
    c("calibrate chessboard {D}/a --out {O}", Error(&["found in 0 of 1", "at least 3"])),
    c("calibrate chessboard {D}/a/x.png {D}/b/x.png --out {O}", Error(&["both write"])),
    c("calibrate chessboard {D}/a --out {D}/a", Error(&["holds the input"])),
    c("calibrate planar {D}/planar_bad.csv --out {O}", Error(&["planar_bad.csv", "line"])),
    c("calibrate planar {D}/pts_good.csv --image-size 0x0 --out {O}", Error(&["--image-size", "range"])),
    c("calibrate planar {D}/pts_good.csv --image-size 640 --out {O}", Error(&["--image-size"])),
    c("calibrate planar {D}/missing.csv --out {O}", Error(&["missing.csv"])),
    c("calibrate", Usage(&["usage"])),
    // ---- odometry
    c("odometry {D}/frames --camera {D}/cam.toml --rate-hz inf --out {O}", Usage(&["--rate-hz", "range"])),
    c("odometry {D}/frames --camera {D}/cam.toml --rate-hz 0 --out {O}", Usage(&["--rate-hz", "range"])),
    c("odometry {D}/frames --camera {D}/cam.toml --rate-hz -200 --out {O}", Usage(&["--rate-hz", "range"])),
    c("odometry {D}/frames --camera {D}/cam.toml --rate-hz NaN --out {O}", Usage(&["--rate-hz", "range"])),
    c("odometry {D}/frames --camera {D}/cam.toml --height-m 0 --out {O}", Usage(&["--height-m", "range"])),
    c("odometry {D}/frames --camera {D}/cam.toml --height-pull 1.5 --out {O}", Usage(&["--height-pull", "range"])),
    c("odometry {D}/frames --camera {D}/cam.toml --height-pull NaN --out {O}", Usage(&["--height-pull", "range"])),
    c("odometry {D}/frames --camera {D}/cam.toml --height-noise-frames -1 --out {O}", Usage(&["--height-noise-frames", "range"])),
    c("odometry {D}/frames --camera {D}/cam.toml --height-noise-frames 0.5 --out {O}", Error(&["height noise window", "at least 1"])),
    c("odometry {D}/frames --camera {D}/cam.toml --mount-right-m 1e9 --out {O}", Usage(&["--mount-right-m", "range"])),
    c("odometry {D}/frames --camera {D}/cam.toml --encoder-rate-hz 0 --out {O}", Usage(&["--encoder-rate-hz"])),
    c("odometry {D}/frames --camera {D}/missing.toml --out {O}", Error(&["missing.toml"])),
    c("odometry {D}/frames --camera {D}/cam_typo.toml --out {O}", Error(&["distorsion"])),
    c("odometry {D}/frames --camera {D}/cam_nested_typo.toml --out {O}", Error(&["k4"])),
    c("odometry {D}/frames --camera {D}/cam_nan.toml --out {O}", Error(&["cam_nan.toml"])),
    c("odometry {D}/frames --camera {D}/cam_zero_f.toml --out {O}", Error(&["focal"])),
    c("odometry {D}/frames --camera {D}/cam_size.toml --out {O}", Error(&["calibrated for 64x48"])),
    c("odometry {D}/frames --camera {D}/cam_no_height.toml --out {O}", Error(&["height"])),
    c("odometry {D}/header.y4m --camera {D}/cam.toml --out {O}", Error(&["no frames"])),
    c("odometry {D}/frames --camera {D}/cam.toml --out {D}/frames", Error(&["input folder"])),
    c("odometry {D}/frames --out {O}", Usage(&["--camera"])),
    // ---- track
    c("track {D}/frames --camera {D}/cam.toml --radius-m 0.05 --colour 245,120,25 --particles 0 --out {O}", Usage(&["--particles", "range"])),
    c("track {D}/frames --camera {D}/cam.toml --radius-m NaN --colour 245,120,25 --out {O}", Usage(&["--radius-m", "range"])),
    c("track {D}/frames --camera {D}/cam.toml --radius-m 0.05 --colour 245,120,25 --boost 1.5 --out {O}", Usage(&["--boost", "range"])),
    c("track {D}/frames --camera {D}/cam.toml --radius-m 0.05 --colour 245,120,25 --gravity NaN --out {O}", Usage(&["--gravity", "range"])),
    c("track {D}/frames --camera {D}/cam_size.toml --radius-m 0.05 --colour 245,120,25 --out {O}", Error(&["calibrated for 64x48"])),
    c("track {D}/frames --camera {D}/cam.toml --radius-m 0.05 --colour 128,128,128 --out {O}", Error(&["grey", "patch"])),
    c("track {D}/frames --camera {D}/cam.toml --radius-m 0.05 --colour 300,0,0 --out {O}", Error(&["--colour", "0..=255"])),
    c("track {D}/frames --camera {D}/cam.toml --radius-m 0.05 --patch 1,2 --out {O}", Error(&["--patch", "3 comma-separated"])),
    c("track {D}/frames --camera {D}/cam.toml --radius-m 0.05 --patch 5,5,NaN --out {O}", Error(&["--patch"])),
    c("track {D}/frames --camera {D}/cam.toml --radius-m 0.05 --out {O}", Error(&["--patch", "--colour"])),
    c("track {D}/frames --camera {D}/cam.toml --radius-m 0.05 --colour 245,120,25 --out {D}/frames", Error(&["input folder"])),
    c("track {D}/frames --radius-m 0.05 --colour 245,120,25 --out {O}", Usage(&["--camera"])),
    c("track eval {D}/missing.csv {D}/missing.csv", Error(&["missing.csv"])),
    c("track study --seeds 1,x", Error(&["--seeds"])),
    c("track study --streams 0", Usage(&["--streams", "range"])),
    c("track head --steps 0 --out {O}", Usage(&["--steps", "range"])),
    c("track head --particles 0 --out {O}", Usage(&["--particles", "range"])),
    // ---- retina
    c("retina learn --experiment 3 --out {O}", Usage(&["--experiment", "range"])),
    c("retina learn --experiment 1 --iterations 0 --out {O}", Usage(&["--iterations", "range"])),
    c("retina learn --experiment 1 --learning-rate NaN --out {O}", Usage(&["--learning-rate", "range"])),
    c("retina learn --experiment 1 --simplicity -1 --out {O}", Usage(&["--simplicity", "range"])),
    c("retina learn --experiment 1 --blur inf --out {O}", Usage(&["--blur", "range"])),
    c("retina learn --experiment 2 --motor-smoothness NaN --out {O}", Usage(&["--motor-smoothness", "range"])),
    c("retina learn --experiment 2 --actions all --out {O}", Error(&["2D motor space"])),
    c("retina learn --experiment 2 --small --out {O}", Error(&["--small"])),
    c("retina learn --experiment 1 --actions all --motor-space cells --out {O}", Error(&["2D motor space"])),
    c("retina learn --experiment 2 --motor-space values --out {O}", Error(&["--motor-space is for experiment 1"])),
    c("retina learn --experiment 1 --motor-space grid --out {O}", Usage(&["--motor-space"])),
    c("retina learn --experiment 1 --small --resume --out {O}", Error(&["no checkpoint"])),
    c("retina learn --experiment 1 --small --images {D}/missing --out {O}", Error(&["missing"])),
    c("retina summary", Usage(&["runs"])),
    c("retina summary {D}/missing", Error(&["missing", "retina.json"])),
    c("retina summary {D}/empty_dir", Error(&["empty_dir", "retina.json"])),
    c("retina summary {D}/retina_bad", Error(&["retina_bad", "not json"])),
    c("retina summary {D}/retina_old", Error(&["retina_old", "action_scale"])),
    c("generate ball --frames 0 --out {O}", Usage(&["--frames", "range"])),
    c("generate ball --frames 10 --occluded-frames 8 --out {O}", Error(&["occlusion", "do not fit"])),
    c("generate ball --noise NaN --out {O}", Usage(&["--noise", "range"])),
    // ---- odometry eval
    c("odometry eval {D}/dup.tum {D}/gt.tum --plot {O}/t.png", Error(&["dup.tum", "does not increase"])),
    c("odometry eval {D}/back.tum {D}/gt.tum --plot {O}/t.png", Error(&["back.tum", "does not increase"])),
    c("odometry eval {D}/bad_q.tum {D}/gt.tum --plot {O}/t.png", Error(&["quaternion"])),
    c("odometry eval {D}/missing.tum {D}/gt.tum --plot {O}/t.png", Error(&["missing.tum"])),
    c("odometry eval {D}/late.tum {D}/gt.tum --plot {O}/t.png", Error(&["pair up"])),
    c("odometry eval {D}/gt.tum {D}/gt.tum --max-dt 0 --plot {O}/t.png", Usage(&["--max-dt", "range"])),
    c("odometry eval {D}/still.tum {D}/still.tum --plot {O}/t.png", Error(&["do not move"])),
    c("odometry eval {D}/short.tum {D}/gt.tum --plot {O}/t.png", Error(&["short.tum", "line"])),
    c("odometry eval {D}/empty.tum {D}/gt.tum --plot {O}/t.png", Error(&["empty.tum"])),
    // ---- logpolar
    c("logpolar {D}/img.png --max-radius 1e-30 --out {O}", Usage(&["--max-radius", "range"])),
    c("logpolar {D}/img.png --rings 0 --out {O}", Usage(&["--rings", "range"])),
    c("logpolar {D}/img.png --sectors 100000 --out {O}", Usage(&["--sectors", "range"])),
    c("logpolar {D}/img.png --fovea-radius 0 --out {O}", Usage(&["--fovea-radius", "range"])),
    c("logpolar {D}/img.png --fovea NaN,1 --out {O}", Usage(&["--fovea"])),
    c("logpolar {D}/img.png --fovea 1,2,3 --out {O}", Usage(&["--fovea", "x,y"])),
    c("logpolar {D}/img.png --fovea-radius 90 --max-radius 40 --out {O}", Error(&["radius"])),
    c("logpolar {D}/missing.png --out {O}", Error(&["missing.png"])),
    c("logpolar {D}/empty.png --out {O}", Error(&["empty.png"])),
    c("logpolar {D}/huge.pgm --out {O}", Error(&["huge.pgm", "megapixels"])),
    c("logpolar {D}/header.y4m --out {O}", Error(&["no frames"])),
    c("logpolar {D}/img.png --out {D}", Error(&["holds the input"])),
    c("logpolar {D}/frames --out {D}/frames", Error(&["input folder"])),
    c("logpolar register {D}/img.png {D}/small.png", Error(&["160x120"])),
    c("logpolar register {D}/img.png {D}/missing.png", Error(&["missing.png"])),
    c("logpolar vergence {D}/img.png {D}/img.png --gaze 1,2 --radius 1", Usage(&["--radius", "range"])),
    c("logpolar vergence {D}/img.png {D}/img.png --gaze 1,2 --max-disparity 0", Usage(&["--max-disparity", "range"])),
    c("logpolar vergence {D}/img.png {D}/img.png --gaze inf,2", Usage(&["--gaze"])),
    c("logpolar vergence {D}/img.png {D}/small.png --gaze 100,100", Error(&["160x120"])),
    // ---- undistort
    c("undistort {D}/a --camera {D}/cam.toml --out {D}/a", Error(&["holds the input"])),
    c("undistort {D}/a/x.png {D}/b/x.png --camera {D}/cam.toml --out {O}", Error(&["both write"])),
    c("undistort {D}/img.png --camera {D}/cam_size.toml --out {O}", Error(&["calibrated for 64x48"])),
    c("undistort {D}/img.png --camera {D}/cam_typo.toml --out {O}", Error(&["distorsion"])),
    c("undistort {D}/img.png --camera {D}/cam_nan.toml --out {O}", Error(&["cam_nan.toml"])),
    c("undistort {D}/img.png --camera {D}/missing.toml --out {O}", Error(&["missing.toml"])),
    c("undistort {D}/img.png --out {O}", Usage(&["--camera"])),
    c("undistort {D}/corrupt.png --camera {D}/cam.toml --out {O}", Error(&["corrupt.png"])),
    // ---- triangulate
    c("triangulate --camera {D}/p0.json --camera {D}/p0.json {D}/matches.csv --out {O}/p.csv", Error(&["same centre"])),
    c("triangulate --camera {D}/p0.json --camera {D}/p_rot.json {D}/matches.csv --out {O}/p.csv", Error(&["same centre"])),
    c("triangulate --camera {D}/p0.json --camera {D}/p_zero.json {D}/matches.csv --out {O}/p.csv", Error(&["camera 1", "singular"])),
    c("triangulate --camera {D}/p_affine.json --camera {D}/p1.json {D}/matches.csv --out {O}/p.csv", Error(&["camera 0", "singular"])),
    c("triangulate --camera {D}/p0.json {D}/matches.csv --out {O}/p.csv", Error(&["two"])),
    c("triangulate --camera {D}/p0.json --camera {D}/p1.json --camera {D}/p1.json {D}/matches.csv --seed-form --out {O}/p.csv", Error(&["--seed-form"])),
    c("triangulate --camera {D}/p0.json --camera {D}/p1.json {D}/pts_extra.csv --out {O}/p.csv", Error(&["got 6"])),
    c("triangulate --camera {D}/p0.json --camera {D}/p1.json {D}/behind.csv --out {O}/p.csv", Error(&["behind"])),
    c("triangulate --camera {D}/p0.json --camera {D}/not_json.json {D}/matches.csv --out {O}/p.csv", Error(&["not_json.json", "json"])),
    c("triangulate --camera {D}/p0.json --camera {D}/p_short.json {D}/matches.csv --out {O}/p.csv", Error(&["p_short.json", "3 rows"])),
    c("triangulate --camera {D}/p0.json --camera {D}/p1.json {D}/missing.csv --out {O}/p.csv", Error(&["missing.csv"])),
    c("triangulate --camera {D}/p0.json --camera {D}/p1.json {D}/matches.csv --truth {D}/truth_3.csv --out {O}/p.csv", Error(&["3 points for 2 matches"])),
    c("triangulate --camera {D}/p0.json --camera {D}/p1.json {D}/matches.csv --truth {D}/pts_extra.csv --out {O}/p.csv", Error(&["pts_extra.csv", "got 6"])),
    // ---- stereo
    c("stereo {D}/img.png {D}/img.png --focal-px 0 --baseline 1 --out {O}", Usage(&["--focal-px", "range"])),
    c("stereo {D}/img.png {D}/img.png --focal-px 500 --baseline -1 --out {O}", Usage(&["--baseline", "range"])),
    c("stereo {D}/img.png {D}/img.png --focal-px 500 --baseline NaN --out {O}", Usage(&["--baseline", "range"])),
    c("stereo {D}/img.png {D}/img.png --doffs NaN --out {O}", Usage(&["--doffs", "range"])),
    c("stereo {D}/img.png {D}/img.png --uniqueness NaN --out {O}", Usage(&["--uniqueness", "range"])),
    c("stereo {D}/img.png {D}/img.png --uniqueness 1.5 --out {O}", Usage(&["--uniqueness", "range"])),
    c("stereo {D}/img.png {D}/img.png --max-disp 0 --out {O}", Usage(&["--max-disp", "range"])),
    c("stereo {D}/img.png {D}/img.png --max-disp 1000 --out {O}", Usage(&["--max-disp", "range"])),
    c("stereo {D}/img.png {D}/img.png --method bm --block 4 --out {O}", Error(&["block size 4", "odd"])),
    c("stereo {D}/img.png {D}/img.png --block 9 --out {O}", Error(&["--block", "bm"])),
    c("stereo {D}/img.png {D}/img.png --paths 6 --out {O}", Error(&["--paths 6"])),
    c("stereo {D}/img.png {D}/img.png --method bm --paths 4 --out {O}", Error(&["--paths", "sgm"])),
    c("stereo {D}/img.png {D}/img.png --penalties 200 100 --out {O}", Error(&["p1"])),
    c("stereo {D}/img.png {D}/small.png --out {O}", Error(&["differ in size"])),
    c("stereo {D}/img.png {D}/img.png --truth {D}/small.pfm --out {O}", Error(&["small.pfm"])),
    c("stereo {D}/img.png {D}/img.png --focal-px 500 --out {O}", Error(&["--baseline"])),
    c("stereo {D}/img.png {D}/img.png --doffs 3 --out {O}", Error(&["--doffs", "--focal-px"])),
    c("stereo {D}/img.png {D}/img.png --principal-point 3,4 --out {O}", Error(&["--principal-point", "--focal-px"])),
    c("stereo {D}/img.png {D}/img.png --principal-point 3 --out {O}", Usage(&["--principal-point", "x,y"])),
    c("stereo {D}/img.png {D}/img.png --truth {D}/img.png --out {O}", Error(&["img.png"])),
    // ---- generate
    c("generate attention --frames 0 --out {O}", Usage(&["--frames", "range"])),
    c("generate attention --frames 1 --out {O}", Usage(&["--frames", "range"])),
    c("generate attention --noise -1 --out {O}", Usage(&["--noise", "range"])),
    c("generate attention --noise NaN --out {O}", Usage(&["--noise", "range"])),
    c("generate attention --frames 10 --event-frame 40 --out {O}", Error(&["--event-frame"])),
    c("generate attention --pan-px-per-frame 1e9 --out {O}", Usage(&["--pan-px-per-frame", "range"])),
    c("generate attention --scenario nope --out {O}", Usage(&["nope"])),
    c("generate attention --scenario static --event-frame 3 --out {O}", Error(&["--event-frame", "sudden"])),
    c("generate attention --pan-px-per-frame 3 --out {O}", Error(&["--pan-px-per-frame", "pan"])),
    c("generate chessboard --noise -1 --out {O}", Usage(&["--noise", "range"])),
    c("generate chessboard --views 0 --out {O}", Usage(&["--views", "range"])),
    c("generate chessboard --max-tilt-deg 89 --out {O}", Usage(&["--max-tilt-deg", "range"])),
    c("generate chessboard --board 1x1 --out {O}", Error(&["--board", "range"])),
    c("generate chessboard --square 0mm --out {O}", Error(&["range"])),
    c("generate chessboard --camera {D}/cam_typo.toml --out {O}", Error(&["distorsion"])),
    c("generate ground --frames 0 --out {O}", Usage(&["--frames", "range"])),
    c("generate ground --frames 1000000 --out {O}", Usage(&["--frames", "range"])),
    c("generate ground --texture marble --out {O}", Usage(&["marble"])),
    c("synth ground --seed -4 --out {O}", Usage(&["--seed"])),
    c("synth ground --supersample 0 --out {O}", Usage(&["--supersample", "range"])),
    c("synth ground --k1 NaN --out {O}", Usage(&["--k1", "range"])),
    c("synth ground --k1 -0.9 --out {O}", Usage(&["--k1", "range"])),
    c("synth ground --vignetting 1 --out {O}", Usage(&["--vignetting", "range"])),
    c("synth ground --rolling-shutter 1.5 --out {O}", Usage(&["--rolling-shutter", "range"])),
    c("synth ground --texture carpet --out {O}", Usage(&["--texture", "carpet"])),
    // ---- bench
    c("bench saliency --width 100000 --height 100000", Usage(&["--width", "range"])),
    c("bench saliency --height 0", Usage(&["--height", "range"])),
    c("bench saliency --frames 0", Usage(&["--frames", "range"])),
    c("bench odometry --frames 3", Error(&["bench odometry does not use --frames"])),
    c("bench attention --width 100", Error(&["does not use --width"])),
    c("bench geometry --image {D}/img.png", Error(&["does not use --image"])),
    c("bench logpolar --preset stb", Error(&["does not use --preset"])),
    c("bench attention --backend scalar", Error(&["does not use --backend"])),
    c("bench saliency --backend quantum --frames 1", Error(&["quantum"])),
    c("bench saliency --image {D}/missing.png --frames 1", Error(&["missing.png"])),
    c("bench teleport", Usage(&["teleport"])),
    // ---- demo and the top level
    c("demo --out {D}/img.png", Error(&["img.png"])),
    c("", Usage(&["usage"])),
    c("levitate", Usage(&["levitate"])),
    c("--no-such-flag", Usage(&["--no-such-flag"])),
];

/// Writes every fixture the cases name into `d`.
fn fixtures(d: &Path) {
    let w = |name: &str, bytes: &[u8]| std::fs::write(d.join(name), bytes).unwrap();
    let chelsea = image::open(ocellus_testdata::asset("chelsea.png")).unwrap().to_rgb8();
    let img = image::imageops::resize(&chelsea, 320, 256, image::imageops::FilterType::Triangle);
    img.save(d.join("img.png")).unwrap();
    image::imageops::resize(&chelsea, 160, 120, image::imageops::FilterType::Triangle)
        .save(d.join("small.png"))
        .unwrap();
    for sub in [
        "a",
        "b",
        "frames",
        "empty_dir",
        "stim",
        "fix",
        "points_extra",
        "mp4_is_dir/overlays.mp4",
        "retina_bad",
        "retina_old",
    ] {
        std::fs::create_dir_all(d.join(sub)).unwrap();
    }
    img.save(d.join("a/x.png")).unwrap();
    img.save(d.join("b/x.png")).unwrap();
    for k in 0..3 {
        let shifted = image::RgbImage::from_fn(320, 256, |x, y| *img.get_pixel((x + 4 * k) % 320, y));
        shifted.save(d.join(format!("frames/f{k}.png"))).unwrap();
    }
    img.save(d.join("stim/s1.png")).unwrap();
    image::GrayImage::from_fn(320, 256, |x, _| image::Luma([(x % 256) as u8])).save(d.join("fix/s1.png")).unwrap();
    std::fs::write(d.join("points_extra/s1.csv"), "x,y,subject\n10,20,1\n").unwrap();
    w("empty.png", b"");
    let mut corrupt = b"\x89PNG\r\n\x1a\n".to_vec();
    corrupt.extend((0..200u32).map(|i| (i * 37 % 251) as u8));
    w("corrupt.png", &corrupt);
    w("text.png", b"this is not an image\n");
    w("notes.txt", b"not an image either\n");
    w("retina_bad/retina.json", b"{ \"experiment\": 1,");
    w("retina_old/retina.json", b"{ \"experiment\": 1, \"config\": { \"actions\": \"translation\" } }");
    let jpg = std::fs::read(ocellus_testdata::data_file("rocket.jpg")).unwrap();
    w("trunc.jpg", &jpg[..jpg.len() / 2]);
    let mut huge = b"P5\n20000 20000\n255\n".to_vec();
    huge.extend([0u8; 64]);
    w("huge.pgm", &huge);
    w("header.y4m", b"YUV4MPEG2 W320 H256 F30:1 Ip A1:1 C444\n");
    w("cfg_typo.toml", b"map_levle = 3\n");
    w("cfg_gabor_typo.toml", b"[gabor]\nsiz = 15\n");
    w("cfg_even.toml", b"[gabor]\nsize = 16\n");
    w("cfg_syntax.toml", b"map_level = [\n");
    let cam = "height_m = 0.3\n[intrinsics]\nfx = 300.0\nfy = 300.0\ncx = 159.5\ncy = 127.5\nskew = 0.0\n";
    w("cam.toml", format!("image_size = [320, 256]\n{cam}").as_bytes());
    w("cam_size.toml", format!("image_size = [64, 48]\n{cam}").as_bytes());
    w("cam_typo.toml", format!("distorsion = 0.1\n{cam}").as_bytes());
    w("cam_nested_typo.toml", format!("{cam}[distortion]\nk4 = 0.1\n").as_bytes());
    w("cam_nan.toml", cam.replace("fx = 300.0", "fx = nan").as_bytes());
    w("cam_zero_f.toml", cam.replace("fx = 300.0", "fx = 0.0").as_bytes());
    w("cam_no_height.toml", cam.replace("height_m = 0.3\n", "").as_bytes());
    // A camera for DLT: 3D points in a box in front of it and their pixels.
    let p = nalgebra::Matrix3x4::new(800.0, 0.0, 320.0, 40.0, 0.0, 800.0, 240.0, -20.0, 0.0, 0.0, 1.0, 4.0);
    let project = |p: &nalgebra::Matrix3x4<f64>, x: [f64; 3]| {
        let h = p * nalgebra::Vector4::new(x[0], x[1], x[2], 1.0);
        [h.x / h.z, h.y / h.z]
    };
    let pts: Vec<[f64; 3]> =
        (0..12).map(|i| [(i % 3) as f64 * 0.3 - 0.3, (i / 3 % 2) as f64 * 0.4 - 0.2, (i % 4) as f64 * 0.25]).collect();
    let rows = |p: &nalgebra::Matrix3x4<f64>, pts: &[[f64; 3]]| -> String {
        pts.iter()
            .map(|x| {
                let u = project(p, *x);
                format!("{},{},{},{},{}\n", x[0], x[1], x[2], u[0], u[1])
            })
            .collect()
    };
    w("pts_good.csv", rows(&p, &pts).as_bytes());
    w("pts_few.csv", rows(&p, &pts[..5]).as_bytes());
    let planar: Vec<[f64; 3]> = pts.iter().map(|x| [x[0], x[1], 0.5]).collect();
    w("pts_planar.csv", rows(&p, &planar).as_bytes());
    w("pts_nan.csv", rows(&p, &pts).replacen("0.25", "nan", 1).as_bytes());
    w("pts_extra.csv", b"1,2,3,4,5,6\n1,2,3,4,5,6\n");
    w("truth_3.csv", b"X,Y,Z\n0,0,1\n0,1,1\n1,0,1\n");
    w("pts_short.csv", b"1,2,3\n1,2,3,4,5\n");
    let affine = nalgebra::Matrix3x4::new(800.0, 10.0, 5.0, 320.0, -4.0, 790.0, 12.0, 240.0, 0.0, 0.0, 0.0, 1.0);
    w("pts_affine.csv", rows(&affine, &pts).as_bytes());
    w("planar_bad.csv", b"view,X,Y,u,v\n0,1,2,3\n");
    // Cameras for triangulation: two views 0.5 apart, one turned about the first's centre.
    let json = |p: &nalgebra::Matrix3x4<f64>| {
        let rows: Vec<Vec<f64>> = (0..3).map(|i| (0..4).map(|j| p[(i, j)]).collect()).collect();
        serde_json::json!({ "projection_matrix": rows }).to_string()
    };
    let k = nalgebra::Matrix3::new(700.0, 0.0, 320.0, 0.0, 700.0, 240.0, 0.0, 0.0, 1.0);
    let pose = |r: nalgebra::Matrix3<f64>, c: nalgebra::Vector3<f64>| {
        let mut rt = nalgebra::Matrix3x4::zeros();
        rt.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
        rt.fixed_view_mut::<3, 1>(0, 3).copy_from(&(-(r * c)));
        k * rt
    };
    let eye = nalgebra::Matrix3::identity();
    let p0 = pose(eye, nalgebra::Vector3::zeros());
    let p1 = pose(eye, nalgebra::Vector3::new(0.5, 0.0, 0.0));
    let turned = *nalgebra::Rotation3::from_euler_angles(0.0, 0.3, 0.0).matrix();
    w("p0.json", json(&p0).as_bytes());
    w("p1.json", json(&p1).as_bytes());
    w("p_rot.json", json(&pose(turned, nalgebra::Vector3::zeros())).as_bytes());
    w("p_zero.json", json(&nalgebra::Matrix3x4::zeros()).as_bytes());
    let flat = nalgebra::Matrix3x4::new(700.0, 0.0, 0.0, 320.0, 0.0, 700.0, 0.0, 240.0, 0.0, 0.0, 0.0, 1.0);
    w("p_affine.json", json(&flat).as_bytes());
    w("p_short.json", br#"{"projection_matrix": [[1, 0, 0, 0], [0, 1, 0, 0]]}"#);
    w("not_json.json", b"projection_matrix = 3\n");
    let matches = |x: [f64; 3]| {
        let (a, b) = (project(&p0, x), project(&p1, x));
        format!("{},{},{},{}\n", a[0], a[1], b[0], b[1])
    };
    w("matches.csv", format!("{}{}", matches([0.1, 0.2, 3.0]), matches([-0.2, 0.1, 5.0])).as_bytes());
    w("behind.csv", format!("{}{}", matches([0.1, 0.2, -3.0]), matches([-0.2, 0.1, -5.0])).as_bytes());
    // Trajectories.
    let tum = |rows: &[(f64, f64)]| -> String { rows.iter().map(|(t, x)| format!("{t} {x} 0 0 0 0 0 1\n")).collect() };
    let gt: Vec<(f64, f64)> = (0..20).map(|i| (i as f64 * 0.005, i as f64 * 0.01)).collect();
    w("gt.tum", tum(&gt).as_bytes());
    let mut dup = gt.clone();
    dup[5].0 = dup[4].0;
    w("dup.tum", tum(&dup).as_bytes());
    let mut back = gt.clone();
    back.swap(7, 8);
    w("back.tum", tum(&back).as_bytes());
    w("bad_q.tum", b"0 0 0 0 0 0 0 0\n0.1 0 0 0 0 0 0 0\n");
    let late: Vec<(f64, f64)> = gt.iter().map(|(t, x)| (t + 100.0, *x)).collect();
    w("late.tum", tum(&late).as_bytes());
    let still: Vec<(f64, f64)> = gt.iter().map(|(t, _)| (*t, 0.0)).collect();
    w("still.tum", tum(&still).as_bytes());
    w("short.tum", b"0 1 2 3\n");
    w("empty.tum", b"");
    ocellus_io::pfm::write(d.join("small.pfm"), &ocellus_image::Plane::<f32>::new(16, 16)).unwrap();
}

/// Files under `dir` (recursively).
fn files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() {
                out.extend(files(&p));
            } else {
                out.push(p);
            }
        }
    }
    out
}

/// Why an output file is garbage, if it is: NaN or infinity in a data file.
fn garbage(p: &Path) -> Option<String> {
    let ext = p.extension().and_then(|e| e.to_str()).unwrap_or("");
    match ext {
        "csv" | "tum" | "json" | "toml" => {
            let text = std::fs::read_to_string(p).ok()?;
            let lower = text.to_lowercase();
            (lower.contains("nan") || lower.contains("inf")).then(|| format!("{} holds NaN or inf", p.display()))
        }
        "npy" => {
            let a = ocellus_io::npy::read(p).ok()?;
            a.data.iter().any(|v| !v.is_finite()).then(|| format!("{} holds NaN or inf", p.display()))
        }
        _ => None,
    }
}

#[test]
fn every_bad_input_gets_a_clear_error() {
    let root = tmpdir("bad-input");
    let d = root.join("fixtures");
    std::fs::create_dir_all(&d).unwrap();
    fixtures(&d);
    // A broken ffmpeg on the PATH: the bad-input runs must never reach a real one.
    let fake = root.join("bin");
    std::fs::create_dir_all(&fake).unwrap();
    let ffmpeg = fake.join("ffmpeg");
    std::fs::write(&ffmpeg, "#!/bin/sh\necho 'fake ffmpeg: broken' >&2\nexit 3\n").unwrap();
    std::fs::set_permissions(&ffmpeg, std::os::unix::fs::PermissionsExt::from_mode(0o755)).unwrap();
    let path = format!("{}:{}", fake.display(), std::env::var("PATH").unwrap_or_default());
    let (mut usage, mut errors, mut failures) = (0usize, 0usize, Vec::new());
    for (i, case) in CASES.iter().enumerate() {
        let out = root.join(format!("out{i}"));
        std::fs::create_dir_all(&out).unwrap();
        let args: Vec<String> = case
            .args
            .split_whitespace()
            .map(|a| a.replace("{D}", &d.display().to_string()).replace("{O}", &out.display().to_string()))
            .collect();
        let o = ocellus().args(&args).env("PATH", &path).env_remove("OCELLUS_MAX_MEMORY_MB").output().unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr).to_lowercase();
        let (want_code, words) = match case.expect {
            Usage(w) => (2, w),
            Error(w) => (1, w),
        };
        let mut why = Vec::new();
        if let Some(sig) = o.status.signal() {
            why.push(format!("killed by signal {sig}"));
        } else if o.status.code() != Some(want_code) {
            why.push(format!("exit {:?}, wanted {want_code}", o.status.code()));
        }
        if stderr.contains("panicked") {
            why.push("panicked".into());
        }
        for w in words {
            if !stderr.contains(&w.to_lowercase()) {
                why.push(format!("message lacks '{w}'"));
            }
        }
        why.extend(files(&out).iter().filter_map(|p| garbage(p)));
        if why.is_empty() {
            match case.expect {
                Usage(_) => usage += 1,
                Error(_) => errors += 1,
            }
        } else {
            failures.push(format!("ocellus {}: {}\n    stderr: {}", case.args, why.join("; "), stderr.trim()));
        }
    }
    println!(
        "bad-input suite: {} cases; {usage} usage errors (exit 2) and {errors} ocellus errors (exit 1) as expected; {} wrong",
        CASES.len(),
        failures.len()
    );
    assert!(CASES.len() >= 150, "the suite must keep at least 150 cases, has {}", CASES.len());
    assert!(failures.is_empty(), "{} of {} cases wrong:\n{}", failures.len(), CASES.len(), failures.join("\n"));
    std::fs::remove_dir_all(&root).unwrap();
}

/// Standard output that cannot be written: a clear error and a non-zero exit, on every kind
/// of subcommand that prints; a reader that closes the pipe: a quiet end.
#[test]
fn failed_stdout_writes_are_errors_and_closed_pipes_end_quietly() {
    let root = tmpdir("stdout");
    let img = ocellus_testdata::asset("chelsea.png");
    let full = || std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
    let runs: Vec<Vec<String>> = vec![
        vec!["saliency".into(), img.display().to_string(), "--out".into(), root.join("s").display().to_string()],
        vec!["saliency".into(), "--print-config".into()],
        vec![
            "plan".into(),
            "corridor".into(),
            "--steps".into(),
            "2".into(),
            "--out".into(),
            root.join("p").display().to_string(),
        ],
        vec!["logpolar".into(), img.display().to_string(), "--out".into(), root.join("l").display().to_string()],
        vec![
            "generate".into(),
            "attention".into(),
            "--frames".into(),
            "2".into(),
            "--event-frame".into(),
            "1".into(),
            "--out".into(),
            root.join("g").display().to_string(),
        ],
    ];
    for args in &runs {
        let o = ocellus().args(args).stdout(full()).stderr(Stdio::piped()).output().unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(
            stderr.contains("cannot write to standard output") && !stderr.contains("panicked"),
            "{args:?}: {stderr}"
        );
    }
    // A closed pipe: the process ends without a message, with the status of SIGPIPE.
    let mut child =
        ocellus().args(["saliency", "--print-config"]).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.code() == Some(141) || o.status.success(), "{:?} {stderr}", o.status);
    assert!(stderr.is_empty(), "{stderr}");
    std::fs::remove_dir_all(&root).unwrap();
}

/// A broken ffmpeg: ocellus says that ffmpeg failed, with its message, exits non-zero, and
/// keeps the overlay frames already written.
#[test]
fn a_failing_ffmpeg_is_reported_and_frames_are_kept() {
    let root = tmpdir("ffmpeg");
    let frames = root.join("frames");
    std::fs::create_dir_all(&frames).unwrap();
    let img = image::open(ocellus_testdata::asset("chelsea.png")).unwrap().to_rgb8();
    let img = image::imageops::resize(&img, 320, 256, image::imageops::FilterType::Triangle);
    for k in 0..3 {
        img.save(frames.join(format!("f{k}.png"))).unwrap();
    }
    let bin = root.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    // Reads a little, then dies: the pipe closes under ocellus.
    std::fs::write(
        bin.join("ffmpeg"),
        "#!/bin/sh\nhead -c 1000 >/dev/null\necho 'fake ffmpeg: encoder exploded' >&2\nexit 3\n",
    )
    .unwrap();
    std::fs::set_permissions(bin.join("ffmpeg"), std::os::unix::fs::PermissionsExt::from_mode(0o755)).unwrap();
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default());
    let out = root.join("out");
    let o = ocellus().arg("attend").arg(&frames).arg("--out").arg(&out).env("PATH", &path).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("ffmpeg") && stderr.contains("encoder exploded"), "{stderr}");
    assert!(out.join("overlays/frame_00000.png").is_file(), "the frames written before ffmpeg failed are kept");
    std::fs::remove_dir_all(&root).unwrap();
}
