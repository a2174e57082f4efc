// The area emitters' direct light shared by a pixel's samples (frame/cpu.rs shared_direct,
// frame/direct.rs): whether they share it, and its evaluation at their mean. Included by
// compose.frag and direct_blocks.frag after frame.glsl.

// The samples of a pixel share one evaluation of the area emitters' direct light, at their mean
// position, where they all face the eye on one flat surface of one material (on one face slot
// where shading normals interpolate): that light is smooth there (a penumbra over 32 emitter
// samples) and it is most of the frame's cost. Point, spot and directional lights and instant
// radiosity's VPLs stay per sample: their shadows can be sharper than a pixel (frame/cpu.rs
// shared_direct). Returns the samples' mean position, their normals' sum and the first slot.
bool ar_shares_direct(ivec2 px, int ss, out vec3 mid, out vec3 normal_sum, out uint slot0) {
    mid = vec3(0.0);
    normal_sum = vec3(0.0);
    slot0 = 0u;
    for (int k = 0; k < ss * ss; k++) {
        ivec2 t = px * ss + ivec2(k % ss, k / ss);
        vec4 g = texelFetch(gbuf_position, t, 0);
        if (ar_gbuf_background(g.w)) {
            return false;
        }
        uint slot = ar_gbuf_leaf(g.w);
        FrameElement e = elements[slot];
        if (dot(pc.eye.xyz - g.xyz, e.face_normal.xyz) <= 0.0) {
            return false;
        }
        if (k == 0) {
            slot0 = slot;
        } else if (slot != slot0) {
            FrameElement a = elements[slot0];
            FrameElement b = elements[slot];
            if (a.ids.y != b.ids.y || a.ids.w != b.ids.w || a.cos_norm.y > 0.5 || b.cos_norm.y > 0.5) {
                return false;
            }
        }
        mid += g.xyz;
        if (e.cos_norm.y > 0.5) {
            normal_sum += texelFetch(gbuf_normal, t, 0).xyz;
        }
    }
    mid /= float(ss * ss);
    return true;
}

// The shared lights a..b's direct light at the samples' mean `mid` (from ar_shares_direct) on
// face slot `slot0` (0 where the face turns from the eye there).
vec3 ar_shared_direct(vec3 mid, vec3 normal_sum, uint slot0, uint a, uint b) {
    FrameElement e = elements[slot0];
    vec3 n = e.face_normal.xyz;
    vec3 wo = normalize(pc.eye.xyz - mid);
    if (dot(wo, n) <= 0.0) {
        return vec3(0.0);
    }
    vec3 ns = n;
    if (e.cos_norm.y > 0.5) {
        ns = ar_shading_normal(normal_sum, n, wo);
    }
    return ar_direct_radiance(mid, n, ns, materials[e.ids.w], wo, a, b, b, b);
}
