#version 450
// The item buffer: element id (+1; 0 is nothing) and linear distance from the shooter's eye.
layout(location = 0) in vec3 rel;
layout(location = 1) flat in uint id;
layout(location = 0) out uint item;
layout(location = 1) out float dist;

void main() {
    item = id;
    dist = length(rel);
}
