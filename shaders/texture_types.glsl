// Texture records as the GPU reads them (std430): mirrors of
// glint_cpu::texture::{GpuTexture, TexRef, MaterialTextures, TriangleUv}.
#ifndef GLINT_TEXTURE_TYPES_GLSL
#define GLINT_TEXTURE_TYPES_GLSL

#define NO_TEXTURE 0xffffffffu
#define WRAP_REPEAT 0u
#define WRAP_CLAMP 1u
#define WRAP_MIRROR 2u
#define TEX_NEAREST 16u
#define MAP_NONE 0u
#define MAP_GLTF 1u
#define MAP_EXTRAS 2u

struct Texture {
    uint offset;  // first texel in texels[]
    uint width;
    uint height;
    uint flags;   // bits 0-1 wrap S, 2-3 wrap T, bit 4 nearest
};

struct TexRef {
    uint texture;  // index into textures[], or NO_TEXTURE
    uint tex_coord;
    float scale;   // normalTexture scale
    uint pad;
    vec4 transform[2];  // uv' = (dot(r0.xy, uv) + r0.z, dot(r1.xy, uv) + r1.z)
};

struct MaterialTextures {
    uint mode;           // MAP_*
    float alpha_cutoff;  // < 0: opaque
    float base_alpha;
    uint blend;          // 1: alphaMode BLEND (stochastic transparency)
    vec4 base_factor;
    vec4 mr_factor;      // metallic, roughness, transmission, ior
    vec4 coat_factor;    // clearcoat, clearcoat roughness, specular, unused
    vec4 specular_color_factor;
    TexRef base_color;
    TexRef metallic_roughness;
    TexRef normal;
    TexRef emissive;
    TexRef transmission;         // .r x transmission factor
    TexRef clearcoat;            // .r x clearcoat factor
    TexRef clearcoat_roughness;  // .g x clearcoat roughness factor
    TexRef specular;             // .a x specular factor
    TexRef specular_color;       // sRGB rgb x specular colour factor
    TexRef clearcoat_normal;     // on the unmapped frame (texture::clearcoat_normal)
};

struct TriangleUv {
    vec4 uv[3];   // .xy TEXCOORD_0, .zw TEXCOORD_1
    vec4 extra;   // .x bitangent sign
};

#endif
