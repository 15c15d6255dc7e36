// The path tracer's binding table (descriptor set 0), shared by
// shaders/pathtrace.comp and the host (src/gpu/render.rs). Rust mirrors:
//
//   binding 0  uniform Params          glint_cpu::integrator::GpuParams (std140, 176 B)
//   binding 1  Triangle triangles[]    glint_cpu::Triangle (48 B), BVH leaf order
//   binding 2  Bvh4Node bvh_nodes[]    glint_cpu::Bvh4Node (128 B), the 4-wide BVH
//   binding 3  vec4 shading[]          glint_cpu::Scene::shading: packed normals and tangents
//                                      of the triangles that have them (Triangle flags)
//   binding 4  Material materials[]    glint_cpu::GpuMaterial (96 B)
//   binding 5  Emitter emitters[]      glint_cpu::lights::GpuEmitter (16 B), emitter order
//   binding 6  Light lights[]          glint_cpu::lights::GpuLight (48 B)
//   binding 7  vec4 accum[]            4 per pixel: sum, sum of squares, variance batch
//                                      running sum, sum of squared batch sums (glint_cpu::Film);
//                                      continued sample by sample in sample order (the host zeroes it)
//   binding 8  uint ray_counts[]       1 per pixel; ADDED to
//   binding 9  uint texels[]           glint_cpu::texture::SceneTextures::texels (RGBA8)
//   binding 10 Texture textures[]      glint_cpu::texture::GpuTexture (16 B)
//   binding 11 MaterialTextures material_textures[]  glint_cpu::texture::MaterialTextures (512 B)
//   binding 12 TriangleUv triangle_uvs[]  glint_cpu::texture::TriangleUv (64 B), triangle order
//   (bindings 9-12 hold one dummy element when params.textured == 0)
//   binding 13 vec4 env_texels[]       glint_cpu::envmap::EnvMap::texels (radiance, row 0 the top)
//   binding 14 float env_dist[]        EnvMap::marginal then EnvMap::conditional
//   (bindings 13-14 hold one dummy element when params.env_width == 0)
//   binding 15 float ms_tables[]       glint_cpu::bsdf::multiscatter::gpu_tables (multiscatter)
//   binding 16 uint active_pixels[]        1 per pixel: 0 skips the pixel (--adaptive, glint_cpu::adaptive;
//                                      the host writes it between passes; all 1 otherwise)
//   With GLINT_RAY_QUERY (the kernel pathtrace_rq, --traversal hardware; src/gpu/accel.rs):
//   binding 17 uint tri_map[]          the acceleration structure's geometries' triangles
//                                      (ray_query.glsl); one dummy element without alpha tests
//   binding 18 accelerationStructureEXT tlas  the scene's top-level acceleration structure
//   (binding 2 then holds one dummy element: the BVH is not read)
//
// Push constants: uint sample_start, sample_count: a dispatch renders
// samples [sample_start, sample_start + sample_count) of every pixel, one
// invocation per pixel, 8x8 workgroups. Arrays may hold a dummy element
// (Vulkan buffers cannot be empty): the counts in Params are the truth.
// glint_cpu::integrator::gpu_scene_data fills Params and bindings 4-6.
#ifndef GLINT_BINDINGS_GLSL
#define GLINT_BINDINGS_GLSL

#include "bvh_types.glsl"
#include "bsdf/material.glsl"
#include "texture_types.glsl"

// glint_cpu::scene::TRI_*: Triangle flags (p2.w) say which shading data a
// triangle has, and its offset in vec4s into shading[].
#define TRI_NORMALS 2u
#define TRI_TANGENTS 4u
#define TRI_SHADING_SHIFT 3u

struct Emitter {
    uint tri;   // index into triangles[]
    float cdf;  // inclusive CDF of the power distribution
    float pmf;  // this emitter's probability
    float area;
};

