// Shared code of the frame passes (shadow maps, G-buffer, splat, compose); mirrors
// src/frame/{lights,shadow,surfaces,shading}.rs, which the CPU frame uses. Constants here are checked
// against the Rust ones by tests in src/frame/shadow.rs and src/frame/surfaces.rs.
#ifndef ANTIRADIANCE_FRAME_GLSL
#define ANTIRADIANCE_FRAME_GLSL
#define AR_FRAME_PASS
#include "common.glsl"
#include "bins.glsl"

layout(binding = AR_FRAME_I_TOTAL) uniform sampler2D i_total;
layout(std430, binding = AR_FRAME_MATERIALS) readonly buffer Materials { Material materials[]; };
layout(std430, binding = AR_FRAME_BIN_CENTERS) readonly buffer BinCenters { vec4 bin_centers[]; };
layout(std430, binding = AR_FRAME_ELEMENTS) readonly buffer Elements { FrameElement elements[]; };
layout(std430, binding = AR_FRAME_ADJ_OFFSETS) readonly buffer AdjOffsets { uint adj_offsets[]; };
layout(std430, binding = AR_FRAME_ADJ_LIST) readonly buffer AdjList { AdjEntry adj_list[]; };
layout(std430, binding = AR_FRAME_LIGHTS) readonly buffer Lights { Light lights[]; };
layout(std430, binding = AR_FRAME_SHADOW_VIEWS) readonly buffer ShadowViews { ShadowView shadow_views[]; };
layout(binding = AR_FRAME_SHADOW_MAP) uniform sampler2D shadow_map;
layout(binding = AR_FRAME_GBUF_POSITION) uniform sampler2D gbuf_position;
layout(binding = AR_FRAME_GBUF_VERTEX) uniform sampler2D gbuf_vertex;
layout(binding = AR_FRAME_GBUF_NORMAL) uniform sampler2D gbuf_normal;
layout(binding = AR_FRAME_SPLAT) uniform sampler2D splat_sum;
layout(binding = AR_FRAME_SPLAT_BINS) uniform sampler2D splat_bins;
layout(binding = AR_FRAME_DIRECT_BLOCKS) uniform sampler2D direct_blocks;
layout(std430, binding = AR_FRAME_VERTEX_POSITIONS) readonly buffer VertexPositions { vec4 vertex_positions[]; };
layout(binding = AR_FRAME_VERTEX_VALUES) uniform sampler2D vertex_values;
layout(std430, binding = AR_FRAME_EMITTERS) readonly buffer Emitters { EmitterTriangle emitter_tris[]; };

const float AR_SHADOW_DEPTH_BIAS = 0.1;
const float AR_SHADOW_RELATIVE_BIAS = 1e-5;
const float AR_SHADOW_GRAZING = 0.001;
const float AR_SHADOW_FILTER_RADIUS = 1.0;
const int AR_SHADOW_TAPS = 2;
const uint AR_MODE_VERTEX = 1u;

// The G-buffer's position w (glsl/gbuffer.frag): 0 where nothing was hit, else the leaf slot + 1,
// negative on an emitting leaf.
bool ar_gbuf_background(float w) { return abs(w) < 0.5; }
bool ar_gbuf_emitter(float w) { return w < -0.5; }
uint ar_gbuf_leaf(float w) { return uint(abs(w) + 0.5) - 1u; }

uint ar_nu() { return pc.sizes.z & 0xFFFFu; }
uint ar_nv() { return pc.sizes.z >> 16; }

// lights.rs front_bin: a bin on side `side` of the plane with normal n.
uint ar_front_bin(vec3 dir, vec3 n, float side) {
    uint b = ar_bin_of(dir, ar_nu(), ar_nv());
    const float k[6] = float[](0.25, 0.5, 1.0, 2.0, 4.0, 16.0);
    for (int i = 0; i < 6; i++) {
        if (side * dot(bin_centers[b].xyz, n) > 0.05) {
            break;
        }
        b = ar_bin_of(normalize(dir) + n * (side * k[i]), ar_nu(), ar_nv());
    }
    return b;
}

