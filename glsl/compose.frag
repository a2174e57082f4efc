#version 450
// Final pixel (src/gpu/passes/compose.rs): per sample, emission + per-pixel direct light with
// the shadow maps + indirect (vertex-interpolated, or the normalized splat sum); environment
// where nothing was hit; back faces are black (one-sided surfaces). Averages the 2x2 samples.
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"

layout(location = 0) out vec4 color;

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    int ss = int(pc.misc.w);
    vec3 sum = vec3(0.0);
    for (int sy = 0; sy < ss; sy++) {
        for (int sx = 0; sx < ss; sx++) {
            ivec2 t = px * ss + ivec2(sx, sy);
            vec4 g = texelFetch(gbuf_position, t, 0);
            if (g.w < 0.5) {
                sum += pc.environment.rgb;
                continue;
            }
            FrameElement e = elements[uint(g.w + 0.5) - 1u];
            vec3 n = e.normal_area.xyz;
            vec3 wo = normalize(pc.eye.xyz - g.xyz);
            if (dot(wo, n) <= 0.0) {
                continue;
            }
            Material m = materials[e.ids.w];
            vec3 l = m.ke.rgb + ar_direct_radiance(g.xyz, n, m, wo);
            // Only the shading kinds the scene has are compiled in (AR_VERTEX, AR_SPLAT).
            if (e.ids.z == AR_MODE_VERTEX) {
                if (AR_VERTEX) {
                    l += texelFetch(gbuf_vertex, t, 0).rgb;
                }
            } else if (AR_SPLAT) {
                vec4 s = texelFetch(splat_sum, t, 0);
                if (s.a > 0.0) {
                    l += s.rgb / s.a;
                }
            }
            // Discretization can leave a slightly negative indirect term (antiradiance
            // over-cancelling); radiance is never negative (as in frame/cpu.rs).
            sum += max(l, vec3(0.0));
        }
    }
    color = vec4(sum / float(ss * ss), 1.0);
}
