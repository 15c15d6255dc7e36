// Hardware traversal through a ray tracing pipeline (`--traversal hardware
// --ray-tracing pipeline`, or `hardware` on a device without ray queries):
// bvh.glsl's bvh_intersect and bvh_occluded, under the same names and
// contracts, as traceRayEXT calls from ray generation (rt/raygen.rgen,
// which is pathtrace.glsl). Closest hits come back through
// rt/closest_hit.rchit, misses through the miss shaders; alpha-tested
// triangles (the non-opaque geometry, tri_map.glsl) run
// rt/any_hit.rahit, the same alpha test as bvh.glsl's BVH_PRESENT.
//
// Shadow rays stop at the first hit kept and skip the closest-hit shader:
// the ray counts as occluded unless the shadow miss shader clears it.
//
// Interval: [0, tmax], as ray_query.glsl's (the path tracer's rays never
// touch either end).
//
// The includer declares (bindings.glsl with GLINT_RAY_TRACING) `tlas` and
// `tri_map`, and `#define RQ_MASKED <expression>`.
#ifndef GLINT_RT_TRACE_GLSL
#define GLINT_RT_TRACE_GLSL

#include "bvh_types.glsl"
#include "tri_map.glsl"
#include "rt/payload.glsl"

layout(location = RT_HIT_PAYLOAD) rayPayloadEXT RtHit rt_hit;
layout(location = RT_SHADOW_PAYLOAD) rayPayloadEXT uint rt_occluded;

// Closest hit in [0, tmax].
bool bvh_intersect(vec3 o, vec3 d, float tmax, out Hit hit) {
    traceRayEXT(tlas, gl_RayFlagsNoneEXT, 0xffu, 0u, 0u, RT_MISS_HIT, o, 0.0, d, tmax,
                RT_HIT_PAYLOAD);
    if (rt_hit.geometry == RT_MISS) {
        hit = Hit(tmax, BVH_NO_HIT, 0.0, 0.0);
        return false;
    }
    hit = Hit(rt_hit.t, rq_triangle(rt_hit.instance, rt_hit.geometry, rt_hit.primitive), rt_hit.u,
              rt_hit.v);
    return true;
}

// Any hit in [0, tmax]: the first one kept ends the traversal.
bool bvh_occluded(vec3 o, vec3 d, float tmax) {
    rt_occluded = 1u;
    traceRayEXT(tlas, gl_RayFlagsTerminateOnFirstHitEXT | gl_RayFlagsSkipClosestHitShaderEXT,
                0xffu, 0u, 0u, RT_MISS_SHADOW, o, 0.0, d, tmax, RT_SHADOW_PAYLOAD);
    return rt_occluded != 0u;
}

#endif