// surfaces.rs display_radiance: I_total in the bin toward the eye, as radiance, of the leaf
// with unit normal n, area times cosine normalization `ac` and table row `row`.
// surfaces.rs display_radiance_in: that leaf's I_total in bin `b` (the splat's, found by the
// G-buffer for the pixel), as radiance; zero where the bin is not in front of it.
vec3 ar_display_radiance_in(vec3 n, float ac, uint row, uint b) {
    float cb = dot(bin_centers[b].xyz, n);
    if (cb <= 0.0) {
        return vec3(0.0);
    }
    ivec2 t = ivec2((row / pc.sizes.w) * (ar_nu() * ar_nv()) + b, row % pc.sizes.w);
    return texelFetch(i_total, t, 0).rgb * pc.eye.w / (ac * cb);
}

vec3 ar_display_radiance_of(vec3 n, float ac, uint row, vec3 wo) {
    if (dot(wo, n) <= 0.0) {
        return vec3(0.0);
    }
    return ar_display_radiance_in(n, ac, row, ar_front_bin(wo, n, 1.0));
}

// ar_display_radiance_of the leaf in slot `leaf`.
vec3 ar_display_radiance(uint leaf, vec3 wo) {
    FrameElement e = elements[leaf];
    return ar_display_radiance_of(e.normal_area.xyz, e.normal_area.w * e.cos_norm.x, e.ids.x, wo);
}

// shading.rs MIN_EYE_COSINE.
const float AR_MIN_EYE_COSINE = 0.01;

// shading.rs shading_normal: the interpolated normal, tilted toward the eye until its cosine
// to wo is AR_MIN_EYE_COSINE where it is less; the face normal where it cannot be normalized.
vec3 ar_shading_normal(vec3 interpolated, vec3 geometric, vec3 wo) {
    float len = length(interpolated);
    if (!(len > 0.0)) {
        return geometric;
    }
    vec3 n = interpolated / len;
    float c = dot(n, wo);
    if (c < AR_MIN_EYE_COSINE) {
        n += wo * (AR_MIN_EYE_COSINE - c);
        len = length(n);
        if (!(len > 0.0)) {
            return geometric;
        }
        n /= len;
    }
    return n;
}

// shading.rs eye_direction: wo turned by the rotation taking `shading` onto `geometric`.
vec3 ar_eye_direction(vec3 wo, vec3 shading, vec3 geometric) {
    vec3 v = cross(shading, geometric);
    float c = dot(shading, geometric);
    return wo * c + cross(v, wo) + v * (dot(v, wo) / max(1.0 + c, 1e-12));
}

float ar_splat_weight(float d, float r) {
    float x = d / r;
    if (x >= 1.0) {
        return 0.0;
    }
    float a = 1.0 - x * x;
    return a * a;
}

// lights.rs brdf.
vec3 ar_brdf(Material m, vec3 n, vec3 travel, vec3 wo) {
    vec3 f = m.kd.rgb / AR_PI;
    if (max(m.ks_ns.r, max(m.ks_ns.g, m.ks_ns.b)) > 0.0) {
        vec3 r = travel - 2.0 * dot(travel, n) * n;
        float c = dot(r, wo);
        if (c > 0.0) {
            f += m.ks_ns.rgb * ((m.ks_ns.a + 2.0) / (2.0 * AR_PI) * pow(c, m.ks_ns.a));
        }
    }
    return f;
}

