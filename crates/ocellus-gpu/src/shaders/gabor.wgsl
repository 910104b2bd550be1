// Gabor energy M_theta = |I * G_0| + |I * G_pi/2| for every angle at once (SPEC 1.4), by
// direct 2D correlation with the mean-removed, unit-norm kernels, edge pixels repeated
// outward (clamp). `kernels[t * n_angles + a]` holds (even, odd) of tap t (row-major,
// size x size) for angle a; `dst` holds one plane per angle.
struct Dims { w: u32, h: u32, size: u32, n_angles: u32 }
@group(0) @binding(0) var<uniform> dims: Dims;
@group(0) @binding(1) var<storage, read> src: array<f32>;
@group(0) @binding(2) var<storage, read> kernels: array<vec2<f32>>;
@group(0) @binding(3) var<storage, read_write> dst: array<f32>;

const MAX_ANGLES: u32 = 8u;

@compute @workgroup_size(16, 16)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let x = i32(id.x);
    let y = i32(id.y);
    let w = i32(dims.w);
    let h = i32(dims.h);
    if (x >= w || y >= h) {
        return;
    }
    let half = i32(dims.size / 2u);
    var acc: array<vec2<f32>, MAX_ANGLES>;
    for (var a = 0u; a < MAX_ANGLES; a++) {
        acc[a] = vec2<f32>(0.0, 0.0);
    }
    var t = 0u;
    for (var j = -half; j <= half; j++) {
        let row = clamp(y + j, 0, h - 1) * w;
        for (var i = -half; i <= half; i++) {
            let v = src[row + clamp(x + i, 0, w - 1)];
            for (var a = 0u; a < dims.n_angles; a++) {
                acc[a] += v * kernels[t * dims.n_angles + a];
            }
            t++;
        }
    }
    let plane = dims.w * dims.h;
    let p = u32(y) * dims.w + u32(x);
    for (var a = 0u; a < dims.n_angles; a++) {
        dst[a * plane + p] = abs(acc[a].x) + abs(acc[a].y);
    }
}
