#version 450
// Local pass for Lambertian leaves: reflection from the irradiance image (fast path) and
// antiradiance.
#include "local.glsl"

void main() {
    ar_local(false);
}
