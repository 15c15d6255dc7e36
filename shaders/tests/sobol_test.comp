#version 460
// Differential test kernel for shaders/integrator/sobol.glsl: per query,
// sobol_sample(key, pixel, sample, dim), and the path sampler of kind
// (dim & 1) for that (key, pixel, sample): its pixel 2D and the numbers of
// bounce (dim >> 1) % 6 (after drawing the bounces before it), as float
// bits; tests/gpu_sobol.rs compares them with cpu/src/sobol.rs.
layout(local_size_x = 64) in;

#include "integrator/sobol.glsl"
#include "integrator/sobol.glsl" // twice on purpose: the include guards must hold

struct Query {
    uint key;
    uint pixel;
    uint sample_index;
    uint dim;
};

layout(std430, set = 0, binding = 0) readonly buffer Queries { Query queries[]; };
// 3 per query: (sobol, pixel.x, pixel.y, light_cat), (light_idx, light.x,
// light.y, bsdf_lobe), (bsdf.x, bsdf.y, rr, 0).
layout(std430, set = 0, binding = 1) buffer Results { uvec4 results[]; };

layout(push_constant) uniform Push {
    uint n;
};

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= n) {
        return;
    }
    Query q = queries[i];
    float v = sobol_sample(q.key, q.pixel, q.sample_index, q.dim);
    Sampler smp = sampler_new(q.dim & 1u, q.key, q.pixel, q.sample_index);
    vec2 px = sampler_pixel_2d(smp);
    uint bounces = (q.dim >> 1u) % 6u;
    for (uint k = 0u; k < bounces; k++) {
        sampler_bounce(smp);
    }
    BounceSamples b = sampler_bounce(smp);
    results[3u * i] = floatBitsToUint(vec4(v, px, b.light_cat));
    results[3u * i + 1u] = floatBitsToUint(vec4(b.light_idx, b.light, b.bsdf_lobe));
    results[3u * i + 2u] = uvec4(floatBitsToUint(vec3(b.bsdf, b.rr)), 0u);
}
