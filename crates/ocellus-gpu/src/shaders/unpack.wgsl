// 8-bit interleaved RGB (packed 4 bytes per u32, little-endian) to three float planes in
// [0, 1]: level 0 of the colour pyramids.
struct Dims { n: u32, a: u32, b: u32, c: u32 }
@group(0) @binding(0) var<uniform> dims: Dims;
@group(0) @binding(1) var<storage, read> src: array<u32>;
@group(0) @binding(2) var<storage, read_write> r: array<f32>;
@group(0) @binding(3) var<storage, read_write> g: array<f32>;
@group(0) @binding(4) var<storage, read_write> b: array<f32>;

fn byte_at(k: u32) -> f32 {
    return f32((src[k >> 2u] >> ((k & 3u) * 8u)) & 255u);
}

@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = id.y * 65535u * 256u + id.x;
    if (p >= dims.n) {
        return;
    }
    r[p] = byte_at(3u * p) / 255.0;
    g[p] = byte_at(3u * p + 1u) / 255.0;
    b[p] = byte_at(3u * p + 2u) / 255.0;
}
