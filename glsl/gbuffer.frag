#version 450
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"

layout(location = 0) in vec3 world;
layout(location = 1) flat in uint leaf;
layout(location = 2) in vec3 vertex_radiance;
layout(location = 3) in vec3 normal;
layout(location = 4) flat in uint emits;
layout(location = 0) out vec4 out_position;  // xyz, ±(leaf slot + 1) (frame.glsl ar_gbuf_leaf)
layout(location = 1) out vec4 out_vertex;
layout(location = 2) out vec4 out_normal;  // interpolated shading normal (not normalized)

void main() {
    out_position = vec4(world, emits != 0u ? -float(leaf + 1u) : float(leaf + 1u));
    out_vertex = vec4(vertex_radiance, 0.0);
    out_normal = vec4(normal, 0.0);
}
