#version 450
// Global pass (eq. 16): a link is one line per rectangle of receiver bins its filter reaches
// (its footprint on the bins' grid, less the bins a leaf receiver never reads), drawn as a line
// as wide as the rectangle is tall into the receiver's tile of L_in. The sender's I_ex is
// fetched once per line, here, and handed to the fragments flat. Line records are pulled by
// vertex index (2 vertices each, no instancing): a CPU rasterizer shades vertices eight at a
// time, which one instance of two vertices would leave three-quarters idle.
#include "common.glsl"

layout(binding = AR_BINDING_LEAF_EX) uniform sampler2D leaf_ex;
layout(binding = AR_BINDING_CLUSTER_EX) uniform sampler2D cluster_even;
layout(binding = AR_BINDING_CLUSTER_EX_ODD) uniform sampler2D cluster_odd;
// Combos (src/gpu/layout.rs GpuCombo): bin | layer << 16, the rectangle (u0, v0, width, height,
// 8 bits each), the mask of the bins that blend (64 bits).
layout(std430, binding = AR_BINDING_COMBOS) readonly buffer Combos { uvec4 combos[]; };

// Line records (src/gpu/layout.rs GpuLink): receiver | combo_hi << 22, sender | combo_lo << 22,
// form factor bits; three words each.
layout(std430, binding = AR_BINDING_LINKS) readonly buffer Links { uint link_words[]; };

layout(location = 0) flat out vec3 sent;     // F · I_ex(sender, bin)
// Packed to keep the per-line setup small: corner x | y << 16 (texel of the rectangle's first
// bin), its filter-table column | the rectangle's width << 16, the filter-table row.
layout(location = 1) flat out uvec3 place;
layout(location = 2) flat out uvec2 mask;    // bit dv·width + du: bin (du, dv) blends

void main() {
    uint li = uint(gl_VertexIndex) >> 1;
    uvec2 link = uvec2(link_words[3u * li], link_words[3u * li + 1u]);
    uint mask_bits = (1u << AR_LINK_ROW_BITS) - 1u;
    uint receiver = link.x & mask_bits;
    uint sender = link.y & mask_bits;
    uint combo = ((link.x >> AR_LINK_ROW_BITS) << (32u - AR_LINK_ROW_BITS)) | (link.y >> AR_LINK_ROW_BITS);
    uvec4 c = combos[combo];
    uint bin = c.x & 0xffffu;
    uvec4 r = (uvec4(c.y) >> uvec4(0u, 8u, 16u, 24u)) & 0xffu;
    ivec2 o = ar_in_origin(receiver) + ivec2(r.xy);
    // Drawn as wide as the rectangle is tall (the draw's line width).
    gl_Position = ar_rect_line_end(o, r.zw, (gl_VertexIndex & 1) != 0);
    place = uvec3(uint(o.x) | uint(o.y) << 16, (r.y * AR_GRID_COLUMNS + r.x) | r.z << 16,
        (c.x >> 16) * AR_BINS + bin);
    mask = c.zw;
    // Flat outputs come from the first vertex of a line; the second one skips the fetch.
    if ((gl_VertexIndex & 1) == 0) {
        float form_factor = uintBitsToFloat(link_words[3u * li + 2u]);
        ivec2 s = ar_texel(sender, bin);
        // Leaves and the two cluster parities live in separate images; each draw's senders
        // live in one of them (lines are drawn by sender image), so one fetch per line.
        vec3 i_ex = pc.sender == AR_SENDER_LEAF ? texelFetch(leaf_ex, s, 0).rgb
            : pc.sender == AR_SENDER_EVEN ? texelFetch(cluster_even, s, 0).rgb
            : texelFetch(cluster_odd, s, 0).rgb;
        sent = i_ex * form_factor;
    } else {
        sent = vec3(0.0);
    }
}
