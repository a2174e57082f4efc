#version 450
// Convergence figures of one iteration, reduced on the GPU so that only a few bytes come back
// (src/solver/convergence.rs is the CPU definition): over the leaves' rows, Σ|new − old|²,
// Σ|new|², the flux leaving through front bins (mean of RGB, before ×ω) and the largest |new|
// (infinite when anything is not finite). Stage 0: every workgroup reduces a stride of texels
// into partials[group]; stage 1: one workgroup reduces the partials into results[slot].
layout(local_size_x = 256) in;

layout(binding = 0) uniform sampler2D old_ex;
layout(binding = 1) uniform sampler2D new_ex;
layout(binding = 2) uniform sampler2D attr_normal_area;
layout(binding = 3) uniform sampler2D attr_leaf;
layout(std430, binding = 4) readonly buffer BinCenters { vec4 centers[]; };
layout(std430, binding = 5) buffer Partials { vec4 partials[]; };
layout(std430, binding = 6) buffer Results { vec4 results[]; };

layout(push_constant) uniform ReduceConstants {
    uint bins;
    uint rows_per_column;
    uint pad;
    uint rows;
    uint width;
    uint stage;
    uint slot;
    uint groups;
} pc;

shared vec4 sums[256];

const float AR_HUGE = 3.0e38;

vec4 combine(vec4 a, vec4 b) {
    return vec4(a.xyz + b.xyz, max(a.w, b.w));
}

vec4 texel_figures(uint i) {
    uint x = i % pc.width;
    uint y = i / pc.width;
    uint row = (x / pc.bins) * pc.rows_per_column + y;
    if (row >= pc.rows) {
        return vec4(0.0);
    }
    ivec2 rt = ivec2(row / pc.rows_per_column, row % pc.rows_per_column);
    vec4 lf = texelFetch(attr_leaf, rt, 0);
    if (lf.z == 0.0) {
        return vec4(0.0);
    }
    uint bin = x % pc.bins;
    vec3 a = texelFetch(new_ex, ivec2(x, y), 0).rgb;
    vec3 b = texelFetch(old_ex, ivec2(x, y), 0).rgb;
    vec3 n = texelFetch(attr_normal_area, rt, 0).xyz;
    float flux = dot(centers[bin].xyz, n) > 0.0 ? (a.r + a.g + a.b) / 3.0 : 0.0;
    bool finite = !any(isnan(a)) && !any(isinf(a));
    float peak = finite ? max(max(abs(a.r), abs(a.g)), abs(a.b)) : AR_HUGE;
    vec3 d = a - b;
    return vec4(dot(d, d), dot(a, a), flux, peak);
}

void main() {
    uint t = gl_LocalInvocationID.x;
    vec4 s = vec4(0.0);
    if (pc.stage == 0u) {
        uint texels = pc.width * pc.rows_per_column;
        uint stride = pc.groups * 256u;
        for (uint i = gl_WorkGroupID.x * 256u + t; i < texels; i += stride) {
            s = combine(s, texel_figures(i));
        }
    } else {
        for (uint i = t; i < pc.groups; i += 256u) {
            s = combine(s, partials[i]);
        }
    }
    sums[t] = s;
    barrier();
    for (uint h = 128u; h > 0u; h >>= 1) {
        if (t < h) {
            sums[t] = combine(sums[t], sums[t + h]);
        }
        barrier();
    }
    if (t == 0u) {
        if (pc.stage == 0u) {
            partials[gl_WorkGroupID.x] = sums[0];
        } else {
            results[pc.slot] = sums[0];
        }
    }
}
