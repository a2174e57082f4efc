#version 450
// Blend-rounding probe: every fragment adds 0.7 (not representable in binary), so the sum
// after many hits shows whether float16 blending rounds to nearest or truncates.
layout(location = 0) out vec4 value;

void main() {
    value = vec4(0.7);
}
