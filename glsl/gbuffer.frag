#version 450
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"

layout(location = 0) in vec3 world;
layout(location = 1) flat in uint leaf;
layout(location = 2) in vec3 vertex_radiance;
layout(location = 3) in vec3 normal;
layout(location = 4) flat in uint emits;
layout(location = 0) out vec4 out_position;  // xyz, ±(leaf slot + 1) (frame.glsl ar_gbuf_leaf)
layout(location = 1) out vec4 out_vertex;  // rgb vertex radiance
layout(location = 2) out vec4 out_normal;  // interpolated shading normal (not normalized)

void main() {
    // Back-to-back twins (the two faces of a two-sided surface) lie at one depth: the face
    // turned toward the eye wins the tie, as the CPU ray caster prefers it (raycast.rs
    // closest). Reversed depth, GREATER: a back face is pushed farther by a few ulps of its
    // depth and by a small part of its depth's step per pixel, since each triangle's depth plane
    // is rounded by about its slope times the pixel coordinate's ulp: at grazing views the
    // twins' depths differed by more than the ulps alone (the corridors' zero-thickness walls
    // showed their black backs in a third of a wall's pixels).
    bool front = dot(pc.eye.xyz - world, elements[leaf].face_normal.xyz) > 0.0;
    float z = gl_FragCoord.z;
    gl_FragDepth = front ? z : max(z - (4.0e-7 * z + 4.0e-4 * fwidth(z)), 0.0);
    out_position = vec4(world, emits != 0u ? -float(leaf + 1u) : float(leaf + 1u));
    out_vertex = vec4(vertex_radiance, 0.0);
    out_normal = vec4(normal, 0.0);
}
