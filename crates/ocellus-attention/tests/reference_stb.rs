//! The `stb` preset against maps made by the SaliencyToolbox itself (testdata/reference).
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

use ocellus_attention::{config::ChannelKind, SaliencyConfig, SaliencyEngine};
use ocellus_image::Plane;
use ocellus_testdata::data_file;

fn pearson(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma) * (x - ma);
        sbb += (y - mb) * (y - mb);
    }
    sab / (saa.sqrt() * sbb.sqrt())
}

fn flat(p: &Plane<f32>) -> Vec<f64> {
    p.to_vec().into_iter().map(|v| v as f64).collect()
}

/// (saliency CC, [colour, intensity, orientation] CC) for one reference image.
fn compare(name: &str) -> (f64, [f64; 3]) {
    let img = ocellus_io::read_image(data_file(&format!("reference/{name}_640x480.png"))).unwrap();
    let mut engine = SaliencyEngine::new(SaliencyConfig::stb(), 640, 480).unwrap();
    let sal = engine.process(&img).unwrap().clone();
    assert_eq!(sal.size(), (40, 30));
    let ref_sal = ocellus_io::npy::read(data_file(&format!("reference/{name}_stb_salmap_30x40.npy"))).unwrap();
    assert_eq!(ref_sal.shape, vec![30, 40]);
    let cc_sal = pearson(&flat(&sal), &ref_sal.data);
    let ref_cm = ocellus_io::npy::read(data_file(&format!("reference/{name}_stb_conspicuity_30x40x3.npy"))).unwrap();
    assert_eq!(ref_cm.shape, vec![30, 40, 3]);
    let mut ccs = [0.0; 3];
    for (k, kind) in [ChannelKind::Color, ChannelKind::Intensity, ChannelKind::Orientation].iter().enumerate() {
        let ci = engine.config().channels.iter().position(|c| &c.kind == kind).unwrap();
        let ours = flat(engine.conspicuity(ci).unwrap());
        let theirs: Vec<f64> = (0..1200).map(|i| ref_cm.data[i * 3 + k]).collect();
        ccs[k] = pearson(&ours, &theirs);
    }
    println!(
        "{name}: saliency CC {cc_sal:.4}; conspicuity CC colour {:.4} intensity {:.4} orientation {:.4}",
        ccs[0], ccs[1], ccs[2]
    );
    (cc_sal, ccs)
}

#[test]
fn stb_preset_matches_saliency_toolbox_astronaut() {
    let (s, c) = compare("astronaut");
    assert!(s >= 0.95, "saliency CC {s}");
    assert!(c.iter().all(|&v| v >= 0.90), "conspicuity CC {c:?}");
}

#[test]
fn stb_preset_matches_saliency_toolbox_chelsea() {
    let (s, c) = compare("chelsea");
    assert!(s >= 0.95, "saliency CC {s}");
    assert!(c.iter().all(|&v| v >= 0.90), "conspicuity CC {c:?}");
}
