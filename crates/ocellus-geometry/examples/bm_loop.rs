//! Runs block matching on the motorcycle pair repeatedly and prints the median time: a
//! profiling aid (reads testdata/).
#![allow(clippy::unwrap_used, clippy::expect_used)]
use ocellus_geometry::block_matching::{block_match, BlockMatching};

fn main() {
    let grey = |n: &str| ocellus_io::read_image(ocellus_testdata::data_file(n)).unwrap().to_luma8();
    let (l, r) = (grey("motorcycle_left.png"), grey("motorcycle_right.png"));
    let mut t: Vec<f64> = (0..40)
        .map(|_| {
            let s = std::time::Instant::now();
            block_match(&l, &r, &BlockMatching::default()).unwrap();
            s.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    t.sort_by(f64::total_cmp);
    println!("block matching median {:.2} ms", t[t.len() / 2]);
}
