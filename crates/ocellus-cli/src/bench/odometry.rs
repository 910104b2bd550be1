//! `ocellus bench odometry`: visual odometry per frame on one core, seed and robust modes.

use super::timing::median;
use crate::generate_ground::textures;
use anyhow::Result;
use ocellus_image::Backend;
use ocellus_odometry::kinematics::Mount;
use ocellus_odometry::sad_flow::{group_flows, SadFlowConfig};
use ocellus_odometry::vo::{OdometryConfig, VisualOdometry};
use ocellus_synth::ground::{GroundConfig, GroundScene, GroundTexture};
use serde_json::json;
use std::time::Instant;

/// Runs the benchmark on 40 generated 640x480 frames of each texture (rendering excluded).
pub fn run(json_out: bool, backend: Backend) -> Result<()> {
    let tex = textures()?;
    let mut frames = Vec::new();
    for texture in [GroundTexture::Brick, GroundTexture::Grass, GroundTexture::Gravel] {
        let scene = GroundScene::new(GroundConfig { frames: 40, ..GroundConfig::easy(texture, 1) }, tex.clone())?;
        for k in 0..scene.len() {
            frames.push(scene.frame(k)?);
        }
    }
    let mut t_flow = Vec::new();
    let mut t_step = Vec::new();
    let mut t_robust = Vec::new();
    for _ in 0..3 {
        let mut cfg = OdometryConfig::robust(0.3, 600.0, Mount { right_m: 0.0, forward_m: 0.05 });
        // The robust mode searches with its own flow settings.
        cfg.robust.flow.backend = backend;
        let mut vo = VisualOdometry::new(cfg)?;
        for f in &frames {
            let t = Instant::now();
            vo.step(f)?;
            t_robust.push(t.elapsed().as_secs_f64() * 1e3);
        }
        for w in frames.windows(2) {
            let t = Instant::now();
            let _ = group_flows(&w[0], &w[1], &SadFlowConfig { backend, ..SadFlowConfig::default() });
            t_flow.push(t.elapsed().as_secs_f64() * 1e3);
        }
        let mut cfg = OdometryConfig::seed(0.3, 600.0, Mount { right_m: 0.0, forward_m: 0.05 });
        cfg.flow.backend = backend;
        let mut vo = VisualOdometry::new(cfg)?;
        for f in &frames {
            let t = Instant::now();
            vo.step(f)?;
            t_step.push(t.elapsed().as_secs_f64() * 1e3);
        }
    }
    let step = median(&mut t_step);
    let robust = median(&mut t_robust);
    let v = json!({
        "backend": backend.name(),
        "ms_per_frame_1thread_seed": step,
        "fps_1thread_seed": 1e3 / step.max(1e-9),
        "ms_per_frame_1thread_robust": robust,
        "fps_1thread_robust": 1e3 / robust.max(1e-9),
        "ms_sad_group_flows_1thread": median(&mut t_flow),
    });
    if json_out {
        outln!("{v}");
    } else {
        outln!("odometry benchmark, 640x480, one thread, medians over {} frames x 3:", frames.len());
        for (k, val) in v.as_object().into_iter().flatten() {
            outln!("  {k:<30} {:.4}", val.as_f64().unwrap_or(f64::NAN));
        }
    }
    Ok(())
}
