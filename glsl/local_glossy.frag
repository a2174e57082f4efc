#version 450
// Local pass for glossy leaves: the general Phong BRDF sum over incident bins, and antiradiance.
#include "local.glsl"

void main() {
    ar_local(true);
}
