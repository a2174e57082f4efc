#version 450
// Global pass (eq. 16): a link is one line per run of receiver bins it reaches (its filter's
// support, less the bins a leaf receiver never reads), drawn into the receiver's row of L_in.
// The sender's I_ex is fetched once per line, here, and handed to the fragments flat. Links are
// pulled by vertex index (2 · runs vertices each, no instancing): a CPU rasterizer shades
// vertices eight at a time, which one instance of two vertices would leave three-quarters idle.
#include "common.glsl"

layout(binding = AR_BINDING_LEAF_EX) uniform sampler2D leaf_ex;
layout(binding = AR_BINDING_CLUSTER_EX) uniform sampler2D cluster_even;
layout(binding = AR_BINDING_CLUSTER_EX_ODD) uniform sampler2D cluster_odd;
layout(std430, binding = AR_BINDING_COMBOS) readonly buffer Combos { uvec2 combos[]; };
layout(std430, binding = AR_BINDING_RUNS) readonly buffer Runs { uint runs[]; };

// Link records (src/gpu/layout.rs GpuLink): receiver | combo_hi << 22, sender | combo_lo << 22,
// form factor bits; three words each.
layout(std430, binding = AR_BINDING_LINKS) readonly buffer Links { uint link_words[]; };

layout(location = 0) flat out vec3 sent;     // F · I_ex(sender, bin)
layout(location = 1) flat out int filter_row;
layout(location = 2) flat out int row_start;  // texel column of the receiver row's first position

void main() {
    uint per = 2u * pc.runs;
    uint li = uint(gl_VertexIndex) / per;
    uint k = (uint(gl_VertexIndex) - li * per) >> 1;
    uvec2 link = uvec2(link_words[3u * li], link_words[3u * li + 1u]);
    float form_factor = uintBitsToFloat(link_words[3u * li + 2u]);
    uint mask = (1u << AR_LINK_ROW_BITS) - 1u;
    uint receiver = link.x & mask;
    uint sender = link.y & mask;
    uint combo = ((link.x >> AR_LINK_ROW_BITS) << (32u - AR_LINK_ROW_BITS)) | (link.y >> AR_LINK_ROW_BITS);
    uvec2 c = combos[combo];
    uint bin = c.x & 0xffffu;
    if (k >= (c.y >> 24)) {
        gl_Position = AR_NOWHERE;
        return;
    }
    uint run = runs[(c.y & 0xffffffu) + k];
    gl_Position = ar_line_end(receiver, (gl_VertexIndex & 1) == 0 ? run & 0xffffu : run >> 16);
    row_start = ar_texel(receiver, 0u).x;
    filter_row = int((c.x >> 16) * AR_BINS + bin);
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
