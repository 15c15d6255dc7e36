#version 460
// Differential test kernel for shaders/bsdf: evaluates bsdf_eval, bsdf_pdf,
// bsdf_sample and bsdf_is_delta for each query; tests/gpu_bsdf.rs compares
// the results with the CPU crate (cpu/src/bsdf).
layout(local_size_x = 64) in;

// The multiscatter tables (glint_cpu::bsdf::multiscatter::gpu_tables),
// declared before the BSDFs that read them.
layout(std430, set = 0, binding = 2) readonly buffer MsTables { float ms_tables[]; };
#define MS_TABLE(i) ms_tables[i]

#include "bsdf/bsdf.glsl"
#include "bsdf/bsdf.glsl" // twice on purpose: the include guards must hold

// wo.w = uc, wi.w = u.x, u.x = u.y, u.y = material index (uint bits).
struct Query {
    vec4 wo;
    vec4 wi;
    vec4 u;
};

struct Result {
    vec4 f_pdf;        // bsdf_eval(wo, wi), bsdf_pdf(wo, wi)
    vec4 s_wi_pdf;     // sample: wi, pdf
    vec4 s_weight_eta; // sample: weight, eta
    uvec4 flags;       // x: sample returned true, y: sample delta, z: bsdf_is_delta
};

layout(std430, set = 0, binding = 0) readonly buffer Materials { Material materials[]; };
layout(std430, set = 0, binding = 1) readonly buffer Queries { Query queries[]; };
layout(std430, set = 0, binding = 3) buffer Results { Result results[]; };

layout(push_constant) uniform Push {
    uint n;
};

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= n) {
        return;
    }
    Query q = queries[i];
    Material m = materials[floatBitsToUint(q.u.y)];
    vec3 wo = q.wo.xyz;
    vec3 wi = q.wi.xyz;
    Result r;
    r.f_pdf = vec4(bsdf_eval(m, wo, wi), bsdf_pdf(m, wo, wi));
    BsdfSample s;
    bool ok = bsdf_sample(m, wo, q.wo.w, vec2(q.wi.w, q.u.x), s);
    r.s_wi_pdf = vec4(s.wi, s.pdf);
    r.s_weight_eta = vec4(s.weight, s.eta);
    r.flags = uvec4(ok ? 1u : 0u, s.delta ? 1u : 0u, bsdf_is_delta(m) ? 1u : 0u, 0u);
    results[i] = r;
}
