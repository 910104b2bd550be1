// Intensity and colour opponency of one pyramid level (SPEC 1.3, Walther & Koch 2006):
// I = w . (r, g, b); RG = (r - g) / max, BY = (b - min(r, g)) / max, both 0 where
// max(r, g, b) < threshold (or is not positive).
struct Dims { n: u32, a: u32, b: u32, c: u32, wr: f32, wg: f32, wb: f32, threshold: f32 }
@group(0) @binding(0) var<uniform> dims: Dims;
@group(0) @binding(1) var<storage, read> r: array<f32>;
@group(0) @binding(2) var<storage, read> g: array<f32>;
@group(0) @binding(3) var<storage, read> b: array<f32>;
@group(0) @binding(4) var<storage, read_write> intensity: array<f32>;
@group(0) @binding(5) var<storage, read_write> rg: array<f32>;
@group(0) @binding(6) var<storage, read_write> by: array<f32>;

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.x;
    if (p >= dims.n) {
        return;
    }
    let rr = r[p];
    let gg = g[p];
    let bb = b[p];
    intensity[p] = dims.wr * rr + dims.wg * gg + dims.wb * bb;
    let mx = max(max(rr, gg), bb);
    if (mx < dims.threshold || mx <= 0.0) {
        rg[p] = 0.0;
        by[p] = 0.0;
    } else {
        rg[p] = (rr - gg) / mx;
        by[p] = (bb - min(rr, gg)) / mx;
    }
}
