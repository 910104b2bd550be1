//! Prints SGM stage times on the motorcycle pair (reads testdata/): a profiling aid.
#![allow(clippy::unwrap_used, clippy::expect_used)]
use ocellus_geometry::sgm::{Sgm, SgmMatcher, SgmPaths};

fn main() {
    let grey = |n: &str| ocellus_io::read_image(ocellus_testdata::data_file(n)).unwrap().to_luma8();
    let (l, r) = (grey("motorcycle_left.png"), grey("motorcycle_right.png"));
    for paths in [SgmPaths::Eight, SgmPaths::Four] {
        let mut m = SgmMatcher::new(Sgm { paths, median: true, ..Sgm::default() }, l.width(), l.height()).unwrap();
        for _ in 0..5 {
            m.compute(&l, &r).unwrap();
        }
        println!("{paths:?}: {:?}", m.timings());
    }
}