// lights.rs incident.
bool ar_incident(Light l, vec3 p, out vec3 travel, out vec3 irradiance) {
    uint kind = l.kind_views.x;
    if (kind == 0u) {
        travel = l.direction.xyz;
        irradiance = l.power.rgb;
        return true;
    }
    vec3 v = p - l.position.xyz;
    float r2 = dot(v, v);
    travel = vec3(0.0);
    irradiance = vec3(0.0);
    if (r2 <= 0.0) {
        return false;
    }
    travel = v * inversesqrt(r2);
    irradiance = l.power.rgb / r2;
    if (kind == 2u) {
        float angle = acos(clamp(dot(travel, l.direction.xyz), -1.0, 1.0));
        float beam = l.params.x;
        float cutoff = l.power.w;
        float f = angle <= beam ? 1.0 : (angle >= cutoff ? 0.0 : (cutoff - angle) / (cutoff - beam));
        if (f <= 0.0) {
            return false;
        }
        irradiance *= f;
    }
    if (kind == 3u) {
        // A disc of the sample's area on its axis: L·A·cos/(r² + A/π), bounded as r → 0.
        float cos_e = dot(travel, l.direction.xyz);
        if (cos_e <= 0.0) {
            return false;
        }
        float area = l.params.x;
        irradiance = l.power.rgb * (area * cos_e / (r2 + area / AR_PI));
    }
    return true;
}

// lights.rs projected_solid_angle: the cosine-weighted solid angle of a cell seen from p, over
// its part in front of p's plane of normal n. Written without a polygon array: each edge
// contributes its part in front, and where the plane cuts the cell one closing edge runs along
// it from the point where an edge leaves the front to the point where another enters (local
// arrays indexed per pixel are slow on llvmpipe: that form cost the compose pass 68%).
float ar_cell_edge(vec3 x, vec3 y, vec3 n) {
    vec3 c = cross(x, y);
    float len = length(c);
    // A degenerate edge (the closing edge where the plane does not cut the cell) adds nothing.
    return len > 0.0 ? atan(len, dot(x, y)) * dot(c, n) / len : 0.0;
}

float ar_cell_side(vec3 s, vec3 e, vec3 n, inout vec3 leave, inout vec3 enter) {
    float ds = dot(s, n);
    float de = dot(e, n);
    vec3 x = s + (e - s) * (ds / (ds - de));
    bool fs = ds > 0.0;
    bool fe = de > 0.0;
    leave += fs && !fe ? x : vec3(0.0);
    enter += !fs && fe ? x : vec3(0.0);
    return fs || fe ? ar_cell_edge(fs ? s : x, fe ? e : x, n) : 0.0;
}

float ar_cell(Light l, vec3 p, vec3 n) {
    vec3 a = l.cell[0].xyz - p;
    vec3 b = l.cell[1].xyz - p;
    vec3 c = l.cell[2].xyz - p;
    vec3 leave = vec3(0.0);
    vec3 enter = vec3(0.0);
    float sum = ar_cell_side(a, b, n, leave, enter) + ar_cell_side(b, c, n, leave, enter)
              + ar_cell_side(c, a, n, leave, enter);
    sum += ar_cell_edge(leave, enter, n);
    return 0.5 * abs(sum);
}

// lights.rs irradiance_on: the irradiance `e` (from ar_incident) delivers on a surface of
// normal n at p, `cosv` its cosine; an emitter sample with a cell gives its cell's, up to
// CELL_FAR (1e3) cell areas of squared distance.
vec3 ar_irradiance_on(Light l, vec3 e, float cosv, vec3 p, vec3 n) {
    vec3 d = p - l.position.xyz;
    if (l.kind_views.x == 3u && l.kind_views.w == 1u && dot(d, d) <= 1e3 * l.params.x) {
        if (dot(p - l.cell[0].xyz, l.direction.xyz) <= 0.0) {
            return vec3(0.0);
        }
        return l.power.rgb * ar_cell(l, p, n);
    }
    return e * cosv;
}

// shadow.rs pack_normal: octahedral coordinates, 11 bits each, as the integer u*2048 + v.
float ar_pack_normal(vec3 n) {
    n /= abs(n.x) + abs(n.y) + abs(n.z);
    vec2 uv = n.xy;
    if (n.z < 0.0) {
        uv = (1.0 - abs(uv.yx)) * vec2(uv.x >= 0.0 ? 1.0 : -1.0, uv.y >= 0.0 ? 1.0 : -1.0);
    }
    vec2 q = clamp(floor((uv * 0.5 + 0.5) * 2047.0 + 0.5), 0.0, 2047.0);
    return q.x * 2048.0 + q.y;
}

