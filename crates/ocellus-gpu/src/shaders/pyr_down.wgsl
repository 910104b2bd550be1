// One pass of the pyramid's separable low-pass and decimation (SPEC 1.2), with the taps of
// each output index from a table (input index, weight; truncated and renormalized at the
// borders, zero-weight padding). `vertical`: dst (w x h_out) from src (w x h_in);
// `horizontal`: dst (w_out x h) from src (w_in x h).
struct Dims { w_in: u32, h_in: u32, w_out: u32, h_out: u32, k: u32, a: u32, b: u32, c: u32 }
struct Tap { i: u32, w: f32 }
@group(0) @binding(0) var<uniform> dims: Dims;
@group(0) @binding(1) var<storage, read> src: array<f32>;
@group(0) @binding(2) var<storage, read> taps: array<Tap>;
@group(0) @binding(3) var<storage, read_write> dst: array<f32>;

@compute @workgroup_size(64, 4)
fn vertical(@builtin(global_invocation_id) id: vec3<u32>) {
    let x = id.x;
    let j = id.y;
    if (x >= dims.w_out || j >= dims.h_out) {
        return;
    }
    var s = 0.0;
    for (var t = 0u; t < dims.k; t++) {
        let tap = taps[j * dims.k + t];
        s += tap.w * src[tap.i * dims.w_in + x];
    }
    dst[j * dims.w_out + x] = s;
}

@compute @workgroup_size(64, 4)
fn horizontal(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    let y = id.y;
    if (i >= dims.w_out || y >= dims.h_out) {
        return;
    }
    var s = 0.0;
    for (var t = 0u; t < dims.k; t++) {
        let tap = taps[i * dims.k + t];
        s += tap.w * src[y * dims.w_in + tap.i];
    }
    dst[y * dims.w_out + i] = s;
}
