#version 450
// Line-coverage test: every fragment adds one, so the target counts hits per texel.
layout(location = 0) out vec4 hits;

void main() {
    hits = vec4(1.0);
}
