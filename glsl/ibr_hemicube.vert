#version 450
// Image-based radiosity: every face slot's corners drawn into one face of a VPL's hemicube
// (src/methods/ibr/gpu.rs), its rows laid out as src/methods/ibr/hemicube.rs orders the CPU's
// texels (row j at up = -1 + (j + 0.5)·2/H; a side face's rows over the upper half only);
// reversed depth (near/w), so the nearest face keeps each texel. pr_hemicube.frag writes the
// item (slot + 1) and the distance.
layout(push_constant) uniform IbrFace {
    vec4 eye;      // the VPL lifted off its surface; w: the near plane
    vec4 forward;  // the face's axis; w: 1 on a side face
    vec4 right;
    vec4 up;
} pc;

layout(location = 0) in vec3 position;
layout(location = 1) in uint slot;
layout(location = 2) in vec3 normal;  // the face's unit normal
layout(location = 0) out vec3 rel;
layout(location = 1) flat out uint id;
layout(location = 2) flat out float side;

void main() {
    id = slot + 1u;
    rel = position - pc.eye.xyz;
    side = dot(rel, normal);
    float w = dot(rel, pc.forward.xyz);
    float y = dot(rel, pc.up.xyz);
    // A side face keeps up in [0, 1]: NDC 2·up − 1 over its H/2 rows.
    if (pc.forward.w > 0.5) {
        y = 2.0 * y - w;
    }
    gl_Position = vec4(dot(rel, pc.right.xyz), y, pc.eye.w, w);
}
