#version 450
// Progressive refinement: every element's corners drawn into one face of the shooter's hemicube
// (src/methods/progressive/gpu.rs), a perspective view from the shooter's centre lifted off its
// surface; reversed depth (near/z), so the nearest element keeps each texel.
#extension GL_GOOGLE_include_directive : require
#include "pr_common.glsl"

layout(std430, binding = PR_BINDING_LEAVES) readonly buffer Leaves { PrLeaf leaves[]; };
layout(std430, binding = PR_BINDING_SHOT) readonly buffer Shot { PrShot shot; };

layout(location = 0) in vec3 position;
layout(location = 1) in uint leaf;
layout(location = 0) out vec3 rel;
layout(location = 1) flat out uint id;
layout(location = 2) flat out float side;

void main() {
    id = leaf + 1u;
    uint s = shot.shooter;
    if (s == PR_NONE) {
        // Nothing to shoot: outside the clip volume.
        rel = vec3(0.0);
        side = 0.0;
        gl_Position = vec4(0.0, 0.0, 2.0, 1.0);
        return;
    }
    vec3 n = leaves[s].normal.xyz;
    vec3 eye = leaves[s].center.xyz + n * pc.eps;
    vec3 t, b, fw, rt, up;
    pr_basis(n, t, b);
    pr_face(pc.face, n, t, b, fw, rt, up);
    rel = position - eye;
    side = dot(rel, leaves[leaf].normal.xyz);
    gl_Position = vec4(dot(rel, rt), -dot(rel, up), pc.near, dot(rel, fw));
}
