//! Combining maps (SPEC 1.7): sums, weights, and packing maps into SIMD lanes so eight of
//! them go through N(.) at once. All maps of one call have the same size.

use ocellus_image::preserving::Lanes;
use ocellus_image::Plane;

#[cfg(target_arch = "x86_64")]
mod x86;

/// Packs up to eight same-size maps into the lanes of `lanes` (missing maps give zeros).
pub fn interleave(maps: &[Option<&Plane<f32>>; 8], lanes: &mut Plane<Lanes>) {
    let Some(first) = maps[0] else { return };
    let (w, h) = first.size();
    lanes.resize(w, h);
    #[cfg(target_arch = "x86_64")]
    let fast = ocellus_image::simd::avx2_available() && maps.iter().flatten().all(|m| m.size() == (w, h));
    for y in 0..h {
        let rows: [Option<&[f32]>; 8] = maps.map(|m| m.map(|p| p.row(y)));
        #[cfg(target_arch = "x86_64")]
        if fast {
            // SAFETY: AVX2 was checked above, and every map is w x h, so each row holds the
            // `w` values read.
            unsafe { x86::interleave_row(&rows, lanes.row_mut(y)) };
            continue;
        }
        for (x, px) in lanes.row_mut(y).iter_mut().enumerate() {
            *px = rows.map(|r| r.map_or(0.0, |r| r[x]));
        }
    }
}

/// `acc += lane l of lanes`.
pub fn add_lane(acc: &mut Plane<f32>, lanes: &Plane<Lanes>, l: usize) {
    for y in 0..acc.height() {
        let src = lanes.row(y);
        acc.row_mut(y).iter_mut().zip(src).for_each(|(a, p)| *a += p[l]);
    }
}

/// `dst = lane l of lanes`.
pub fn copy_lane(dst: &mut Plane<f32>, lanes: &Plane<Lanes>, l: usize) {
    for y in 0..dst.height() {
        let src = lanes.row(y);
        dst.row_mut(y).iter_mut().zip(src).for_each(|(a, p)| *a = p[l]);
    }
}

/// `acc += x`.
pub fn add_into(acc: &mut Plane<f32>, x: &Plane<f32>) {
    for y in 0..acc.height() {
        let xr = x.row(y);
        acc.row_mut(y).iter_mut().zip(xr).for_each(|(a, b)| *a += b);
    }
}

/// `p *= f`.
pub fn scale(p: &mut Plane<f32>, f: f32) {
    for y in 0..p.height() {
        p.row_mut(y).iter_mut().for_each(|v| *v *= f);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Packing puts map l's pixel (x, y) in lane l of pixel (x, y), zeros for missing maps,
    /// at widths around the transpose's block of eight.
    #[test]
    fn interleave_places_each_map_in_its_lane() {
        for (w, h) in [(1, 1), (7, 2), (8, 3), (9, 2), (40, 30), (43, 5)] {
            let maps: Vec<Plane<f32>> =
                (0..6).map(|l| Plane::from_fn(w, h, |x, y| (l * 10000 + y * 100 + x) as f32)).collect();
            let sel: [Option<&Plane<f32>>; 8] = std::array::from_fn(|l| if l == 3 { None } else { maps.get(l) });
            let mut lanes = Plane::default();
            interleave(&sel, &mut lanes);
            for y in 0..h {
                for x in 0..w {
                    let px = lanes.get(x, y);
                    for l in 0..8 {
                        let want = if l == 3 || l >= 6 { 0.0 } else { (l * 10000 + y * 100 + x) as f32 };
                        assert_eq!(px[l], want, "{w}x{h} ({x}, {y}) lane {l}");
                    }
                }
            }
        }
    }
}
