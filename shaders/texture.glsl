// glTF textures: the GLSL mirror of glint_cpu::texture (cpu/src/texture.rs),
// function for function under the same names (conventions there: UV origin
// at the image's top-left, bilinear or nearest, wrap modes, sRGB decode per
// texel before filtering).
//
// The including kernel must, BEFORE including this file, declare the
// buffers `uint texels[]`, `Texture textures[]`, `MaterialTextures
// material_textures[]` and `TriangleUv triangle_uvs[]` (bindings.glsl does).
#ifndef GLINT_TEXTURE_GLSL
#define GLINT_TEXTURE_GLSL

#include "features.glsl"
#include "texture_types.glsl"
#include "bsdf/material.glsl"
#include "bsdf/fresnel.glsl"

float srgb_to_linear(float c) {
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

vec4 unpack_texel(uint t) {
    return vec4(float(t & 255u), float((t >> 8) & 255u), float((t >> 16) & 255u), float(t >> 24)) / 255.0;
}

// Texel index i wrapped into [0, n). After reduce_coord, i >= -n - 1, so
// i + 4n is non-negative and the modulo is well defined.
int wrap_texel(int i, int n, uint mode) {
    if (mode == WRAP_CLAMP) {
        return clamp(i, 0, n - 1);
    }
    if (mode == WRAP_MIRROR) {
        int k = int(uint(i + 4 * n) % uint(2 * n));
        return k >= n ? 2 * n - 1 - k : k;
    }
    return int(uint(i + 4 * n) % uint(n));
}

float reduce_coord(float x, uint mode) {
    if (isnan(x)) {
        x = 0.0;
    }
    if (mode == WRAP_CLAMP) {
        return clamp(x, -1.0, 2.0);
    }
    if (mode == WRAP_MIRROR) {
        return x - 2.0 * floor(0.5 * x);
    }
    return x - floor(x);
}

vec4 texture_fetch(Texture t, int x, int y, bool srgb) {
    int w = int(t.width);
    int h = int(t.height);
    x = wrap_texel(x, w, t.flags & 3u);
    y = wrap_texel(y, h, (t.flags >> 2) & 3u);
    vec4 c = unpack_texel(texels[t.offset + uint(y * w + x)]);
    if (srgb) {
        return vec4(srgb_to_linear(c.x), srgb_to_linear(c.y), srgb_to_linear(c.z), c.w);
    }
    return c;
}

vec4 texture_sample(Texture t, vec2 uv, bool srgb) {
    float u = reduce_coord(uv.x, t.flags & 3u);
    float v = reduce_coord(uv.y, (t.flags >> 2) & 3u);
    float x = u * float(t.width);
    float y = v * float(t.height);
    if ((t.flags & TEX_NEAREST) != 0u) {
        return texture_fetch(t, int(floor(x)), int(floor(y)), srgb);
    }
    x -= 0.5;
    y -= 0.5;
    float x0 = floor(x);
    float y0 = floor(y);
    float fx = x - x0;
    float fy = y - y0;
    int ix = int(x0);
    int iy = int(y0);
    vec4 a = texture_fetch(t, ix, iy, srgb);
    vec4 b = texture_fetch(t, ix + 1, iy, srgb);
    vec4 c = texture_fetch(t, ix, iy + 1, srgb);
    vec4 d = texture_fetch(t, ix + 1, iy + 1, srgb);
    return (a * (1.0 - fx) + b * fx) * (1.0 - fy) + (c * (1.0 - fx) + d * fx) * fy;
}

vec2 texref_apply(TexRef r, vec2 uv) {
    return vec2(r.transform[0].x * uv.x + r.transform[0].y * uv.y + r.transform[0].z,
                r.transform[1].x * uv.x + r.transform[1].y * uv.y + r.transform[1].z);
}

vec2 triangle_uv_at(uint tri, uint set, float u, float v) {
    float w = 1.0 - u - v;
    TriangleUv t = triangle_uvs[tri];
    if (set == 1u) {
        return w * t.uv[0].zw + u * t.uv[1].zw + v * t.uv[2].zw;
    }
    return w * t.uv[0].xy + u * t.uv[1].xy + v * t.uv[2].xy;
}

// SceneTextures::lookup.
vec4 texture_lookup(TexRef r, uint tri, float u, float v, bool srgb) {
    vec2 uv = triangle_uv_at(tri, r.tex_coord, u, v);
    return texture_sample(textures[r.texture], texref_apply(r, uv), srgb);
}

// texture::hash_u32 (lowbias32).
uint hash_u32(uint x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

// texture::blend_random: BLEND's uniform number for (triangle, ray), from
// the same bits as the CPU's.
float blend_random(uint tri, vec3 o, vec3 d) {
    uint h = hash_u32(tri ^ 0x9e3779b9u);
    h = hash_u32(h ^ floatBitsToUint(o.x));
    h = hash_u32(h ^ floatBitsToUint(o.y));
    h = hash_u32(h ^ floatBitsToUint(o.z));
    h = hash_u32(h ^ floatBitsToUint(d.x));
    h = hash_u32(h ^ floatBitsToUint(d.y));
    h = hash_u32(h ^ floatBitsToUint(d.z));
    return float(h >> 8) * (1.0 / 16777216.0);
}

// SceneTextures::alpha_pass: MASK keeps alpha >= cutoff, BLEND keeps a hit
// with probability alpha.
bool alpha_pass(uint material, uint tri, float u, float v, vec3 o, vec3 d) {
    MaterialTextures m = material_textures[material];
    if (m.alpha_cutoff < 0.0 && m.blend == 0u) {
        return true;
    }
    float a = m.base_alpha;
    if (m.base_color.texture != NO_TEXTURE) {
        a *= texture_lookup(m.base_color, tri, u, v, false).w;
    }
    if (m.blend != 0u) {
        return blend_random(tri, o, d) < a;
    }
    return a >= m.alpha_cutoff;
}

bool material_textures_used(MaterialTextures m) {
    return m.mode != MAP_NONE || m.alpha_cutoff >= 0.0 || m.blend != 0u
        || m.normal.texture != NO_TEXTURE || m.emissive.texture != NO_TEXTURE
        || m.clearcoat_normal.texture != NO_TEXTURE;
}

// glint_cpu::loader::conductor_from_f0 (MAX_F0 = 0.999); the roughness
// keeps the material's `multiscatter` bit, whose Kulla-Conty lobe then needs
// the new conductor's F_avg in the .w's (conductor_f_avg).
void conductor_from_f0(inout Material g, vec3 f0, float alpha, uint multiscatter) {
    f0 = clamp(f0, vec3(0.0), vec3(0.999));
    vec3 k = 2.0 * sqrt(f0 / (vec3(1.0) - f0));
    vec3 f_avg = multiscatter != 0u ? fresnel_conductor_avg(vec3(1.0), k) : vec3(0.0);
    g.eta = vec4(1.0, 1.0, 1.0, f_avg.x);
    g.k = vec4(k, f_avg.y);
    g.specular = vec4(1.0, 1.0, 1.0, f_avg.z);
    g.alpha_u = alpha;
    g.alpha_v = alpha;
    g.shadowing = SHADOWING_CORRELATED | multiscatter;
}

// The coat's KHR texture slots, by textured_coat's bit.
const uint SLOT_TRANSMISSION = 0u;
const uint SLOT_CLEARCOAT = 1u;
const uint SLOT_CLEARCOAT_ROUGHNESS = 2u;
const uint SLOT_SPECULAR = 3u;
const uint SLOT_SPECULAR_COLOR = 4u;
const uint COAT_SLOTS = 5u;

TexRef coat_slot(MaterialTextures mt, uint i) {
    if (i == SLOT_TRANSMISSION) {
        return mt.transmission;
    } else if (i == SLOT_CLEARCOAT) {
        return mt.clearcoat;
    } else if (i == SLOT_CLEARCOAT_ROUGHNESS) {
        return mt.clearcoat_roughness;
    } else if (i == SLOT_SPECULAR) {
        return mt.specular;
    }
    return mt.specular_color;
}

// texture::textured_coat on the record's coat (coat.xyz the specular
// scale, extra.xyz transmission, clear coat weight and alpha): only the
// textured parameters are replaced. The filled slots' lookups go through
// one texture_lookup call in a loop over their bits, which the compiler
// cannot unroll: lavapipe inlines every call, and five call sites were five
// copies of the bilinear lookup (the generic kernel compiles cold in 69 s
// instead of 83 s; docs/benchmarks.md). The early return keeps materials
// without these slots as fast as before. Each field is written by one slot,
// so the order is free; the specular scale multiplies as before (factor,
// then colour).
void textured_coat(MaterialTextures mt, inout Material r, uint tri, float u, float v) {
    if (!HAS(F_EXTENSION_TEXTURES)) {
        return;
    }
    uint filled = 0u;
    for (uint i = 0u; i < COAT_SLOTS; i++) {
        if (coat_slot(mt, i).texture != NO_TEXTURE) {
            filled |= 1u << i;
        }
    }
    if (filled == 0u) {
        return;
    }
    bool specular = (filled & ((1u << SLOT_SPECULAR) | (1u << SLOT_SPECULAR_COLOR))) != 0u;
    float factor = mt.coat_factor.z;
    vec3 color = mt.specular_color_factor.xyz;
    while (filled != 0u) {
        uint i = uint(findLSB(filled));
        filled &= filled - 1u;
        vec4 t = texture_lookup(coat_slot(mt, i), tri, u, v, i == SLOT_SPECULAR_COLOR);
        if (i == SLOT_TRANSMISSION) {
            r.extra.x = mt.mr_factor.z * t.x;
        } else if (i == SLOT_CLEARCOAT) {
            r.extra.y = mt.coat_factor.x * t.x;
        } else if (i == SLOT_CLEARCOAT_ROUGHNESS) {
            float cr = mt.coat_factor.y * t.y;
            r.extra.z = cr * cr;
        } else if (i == SLOT_SPECULAR) {
            factor *= t.w;
        } else {
            color *= t.xyz;
        }
    }
    if (specular) {
        r.coat.xyz = min(factor * color, vec3(1.0));
    }
}

// texture::textured_bsdf, on the GPU material record. The glTF mapping is
// always the metallic blend (metallic 0 and 1 its ends), so that one kernel
// path serves every texel; the record's coat and `multiscatter` bit stay.
Material textured_bsdf(MaterialTextures mt, Material g, uint tri, float u, float v) {
    vec3 base_tex = vec3(1.0);
    if (mt.base_color.texture != NO_TEXTURE) {
        base_tex = texture_lookup(mt.base_color, tri, u, v, true).xyz;
    }
    if (mt.mode == MAP_GLTF) {
        vec3 base = mt.base_factor.xyz * base_tex;
        float metallic = mt.mr_factor.x;
        float roughness = mt.mr_factor.y;
        if (mt.metallic_roughness.texture != NO_TEXTURE) {
            vec4 c = texture_lookup(mt.metallic_roughness, tri, u, v, false);
            roughness *= c.y;
            metallic *= c.z;
        }
        float alpha = roughness * roughness;
        uint ms = g.shadowing & SHADOWING_MULTISCATTER;
        Material r = g;
        if (g.kind != KIND_METALLIC && g.kind != KIND_COATED) {
            // A conductor's record carries no coat: glTF's default one.
            r.coat = vec4(1.0, 1.0, 1.0, 1.5);
            r.extra = vec4(0.0);
        }
        textured_coat(mt, r, tri, u, v);
        // A solid (KHR_materials_volume) transmissive material stays the
        // dielectric; thin-walled transmission rides in the coat (extra.x).
        if (g.kind == KIND_DIELECTRIC) {
            r.kind = KIND_DIELECTRIC;
            r.eta = vec4(mt.mr_factor.w, 0.0, 0.0, 0.0);
            r.alpha_u = alpha;
            r.alpha_v = alpha;
            r.shadowing = SHADOWING_CORRELATED | ms;
        } else {
            conductor_from_f0(r, base, alpha, ms);
            r.kind = KIND_METALLIC;
            r.reflectance = vec4(base, metallic);
        }
        return r;
    }
    if (mt.mode == MAP_EXTRAS) {
        if (g.kind == KIND_DIFFUSE || g.kind == KIND_PLASTIC || g.kind == KIND_ROUGH_PLASTIC) {
            g.reflectance.xyz *= base_tex;
        } else if (g.kind == KIND_CONDUCTOR) {
            g.specular.xyz *= base_tex;
        }
    }
    return g;
}

vec3 perturb_normal(vec3 rgb, float scale, vec3 n, vec3 t, vec3 b) {
    vec3 m = rgb * 2.0 - vec3(1.0);
    vec3 p = t * (m.x * scale) + b * (m.y * scale) + n * m.z;
    float len2 = dot(p, p);
    if (len2 > 0.0 && !isinf(len2)) {
        return p / sqrt(len2);
    }
    return n;
}

// texture::valid_reflection_normal (Cycles' ensure_valid_specular_reflection).
vec3 valid_reflection_normal(vec3 ng, vec3 wo, vec3 n) {
    float side = dot(wo, ng) < 0.0 ? -1.0 : 1.0;
    ng *= side;
    n *= side;
    float iz = dot(wo, ng);
    vec3 r = 2.0 * dot(n, wo) * n - wo;
    float threshold = min(0.9 * iz, 0.01);
    if (dot(r, ng) >= threshold) {
        return n * side;
    }
    vec3 x = n - dot(n, ng) * ng;
    float xl2 = dot(x, x);
    x = xl2 > 0.0 ? x / sqrt(xl2) : vec3(0.0);
    float ix = dot(wo, x);
    float a = ix * ix + iz * iz;
    if (!(a > 0.0) || xl2 == 0.0) {
        return ng * side;
    }
    float b = 2.0 * (a + iz * threshold);
    float c = (threshold + iz) * (threshold + iz);
    float disc = sqrt(max(b * b - 4.0 * a * c, 0.0));
    float nz2 = ix < 0.0 ? 0.25 * (b + disc) / a : 0.25 * (b - disc) / a;
    float nx = sqrt(max(1.0 - nz2, 0.0));
    float nz = sqrt(max(nz2, 0.0));
    vec3 m = nx * x + nz * ng;
    float ml2 = dot(m, m);
    return (ml2 > 0.0 ? m / sqrt(ml2) : vec3(0.0)) * side;
}

// texture::normal_mapped: the frame's (s, t, n) are (tangent, cross(n, s), n).
vec3 normal_mapped(MaterialTextures mt, uint tri, float u, float v, vec3 ng, vec3 wo, vec3 fs, vec3 ft, vec3 fn) {
    if (mt.normal.texture == NO_TEXTURE) {
        return fn;
    }
    vec3 c = texture_lookup(mt.normal, tri, u, v, false).xyz;
    float sign_b = triangle_uvs[tri].extra.x;
    vec3 n = perturb_normal(c, mt.normal.scale, fn, fs, ft * sign_b);
    return dot(n, ng) > 0.0 ? valid_reflection_normal(ng, wo, n) : fn;
}

// bsdf::clearcoat::encode_coat_normal: 0, or 1 + qx STRIDE + qy, an
// integer an f32 holds exactly (bsdf/material.glsl).
float encode_coat_normal(vec2 xy) {
    if (xy == vec2(0.0)) {
        return 0.0;
    }
    float steps = float(COAT_NORMAL_STEPS);
    uvec2 q = uvec2(floor((clamp(xy, vec2(-1.0), vec2(1.0)) + 1.0) * steps + 0.5));
    return float(1u + q.x * COAT_NORMAL_STRIDE + q.y);
}

// texture::clearcoat_normal, encoded for Material.extra.w: the coat's
// normal (clearcoatNormalTexture on the unmapped frame (us, ut, un), else
// un) in the shading frame (fs, ft, fn).
float clearcoat_normal_code(MaterialTextures mt, uint tri, float u, float v, vec3 ng,
                            vec3 us, vec3 ut, vec3 un, vec3 fs, vec3 ft, vec3 fn) {
    vec3 n = un;
    if (HAS(F_EXTENSION_TEXTURES) && mt.clearcoat_normal.texture != NO_TEXTURE) {
        vec3 c = texture_lookup(mt.clearcoat_normal, tri, u, v, false).xyz;
        float sign_b = triangle_uvs[tri].extra.x;
        n = perturb_normal(c, mt.clearcoat_normal.scale, un, us, ut * sign_b);
    }
    vec3 local = vec3(dot(n, fs), dot(n, ft), dot(n, fn));
    if (dot(n, ng) <= 0.0 || local.z <= 0.0 || n == fn) {
        return 0.0;
    }
    return encode_coat_normal(local.xy);
}

// texture::emission_factor.
// The caller checks that the scene has textures at all.
vec3 emission_factor(uint material, uint tri, float u, float v) {
    MaterialTextures mt = material_textures[material];
    if (mt.emissive.texture == NO_TEXTURE) {
        return vec3(1.0);
    }
    return texture_lookup(mt.emissive, tri, u, v, true).xyz;
}

#endif
