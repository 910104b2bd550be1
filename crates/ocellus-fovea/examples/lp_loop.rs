//! Times the log-polar map at 640x480 for a few field settings: a tuning aid.
#![allow(clippy::unwrap_used, clippy::expect_used)]
use ocellus_fovea::logpolar::{Fields, LogPolarConfig, LogPolarMap, Scratch};
use ocellus_image::Plane;

fn main() {
    let src = ocellus_io::read_image(ocellus_testdata::data_file("retina.jpg")).unwrap().to_u8();
    let rgb = Plane::from_fn(640, 480, |x, y| src.get(x + 385, y + 465));
    let grey = rgb.map(|p| ((p[0] as u32 + p[1] as u32 + p[2] as u32) / 3) as u8);
    for (fields, mft, top) in [
        (Fields::Pyramid, 1.0, 4),
        (Fields::Pyramid, 1.0, 0),
        (Fields::Pyramid, 2.0, 4),
        (Fields::Area, 1.0, 4),
        (Fields::Area, 2.0, 4),
    ] {
        let cfg =
            LogPolarConfig { min_field_texels: mft, fields, max_level: top, ..LogPolarConfig::for_image(640, 480) };
        let t = std::time::Instant::now();
        let map = LogPolarMap::new(&cfg, 640, 480).unwrap();
        let build = t.elapsed().as_secs_f64() * 1e3;
        let mut scratch = Scratch::default();
        let mut out = Plane::default();
        let mut rgb_out = Vec::new();
        let (mut tg, mut tc) = (Vec::new(), Vec::new());
        for _ in 0..300 {
            let t = std::time::Instant::now();
            map.sample_grey_into(&grey, &mut scratch, &mut out).unwrap();
            tg.push(t.elapsed().as_secs_f64() * 1e6);
            let t = std::time::Instant::now();
            map.sample_rgb_into(&rgb, &mut scratch, &mut rgb_out).unwrap();
            tc.push(t.elapsed().as_secs_f64() * 1e6);
        }
        tg.sort_by(f64::total_cmp);
        tc.sort_by(f64::total_cmp);
        println!(
            "{fields:?} min_field_texels {mft} max_level {top}: {} entries ({:.1}/cell), build {build:.1} ms, grey {:.1} us, rgb {:.1} us",
            map.table_entries(),
            map.table_entries() as f64 / (map.rows() * map.sectors()) as f64,
            tg[150],
            tc[150]
        );
    }
}
