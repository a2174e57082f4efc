#version 450
// Shadow maps: element corners seen from one light view (src/gpu/passes/shadow.rs).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"

layout(location = 0) in vec3 position;
layout(location = 0) out vec3 world;

void main() {
    world = position;
    gl_Position = shadow_views[pc.misc.y].view_proj * vec4(position, 1.0);
}
