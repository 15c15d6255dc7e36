// The scene structs BVH traversal reads (BvhNode, Bvh4Node, Triangle:
// glint_abi.glsl, generated from glint_cpu::abi) and the hit it returns.
// Kept apart from bvh.glsl so a kernel can declare its buffers of these
// types first, then include bvh.glsl (which needs those buffers).
//
// Bvh4Node: one coordinate of the four child boxes per vec4 (slot i's box:
// (lo_x[i], lo_y[i], lo_z[i]) .. (hi_x[i], hi_y[i], hi_z[i])). child[i]: a
// node index (bit 31 clear), a leaf (bit 31 set; bits 0..27 first
// triangle, bits 27..31 count - 1) or BVH4_SLOT_EMPTY (always after the
// used ones). BvhNode: min_left = (aabb_min, left_or_first), max_count =
// (aabb_max, tri_count), the integers read with floatBitsToUint. Triangle:
// .w of p0, p1, p2 hold the material index, the emitter index (NO_LIGHT:
// none) and the flags (floatBitsToUint).
#ifndef GLINT_BVH_TYPES_GLSL
#define GLINT_BVH_TYPES_GLSL

#include "glint_abi.glsl"

// A traversal's closest hit, as both traversals (bvh.glsl, ray_query.glsl)
// return it; glint_cpu::bvh::Hit.
struct Hit {
    float t;
    // Index into triangles[].
    uint tri;
    // Barycentrics: p = (1 - u - v) p0 + u p1 + v p2.
    float u;
    float v;
};

#define BVH_INF uintBitsToFloat(0x7f800000u)
#define BVH_NO_HIT 0xffffffffu

#endif