#define LIGHT_POINT 0u
#define LIGHT_SPOT 1u
#define LIGHT_DIRECTIONAL 2u

struct Light {
    vec3 position;
    uint kind;
    vec3 direction;  // spot: where it points; directional: where light travels
    float cos_outer;
    vec3 intensity;  // point, spot: intensity; directional: irradiance
    float cos_inner;
};

layout(std140, set = 0, binding = 0) uniform ParamsBlock {
    vec4 cam_origin;
    vec4 cam_right;   // scaled by tan(yfov/2) * aspect
    vec4 cam_up;      // scaled by tan(yfov/2)
    vec4 cam_forward;
    vec4 background;
    uint width;
    uint height;
    uint spp;
    uint max_depth;   // 0xffffffff: unbounded
    uint seed_key;
    uint triangle_count;
    uint bvh_node_count;
    uint emitter_count;
    uint light_count;
    uint nee;         // 1: next-event estimation on
    uint mis;         // glint_cpu::Mis::code: 0 power, 1 balance, 2 none
    uint sampler_kind; // glint_cpu::SamplerKind::code
    float p_area;
    float p_punctual;
    float p_background;
    uint variance_batch; // samples per variance batch (glint_cpu::Film::batch)
    uint textured;    // 1: some material has textures (bindings 9-12 are real)
    uint masked;      // 1: some material has an alpha mask (traversal tests it)
    uint env_width;   // environment map size; 0: none (bindings 13-14 dummies)
    uint env_height;
    float env_rot_sin; // the environment map's rotation about +Y
    float env_rot_cos;
    uint env_pad0;
    uint env_pad1;
} params;

layout(std430, set = 0, binding = 1) readonly buffer TriangleBuffer { Triangle triangles[]; };
layout(std430, set = 0, binding = 2) readonly buffer BvhNodeBuffer { Bvh4Node bvh_nodes[]; };
layout(std430, set = 0, binding = 3) readonly buffer ShadingBuffer { vec4 shading[]; };
layout(std430, set = 0, binding = 4) readonly buffer MaterialBuffer { Material materials[]; };
layout(std430, set = 0, binding = 5) readonly buffer EmitterBuffer { Emitter emitters[]; };
layout(std430, set = 0, binding = 6) readonly buffer LightBuffer { Light lights[]; };
layout(std430, set = 0, binding = 7) buffer AccumBuffer { vec4 accum[]; };
layout(std430, set = 0, binding = 8) buffer RayCountBuffer { uint ray_counts[]; };
layout(std430, set = 0, binding = 9) readonly buffer TexelBuffer { uint texels[]; };
layout(std430, set = 0, binding = 10) readonly buffer TextureBuffer { Texture textures[]; };
layout(std430, set = 0, binding = 11) readonly buffer MaterialTextureBuffer { MaterialTextures material_textures[]; };
layout(std430, set = 0, binding = 12) readonly buffer TriangleUvBuffer { TriangleUv triangle_uvs[]; };
layout(std430, set = 0, binding = 13) readonly buffer EnvTexelBuffer { vec4 env_texels[]; };
layout(std430, set = 0, binding = 14) readonly buffer EnvDistBuffer { float env_dist[]; };
layout(std430, set = 0, binding = 15) readonly buffer MsTableBuffer { float ms_tables[]; };
layout(std430, set = 0, binding = 16) readonly buffer ActiveBuffer { uint active_pixels[]; };
#ifdef GLINT_RAY_QUERY
layout(std430, set = 0, binding = 17) readonly buffer TriMapBuffer { uint tri_map[]; };
layout(set = 0, binding = 18) uniform accelerationStructureEXT tlas;
#endif
// bsdf/multiscatter.glsl reads its tables through this hook.
#define MS_TABLE(i) ms_tables[i]

layout(push_constant) uniform SamplePush {
    uint sample_start;
    uint sample_count;
} push;

#define BVH_NODE_COUNT (params.bvh_node_count)

#endif
