// Which bins of a node the push adds its parent's incident radiance to (src/system.rs
// System::pushes): every bin of a cluster (its normal attribute is zero), a leaf's front bins
// only: a cluster's light is meant for the leaves that face its sender, so it is not blocked at
// the others' backs. Light reaching a leaf's back through its own links still is.
#ifndef ANTIRADIANCE_PUSH_GLSL
#define ANTIRADIANCE_PUSH_GLSL
#include "common.glsl"

layout(binding = AR_BINDING_ATTR_NORMAL_AREA) uniform sampler2D attr_normal_area;
layout(binding = AR_BINDING_ATTR_LEAF) uniform sampler2D attr_leaf;
layout(std430, binding = AR_BINDING_BIN_CENTERS) readonly buffer BinCenters { vec4 centers[]; };

// src/system.rs READ_MARGIN: bins this close to a leaf's plane count as its front.
const float AR_READ_MARGIN = 1e-4;

bool ar_pushes(uint row, uint j) {
    vec3 n = texelFetch(attr_normal_area, ar_row_texel(row), 0).xyz;
    return dot(centers[j].xyz, n) < AR_READ_MARGIN;
}

// src/system.rs System::push_factor: a leaf's factor on what its ancestors push (the receiver
// calibration, src/system/receivers.rs), |attr_leaf z| (src/gpu/pack.rs); 1 for a cluster (z 0).
float ar_push_factor(uint row) {
    float z = texelFetch(attr_leaf, ar_row_texel(row), 0).z;
    return z == 0.0 ? 1.0 : abs(z);
}

#endif
