#version 460
// Differential test kernel for shaders/texture.glsl: texture_sample at
// arbitrary UVs (every wrap mode and filter, sRGB or not), and
// texture_lookup / alpha_pass / textured_bsdf through a material's slots;
// tests/gpu_textures.rs compares the results with glint_cpu::texture.
layout(local_size_x = 64) in;

#include "texture_types.glsl"

layout(std430, set = 0, binding = 0) readonly buffer TexelBuffer { uint texels[]; };
layout(std430, set = 0, binding = 1) readonly buffer TextureBuffer { Texture textures[]; };
layout(std430, set = 0, binding = 2) readonly buffer MaterialTextureBuffer { MaterialTextures material_textures[]; };
layout(std430, set = 0, binding = 3) readonly buffer TriangleUvBuffer { TriangleUv triangle_uvs[]; };

#include "texture.glsl"

// uv_srgb: (u, v, srgb, unused); ids: (texture, material, triangle, unused);
// bary: (u, v) on the triangle, then two more numbers; the alpha test's
// ray is o = (uv, bary.z), d = (bary.xy, bary.w).
struct Query {
    vec4 uv_srgb;
    uvec4 ids;
    vec4 bary;
};

struct Result {
    vec4 sample_;      // texture_sample(textures[ids.x], uv, srgb)
    vec4 base;         // texture_lookup(base_color slot, tri, bary, true)
    vec4 reflectance;  // textured_bsdf(...).reflectance (w: metallic)
    vec4 k_alpha;      // textured_bsdf(...).k.xyz, alpha_u
    uvec4 flags;       // x: alpha_pass, y: textured kind, z: blend_random's bits
    vec4 coat;         // textured_bsdf(...).coat (specular scale, ior)
    vec4 extra;        // textured_bsdf(...).extra (transmission, clear coat)
};

layout(std430, set = 0, binding = 4) readonly buffer Queries { Query queries[]; };
layout(std430, set = 0, binding = 5) buffer Results { Result results[]; };

layout(push_constant) uniform Push {
    uint n;
};

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= n) {
        return;
    }
    Query q = queries[i];
    Result r;
    r.sample_ = texture_sample(textures[q.ids.x], q.uv_srgb.xy, q.uv_srgb.z != 0.0);
    MaterialTextures mt = material_textures[q.ids.y];
    r.base = texture_lookup(mt.base_color, q.ids.z, q.bary.x, q.bary.y, true);
    Material m;
    m.kind = KIND_DIFFUSE;
    m.shadowing = 0u;
    m.alpha_u = 0.0;
    m.alpha_v = 0.0;
    m.reflectance = vec4(0.5, 0.5, 0.5, 0.0);
    m.eta = vec4(0.0);
    m.k = vec4(0.0);
    m.specular = vec4(1.0);
    m.emission = vec4(0.0);
    Material t = textured_bsdf(mt, m, q.ids.z, q.bary.x, q.bary.y);
    r.reflectance = t.reflectance;
    r.k_alpha = vec4(t.k.xyz, t.alpha_u);
    r.coat = t.coat;
    r.extra = t.extra;
    vec3 ro = vec3(q.uv_srgb.xy, q.bary.z);
    vec3 rd = vec3(q.bary.xy, q.bary.w);
    r.flags = uvec4(alpha_pass(q.ids.y, q.ids.z, q.bary.x, q.bary.y, ro, rd) ? 1u : 0u, t.kind,
                    floatBitsToUint(blend_random(q.ids.z, ro, rd)), 0u);
    results[i] = r;
}
