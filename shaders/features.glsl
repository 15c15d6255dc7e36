// The kernel's feature set: glint_cpu::features::Features, as Vulkan
// specialization constant 0 (src/gpu/render.rs sets it). Every HAS(F_...)
// folds to a constant when the pipeline is built, and the driver removes
// the code behind a false one. Unspecialized (test kernels, --kernel
// generic) every feature is on.
#ifndef GLINT_FEATURES_GLSL
#define GLINT_FEATURES_GLSL

layout(constant_id = 0) const uint GLINT_FEATURES = 0xffffffffu;

#include "glint_abi.glsl" // the F_* bits, glint_cpu::abi's FEATURE_CONSTANTS

#define HAS(f) ((GLINT_FEATURES & (f)) != 0u)

#endif
