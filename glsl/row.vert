#version 450
// One line across all bins of a row (pull, one line per node), passing the other row
// the fragment shader reads.
#include "common.glsl"

layout(location = 0) in uvec2 pair;   // row written, row read (parent or right child)
layout(location = 0) flat out uint row;
layout(location = 1) flat out uint other;

void main() {
    gl_Position = ar_line_end(pair.x, (gl_VertexIndex & 1) == 0 ? 0u : AR_BINS);
    row = pair.x;
    other = pair.y;
}
