#version 450
// The shared vertices' display radiance toward the eye, one texel per vertex
// (src/gpu/passes/vertex_values.rs, frame/surfaces.rs vertex_values): the weighted display
// radiance of the leaves listed at the vertex that face the eye, in the bin toward the eye as
// the leaf's shading normal at the vertex sees it. The G-buffer's vertex shader reads it.
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"

layout(location = 0) out vec4 out_value;

void main() {
    uint v = uint(gl_FragCoord.y) * AR_VERTEX_VALUES_WIDTH + uint(gl_FragCoord.x);
    if (!AR_VERTEX || v >= uint(vertex_positions.length())) {
        out_value = vec4(0.0);
        return;
    }
    vec3 wo = normalize(pc.eye.xyz - vertex_positions[v].xyz);
    vec3 acc = vec3(0.0);
    float w = 0.0;
    for (uint i = adj_offsets[v]; i < adj_offsets[v + 1u]; i++) {
        AdjEntry a = adj_list[i];
        uint e = a.leaf;
        vec4 na = elements[e].normal_area;
        if (dot(wo, na.xyz) > 0.0) {
            vec3 dir = wo;
            if (elements[e].cos_norm.y > 0.5) {
                vec3 ns = ar_shading_normal(vec3(a.nx, a.ny, a.nz), na.xyz, wo);
                dir = ar_eye_direction(wo, ns, na.xyz);
            }
            acc += ar_display_radiance(e, dir) * a.w;
            w += a.w;
        }
    }
    out_value = vec4(w > 0.0 ? acc / w : vec3(0.0), 1.0);
}
