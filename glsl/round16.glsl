// Float16 blending rounded to nearest, emulated (src/gpu/blend16.rs): instead of blending into
// its float32 target, a fragment adds its value into the ROUNDED buffer (float32 bits, four
// words per texel of the incident tables) by compare-and-swap, rounding each sum to the nearest
// float16 as a device's float16 blending does; the pass's target is then overwritten from the
// buffer. Test-only: lavapipe's float16 blending truncates, so without it the paper's float16
// path never runs in CI.
#ifndef ANTIRADIANCE_ROUND16_GLSL
#define ANTIRADIANCE_ROUND16_GLSL
#include "common.glsl"

layout(std430, binding = AR_BINDING_ROUNDED) coherent buffer Rounded { uint rounded[]; };

void ar_round_add(ivec2 p, vec3 v) {
    uint base = 4u * (uint(p.y) * AR_ROUND_WIDTH + uint(p.x));
    for (int c = 0; c < 3; c++) {
        // The source is converted to the target's format before it blends.
        float add = ar_round_f16(v[c]);
        if (add == 0.0) {
            continue;
        }
        uint old = rounded[base + uint(c)];
        for (;;) {
            uint next = floatBitsToUint(ar_round_f16(uintBitsToFloat(old) + add));
            uint seen = atomicCompSwap(rounded[base + uint(c)], old, next);
            if (seen == old) {
                break;
            }
            old = seen;
        }
    }
}

#endif
