//! Steady state allocates nothing: after the first frames, `process` reuses every buffer.
#![allow(clippy::unwrap_used, clippy::expect_used)] // tests abort on broken set-up

use ocellus_attention::{SaliencyConfig, SaliencyEngine};
use ocellus_image::convert::RgbImage;
use ocellus_image::Plane;
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;
static ALLOCS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator, only counting calls.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        ALLOCS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        ALLOCS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(p, l, n) }
    }
}

#[global_allocator]
static A: Counting = Counting;

#[test]
fn process_does_not_allocate_in_steady_state() {
    let img = ocellus_io::read_image(ocellus_testdata::data_file("reference/chelsea_640x480.png")).unwrap();
    let other = RgbImage::U8(Plane::from_fn(640, 480, |x, y| [(x % 256) as u8, (y % 256) as u8, 90]));
    for preset in SaliencyConfig::PRESETS {
        let mut e = SaliencyEngine::new(SaliencyConfig::preset(preset).unwrap(), 640, 480).unwrap();
        e.process(&img).unwrap();
        e.process(&other).unwrap();
        let before = ALLOCS.load(Ordering::Relaxed);
        for _ in 0..3 {
            e.process(&img).unwrap();
            e.process(&other).unwrap();
        }
        let n = ALLOCS.load(Ordering::Relaxed) - before;
        assert_eq!(n, 0, "{preset}: {n} allocations in 6 steady-state frames");
    }
}
