//! Times the log-polar map at 640x480: a tuning aid. Arguments: `grey|rgb`, fields
//! (`pyramid|area`), max level.
#![allow(clippy::unwrap_used, clippy::expect_used)]
use ocellus_fovea::logpolar::{Fields, LogPolarConfig, LogPolarMap, Scratch};
use ocellus_image::Plane;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let rgb_mode = args.get(1).is_some_and(|a| a == "rgb");
    let fields = if args.get(2).is_some_and(|a| a == "area") { Fields::Area } else { Fields::Pyramid };
    let top: usize = args.get(3).and_then(|a| a.parse().ok()).unwrap_or(4);
    let src = ocellus_io::read_image(ocellus_testdata::data_file("retina.jpg")).unwrap().to_u8();
    let rgb = Plane::from_fn(640, 480, |x, y| src.get(x + 385, y + 465));
    let grey = rgb.map(|p| ((p[0] as u32 + p[1] as u32 + p[2] as u32) / 3) as u8);
    let cfg = LogPolarConfig { fields, max_level: top, ..LogPolarConfig::for_image(640, 480) };
    let t = std::time::Instant::now();
    let map = LogPolarMap::new(&cfg, 640, 480).unwrap();
    let build = t.elapsed().as_secs_f64() * 1e3;
    let mut scratch = Scratch::default();
    let mut out = Plane::default();
    let mut rgb_out = <[Plane<f32>; 3]>::default();
    let mut ts = Vec::new();
    for _ in 0..3000 {
        let t = std::time::Instant::now();
        if rgb_mode {
            map.sample_rgb_into(&rgb, &mut scratch, &mut rgb_out).unwrap();
        } else {
            map.sample_grey_into(&grey, &mut scratch, &mut out).unwrap();
        }
        ts.push(t.elapsed().as_secs_f64() * 1e6);
    }
    ts.sort_by(f64::total_cmp);
    println!(
        "{} {fields:?} max_level {top}: {} entries, build {build:.1} ms, {:.1} us",
        if rgb_mode { "rgb" } else { "grey" },
        map.table_entries(),
        ts[ts.len() / 2]
    );
}
