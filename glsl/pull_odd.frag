#version 450
// Pull into clusters at odd depths; their cluster children are even.
#include "common.glsl"
layout(binding = AR_BINDING_CLUSTER_EX) uniform sampler2D children;
#define AR_CHILDREN children
#include "pull.glsl"
