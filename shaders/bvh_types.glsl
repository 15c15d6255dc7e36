// The scene structs BVH traversal reads, mirrors of glint_cpu::bvh::BvhNode
// (32 B), glint_cpu::bvh::Bvh4Node (128 B) and glint_cpu::scene::Triangle
// (48 B) in std430. Kept apart from
// bvh.glsl so a kernel can declare its buffers of these types first, then
// include bvh.glsl (which needs those buffers).
#ifndef GLINT_BVH_TYPES_GLSL
#define GLINT_BVH_TYPES_GLSL

// tinybvh's node: min_left = (aabb_min, left_or_first), max_count =
// (aabb_max, tri_count), the integers read with floatBitsToUint. Leaf when
// tri_count > 0: triangles [left_or_first, left_or_first + tri_count);
// interior: children left_or_first and left_or_first + 1. Node 0 is the root.
struct BvhNode {
    vec4 min_left;
    vec4 max_count;
};

// glint_cpu::bvh::Bvh4Node: the 4-wide node, one coordinate of the four
// child boxes per vec4 (slot i's box: (lo_x[i], lo_y[i], lo_z[i]) ..
// (hi_x[i], hi_y[i], hi_z[i])). child[i]: a node index (bit 31 clear), a leaf
// (bit 31 set; bits 0..27 first triangle, bits 27..31 count - 1) or
// 0xffffffff, an empty slot (always after the used ones). Node 0 is the root.
// pad is zero. Pinned to the Rust layout by tests/gpu_bvh.rs
// (shaders/tests/bvh4_layout.comp).
struct Bvh4Node {
    vec4 lo_x;
    vec4 hi_x;
    vec4 lo_y;
    vec4 hi_y;
    vec4 lo_z;
    vec4 hi_z;
    uvec4 child;
    uvec4 pad;
};

// World-space vertices; .w of p0, p1, p2 hold the material index, the
// emitter index (0xffffffff: none) and the flags (floatBitsToUint).
struct Triangle {
    vec4 p0;
    vec4 p1;
    vec4 p2;
};

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
