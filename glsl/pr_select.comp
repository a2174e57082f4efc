#version 450
// Progressive refinement, shooter selection (one workgroup): the element with the most unshot
// power (area × mean unshot radiosity; ties to the lowest index, as on the CPU), and the figures
// of the state before the shot: unshot power of all elements, the shooter's, its index and the
// exitant flux (means of RGB) into figures[slot].
#extension GL_GOOGLE_include_directive : require
#include "pr_common.glsl"

layout(local_size_x = 256) in;

layout(std430, binding = PR_BINDING_LEAVES) readonly buffer Leaves { PrLeaf leaves[]; };
layout(std430, binding = PR_BINDING_STATE) readonly buffer States { PrState state[]; };
layout(std430, binding = PR_BINDING_SHOT) writeonly buffer Shot { PrShot shot; };
layout(std430, binding = PR_BINDING_FIGURES) writeonly buffer Figures { vec4 figures[]; };

shared float best[256];
shared uint best_index[256];
shared float unshot_sum[256];
shared float flux_sum[256];

void main() {
    uint t = gl_LocalInvocationID.x;
    float p_best = 0.0;
    uint i_best = PR_NONE;
    float unshot = 0.0;
    float flux = 0.0;
    for (uint i = t; i < pc.leaves; i += 256u) {
        float a = leaves[i].c0_area.w;
        vec3 u = state[i].unshot.rgb;
        float p = a * (u.r + u.g + u.b) / 3.0;
        unshot += p;
        vec3 radiosity = state[i].base.rgb + leaves[i].albedo.rgb * state[i].gathered.rgb;
        flux += a * (radiosity.r + radiosity.g + radiosity.b) / 3.0;
        if (p > p_best) {
            p_best = p;
            i_best = i;
        }
    }
    best[t] = p_best;
    best_index[t] = i_best;
    unshot_sum[t] = unshot;
    flux_sum[t] = flux;
    barrier();
    for (uint h = 128u; h > 0u; h >>= 1) {
        if (t < h) {
            float q = best[t + h];
            uint j = best_index[t + h];
            if (q > best[t] || (q == best[t] && j < best_index[t])) {
                best[t] = q;
                best_index[t] = j;
            }
            unshot_sum[t] += unshot_sum[t + h];
            flux_sum[t] += flux_sum[t + h];
        }
        barrier();
    }
    if (t == 0u) {
        uint s = best[0] > 0.0 ? best_index[0] : PR_NONE;
        shot.shooter = s;
        shot.pad0 = 0u;
        shot.pad1 = 0u;
        shot.pad2 = 0u;
        shot.unshot = s == PR_NONE ? vec4(0.0) : vec4(state[s].unshot.rgb, best[0]);
        figures[pc.slot] = vec4(unshot_sum[0], best[0], uintBitsToFloat(s), flux_sum[0]);
    }
}
