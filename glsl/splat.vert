#version 450
// Splat fans (§4.3): an octagon around each element center, in the element's plane, covering
// the disc of its splat radius (src/gpu/passes/splat.rs). 8 triangles, 24 vertices per instance.
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"

layout(location = 0) in uint leaf;
// The splatted leaf's record, handed to its fragments (one fetch per vertex, not per fragment).
layout(location = 0) flat out vec4 center_radius;
layout(location = 1) flat out vec4 normal_ac;   // unit normal, area × cosine normalization
layout(location = 2) flat out uvec2 row_surface; // table row, flat-surface id

void main() {
    FrameElement e = elements[leaf];
    vec3 n = e.normal_area.xyz;
    vec3 t = normalize(abs(n.x) < 0.9 ? cross(n, vec3(1.0, 0.0, 0.0)) : cross(n, vec3(0.0, 1.0, 0.0)));
    vec3 b = cross(n, t);
    float r = e.center_radius.w / cos(AR_PI / 8.0);
    uint k = uint(gl_VertexIndex) / 3u;
    uint corner = uint(gl_VertexIndex) % 3u;
    vec3 p = e.center_radius.xyz;
    if (corner != 0u) {
        float a = float(k + corner - 1u) * (AR_PI / 4.0);
        p += r * (cos(a) * t + sin(a) * b);
    }
    center_radius = e.center_radius;
    normal_ac = vec4(n, e.normal_area.w * e.cos_norm.x);
    row_surface = e.ids.xy;
    gl_Position = pc.view_proj * vec4(p, 1.0);
}
