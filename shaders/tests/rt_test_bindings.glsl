// tests/rt_test.rgen's and tests/rt_mask_test.rahit's bindings and push
// constants: tests/ray_query_test.comp's.
#ifndef GLINT_RT_TEST_BINDINGS_GLSL
#define GLINT_RT_TEST_BINDINGS_GLSL

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

#endif
