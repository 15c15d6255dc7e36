// Hardware traversal (`--traversal hardware`): bvh.glsl's bvh_intersect and
// bvh_occluded, under the same names and contracts, through Vulkan ray
// queries (GL_EXT_ray_query) against the scene's acceleration structures
// (src/gpu/accel.rs). pathtrace.comp includes this file instead of
// bvh.glsl when build.rs compiles it with GLINT_RAY_QUERY defined (the
// kernel `pathtrace_rq`), so the BSDFs, lights, sampler and film are the
// same source.
//
// Geometry and the map back to triangles[]: tri_map.glsl.
//
// The including kernel must, BEFORE including this file, declare
//   - `uniform accelerationStructureEXT tlas` and a buffer array
//     `uint tri_map[]` (`#extension GL_EXT_ray_query : require` first),
//   - `#define RQ_MASKED <expression>`: nonzero when geometry 1 exists,
//   - optionally `#define BVH_PRESENT(tri, u, v, o, d)` as for bvh.glsl.
//
// Interval: ray queries accept hits in [tmin, tmax] with tmin = 0 here;
// bvh.glsl's is open, (0, tmax). The path tracer's rays start off the
// surface (offset_origin) and end short of the light (shadow_tmax), so the
// ends are never hit in either.
#ifndef GLINT_RAY_QUERY_GLSL
#define GLINT_RAY_QUERY_GLSL

#ifndef BVH_PRESENT
#define BVH_PRESENT(tri, u, v, o, d) true
#endif

#include "bvh_types.glsl"
#include "tri_map.glsl"

// Runs the alpha test on each non-opaque candidate of query q, confirming
// those it keeps; opaque triangles commit without coming here.
#define RQ_PROCEED(q, o, d)                                                              \
    while (rayQueryProceedEXT(q)) {                                                      \
        uint ctri = rq_triangle(uint(rayQueryGetIntersectionInstanceCustomIndexEXT(q, false)), \
                                uint(rayQueryGetIntersectionGeometryIndexEXT(q, false)), \
                                uint(rayQueryGetIntersectionPrimitiveIndexEXT(q, false))); \
        vec2 cb = rayQueryGetIntersectionBarycentricsEXT(q, false);                      \
        if (BVH_PRESENT(ctri, cb.x, cb.y, o, d)) {                                       \
            rayQueryConfirmIntersectionEXT(q);                                           \
        }                                                                                \
    }

// Closest hit in [0, tmax].
bool bvh_intersect(vec3 o, vec3 d, float tmax, out Hit hit) {
    hit = Hit(tmax, BVH_NO_HIT, 0.0, 0.0);
    rayQueryEXT q;
    rayQueryInitializeEXT(q, tlas, gl_RayFlagsNoneEXT, 0xffu, o, 0.0, d, tmax);
    RQ_PROCEED(q, o, d)
    if (rayQueryGetIntersectionTypeEXT(q, true) != gl_RayQueryCommittedIntersectionTriangleEXT) {
        return false;
    }
    vec2 b = rayQueryGetIntersectionBarycentricsEXT(q, true);
    hit.t = rayQueryGetIntersectionTEXT(q, true);
    hit.tri = rq_triangle(uint(rayQueryGetIntersectionInstanceCustomIndexEXT(q, true)),
                          uint(rayQueryGetIntersectionGeometryIndexEXT(q, true)),
                          uint(rayQueryGetIntersectionPrimitiveIndexEXT(q, true)));
    hit.u = b.x;
    hit.v = b.y;
    return true;
}

// Any hit in [0, tmax]: the first one kept ends the traversal.
bool bvh_occluded(vec3 o, vec3 d, float tmax) {
    rayQueryEXT q;
    rayQueryInitializeEXT(q, tlas, gl_RayFlagsTerminateOnFirstHitEXT, 0xffu, o, 0.0, d, tmax);
    RQ_PROCEED(q, o, d)
    return rayQueryGetIntersectionTypeEXT(q, true) != gl_RayQueryCommittedIntersectionNoneEXT;
}

#endif
