// The material record as the GPU reads it (struct Material), its KIND_*
// tags, SHADOWING_* bits and the clear coat normal's COAT_NORMAL_* grid:
// glint_abi.glsl, generated from glint_cpu::abi (cpu/src/abi.rs).
#ifndef GLINT_BSDF_MATERIAL_GLSL
#define GLINT_BSDF_MATERIAL_GLSL

#include "glint_abi.glsl"

#endif
