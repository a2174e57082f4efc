#version 450
// G-buffer at 2x2 samples per pixel (src/gpu/passes/gbuffer.rs). Vertex-interpolated elements get
// their corners' values here: the weighted display radiance of the leaves listed at the
// shared vertex, in the bin toward the eye (surfaces.rs vertex_values); the shading normal (OBJ
// vn) is interpolated by the rasterizer like the position.
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"

layout(location = 0) in vec3 position;
layout(location = 1) in uint leaf;
layout(location = 2) in uint vertex;
layout(location = 3) in vec3 normal;
layout(location = 0) out vec3 world;
layout(location = 1) flat out uint leaf_out;
layout(location = 2) out vec3 vertex_radiance;
layout(location = 3) out vec3 normal_out;
layout(location = 4) flat out uint emits;

// Crack-filling input triangle (src/gpu/frame.rs FILLER): drawn 1e-4 of the distance behind,
// so the elements win wherever they cover.
const uint AR_FILLER = 0x80000000u;

void main() {
    world = position;
    normal_out = normal;
    leaf_out = leaf & ~AR_FILLER;
    // Emitting leaves are marked in the G-buffer (ar_gbuf_emitter): compose's edge test reads
    // 36 samples per pixel and then needs no element or material record.
    vec3 ke = materials[elements[leaf_out].ids.w].ke.rgb;
    emits = max(max(ke.r, ke.g), ke.b) > 0.0 ? 1u : 0u;
    vec3 acc = vec3(0.0);
    float w = 0.0;
    if (AR_VERTEX && vertex != 0xFFFFFFFFu) {
        vec3 wo = normalize(pc.eye.xyz - position);
        for (uint i = adj_offsets[vertex]; i < adj_offsets[vertex + 1u]; i++) {
            AdjEntry a = adj_list[i];
            uint e = a.leaf;
            vec4 na = elements[e].normal_area;
            if (dot(wo, na.xyz) > 0.0) {
                // The bin toward the eye as the leaf's shading normal at the vertex sees it.
                vec3 dir = wo;
                if (elements[e].cos_norm.y > 0.5) {
                    vec3 ns = ar_shading_normal(vec3(a.nx, a.ny, a.nz), na.xyz, wo);
                    dir = ar_eye_direction(wo, ns, na.xyz);
                }
                acc += ar_display_radiance(e, dir) * a.w;
                w += a.w;
            }
        }
    }
    vertex_radiance = w > 0.0 ? acc / w : vec3(0.0);
    vec3 drawn = (leaf & AR_FILLER) != 0u ? pc.eye.xyz + (position - pc.eye.xyz) * 1.0001 : position;
    gl_Position = pc.view_proj * vec4(drawn, 1.0);
}
