#version 460
// Kernel test of the binary traversal in shaders/bvh.glsl (tests/gpu_bvh.rs):
// the reference the wide one is compared and measured against on the GPU.
#define BVH_BINARY
#include "bvh_test_body.glsl"
