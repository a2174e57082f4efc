#version 450
// Final pixel (src/gpu/passes/compose.rs): per sample, emission + per-pixel direct light with
// the shadow maps + indirect (vertex-interpolated, or the normalized splat sum); environment
// where nothing was hit; back faces are black (one-sided surfaces). Averages the 2x2 samples;
// a pixel at an emitter's edge takes its emission from sub-pixel rays (src/frame/edges.rs).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "shared_direct.glsl"

layout(location = 0) out vec4 color;

// edges.rs DENSE_SAMPLES, SPARSE_SAMPLES, MAX_DENSE_TRIANGLES, OCCLUDER_MARGIN.
const uint AR_EDGE_DENSE_SAMPLES = 32u;
const uint AR_EDGE_SPARSE_SAMPLES = 8u;
const uint AR_EDGE_MAX_DENSE_TRIANGLES = 64u;
const float AR_EDGE_OCCLUDER_MARGIN = 0.01;

// edges.rs SampleHit: 0 background, 1 emitter (either side), 2 another surface at `dist`.
uint sample_hit(ivec2 t, out float dist) {
    vec4 g = texelFetch(gbuf_position, t, 0);
    dist = 0.0;
    if (ar_gbuf_background(g.w)) {
        return 0u;
    }
    if (ar_gbuf_emitter(g.w)) {
        return 1u;
    }
    dist = length(g.xyz - pc.eye.xyz);
    return 2u;
}

// The unit camera ray through framebuffer position fb (edges.rs edge_emission's `ray`).
vec3 ar_pixel_ray(mat4 inv, vec2 fb, vec2 size, vec3 eye) {
    vec4 w = inv * vec4(fb / size * 2.0 - 1.0, 0.0, 1.0);
    return normalize(w.xyz / w.w - eye);
}

