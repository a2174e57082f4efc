#version 450
// Local pass, step 1: each leaf's irradiance from links, one texel per row of the irradiance
// image (the first bounces of direct light and of the shadowed environment are tables computed
// once, src/solver/local.rs direct_exitant).
#include "common.glsl"

layout(binding = AR_BINDING_L_PUSH) uniform sampler2D l_push;
layout(binding = AR_BINDING_L_IN) uniform sampler2D l_in;
layout(binding = AR_BINDING_ATTR_NORMAL_AREA) uniform sampler2D attr_normal_area;
layout(binding = AR_BINDING_ATTR_LEAF) uniform sampler2D attr_leaf;
layout(std430, binding = AR_BINDING_BIN_CENTERS) readonly buffer BinCenters { vec4 centers[]; };

layout(location = 0) out vec4 e_t;

void main() {
    uint row = ar_row_at_row_image(ivec2(gl_FragCoord.xy));
    vec3 n = texelFetch(attr_normal_area, ar_row_texel(row), 0).xyz;
    vec4 lf = texelFetch(attr_leaf, ar_row_texel(row), 0);
    float c = lf.x;
    // Push leaves odd depths' incident radiance in the L_in image.
    bool odd = lf.w != 0.0;
    vec3 st = vec3(0.0);
    for (uint l = 0u; l < AR_BINS; ++l) {
        float cos_l = -dot(centers[l].xyz, n);
        if (cos_l > 0.0) {
            float wt = cos_l * pc.omega * c;
            ivec2 t = ar_in_texel(row, l);
            vec3 lt = odd ? texelFetch(l_in, t, 0).rgb : texelFetch(l_push, t, 0).rgb;
            st += lt * wt;
        }
    }
    e_t = vec4(ar_store(st), 0.0);
}
