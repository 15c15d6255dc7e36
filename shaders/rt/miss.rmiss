#version 460
#extension GL_EXT_ray_tracing : require
// A path's ray that hit nothing (rt/trace.glsl's bvh_intersect).
#include "rt/payload.glsl"

layout(location = RT_HIT_PAYLOAD) rayPayloadInEXT RtHit rt_hit;

void main() {
    rt_hit.geometry = RT_MISS;
}
