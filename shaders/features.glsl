// The kernel's feature set: glint_cpu::features::Features, as Vulkan
// specialization constant 0 (src/gpu/render.rs sets it). Every HAS(F_...)
// folds to a constant when the pipeline is built, and the driver removes
// the code behind a false one. Unspecialized (test kernels, --kernel
// generic) every feature is on. The bit values are pinned to the Rust
// constants by tests/kernel_features.rs.
#ifndef GLINT_FEATURES_GLSL
#define GLINT_FEATURES_GLSL

layout(constant_id = 0) const uint GLINT_FEATURES = 0xffffffffu;

#define F_DIFFUSE 1u
#define F_CONDUCTOR 2u
#define F_DIELECTRIC 4u
#define F_METALLIC 8u
#define F_ROUGH 16u
#define F_ANISOTROPIC 32u
#define F_SMITH_CORRELATED 64u
#define F_SMITH_SEPARABLE 128u
#define F_AREA_LIGHTS 256u
#define F_POINT_SPOT 512u
#define F_DIRECTIONAL 1024u
#define F_BACKGROUND 2048u
#define F_BOUNCES 4096u
#define F_NEE 8192u
#define F_COATED 16384u
#define F_PLASTIC 32768u
#define F_THIN_DIELECTRIC 65536u
#define F_NORMAL_MAP 131072u

#define HAS(f) ((GLINT_FEATURES & (f)) != 0u)

#endif
