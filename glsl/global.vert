#version 450
// Global pass (eq. 16): a link is one line per run of receiver bins it reaches (its filter's
// support, less the bins a leaf receiver never reads), drawn into the receiver's row of L_in.
// The sender's I_ex is fetched once per line, here, and handed to the fragments flat.
#include "common.glsl"

layout(binding = AR_BINDING_LEAF_EX) uniform sampler2D leaf_ex;
layout(binding = AR_BINDING_CLUSTER_EX) uniform sampler2D cluster_even;
layout(binding = AR_BINDING_CLUSTER_EX_ODD) uniform sampler2D cluster_odd;
layout(std430, binding = AR_BINDING_COMBOS) readonly buffer Combos { uvec2 combos[]; };
layout(std430, binding = AR_BINDING_RUNS) readonly buffer Runs { uint runs[]; };

layout(location = 0) in uvec2 link;      // receiver | combo_hi << 22, sender | combo_lo << 22
layout(location = 1) in float form_factor;

layout(location = 0) flat out vec3 sent;     // F · I_ex(sender, bin)
layout(location = 1) flat out int filter_row;

void main() {
    uint mask = (1u << AR_LINK_ROW_BITS) - 1u;
    uint receiver = link.x & mask;
    uint sender = link.y & mask;
    uint combo = ((link.x >> AR_LINK_ROW_BITS) << (32u - AR_LINK_ROW_BITS)) | (link.y >> AR_LINK_ROW_BITS);
    uvec2 c = combos[combo];
    uint bin = c.x & 0xffffu;
    uint k = uint(gl_VertexIndex) >> 1;
    if (k >= (c.y >> 24)) {
        gl_Position = AR_NOWHERE;
        return;
    }
    uint run = runs[(c.y & 0xffffffu) + k];
    gl_Position = ar_line_end(receiver, (gl_VertexIndex & 1) == 0 ? run & 0xffffu : run >> 16);
    filter_row = int((c.x >> 16) * pc.bins + bin);
    // Flat outputs come from the first vertex of a line; the second one skips the fetches.
    if ((gl_VertexIndex & 1) == 0) {
        ivec2 s = ar_texel(sender, bin);
        // Leaves and the two cluster parities live in separate images; each draw's senders
        // live in one of them (links are drawn by sender image), so one fetch per line.
        vec3 i_ex = pc.sender == AR_SENDER_LEAF ? texelFetch(leaf_ex, s, 0).rgb
            : pc.sender == AR_SENDER_EVEN ? texelFetch(cluster_even, s, 0).rgb
            : texelFetch(cluster_odd, s, 0).rgb;
        sent = i_ex * form_factor;
    } else {
        sent = vec3(0.0);
    }
}
