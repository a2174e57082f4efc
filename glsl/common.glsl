// Layout constants shared by every pass; mirrors src/gpu/layout.rs (tests there compare the two).
// Tables (I_ex, L_in, L_push, I_total) hold one row per hierarchy node and one texel per bin; rows
// are split into column blocks of `rows_per_column` so the image stays within maxImageDimension2D:
// row r, bin j lives at texel ((r / H) * m + j, r % H). Per-row images (attributes, irradiance)
// use the same rows with one texel each: ((r / H), r % H).
#ifndef ANTIRADIANCE_COMMON_GLSL
#define ANTIRADIANCE_COMMON_GLSL
#extension GL_GOOGLE_include_directive : require

#define AR_BINDING_LEAF_EX 0
#define AR_BINDING_CLUSTER_EX 1
#define AR_BINDING_FILTER 2
#define AR_BINDING_L_IN 3
#define AR_BINDING_L_PUSH 4
#define AR_BINDING_IRRADIANCE_T 5
#define AR_BINDING_IRRADIANCE_D 6
#define AR_BINDING_ATTR_NORMAL_AREA 7
#define AR_BINDING_ATTR_LEAF 8
#define AR_BINDING_DIRECT 9
#define AR_BINDING_LEAF_EX_NEXT 10
#define AR_BINDING_MATERIALS 11
#define AR_BINDING_BIN_CENTERS 12

#define AR_MODE_BOTH 0u
#define AR_MODE_REFLECT 1u
#define AR_MODE_ANTIRADIANCE 2u
#define AR_FLAG_DIRECT 1u
#define AR_FLAG_HALF 2u

layout(push_constant) uniform PassConstants {
    uint bins;
    uint rows_per_column;
    uint target_width;
    uint target_height;
    uint quad_width;
    float line_offset;
    float omega;
    uint flags;
    vec4 environment;  // rgb: environment radiance (scaled); a: source scale (a power of two)
} pc;

struct Material {
    vec4 kd;
    vec4 ks_ns;
    vec4 ke;
};

const float AR_PI = 3.14159265358979;

ivec2 ar_texel(uint row, uint bin) {
    return ivec2((row / pc.rows_per_column) * pc.bins + bin, row % pc.rows_per_column);
}

ivec2 ar_row_texel(uint row) {
    return ivec2(row / pc.rows_per_column, row % pc.rows_per_column);
}

// Row and bin of the table texel under a fragment.
uint ar_row_at(ivec2 p) {
    return (uint(p.x) / pc.bins) * pc.rows_per_column + uint(p.y);
}

uint ar_bin_at(ivec2 p) {
    return uint(p.x) % pc.bins;
}

// Row of the per-row-image texel under a fragment.
uint ar_row_at_row_image(ivec2 p) {
    return uint(p.x) * pc.rows_per_column + uint(p.y);
}

// Rounds to the nearest float16 (ties to even) before a store into a float16 target: some
// drivers (lavapipe) convert by truncation, a bias that antiradiance's cancellations amplify.
// Identity for float32 tables; normal float16 range only (subnormals keep truncating).
vec3 ar_store(vec3 v) {
    if ((pc.flags & AR_FLAG_HALF) == 0u) {
        return v;
    }
    uvec3 b = floatBitsToUint(v);
    return uintBitsToFloat((b + 0x0FFFu + ((b >> 13) & 1u)) & 0xFFFFE000u);
}

// Framebuffer position (texels) to clip space; Vulkan's y axis points down like the texel rows.
vec4 ar_clip(vec2 p) {
    return vec4(p / vec2(pc.target_width, pc.target_height) * 2.0 - 1.0, 0.0, 1.0);
}

#endif
