#version 460
// Kernel test of shaders/ray_query.glsl (--traversal hardware) against the
// software traversal (tests/gpu_ray_query.rs): one ray per invocation,
// closest hit and any hit, the outputs as bvh_test_body.glsl's. With
// pc.masked, binding 0 maps the two geometries back to triangles and
// mask_test.glsl's alpha test runs on the candidates.
#extension GL_EXT_ray_query : require
layout(local_size_x = 64) in;

#include "bvh_types.glsl"
#include "mask_test.glsl"

struct TestRay {
    vec4 o_tmax; // origin, tmax
    vec4 d;      // direction, unused
};

layout(std430, set = 0, binding = 0) readonly buffer TriMap { uint tri_map[]; };
layout(std430, set = 0, binding = 1) readonly buffer Tris { Triangle triangles[]; };
layout(std430, set = 0, binding = 2) readonly buffer Rays { TestRay rays[]; };
layout(std430, set = 0, binding = 3) buffer Hits { uvec4 hits[]; };
layout(std430, set = 0, binding = 4) buffer Occluded { uint occluded[]; };
layout(set = 0, binding = 5) uniform accelerationStructureEXT tlas;

layout(push_constant) uniform Push {
    uint ray_count;
    uint masked;
    uint mode;
} pc;

#define RQ_MASKED pc.masked
#define BVH_PRESENT(tri, u, v, o, d) test_mask(tri, u, v)
#include "ray_query.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.ray_count) {
        return;
    }
    TestRay ray = rays[i];
    Hit h;
    bool found = (pc.mode & 1u) != 0u && bvh_intersect(ray.o_tmax.xyz, ray.d.xyz, ray.o_tmax.w, h);
    hits[i] = found ? uvec4(floatBitsToUint(h.t), h.tri, floatBitsToUint(h.u), floatBitsToUint(h.v))
                    : uvec4(0u, BVH_NO_HIT, 0u, 0u);
    bool occ = (pc.mode & 2u) != 0u && bvh_occluded(ray.o_tmax.xyz, ray.d.xyz, ray.o_tmax.w);
    occluded[i] = occ ? 1u : 0u;
}
