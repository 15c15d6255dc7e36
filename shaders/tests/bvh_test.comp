#version 460
// Kernel test of the 4-wide traversal in shaders/bvh.glsl against
// glint_cpu::Bvh4 and glint_cpu::Bvh (tests/gpu_bvh.rs).
#include "bvh_test_body.glsl"
