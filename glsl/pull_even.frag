#version 450
// Pull into clusters at even depths; their cluster children are odd.
#include "common.glsl"
layout(binding = AR_BINDING_CLUSTER_EX_ODD) uniform sampler2D children;
#define AR_CHILDREN children
#include "pull.glsl"