// shadow.rs unpack_normal.
vec3 ar_unpack_normal(float packed) {
    float qu = floor(packed / 2048.0);
    vec2 uv = vec2(qu, packed - qu * 2048.0) / 2047.0 * 2.0 - 1.0;
    vec3 n = vec3(uv, 1.0 - abs(uv.x) - abs(uv.y));
    if (n.z < 0.0) {
        n.xy = (1.0 - abs(uv.yx)) * vec2(uv.x >= 0.0 ? 1.0 : -1.0, uv.y >= 0.0 ? 1.0 : -1.0);
    }
    return normalize(n);
}

// shadow.rs ShadowMaps::visibility: tent-filtered percentage-closer lookup.
float ar_visibility(Light l, vec3 p, vec3 n, float cosv) {
    // shadow.rs view_for: of a cube's faces, the one whose axis is nearest the direction.
    // Loops here have constant trip counts, so the compiler unrolls them: llvmpipe caps the
    // iterations of a loop per invocation (65535), which nested loops inside the loop over
    // lights reached at ~900 lights (instant radiosity's VPLs), silently dropping light.
    // The candidates' records are the same for every pixel (uniform loads); the best one's
    // dot product is kept, so only the chosen view's record is fetched per pixel.
    uint vi = l.kind_views.y;
    vec3 dir = p - shadow_views[vi].origin.xyz;
    float best = dot(dir, shadow_views[vi].forward.xyz);
    for (uint k = 1u; k < 6u; k++) {
        uint i = l.kind_views.y + min(k, max(l.kind_views.z, 1u) - 1u);
        float d = dot(dir, shadow_views[i].forward.xyz);
        if (k < l.kind_views.z && d > best) {
            vi = i;
            best = d;
        }
    }
    ShadowView v = shadow_views[vi];
    int s = int(v.atlas.z);
    ivec2 base = ivec2(v.atlas.xy);
    bool ortho = v.origin.w > 0.5;
    float texel = 2.0 * v.forward.w * (ortho ? 1.0 : length(p - v.origin.xyz)) / float(s);
    vec4 c = v.view_proj * vec4(p, 1.0);
    float tx = (c.x / c.w + 1.0) * 0.5 * float(s) - 0.5;
    float ty = (c.y / c.w + 1.0) * 0.5 * float(s) - 0.5;
    float own = ortho ? dot(p - v.origin.xyz, v.forward.xyz) : length(p - v.origin.xyz);
    float bias = texel * AR_SHADOW_DEPTH_BIAS + abs(own) * AR_SHADOW_RELATIVE_BIAS;
    // A tent of radius 1 texel weighs the 2x2 texels around the point (shadow.rs TAPS).
    int x0 = int(floor(tx - AR_SHADOW_FILTER_RADIUS)) + 1;
    int y0 = int(floor(ty - AR_SHADOW_FILTER_RADIUS)) + 1;
    float lit = 0.0;
    float total = 0.0;
    for (int j = 0; j < AR_SHADOW_TAPS; j++) {
        int ky = y0 + j;
        float wy = max(1.0 - abs(float(ky) - ty) / AR_SHADOW_FILTER_RADIUS, 0.0);
        for (int i = 0; i < AR_SHADOW_TAPS; i++) {
            int kx = x0 + i;
            float wx = max(1.0 - abs(float(kx) - tx) / AR_SHADOW_FILTER_RADIUS, 0.0);
            float w = wx * wy;
            ivec2 k = ivec2(clamp(kx, 0, s - 1), clamp(ky, 0, s - 1));
            // shadow.rs plane_distance: the receiver's plane under this tap's texel.
            vec2 ndc = (vec2(k) + 0.5) / float(s) * 2.0 - 1.0;
            vec3 side = v.right.xyz * (ndc.x * v.forward.w) - v.up.xyz * (ndc.y * v.forward.w);
            vec3 o = ortho ? v.origin.xyz + side : v.origin.xyz;
            vec3 ray = ortho ? v.forward.xyz : normalize(v.forward.xyz + side);
            float dn = dot(ray, n);
            float d = min(dn > -AR_SHADOW_GRAZING ? own : dot(p - o, n) / dn, own) - bias;
            vec2 t = texelFetch(shadow_map, base + k, 0).rg;
            if (d <= t.x) {
                lit += w;
                total += w;
            } else if (dot(ar_unpack_normal(t.y), p - (o + ray * t.x)) <= bias) {
                // p behind the surface the tap sees: a shadow (in front of it: a crease's
                // other face, no vote; shadow.rs visibility).
                total += w;
            }
        }
    }
    return total > 0.0 ? lit / total : 1.0;
}

