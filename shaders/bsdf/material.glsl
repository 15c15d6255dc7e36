// The material record as the GPU reads it: std430 mirror of GpuMaterial in
// cpu/src/scene.rs (128 bytes: 16 bytes of scalars, then seven vec4s).
#ifndef GLINT_BSDF_MATERIAL_GLSL
#define GLINT_BSDF_MATERIAL_GLSL

#define KIND_DIFFUSE 0u
#define KIND_CONDUCTOR 1u
#define KIND_DIELECTRIC 2u
#define KIND_METALLIC 3u
#define KIND_COATED 4u
#define KIND_PLASTIC 5u
#define KIND_THIN_DIELECTRIC 6u
#define KIND_ROUGH_PLASTIC 7u

// Material.shadowing: 0 height-correlated Smith G2, 1 separable G1 G1.
// Material.extra.w, the clear coat's normal (bsdf::clearcoat's
// COAT_NORMAL_STEPS and COAT_NORMAL_STRIDE): 0, or 1 + qx STRIDE + qy with
// q = floor((x + 1) STEPS + 1/2) in [0, 2 STEPS].
#define COAT_NORMAL_STEPS 2047u
#define COAT_NORMAL_STRIDE 4095u

#define SHADOWING_CORRELATED 0u
#define SHADOWING_SEPARABLE 1u
// Material.shadowing bit 1: `multiscatter` energy compensation.
#define SHADOWING_MULTISCATTER 2u

struct Material {
    uint kind;
    uint shadowing;
    float alpha_u;   // GGX alpha along the tangent s
    float alpha_v;   // GGX alpha along t
    vec4 reflectance; // diffuse / metallic base rgb; .w = metallic weight
    vec4 eta;         // conductor eta rgb; dielectric: .x = int_ior / ext_ior
    vec4 k;           // conductor k rgb
    vec4 specular;    // conductor specular_reflectance rgb
    vec4 emission;    // emitted radiance rgb; .w = 1 when both faces emit
    vec4 coat;        // non-metal coat: KHR_materials_specular scale rgb; .w = IOR
    vec4 extra;       // .x thin-walled transmission probability; .y clear coat weight, .z its alpha
};

#endif
