#version 460
#extension GL_EXT_ray_tracing : require
// The closest hit of a path's ray (rt/trace.glsl's bvh_intersect): where,
// on which primitive of which geometry of which instance.
#include "rt/payload.glsl"

layout(location = RT_HIT_PAYLOAD) rayPayloadInEXT RtHit rt_hit;
hitAttributeEXT vec2 bary;

void main() {
    rt_hit.t = gl_HitTEXT;
    rt_hit.instance = uint(gl_InstanceCustomIndexEXT);
    rt_hit.geometry = uint(gl_GeometryIndexEXT);
    rt_hit.primitive = uint(gl_PrimitiveID);
    rt_hit.u = bary.x;
    rt_hit.v = bary.y;
}
