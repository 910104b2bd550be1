//! Rotation and scale between two views by log-polar phase correlation: a photograph and the
//! same photograph turned and zoomed about its centre (SPEC 4.3).
//!
//! `cargo run --release -p ocellus-fovea --example logpolar_register [ANGLE_DEG SCALE]`

use ocellus_fovea::register::{register, warp_similarity, RegisterOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<f64> = std::env::args().skip(1).map(|a| a.parse()).collect::<Result<_, _>>()?;
    let (angle_deg, scale) = match args[..] {
        [a, s] => (a, s),
        [] => (37.5, 1.3),
        _ => return Err("give ANGLE_DEG SCALE, or nothing".into()),
    };
    let photo = ocellus_io::read_image(ocellus_testdata::data_file("camera.png"))?;
    let a = photo.to_luma8().map(|v| v as f32);
    let b = warp_similarity(&a, angle_deg.to_radians(), scale);
    let t = std::time::Instant::now();
    let r = register(&a, &b, &RegisterOptions::default())?;
    let ms = t.elapsed().as_secs_f64() * 1e3;
    println!("true: {angle_deg:.2} deg, scale {scale:.3}");
    println!("estimated: {:.2} deg, scale {:.3} (peak {:.3}), {ms:.1} ms", r.angle_deg, r.scale, r.peak);
    Ok(())
}
