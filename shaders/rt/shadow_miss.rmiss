#version 460
#extension GL_EXT_ray_tracing : require
// A shadow ray that reached its light (rt/trace.glsl's bvh_occluded).
#include "rt/payload.glsl"

layout(location = RT_SHADOW_PAYLOAD) rayPayloadInEXT uint rt_occluded;

void main() {
    rt_occluded = 0u;
}
