// The path tracer's binding table (descriptor set 0) and push constants,
// shared by shaders/pathtrace.comp and the host (src/gpu/render.rs). Both
// come from glint_cpu::abi::PATH_TRACER_BINDINGS (cpu/src/abi.rs): build.rs
// generates the declarations into glint_bindings.glsl, the host builds
// its descriptor set layout from the same table. Each binding's comment in
// the generated file says what it holds; in short:
//
//   0 params (uniform GpuParams), 1 triangles, 2 bvh_nodes, 3 shading,
//   4 materials, 5 emitters, 6 lights, 7 accum (written), 8 ray_counts
//   (written), 9-12 texels, textures, material_textures, triangle_uvs,
//   13-14 env_texels, env_dist, 15 ms_tables, 16 active_pixels; with
//   GLINT_RAY_QUERY or GLINT_RAY_TRACING (the hardware traversals, the
//   kernel pathtrace_rq and the ray tracing pipeline rt/; src/gpu/accel.rs)
//   17 tri_map and 18 tlas.
//
// Push constants: uint sample_start, sample_count: a dispatch renders
// samples [sample_start, sample_start + sample_count) of every pixel, one
// invocation per pixel, 8x8 workgroups (a ray tracing launch: the same
// grid). In a ray tracing pipeline every stage sees every binding. Arrays may hold a dummy element
// (Vulkan buffers cannot be empty): the counts in params are the truth.
// glint_cpu::integrator::gpu_scene_data fills params and bindings 4-6.
#ifndef GLINT_BINDINGS_GLSL
#define GLINT_BINDINGS_GLSL

#include "bvh_types.glsl"
#include "bsdf/material.glsl"
#include "texture_types.glsl"
#include "glint_bindings.glsl"

// bsdf/multiscatter.glsl reads its tables through this hook.
#define MS_TABLE(i) ms_tables[i]

#define BVH_NODE_COUNT (params.bvh_node_count)

#endif
