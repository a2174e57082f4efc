// Local pass at the leaves (eqs. 18-19): the diffuse fast path (AR_GLOSSY false) and the general
// Phong pass are specializations of this one shader (glsl/local.frag). Mirrors src/solver/local.rs: front bins get I_L = a c cos (kd/pi E + glossy + Ke),
// back bins get -a c |cos| L_t (antiradiance), front bins also lose a c cos L_t (light arriving at
// the back is blocked, not reflected: opaque from both sides), I_total gets the reflected part without emission
// and without the first bounce of direct light. The frozen hemisphere of the asymmetric steps is
// copied from the current I_ex (ping-pong).
#ifndef ANTIRADIANCE_LOCAL_GLSL
#define ANTIRADIANCE_LOCAL_GLSL
#include "common.glsl"
#include "bins.glsl"

layout(binding = AR_BINDING_LEAF_EX) uniform sampler2D leaf_ex;
layout(binding = AR_BINDING_L_PUSH) uniform sampler2D l_push;
layout(binding = AR_BINDING_L_IN) uniform sampler2D l_in;
layout(binding = AR_BINDING_IRRADIANCE_T) uniform sampler2D irradiance_t;
layout(binding = AR_BINDING_ATTR_NORMAL_AREA) uniform sampler2D attr_normal_area;
layout(binding = AR_BINDING_ATTR_LEAF) uniform sampler2D attr_leaf;
layout(binding = AR_BINDING_DIRECT) uniform sampler2D direct;
layout(binding = AR_BINDING_ENVIRONMENT) uniform sampler2D environment;
layout(binding = AR_BINDING_LOBE_NORM) uniform sampler2D lobe_norm;
layout(std430, binding = AR_BINDING_MATERIALS) readonly buffer Materials { Material materials[]; };
layout(std430, binding = AR_BINDING_BIN_CENTERS) readonly buffer BinCenters { vec4 centers[]; };
// Per glossy lobe: bins+1 offsets (0xffffffff: every bin), then the lists (src/gpu/pack.rs).
layout(std430, binding = AR_BINDING_LOBE_BINS) readonly buffer LobeBins { uint lobe_bins[]; };

layout(location = 0) out vec4 out_ex;
layout(location = 1) out vec4 out_total;

// Incident radiance the leaf reflects and turns into antiradiance (from links; the environment
// comes shadowed, as a first bounce, src/frame/environment.rs). Push leaves it in the L_push
// image at even depths and in the L_in image at odd ones (`odd`).
vec3 ar_lt(uint row, uint bin, bool odd) {
    ivec2 t = ar_in_texel(row, bin);
    return odd ? texelFetch(l_in, t, 0).rgb : texelFetch(l_push, t, 0).rgb;
}

void ar_local() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    uint row = ar_row_at(p);
    uint j = ar_bin_at(p);
    vec4 na = texelFetch(attr_normal_area, ar_row_texel(row), 0);
    vec4 lf = texelFetch(attr_leaf, ar_row_texel(row), 0);
    vec3 n = na.xyz;
    float a = na.w;
    float c = lf.x;
    bool odd = lf.w != 0.0;
    Material mat = materials[uint(lf.y)];
    vec3 dir = centers[j].xyz;
    float cj = dot(dir, n);
    vec3 old = texelFetch(leaf_ex, p, 0).rgb;
    vec3 ex = vec3(0.0);
    vec3 tot = vec3(0.0);
    if (cj > 0.0) {
        if (AR_MODE == AR_MODE_ANTIRADIANCE) {
            ex = old; // I_total is write-masked in this mode.
        } else {
            float base = a * c * cj;
            vec3 e_t = texelFetch(irradiance_t, ar_row_texel(row), 0).rgb;
            vec3 r_t = mat.kd.rgb / AR_PI * e_t;
            if (AR_GLOSSY && mat.kd.a >= 0.0) {
                // The truncated lobe (src/brdf.rs LOBE_CUTOFF): only incident bins listed for
                // the mirror direction's bin, and of those only the ones inside the cone.
                // Lists per cell of a lookup grid AR_LOBE_REFINE times finer than the bins'.
                uint nu = AR_BINS / AR_GRID_ROWS * AR_LOBE_REFINE;
                uint nv = AR_GRID_ROWS * AR_LOBE_REFINE;
                uint head = uint(mat.kd.a) * (nu * nv + 1u);
                vec3 mirrored = dir - 2.0 * dot(dir, n) * n;
                uint b = ar_bin_of(mirrored, nu, nv);
                uint first = lobe_bins[head + b];
                bool all = first == 0xffffffffu;
                uint count = all ? AR_BINS : lobe_bins[head + b + 1u] - first;
                // The lobe as the bins sample it (src/brdf.rs DiscreteLobe): the material
                // record carries the effective exponent and the truncation cosine (ke.a, at
                // least 0: the Phong shape is zero behind), lobe_norm the factor of incident bin
                // l that conserves the true albedo. cos α = mirror(l)·dir = l·mirror(dir).
                float ns = mat.ks_ns.a;
                float cut = max(mat.ke.a, 0.0);
                float scale = (ns + 2.0) / (2.0 * AR_PI) * pc.omega * c;
                vec3 glossy = vec3(0.0);
                for (uint k = 0u; k < count; ++k) {
                    uint l = all ? k : lobe_bins[first + k];
                    vec3 inc = centers[l].xyz;
                    float cos_l = -dot(inc, n);
                    float cos_a = dot(inc, mirrored);
                    if (cos_l > 0.0 && cos_a > cut) {
                        float factor = texelFetch(lobe_norm, ar_texel(row, l), 0).r;
                        glossy += (pow(cos_a, ns) * factor * cos_l) * ar_lt(row, l, odd);
                    }
                }
                r_t += mat.ks_ns.rgb * scale * glossy;
            }
            // The shadowed environment's first bounce, reflected once: shown and sent.
            vec3 sky = AR_ENVIRONMENT ? texelFetch(environment, p, 0).rgb : vec3(0.0);
            tot = base * r_t + sky;
            vec3 ke = AR_EMISSION ? mat.ke.rgb * pc.environment.a : vec3(0.0);
            // Light arriving at the back in bin j is blocked: antiradiance out the front.
            // Not on a closed solid's surface (src/solids.rs): attr_leaf z is negative where it
            // blocks (src/gpu/pack.rs attributes).
            vec3 blocked = AR_ANTIRADIANCE && lf.z < 0.0 ? ar_lt(row, j, odd) : vec3(0.0);
            // The first bounce of direct light, reflected once for the whole solve
            // (src/solver/local.rs direct_exitant), adds to I_ex only.
            vec3 first = AR_DIRECT ? texelFetch(direct, p, 0).rgb : vec3(0.0);
            ex = base * (r_t + ke - blocked) + first + sky;
        }
    } else if (cj < 0.0) {
        if (AR_MODE == AR_MODE_REFLECT) {
            ex = old;
        } else if (AR_ANTIRADIANCE) {
            ex = -(a * c * -cj) * ar_lt(row, j, odd);
        }
    }
    // A damped symmetric iteration (src/solver/mod.rs CpuState::damping) keeps part of the last
    // iterate; pull then sums the damped leaves, as the CPU damps every row.
    if (pc.keep != 0.0) {
        ex = mix(ex, old, pc.keep);
    }
    out_ex = vec4(ar_store(ex), 0.0);
    out_total = vec4(ar_store(tot), 0.0);
}

#endif
