// The map-level stages of the saliency pipeline (SPEC 1.5-1.7) on the maps of the front end:
// across-scale rescaling, center-surround differences with attenuated borders, N(.) and the
// combination into conspicuity and saliency maps. Every map of the map level is small (40x30
// for 640x480), so one workgroup owns one map from start to end and loops over its pixels;
// the iterations of N(.) then need no dispatch of their own, only barriers. Each workgroup
// works in its own region of `scratch` (4 maps: the map, the filter's row pass, excitation,
// inhibition).
//
// `tables` holds, as u32 (floats by bit pattern):
// - per rescale job (6 words): source offset, source width, source buffer (0: `planes`,
//   1: `energies`), destination offset in `rescaled`, x table, y table; an axis table has 3 words per output
//   index: i0, i1, weight of i1 (bilinear; nearest has i0 = i1);
// - per feature map (2 words): offsets in `rescaled` of its center and surround;
// - per sub-feature (2 words): its first feature map and their count;
// - per channel (4 words): first sub-feature, count, weight (bits), whether to apply N(.);
// - the 1D kernels of N(.)'s excitation and inhibition and their per-column and per-row
//   energy-preserving factors sum(kernel) / sum(kernel taps inside the map).
struct Params {
    map_w: u32,
    map_h: u32,
    n_rescale: u32,
    n_features: u32,
    n_subs: u32,
    n_channels: u32,
    // 0: none, 1: iterative difference of Gaussians, 2: local maxima (Itti et al. 1998).
    kind: u32,
    iterations: u32,
    relative_inhibition: u32,
    inhibition: f32,
    feature_range: f32,
    flat_tolerance: f32,
    // <= 0: no final rescaling.
    final_range: f32,
    ramp: u32,
    ex_len: u32,
    in_len: u32,
    ex_k: u32,
    in_k: u32,
    ex_fx: u32,
    ex_fy: u32,
    in_fx: u32,
    in_fy: u32,
    rescale_jobs: u32,
    feature_jobs: u32,
    sub_jobs: u32,
    channel_jobs: u32,
    subs_at: u32,
    consp_at: u32,
    saliency_at: u32,
    // The normalized feature maps, after the maps read back.
    normed_at: u32,
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var<uniform> p: Params;
@group(0) @binding(1) var<storage, read> planes: array<f32>;
@group(0) @binding(2) var<storage, read> tables: array<u32>;
@group(0) @binding(3) var<storage, read_write> rescaled: array<f32>;
@group(0) @binding(4) var<storage, read_write> maps: array<f32>;
@group(0) @binding(5) var<storage, read_write> scratch: array<f32>;
@group(0) @binding(6) var<storage, read> energies: array<f32>;

const WG: u32 = 256u;
var<workgroup> red_a: array<f32, 256>;
var<workgroup> red_b: array<f32, 256>;
var<workgroup> shared_word: u32;

fn tf(i: u32) -> f32 {
    return bitcast<f32>(tables[i]);
}

// The same word in every invocation (and known as uniform to the shader compiler).
fn broadcast(i: u32, lid: u32) -> u32 {
    if (lid == 0u) {
        shared_word = tables[i];
    }
    return workgroupUniformLoad(&shared_word);
}

fn source(which: u32, i: u32) -> f32 {
    if (which == 0u) {
        return planes[i];
    }
    return energies[i];
}

// Row `y0` of the source lerped towards row `y1` at column `x` (the CPU's vertical pass).
fn column_lerp(which: u32, src: u32, sw: u32, y0: u32, y1: u32, fy: f32, x: u32) -> f32 {
    let a = source(which, src + y0 * sw + x);
    if (fy == 0.0) {
        return a;
    }
    return fma(fy, source(which, src + y1 * sw + x) - a, a);
}

// One level of one sub-feature to the map level (`ocellus_image::resample::Resampler`).
@compute @workgroup_size(256)
fn rescale(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let j = p.rescale_jobs + 6u * wid.x;
    let src = tables[j];
    let sw = tables[j + 1u];
    let which = tables[j + 2u];
    let dst = tables[j + 3u];
    let xs = tables[j + 4u];
    let ys = tables[j + 5u];
    let n = p.map_w * p.map_h;
    for (var i = lid; i < n; i += WG) {
        let x = i % p.map_w;
        let y = i / p.map_w;
        let ty = ys + 3u * y;
        let y0 = tables[ty];
        let y1 = tables[ty + 1u];
        let fy = tf(ty + 2u);
        let tx = xs + 3u * x;
        let r0 = column_lerp(which, src, sw, y0, y1, fy, tables[tx]);
        let r1 = column_lerp(which, src, sw, y0, y1, fy, tables[tx + 1u]);
        rescaled[dst + i] = fma(tf(tx + 2u), r1 - r0, r0);
    }
}

// Minimum and maximum of scratch[base .. base + n], the same in every invocation.
fn min_max(base: u32, n: u32, lid: u32) -> vec2<f32> {
    var lo = 3.0e38;
    var hi = -3.0e38;
    for (var i = lid; i < n; i += WG) {
        let v = scratch[base + i];
        lo = min(lo, v);
        hi = max(hi, v);
    }
    red_a[lid] = lo;
    red_b[lid] = hi;
    for (var s = WG / 2u; s > 0u; s = s / 2u) {
        workgroupBarrier();
        if (lid < s) {
            red_a[lid] = min(red_a[lid], red_a[lid + s]);
            red_b[lid] = max(red_b[lid], red_b[lid + s]);
        }
    }
    workgroupBarrier();
    let r = vec2<f32>(red_a[0], red_b[0]);
    workgroupBarrier();
    return r;
}

// Sums of two per-invocation values over the workgroup, the same in every invocation.
fn sum2(a: f32, b: f32, lid: u32) -> vec2<f32> {
    red_a[lid] = a;
    red_b[lid] = b;
    for (var s = WG / 2u; s > 0u; s = s / 2u) {
        workgroupBarrier();
        if (lid < s) {
            red_a[lid] = red_a[lid] + red_a[lid + s];
            red_b[lid] = red_b[lid] + red_b[lid + s];
        }
    }
    workgroupBarrier();
    let r = vec2<f32>(red_a[0], red_b[0]);
    workgroupBarrier();
    return r;
}

// The energy-preserving separable filter (`ocellus_image::preserving::PreservingFilter`):
// zero border, each pass rescaled by sum(kernel) / sum(taps inside the map).
fn preserve(src: u32, tmp: u32, dst: u32, k: u32, len: u32, fx: u32, fy: u32, lid: u32) {
    let w = p.map_w;
    let h = p.map_h;
    let n = w * h;
    let hw = i32(len / 2u);
    for (var i = lid; i < n; i += WG) {
        let x = i32(i % w);
        let row = src + (i / w) * w;
        var acc = 0.0;
        for (var t = 0; t < i32(len); t++) {
            let xx = x + t - hw;
            if (xx >= 0 && xx < i32(w)) {
                acc = fma(tf(k + u32(t)), scratch[row + u32(xx)], acc);
            }
        }
        scratch[tmp + i] = acc * tf(fx + u32(x));
    }
    storageBarrier();
    for (var i = lid; i < n; i += WG) {
        let x = i % w;
        let y = i32(i / w);
        var acc = 0.0;
        for (var t = 0; t < i32(len); t++) {
            let yy = y + t - hw;
            if (yy >= 0 && yy < i32(h)) {
                acc = fma(tf(k + u32(t)), scratch[tmp + u32(yy) * w + x], acc);
            }
        }
        scratch[dst + i] = acc * tf(fy + u32(y));
    }
    storageBarrier();
}

// Itti et al. 1998 (`normalize::local_max` of ocellus-attention).
fn local_max(base: u32, range: f32, lid: u32) {
    let w = p.map_w;
    let h = p.map_h;
    let n = w * h;
    var thresh = 1.0;
    var gmax = range;
    if (range > 0.0) {
        thresh = range / 10.0;
    } else {
        gmax = min_max(base, n, lid).y;
    }
    var count = 0.0;
    var sum = 0.0;
    for (var i = lid; i < n; i += WG) {
        let x = i % w;
        let y = i / w;
        if (x >= 1u && y >= 1u && x + 1u < w && y + 1u < h) {
            let v = scratch[base + i];
            if (v >= thresh && v >= scratch[base + i - 1u] && v >= scratch[base + i + 1u]
                && v >= scratch[base + i - w] && v >= scratch[base + i + w]) {
                count += 1.0;
                sum += v;
            }
        }
    }
    let t = sum2(count, sum, lid);
    var f = 1.0;
    if (t.x == 1.0) {
        f = gmax * gmax;
    } else if (t.x > 1.0) {
        let d = gmax - t.y / t.x;
        f = d * d;
    }
    for (var i = lid; i < n; i += WG) {
        scratch[base + i] *= f;
    }
    storageBarrier();
}

// N(.) in place on scratch[base .. base + n] (`Normalizer::apply`): clamp at 0, scale to
// [0, range] when range > 0 (flat maps to range / 2), then compete.
fn normalize(base: u32, range: f32, lid: u32) {
    let n = p.map_w * p.map_h;
    for (var i = lid; i < n; i += WG) {
        scratch[base + i] = max(scratch[base + i], 0.0);
    }
    storageBarrier();
    if (range > 0.0) {
        let mm = min_max(base, n, lid);
        let flat = mm.y - mm.x <= p.flat_tolerance;
        let s = range / (mm.y - mm.x);
        for (var i = lid; i < n; i += WG) {
            if (flat) {
                scratch[base + i] = 0.5 * range;
            } else {
                scratch[base + i] = (scratch[base + i] - mm.x) * s;
            }
        }
        storageBarrier();
    }
    if (p.kind == 1u) {
        for (var it = 0u; it < p.iterations; it++) {
            preserve(base, base + n, base + 2u * n, p.ex_k, p.ex_len, p.ex_fx, p.ex_fy, lid);
            preserve(base, base + n, base + 3u * n, p.in_k, p.in_len, p.in_fx, p.in_fy, lid);
            var c = p.inhibition;
            if (p.relative_inhibition != 0u) {
                c = p.inhibition * min_max(base, n, lid).y;
            }
            for (var i = lid; i < n; i += WG) {
                let v = scratch[base + i] + scratch[base + 2u * n + i] - scratch[base + 3u * n + i] - c;
                scratch[base + i] = max(v, 0.0);
            }
            storageBarrier();
        }
    } else if (p.kind == 2u) {
        local_max(base, range, lid);
    }
}

// The border ramp of `attenuate_borders` at index i of an axis of n pixels.
fn ramp(i: u32, len: u32) -> f32 {
    let r = min(p.ramp, min(p.map_w / 2u, p.map_h / 2u));
    if (i < r) {
        return f32(i + 1u) / f32(r + 1u);
    }
    if (i >= len - r) {
        return f32(len - i) / f32(r + 1u);
    }
    return 1.0;
}

// One feature map: |center - surround|, borders attenuated (kept as the feature map), then
// N(.) with rescaling (kept for the sub-feature sums).
@compute @workgroup_size(256)
fn features(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let f = wid.x;
    let n = p.map_w * p.map_h;
    let base = 4u * n * f;
    let c = tables[p.feature_jobs + 2u * f];
    let s = tables[p.feature_jobs + 2u * f + 1u];
    for (var i = lid; i < n; i += WG) {
        let x = i % p.map_w;
        let y = i / p.map_w;
        let v = abs(rescaled[c + i] - rescaled[s + i]) * ramp(y, p.map_h) * ramp(x, p.map_w);
        scratch[base + i] = v;
        maps[f * n + i] = v;
    }
    storageBarrier();
    normalize(base, p.feature_range, lid);
    for (var i = lid; i < n; i += WG) {
        maps[p.normed_at + f * n + i] = scratch[base + i];
    }
}

// One sub-feature: the sum of its normalized feature maps, N(.) without rescaling.
@compute @workgroup_size(256)
fn subfeatures(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let s = wid.x;
    let n = p.map_w * p.map_h;
    let base = 4u * n * s;
    let first = tables[p.sub_jobs + 2u * s];
    let count = tables[p.sub_jobs + 2u * s + 1u];
    for (var i = lid; i < n; i += WG) {
        var a = 0.0;
        for (var k = 0u; k < count; k++) {
            a += maps[p.normed_at + (first + k) * n + i];
        }
        scratch[base + i] = a;
    }
    storageBarrier();
    normalize(base, 0.0, lid);
    for (var i = lid; i < n; i += WG) {
        maps[p.subs_at + s * n + i] = scratch[base + i];
    }
}

// The conspicuity maps (sum of a channel's sub-features, N(.) when there are several,
// times the channel's weight) and their sum, the saliency map (rescaled when final_range > 0).
@compute @workgroup_size(256)
fn combine(@builtin(local_invocation_index) lid: u32) {
    let n = p.map_w * p.map_h;
    for (var c = 0u; c < p.n_channels; c++) {
        let j = p.channel_jobs + 4u * c;
        let first = tables[j];
        let count = tables[j + 1u];
        let weight = tf(j + 2u);
        for (var i = lid; i < n; i += WG) {
            var a = 0.0;
            for (var k = 0u; k < count; k++) {
                a += maps[p.subs_at + (first + k) * n + i];
            }
            scratch[i] = a;
        }
        storageBarrier();
        if (broadcast(j + 3u, lid) != 0u) {
            normalize(0u, 0.0, lid);
        }
        for (var i = lid; i < n; i += WG) {
            let v = scratch[i] * weight;
            maps[p.consp_at + c * n + i] = v;
            if (c == 0u) {
                maps[p.saliency_at + i] = v;
            } else {
                maps[p.saliency_at + i] += v;
            }
        }
        storageBarrier();
    }
    if (p.final_range > 0.0) {
        for (var i = lid; i < n; i += WG) {
            scratch[i] = maps[p.saliency_at + i];
        }
        storageBarrier();
        normalize(0u, p.final_range, lid);
        for (var i = lid; i < n; i += WG) {
            maps[p.saliency_at + i] = scratch[i];
        }
    }
}
