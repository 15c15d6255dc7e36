#version 460
// bvh_test.comp (the 4-wide traversal) with mask_test.glsl's alpha test at
// the leaves: the software reference for the alpha-tested rays of
// tests/gpu_ray_query.rs.
#include "mask_test.glsl"
#define BVH_PRESENT(tri, u, v, o, d) test_mask(tri, u, v)
#include "bvh_test_body.glsl"
