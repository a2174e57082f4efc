// Direction -> bin mapping shared by all shaders; mirrors src/bins.rs (Clarberg's equal-area
// octahedral map, an nu x nv grid of equal solid angle 4*pi/m). Directions are travel directions.
#ifndef ANTIRADIANCE_BINS_GLSL
#define ANTIRADIANCE_BINS_GLSL

const float AR_HALF_PI = 1.57079632679;

vec2 ar_direction_to_square(vec3 d) {
    float r = sqrt(max(1.0 - abs(d.z), 0.0));
    float phi = atan(abs(d.y), abs(d.x));
    float v = r * phi / AR_HALF_PI;
    float u = r - v;
    if (d.z < 0.0) {
        float uu = 1.0 - v;
        v = 1.0 - u;
        u = uu;
    }
    return vec2(d.x < 0.0 ? -u : u, d.y < 0.0 ? -v : v);
}

uint ar_bin_of(vec3 d, uint nu, uint nv) {
    vec2 s = ar_direction_to_square(normalize(d));
    uint iu = min(uint((s.x + 1.0) * 0.5 * float(nu)), nu - 1u);
    uint iv = min(uint((s.y + 1.0) * 0.5 * float(nv)), nv - 1u);
    return iv * nu + iu;
}

#endif