// edges.rs EmitterTriangles::edge_emission.
vec3 edge_emission(ivec2 px, int ss) {
    uint count = uint(emitter_tris.length());
    uint e = count <= AR_EDGE_MAX_DENSE_TRIANGLES ? AR_EDGE_DENSE_SAMPLES : AR_EDGE_SPARSE_SAMPLES;
    uint kind[4];
    float dist[4];
    for (int q = 0; q < 4; q++) {
        kind[q] = sample_hit(px * ss + ivec2(q % 2, q / 2), dist[q]);
    }
    // Camera rays through framebuffer positions: unproject onto the far plane (reversed depth 0),
    // far from the eye so the subtraction keeps float precision.
    mat4 inv = inverse(pc.view_proj);
    vec2 size = vec2(pc.sizes.xy);  // the output's size (compose.rs)
    vec3 eye = pc.eye.xyz;
    // Most edge pixels need no sub-rays: the ring around an emitter that its footprint misses,
    // and the inside that one triangle covers whole. Every sub-ray is a positive combination of
    // the pixel's 4 corner rays, so a triangle whose barycentric conditions fail (or hold) for
    // all 4 corners alike fails (holds) for every sub-ray: the sub-ray loop below then gives 0,
    // or that triangle's Ke where the 4 samples all hit an emitter (nothing blocks a sub-ray).
    vec3 d00 = ar_pixel_ray(inv, vec2(px), size, eye);
    vec3 d10 = ar_pixel_ray(inv, vec2(px) + vec2(1.0, 0.0), size, eye);
    vec3 d01 = ar_pixel_ray(inv, vec2(px) + vec2(0.0, 1.0), size, eye);
    vec3 d11 = ar_pixel_ray(inv, vec2(px) + vec2(1.0, 1.0), size, eye);
    uint candidates = 0u;
    bool covered = false;
    vec3 covered_ke = vec3(0.0);
    for (uint k = 0u; k < count; k++) {
        EmitterTriangle tri = emitter_tris[k];
        vec3 e1 = tri.c1.xyz - tri.c0.xyz;
        vec3 e2 = tri.c2.xyz - tri.c0.xyz;
        vec3 s = eye - tri.c0.xyz;
        // Möller–Trumbore with the ray's direction d factored out: det = d·a, u·det = d·b,
        // v·det = d·c, t·det = e2·c.
        vec3 a = cross(e2, e1);
        vec3 b = cross(e2, s);
        vec3 c = cross(s, e1);
        vec4 det = vec4(dot(d00, a), dot(d10, a), dot(d01, a), dot(d11, a));
        float sigma = det.x > 0.0 ? 1.0 : -1.0;
        vec4 ad = det * sigma;  // |det| where the corners agree in sign
        vec4 u = vec4(dot(d00, b), dot(d10, b), dot(d01, b), dot(d11, b)) * sigma;
        vec4 v = vec4(dot(d00, c), dot(d10, c), dot(d01, c), dot(d11, c)) * sigma;
        vec4 w = ad - u - v;
        bool agree = all(greaterThan(ad, vec4(1e-30)));
        bool ahead = sigma * dot(e2, c) > 0.0;
        bool missed = agree && (!ahead || all(lessThan(u, vec4(0.0)))
            || all(lessThan(v, vec4(0.0))) || all(lessThan(w, vec4(0.0))));
        if (!missed) {
            candidates++;
            covered = agree && ahead && all(greaterThan(u, vec4(0.0)))
                && all(greaterThan(v, vec4(0.0))) && all(greaterThan(w, vec4(0.0)));
            covered_ke = sigma > 0.0 ? tri.ke.rgb : vec3(0.0);
        }
    }
    if (candidates == 0u) {
        return vec3(0.0);
    }
    if (candidates == 1u && covered && kind[0] == 1u && kind[1] == 1u && kind[2] == 1u
        && kind[3] == 1u) {
        return covered_ke;
    }
    vec3 sum = vec3(0.0);
    for (uint j = 0u; j < e; j++) {
        for (uint i = 0u; i < e; i++) {
            vec3 d = ar_pixel_ray(inv, vec2(px) + (vec2(i, j) + 0.5) / float(e), size, eye);
            float best = 3.0e38;
            bool front = false;
            vec3 ke = vec3(0.0);
            for (uint k = 0u; k < count; k++) {
                EmitterTriangle tri = emitter_tris[k];
                vec3 e1 = tri.c1.xyz - tri.c0.xyz;
                vec3 e2 = tri.c2.xyz - tri.c0.xyz;
                vec3 p = cross(d, e2);
                float det = dot(e1, p);
                if (abs(det) < 1e-30) {
                    continue;
                }
                float inv_det = 1.0 / det;
                vec3 s = eye - tri.c0.xyz;
                float u = dot(s, p) * inv_det;
                if (u < 0.0 || u > 1.0) {
                    continue;
                }
                vec3 q = cross(s, e1);
                float v = dot(d, q) * inv_det;
                if (v < 0.0 || u + v > 1.0) {
                    continue;
                }
                float t = dot(e2, q) * inv_det;
                if (t > 0.0 && t < best) {
                    best = t;
                    front = dot(cross(e1, e2), d) < 0.0;
                    ke = tri.ke.rgb;
                }
            }
            uint q = (2u * j / e) * 2u + 2u * i / e;
            bool blocked = kind[q] == 2u && dist[q] < best * (1.0 - AR_EDGE_OCCLUDER_MARGIN);
            if (best < 3.0e38 && front && !blocked) {
                sum += ke;
            }
        }
    }
    return sum / float(e * e);
}

// The flat surface of pixel `q`'s first sample where it is splatted, else ~0 (frame/splat.rs).
uint ar_first_surface(ivec2 q, int ss) {
    vec4 g = texelFetch(gbuf_position, q * ss, 0);
    if (ar_gbuf_background(g.w)) {
        return 0xFFFFFFFFu;
    }
    FrameElement e = elements[ar_gbuf_leaf(g.w)];
    // As the CPU's (frame/cpu.rs take_pixel_sums): a face seen from behind has no sum to give.
    bool front = dot(pc.eye.xyz - g.xyz, e.face_normal.xyz) > 0.0;
    return (e.ids.z == AR_MODE_VERTEX || !front) ? 0xFFFFFFFFu : e.ids.y;
}

// The normalized sum of a splat texel (0 where no kernel reached it).
vec3 ar_splat_value(vec4 s) {
    return s.a > 0.0 ? s.rgb / s.a : vec3(0.0);
}

