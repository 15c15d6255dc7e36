#version 460
// Kernel test of shaders/bvh.glsl against glint_cpu::bvh (tests/gpu_bvh.rs):
// one ray per invocation, closest hit and any hit.
layout(local_size_x = 64) in;

#include "bvh_types.glsl"

struct TestRay {
    vec4 o_tmax; // origin, tmax
    vec4 d;      // direction, unused
};

layout(std430, set = 0, binding = 0) readonly buffer Nodes { BvhNode bvh_nodes[]; };
layout(std430, set = 0, binding = 1) readonly buffer Tris { Triangle triangles[]; };
layout(std430, set = 0, binding = 2) readonly buffer Rays { TestRay rays[]; };
// (t, tri, u, v) with t, u, v as float bits; tri = 0xffffffff for a miss.
layout(std430, set = 0, binding = 3) buffer Hits { uvec4 hits[]; };
layout(std430, set = 0, binding = 4) buffer Occluded { uint occluded[]; };

layout(push_constant) uniform Push {
    uint ray_count;
    uint node_count;
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
    bool found = bvh_intersect(ray.o_tmax.xyz, ray.d.xyz, ray.o_tmax.w, h);
    hits[i] = found ? uvec4(floatBitsToUint(h.t), h.tri, floatBitsToUint(h.u), floatBitsToUint(h.v))
                    : uvec4(0u, BVH_NO_HIT, 0u, 0u);
    occluded[i] = bvh_occluded(ray.o_tmax.xyz, ray.d.xyz, ray.o_tmax.w) ? 1u : 0u;
}
