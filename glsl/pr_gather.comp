#version 450
// Progressive refinement, one shot received (one invocation per element, after Coombe and
// Harris's reconstruction pass): the shooter's radiance U/π times the exact projected solid angle
// of its triangle at sample points of the receiver, each visible when the hemicube's item buffer
// holds the receiver there or nothing nearer; adaptively subdivided where visibility changes
// across the receiver and the samples differ (src/methods/progressive/mod.rs `receive`). Adds to the gathered irradiance and, times the
// albedo, to the unshot radiosity; the shooter's unshot radiosity becomes zero.
#extension GL_GOOGLE_include_directive : require
#include "pr_common.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = PR_BINDING_LEAVES) readonly buffer Leaves { PrLeaf leaves[]; };
layout(std430, binding = PR_BINDING_STATE) buffer States { PrState state[]; };
layout(std430, binding = PR_BINDING_SHOT) readonly buffer Shot { PrShot shot; };
layout(binding = PR_BINDING_ITEM_ID) uniform usampler2D item_id;
layout(binding = PR_BINDING_ITEM_DIST) uniform sampler2D item_dist;

// Texel tolerance of the distance test: a texel spans 2/size radians at most, over which a
// surface seen at incidence cos recedes by up to that angle / cos of its distance.
const float PR_TEXEL_SLACK = 1.5;
const float PR_MIN_COS = 0.1;

bool visible(vec3 x, uint r, vec3 nr, vec3 eye, vec3 n, vec3 t, vec3 b) {
    vec3 v = x - eye;
    float dn = dot(v, n);
    if (dn <= 0.0) {
        return false;
    }
    float dt = dot(v, t);
    float db = dot(v, b);
    uint f;
    if (dn >= abs(dt) && dn >= abs(db)) {
        f = 0u;
    } else if (abs(dt) >= abs(db)) {
        f = dt > 0.0 ? 1u : 2u;
    } else {
        f = db > 0.0 ? 3u : 4u;
    }
    vec3 fw, rt, up;
    pr_face(f, n, t, b, fw, rt, up);
    float z = dot(v, fw);
    float s = float(pc.size);
    float px = clamp(floor((dot(v, rt) / z * 0.5 + 0.5) * s), 0.0, s - 1.0);
    float rows = f == 0u ? s : 0.5 * s;
    float py = clamp(floor((-dot(v, up) / z * 0.5 + 0.5) * s), 0.0, rows - 1.0);
    ivec2 texel = ivec2(int(f * pc.size) + int(px), int(py));
    uint seen = texelFetch(item_id, texel, 0).r;
    if (seen == 0u || seen == r + 1u) {
        return true;
    }
    float d = length(v);
    float c = max(abs(dot(v, nr)) / d, PR_MIN_COS);
    float slack = d * PR_TEXEL_SLACK * (2.0 / s) / c + 2.0 * pc.eps;
    return texelFetch(item_dist, texel, 0).r >= d - slack;
}

void main() {
    uint r = gl_GlobalInvocationID.x;
    uint s = shot.shooter;
    if (r >= pc.leaves || s == PR_NONE) {
        return;
    }
    if (r == s) {
        state[r].unshot = vec4(0.0);
        return;
    }
    PrLeaf S = leaves[s];
    PrLeaf R = leaves[r];
    vec3 n = S.normal.xyz;
    vec3 eye = S.center.xyz + n * pc.eps;
    vec3 t, b;
    pr_basis(n, t, b);
    vec3 nr = R.normal.xyz;
    // Nothing passes unless part of each lies in front of the other (`facing` on the CPU).
    bool r_front = max(max(dot(R.c0_area.xyz - S.center.xyz, n), dot(R.c1.xyz - S.center.xyz, n)),
                       dot(R.c2.xyz - S.center.xyz, n)) > 0.0;
    bool s_front = max(max(dot(S.c0_area.xyz - R.center.xyz, nr), dot(S.c1.xyz - R.center.xyz, nr)),
                       dot(S.c2.xyz - R.center.xyz, nr)) > 0.0;
    if (!r_front || !s_front) {
        return;
    }
    // The centroid, unless the visibility at three probes differs from its own (a shadow
    // boundary crosses the receiver): then 4, 16, ... sub-triangles (`receive` on the CPU).
    vec3 xc = (R.c0_area.xyz + R.c1.xyz + R.c2.xyz) / 3.0;
    float kc = dot(xc - S.center.xyz, n) > 0.0
        ? pr_projected_solid_angle(xc, nr, S.c0_area.xyz, S.c1.xyz, S.c2.xyz)
        : 0.0;
    bool vc = kc > 0.0 && visible(xc, r, nr, eye, n, t, b);
    float got = vc ? kc : 0.0;
    bool refine = false;
    if (pc.subdivision > 0u) {
        for (int j = 0; j < 3; j++) {
            vec3 w = vec3(1.0 / 6.0);
            w[j] = 2.0 / 3.0;
            vec3 x = w.x * R.c0_area.xyz + w.y * R.c1.xyz + w.z * R.c2.xyz;
            refine = refine || visible(x, r, nr, eye, n, t, b) != vc;
        }
    }
    uint level = 1u;
    while (refine) {
        uint count = 1u << (2u * level);
        float sum = 0.0;
        float lo = 3.0e38;
        float hi = 0.0;
        for (uint k = 0u; k < count; k++) {
            vec3 w = pr_subtriangle(level, k);
            vec3 x = w.x * R.c0_area.xyz + w.y * R.c1.xyz + w.z * R.c2.xyz;
            float v = 0.0;
            if (dot(x - S.center.xyz, n) > 0.0) {
                v = pr_projected_solid_angle(x, nr, S.c0_area.xyz, S.c1.xyz, S.c2.xyz);
                if (v > 0.0 && !visible(x, r, nr, eye, n, t, b)) {
                    v = 0.0;
                }
            }
            sum += v;
            lo = min(lo, v);
            hi = max(hi, v);
        }
        got = sum / float(count);
        refine = level < pc.subdivision && hi - lo > pc.gradient * hi;
        level++;
    }
    vec3 dh = shot.unshot.rgb / PR_PI * got;
    state[r].gathered.rgb += dh;
    state[r].unshot.rgb += R.albedo.rgb * dh;
}