// A sample whose first samples around have no weight on its surface: the normalized sum of the
// first neighbouring pixel whose first sample is on it, in splat.rs NEIGHBOURS order, with
// weight 1 (none: a zero weight).
vec4 ar_splat_neighbour(ivec2 px, int ss, uint surface) {
    ivec2 size = ivec2(pc.sizes.xy);
    for (int k = 0; k < 8; k++) {
        int dx = (k == 0 || k == 4 || k == 6) ? 1 : ((k == 2 || k == 5 || k == 7) ? -1 : 0);
        int dy = (k == 1 || k == 4 || k == 5) ? 1 : ((k == 3 || k == 6 || k == 7) ? -1 : 0);
        ivec2 q = px + ivec2(dx, dy);
        if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) {
            continue;
        }
        if (ar_first_surface(q, ss) == surface) {
            return vec4(ar_splat_value(texelFetch(splat_sum, q, 0)), 1.0);
        }
    }
    return vec4(0.0);
}

// frame/direct.rs SPREAD.
const float AR_DIRECT_SPREAD = 0.1;

// Pixel px's shared direct light from the blocks' corner pixels (frame/direct.rs block_direct):
// the bilinear interpolation, perspective-correct by the corners' inverse depths (in their a),
// with a = 1 where every corner around it with a weight shares it on the
// key of its `slot0` (surface, material, and the slot itself where shading normals interpolate)
// and their lights agree within AR_DIRECT_SPREAD; else a = 0 (the pixel evaluates its own).
vec4 ar_block_direct(ivec2 px, int ss, int block, uint slot0) {
    ivec2 bpx = px / block;
    vec2 f = vec2(px - bpx * block) / float(block);
    ivec2 grid = textureSize(direct_blocks, 0);
    FrameElement e = elements[slot0];
    bool shaded = e.cos_norm.y > 0.5;
    vec3 acc = vec3(0.0);
    float wsum = 0.0;
    float lo = 3.0e38;
    float hi = 0.0;
    for (int k = 0; k < 4; k++) {
        ivec2 c = ivec2(k % 2, k / 2);
        float w = (c.x == 1 ? f.x : 1.0 - f.x) * (c.y == 1 ? f.y : 1.0 - f.y);
        if (w <= 0.0) {
            continue;
        }
        ivec2 q = bpx + c;
        if (any(greaterThanEqual(q, grid))) {
            return vec4(0.0);
        }
        vec4 d = texelFetch(direct_blocks, q, 0);
        if (d.a <= 0.0) {
            return vec4(0.0);
        }
        uint slot = ar_gbuf_leaf(texelFetch(gbuf_position, q * block * ss, 0).w);
        FrameElement o = elements[slot];
        bool same = o.ids.y == e.ids.y && o.ids.w == e.ids.w
            && ((shaded || o.cos_norm.y > 0.5) ? slot == slot0 : true);
        if (!same) {
            return vec4(0.0);
        }
        acc += d.rgb * (w * d.a);
        wsum += w * d.a;
        float s = d.r + d.g + d.b;
        lo = min(lo, s);
        hi = max(hi, s);
    }
    return (hi - lo <= AR_DIRECT_SPREAD * hi && wsum > 0.0) ? vec4(acc / wsum, 1.0) : vec4(0.0);
}

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    int ss = int(pc.misc.w & 0xFFu);
    int block = int(pc.misc.w >> 8u);
    vec3 rest = vec3(0.0);
    vec3 emission = vec3(0.0);
    vec3 mid;
    vec3 normal_sum;
    uint slot0;
    // The area emitters' samples, lights pc.misc.y..z (an empty range where they are not shared).
    uint a = pc.misc.y;
    uint b = pc.misc.z;
    bool shared_direct = a < b && ar_shares_direct(px, ss, mid, normal_sum, slot0);
    // Splat sums per pixel (at its first sample) or per sample (splat.rs, frame/splat.rs).
    bool splat_per_sample = textureSize(splat_sum, 0).x == textureSize(gbuf_position, 0).x;
    // The first samples of this pixel and of the three after it (x + 1, y + 1, both): each
    // sample interpolates bilinearly between those on its surface (frame/splat.rs).
    uint first_surface[4];
    vec3 first_value[4];
    for (int k = 0; k < 4; k++) {
        ivec2 q = px + ivec2(k % 2, k / 2);
        bool inside = AR_SPLAT && !splat_per_sample && all(lessThan(q, ivec2(pc.sizes.xy)));
        first_surface[k] = inside ? ar_first_surface(q, ss) : 0xFFFFFFFFu;
        first_value[k] = inside ? ar_splat_value(texelFetch(splat_sum, q, 0)) : vec3(0.0);
    }
    vec3 direct = vec3(0.0);
    if (shared_direct) {
        // Interpolated from the blocks' corner pixels (direct_blocks.frag), else its own.
        vec4 d = block > 1 ? ar_block_direct(px, ss, block, slot0) : vec4(0.0);
        direct = d.a > 0.5 ? d.rgb : ar_shared_direct(mid, normal_sum, slot0, a, b);
    }
    for (int sy = 0; sy < ss; sy++) {
        for (int sx = 0; sx < ss; sx++) {
            ivec2 t = px * ss + ivec2(sx, sy);
            vec4 g = texelFetch(gbuf_position, t, 0);
            if (ar_gbuf_background(g.w)) {
                rest += pc.environment.rgb;
                continue;
            }
            FrameElement e = elements[ar_gbuf_leaf(g.w)];
            vec3 n = e.face_normal.xyz;
            vec3 wo = normalize(pc.eye.xyz - g.xyz);
            if (dot(wo, n) <= 0.0) {
                continue;
            }
            Material m = materials[e.ids.w];
            // The shading normal (OBJ vn) lights the pixel; without, the face normal (shading.rs).
            vec3 ns = n;
            if (e.cos_norm.y > 0.5) {
                ns = ar_shading_normal(texelFetch(gbuf_normal, t, 0).xyz, n, wo);
            }
            // Every light, less the shared ones where they were shared.
            uint skip = shared_direct ? a : pc.misc.x;
            vec3 l = direct + ar_direct_radiance(g.xyz, n, ns, m, wo, 0u, pc.misc.x, skip, b);
            // Only the shading kinds the scene has are compiled in (AR_VERTEX, AR_SPLAT).
            if (e.ids.z == AR_MODE_VERTEX) {
                if (AR_VERTEX) {
                    l += texelFetch(gbuf_vertex, t, 0).rgb;
                }
            } else if (AR_SPLAT) {
                vec4 s;
                if (splat_per_sample) {
                    s = texelFetch(splat_sum, t, 0);
                } else {
                    vec2 f = vec2(sx, sy) / float(ss);
                    s = vec4(0.0);
                    for (int k = 0; k < 4; k++) {
                        vec2 c = vec2(k % 2, k / 2);
                        float w = (c.x > 0.5 ? f.x : 1.0 - f.x) * (c.y > 0.5 ? f.y : 1.0 - f.y);
                        if (w > 0.0 && first_surface[k] == e.ids.y) {
                            s += vec4(first_value[k] * w, w);
                        }
                    }
                    if (s.a <= 0.0) {
                        s = ar_splat_neighbour(px, ss, e.ids.y);
                    }
                    if (s.a <= 0.0) {
                        // No pixel around has its first sample on this surface: the sample's
                        // own leaf, in its bin (what a sum of that one splat would give).
                        float bin = ar_sample_bin(g.xyz, ar_gbuf_leaf(g.w), t);
                        vec3 own = vec3(0.0);
                        if (bin >= 0.0) {
                            float ac = e.normal_area.w * e.cos_norm.x;
                            own = ar_display_radiance_in(e.normal_area.xyz, ac, e.ids.x, uint(bin + 0.5));
                        }
                        s = vec4(own, 1.0);
                    }
                }
                if (s.a > 0.0) {
                    l += s.rgb / s.a;
                }
            }
            // Discretization can leave a slightly negative indirect term (antiradiance
            // over-cancelling); radiance is never negative (as in frame/cpu.rs).
            rest += max(l, vec3(0.0));
            emission += m.ke.rgb;
        }
    }
    float n = float(ss * ss);
    // An edge pixel: some 2x2 sample of it or of its 8 neighbours hits an emitter.
    ivec2 size = ivec2(pc.sizes.xy);
    bool edge = false;
    for (int dy = -1; dy <= 1 && !edge; dy++) {
        for (int dx = -1; dx <= 1 && !edge; dx++) {
            ivec2 q = px + ivec2(dx, dy);
            if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) {
                continue;
            }
            for (int k = 0; k < ss * ss; k++) {
                float unused;
                if (sample_hit(q * ss + ivec2(k % ss, k / ss), unused) == 1u) {
                    edge = true;
                }
            }
        }
    }
    vec3 l = rest / n + (edge ? edge_emission(px, ss) : emission / n);
    // A viewer's exposure (1 for `render`: the output is the radiance).
    color = vec4(l * pc.environment.w, 1.0);
}
