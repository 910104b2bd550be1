//! Scores the saliency of four MIT1003 photographs (Judd et al. 2009) against their human
//! fixation density maps with the benchmark protocol: the raw map, the map with the shipped
//! blur and centre prior, and the centre prior alone.
//!
//! `cargo run --release -p ocellus-eval --example mit1003_scores`

use ocellus_attention::{SaliencyConfig, SaliencyEngine};
use ocellus_eval::protocol::{mean_se, no_prior, score_all, Sample, DEFAULT_PRIOR};
use ocellus_image::Backend;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = ocellus_testdata::data_file("mit1003");
    let mut samples = Vec::new();
    let mut paths: Vec<_> =
        std::fs::read_dir(dir.join("stimuli"))?.map(|e| e.map(|e| e.path())).collect::<Result<_, _>>()?;
    paths.sort();
    for path in paths {
        let image = ocellus_io::read_image(&path)?;
        let density = ocellus_io::read_image(dir.join("fixation_maps").join(path.file_name().ok_or("no name")?))?;
        let (w, h) = image.size();
        let mut engine = SaliencyEngine::new(SaliencyConfig::ace2009(), w, h)?;
        let map = engine.process(&image)?.clone();
        let density = density.to_grey().map(f64::from);
        samples.push(Sample { map: Some(map), size: density.size(), density: Some(density), fixations: None });
    }
    let centre_only: Vec<Sample> = samples.iter().map(|s| Sample { map: None, ..s.clone() }).collect();
    println!("{} images; mean (standard error) of CC, SIM, KL against the fixation density:", samples.len());
    for (what, set, prior) in [
        ("ace2009 map", &samples, no_prior()),
        ("with blur and centre prior", &samples, DEFAULT_PRIOR),
        ("centre prior alone", &centre_only, DEFAULT_PRIOR),
    ] {
        let scores = score_all(Backend::Auto, set, &prior, &|| ())?;
        let column = |k: usize| mean_se(&scores.iter().filter_map(|s| s.density.map(|d| d[k])).collect::<Vec<_>>());
        let [cc, sim, kl] = [column(0), column(1), column(2)];
        println!(
            "  {what:<28} CC {:.3} ({:.3})  SIM {:.3} ({:.3})  KL {:.3} ({:.3})",
            cc.0, cc.1, sim.0, sim.1, kl.0, kl.1
        );
    }
    Ok(())
}
