#version 450
// One quad over a node's tile of an incident table (push, one per node), drawn as a 4-vertex
// triangle strip per instance, passing the other row the fragment shader reads.
#include "common.glsl"

layout(location = 0) in uvec2 pair;   // row written, row read (the parent)
layout(location = 0) flat out uint row;
layout(location = 1) flat out uint other;

void main() {
    vec2 o = vec2(ar_in_origin(pair.x));
    float x = (gl_VertexIndex & 1) == 0 ? o.x : o.x + float(AR_GRID_COLUMNS);
    float y = (gl_VertexIndex & 2) == 0 ? o.y : o.y + float(AR_GRID_ROWS);
    gl_Position = ar_clip(vec2(x, y));
    row = pair.x;
    other = pair.y;
}
