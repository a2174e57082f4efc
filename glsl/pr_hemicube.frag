#version 450
// The item buffer: element id (+1; 0 is nothing) and linear distance from the shooter's eye.
layout(location = 0) in vec3 rel;
layout(location = 1) flat in uint id;
// (corner − eye)·normal: negative where the face turns toward the eye (constant over its plane).
layout(location = 2) flat in float side;
layout(location = 0) out uint item;
layout(location = 1) out float dist;

void main() {
    item = id;
    dist = length(rel);
    // Back-to-back twins (a two-sided surface's two faces) lie at one depth: the face turned
    // toward the eye wins the tie, as the CPU ray caster prefers it (raycast.rs closest), by a
    // slope-scaled push like gbuffer.frag's but larger (reversed depth, GREATER: farther is
    // smaller): the G-buffer's 4e-7 of the depth left 0.18% of a two-sided box's texels wrong.
    float z = gl_FragCoord.z;
    gl_FragDepth = side < 0.0 ? z : max(z - (1.0e-5 * z + 1.0e-2 * fwidth(z)), 0.0);
}
