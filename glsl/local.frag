#version 450
// Local pass: reflection and antiradiance at the leaves. One shader; the diffuse fast path, the
// Phong sum, the mode, antiradiance, direct light, environment and emission are specialization
// constants (src/gpu/layout.rs `spec`) set per pipeline from the scene's plan.
#include "local.glsl"

void main() {
    ar_local();
}