// lights.rs straddling: an emitter cell within CELL_FAR of p, p in front of it, whose sample point
// lies behind p's plane (normal n) while some corner lies in front: its light arrives from the
// front corners' mean, unshadowed, and ar_irradiance_on takes the cell's part in front.
bool ar_straddles(Light l, vec3 p, vec3 n, out vec3 travel) {
    travel = vec3(0.0);
    vec3 d = p - l.position.xyz;
    if (l.kind_views.x != 3u || l.kind_views.w != 1u || dot(d, d) > 1e3 * l.params.x
        || dot(p - l.cell[0].xyz, l.direction.xyz) <= 0.0) {
        return false;
    }
    vec3 sum = vec3(0.0);
    float k = 0.0;
    for (int j = 0; j < 3; j++) {
        bool front = dot(l.cell[j].xyz - p, n) > 0.0;
        sum += front ? l.cell[j].xyz : vec3(0.0);
        k += front ? 1.0 : 0.0;
    }
    travel = normalize(p - sum / max(k, 1.0));
    return k > 0.0;
}

// lights.rs direct_radiance_from: n the face normal (front side, shadow lookup), ns the shading
// normal (receiver cosine, BRDF); the lights `begin..end` less `skip..skip_end` (ranges, not a
// filter: on lavapipe a loop over lights that are skipped costs nearly as much as one that
// takes them, and each call site is another inlined copy of the loop).
vec3 ar_direct_radiance(vec3 p, vec3 n, vec3 ns, Material m, vec3 wo, uint begin, uint end,
                        uint skip, uint skip_end) {
    vec3 l = vec3(0.0);
    for (uint i = begin; i < end; i++) {
        if (i == skip) {
            i = skip_end;
            if (i >= end) {
                break;
            }
        }
        vec3 travel;
        vec3 e;
        if (!ar_incident(lights[i], p, travel, e)) {
            continue;
        }
        // lights.rs reach: a cell behind the receiver's plane may still straddle it.
        float cos_face = -dot(travel, n);
        bool straddles = cos_face <= 0.0 && ar_straddles(lights[i], p, n, travel);
        float cosv = -dot(travel, ns);
        if ((cos_face <= 0.0 && !straddles) || cosv <= 0.0) {
            continue;
        }
        float v = straddles ? 1.0 : ar_visibility(lights[i], p, n, cos_face);
        if (v > 0.0) {
            l += ar_brdf(m, ns, travel, wo) * ar_irradiance_on(lights[i], e, cosv, p, ns) * v;
        }
    }
    return l;
}

// surfaces.rs display_bin with shading.rs eye_direction: the bin toward the eye of a splatted
// sample at `world` on slot `leaf`, G-buffer texel `t` (its shading normal there where the mesh
// has `vn`); −1 where none (vertex-interpolated, facing away).
float ar_sample_bin(vec3 world, uint leaf, ivec2 t) {
    FrameElement e = elements[leaf];
    vec3 n = e.face_normal.xyz;
    vec3 wo = normalize(pc.eye.xyz - world);
    if (e.ids.z == AR_MODE_VERTEX || dot(wo, n) <= 0.0) {
        return -1.0;
    }
    vec3 dir = wo;
    if (e.cos_norm.y > 0.5) {
        dir = ar_eye_direction(wo, ar_shading_normal(texelFetch(gbuf_normal, t, 0).xyz, n, wo), n);
    }
    return dot(dir, n) > 0.0 ? float(ar_front_bin(dir, n, 1.0)) : -1.0;
}

#endif
