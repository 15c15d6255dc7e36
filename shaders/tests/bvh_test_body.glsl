// The body of the BVH kernel tests (tests/gpu_bvh.rs): one ray per
// invocation, closest hit and any hit, through shaders/bvh.glsl. Included by
// bvh_test.comp (the 4-wide BVH) and bvh2_test.comp (BVH_BINARY defined:
// the binary one); binding 0 holds the matching node array.
layout(local_size_x = 64) in;

#include "bvh_types.glsl"

struct TestRay {
    vec4 o_tmax; // origin, tmax
    vec4 d;      // direction, unused
};

#ifdef BVH_BINARY
layout(std430, set = 0, binding = 0) readonly buffer Nodes { BvhNode bvh_nodes[]; };
#else
layout(std430, set = 0, binding = 0) readonly buffer Nodes { Bvh4Node bvh_nodes[]; };
#endif
layout(std430, set = 0, binding = 1) readonly buffer Tris { Triangle triangles[]; };
layout(std430, set = 0, binding = 2) readonly buffer Rays { TestRay rays[]; };
// (t, tri, u, v) with t, u, v as float bits; tri = 0xffffffff for a miss.
layout(std430, set = 0, binding = 3) buffer Hits { uvec4 hits[]; };
layout(std430, set = 0, binding = 4) buffer Occluded { uint occluded[]; };

// mode: bit 0 runs bvh_intersect, bit 1 bvh_occluded (the throughput test
// times them apart); a query not run writes a miss.
layout(push_constant) uniform Push {
    uint ray_count;
    uint node_count;
    uint mode;
} pc;

#define BVH_NODE_COUNT pc.node_count
#include "bvh.glsl"

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
