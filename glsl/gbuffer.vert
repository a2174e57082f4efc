#version 450
// G-buffer at 2x2 samples per pixel (src/gpu/passes/gbuffer.rs). Vertex-interpolated elements get
// their corners' values here, read from the vertex-values pass (vertex_values.frag: the
// weighted display radiance of the leaves listed at the shared vertex, in the bin toward the
// eye; surfaces.rs vertex_values); the shading normal (OBJ vn) is interpolated by the
// rasterizer like the position.
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
    // Computed once per shared vertex by the vertex-values pass (vertex_values.frag).
    vertex_radiance = vec3(0.0);
    if (AR_VERTEX && vertex != 0xFFFFFFFFu) {
        ivec2 t = ivec2(vertex % AR_VERTEX_VALUES_WIDTH, vertex / AR_VERTEX_VALUES_WIDTH);
        vertex_radiance = texelFetch(vertex_values, t, 0).rgb;
    }
    vec3 drawn = (leaf & AR_FILLER) != 0u ? pc.eye.xyz + (position - pc.eye.xyz) * 1.0001 : position;
    gl_Position = pc.view_proj * vec4(drawn, 1.0);
}
