//! Combining maps (SPEC 1.7): sums, weights, and packing maps into SIMD lanes so eight of
//! them go through N(.) at once. All maps of one call have the same size.

use ocellus_image::preserving::Lanes;
use ocellus_image::Plane;

/// Packs up to eight same-size maps into the lanes of `lanes` (missing maps give zeros).
pub fn interleave(maps: &[Option<&Plane<f32>>; 8], lanes: &mut Plane<Lanes>) {
    let Some(first) = maps[0] else { return };
    lanes.resize(first.width(), first.height());
    for y in 0..first.height() {
        let rows: [Option<&[f32]>; 8] = maps.map(|m| m.map(|p| p.row(y)));
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
