// Texture records as the GPU reads them (std430 Texture, TexRef,
// MaterialTextures, TriangleUv) and their NO_TEXTURE, WRAP_*, TEX_NEAREST
// and MAP_* constants: glint_abi.glsl, generated from glint_cpu::abi
// (cpu/src/abi.rs).
#ifndef GLINT_TEXTURE_TYPES_GLSL
#define GLINT_TEXTURE_TYPES_GLSL

#include "glint_abi.glsl"

#endif
