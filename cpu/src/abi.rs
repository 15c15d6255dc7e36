//! The device ABI: everything the GPU kernels and the host agree on, in one
//! place. Every struct a kernel reads (`#[repr(C)]`, its std430 layout
//! checked field by field), every tag, feature bit and constant both sides
//! use, the path tracer's binding table and its push constants.
//!
//! The GLSL side is generated from this module, never written by hand:
//! the root crate's `build.rs` compiles this same file (`#[path]`) and
//! writes [`glsl_types`] to `$OUT_DIR/glsl/glint_abi.glsl` and
//! [`glsl_bindings`] to `$OUT_DIR/glsl/glint_bindings.glsl`, which the
//! shaders `#include`. The generator checks each struct's std430 (the
//! uniform block's std140) offsets against the Rust `offset_of!`, so a
//! struct whose layouts disagree fails the build. The host builds the
//! path tracer's descriptor layout from [`PATH_TRACER_BINDINGS`]
//! (`src/gpu/render.rs`).
//!
//! Because `build.rs` compiles it too, this file uses only `core`, `std`
//! and `bytemuck`; the types' methods live beside their users
//! (`scene.rs`, `texture.rs`, `bvh/`, ...), which re-export them.

#![allow(non_camel_case_types)]

use std::fmt::Write as _;
use std::mem::{offset_of, size_of};

use bytemuck::{Pod, Zeroable};

/// A GLSL type as one field of a device struct declares it.
pub trait Glsl {
    /// The GLSL type name (`uint`, `vec4`, a device struct's name).
    const TYPE: &'static str;
    /// Array length (0: not an array).
    const ARRAY: usize = 0;
}

macro_rules! glsl_type {
    ($($t:ty => $g:literal),* $(,)?) => {
        $(impl Glsl for $t { const TYPE: &'static str = $g; })*
    };
}
glsl_type! {
    u32 => "uint", i32 => "int", f32 => "float",
    [f32; 2] => "vec2", [f32; 3] => "vec3", [f32; 4] => "vec4",
    [u32; 2] => "uvec2", [u32; 3] => "uvec3", [u32; 4] => "uvec4",
}
impl<const N: usize> Glsl for [[f32; 4]; N] {
    const TYPE: &'static str = "vec4";
    const ARRAY: usize = N;
}

/// One GLSL member of a device struct.
#[derive(Clone, Copy, Debug)]
pub struct GlslField {
    pub ty: &'static str,
    pub name: &'static str,
    /// Array length (0: not an array).
    pub array: usize,
}

/// One Rust field of a device struct and its GLSL member (unused where
/// the field lies inside the previous GLSL member, as the `u32` riding in
/// a `vec4`'s `.w`).
#[derive(Clone, Copy, Debug)]
pub struct Field {
    pub name: &'static str,
    pub offset: usize,
    pub size: usize,
    pub glsl: GlslField,
}

/// A `#[repr(C)]` struct the kernels read.
pub trait DeviceStruct: Glsl + Pod {
    /// The Rust name (for the generated comments).
    const RUST: &'static str;
    const FIELDS: &'static [Field];
}

/// Declares a device struct: the Rust struct as written (attributes,
/// `#[repr(C)]` and derives included) plus its [`DeviceStruct`]
/// description. A field's GLSL member is its own name and type unless
/// `=> "type" "name"` gives another; a GLSL member larger than its Rust
/// field absorbs the fields that follow it (`p0: [f32; 3] => "vec4" "p0"`
/// carries the next field in `.w`).
macro_rules! device_struct {
    (
        $(#[$meta:meta])*
        pub struct $name:ident as $glsl:literal {
            $( $(#[$fmeta:meta])* pub $f:ident : $t:ty $(=> $gt:literal $gn:literal)? ),* $(,)?
        }
    ) => {
        $(#[$meta])*
        pub struct $name {
            $( $(#[$fmeta])* pub $f: $t, )*
        }
        impl Glsl for $name {
            const TYPE: &'static str = $glsl;
        }
        impl DeviceStruct for $name {
            const RUST: &'static str = stringify!($name);
            const FIELDS: &'static [Field] = &[$(Field {
                name: stringify!($f),
                offset: offset_of!($name, $f),
                size: size_of::<$t>(),
                glsl: glsl_member!($t, $f $(, $gt, $gn)?),
            }),*];
        }
    };
}

macro_rules! glsl_member {
    ($t:ty, $f:ident) => {
        GlslField {
            ty: <$t as Glsl>::TYPE,
            name: stringify!($f),
            array: <$t as Glsl>::ARRAY,
        }
    };
    ($t:ty, $f:ident, $gt:literal, $gn:literal) => {
        GlslField {
            ty: $gt,
            name: $gn,
            array: 0,
        }
    };
}

/// A constant both sides use, as GLSL `#define`s it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Constant {
    u32(u32),
    usize(usize),
    f32(f32),
}

/// Declares constants (`NAME: type = value;`, type `u32`, `usize` or
/// `f32`) and the list `$list` of them for the generator.
macro_rules! device_constants {
    ($list:ident; $( $(#[$m:meta])* $name:ident : $t:ident = $e:expr; )*) => {
        $( $(#[$m])* pub const $name: $t = $e; )*
        pub const $list: &[(&str, Constant)] = &[$((stringify!($name), Constant::$t($name))),*];
    };
}

// ---------------------------------------------------------------- triangles

device_constants! { TRIANGLE_CONSTANTS;
    /// `Triangle::light` of a triangle that emits nothing.
    NO_LIGHT: u32 = u32::MAX;
    /// `Triangle::flags` bit: the triangle's material emits on both sides.
    TRI_DOUBLE_SIDED: u32 = 1;
    /// `Triangle::flags` bit: the triangle has vertex normals (three
    /// `vec4`s at its shading offset in `Scene::shading`).
    TRI_NORMALS: u32 = 1 << 1;
    /// `Triangle::flags` bit: the triangle has vertex tangents (three
    /// `vec4`s after its normals, or at its offset when it has none).
    TRI_TANGENTS: u32 = 1 << 2;
    /// `Triangle::flags >> TRI_SHADING_SHIFT`: the triangle's shading
    /// offset, in `vec4`s, into `Scene::shading` (meaningful with either
    /// bit above).
    TRI_SHADING_SHIFT: u32 = 3;
}

device_struct! {
    /// A world-space triangle as traversal reads it: three `vec4`s in std430,
    /// the integers riding in `.w` (read with `floatBitsToUint` in GLSL).
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct Triangle as "Triangle" {
        pub p0: [f32; 3] => "vec4" "p0",
        /// Index into `Scene::materials`.
        pub material: u32,
        pub p1: [f32; 3] => "vec4" "p1",
        /// Index of this triangle in the emitter list, or [`NO_LIGHT`].
        pub light: u32,
        pub p2: [f32; 3] => "vec4" "p2",
        /// Bit 0 ([`TRI_DOUBLE_SIDED`]): the triangle's material emits on
        /// both sides; bits 1-2 ([`TRI_NORMALS`], [`TRI_TANGENTS`]): what
        /// shading data it has; bits 3-31: where ([`TRI_SHADING_SHIFT`]).
        pub flags: u32,
    }
}
const _: () = assert!(size_of::<Triangle>() == 48);

// ---------------------------------------------------------------- BVH

device_constants! { BVH_CONSTANTS;
    /// Entries of the binary traversal stack (CPU and GPU). The builder's
    /// depth limit (`bvh::MAX_DEPTH`) keeps it from overflowing.
    BVH_STACK_SIZE: usize = 64;
    /// Ize 2013 ("Robust BVH ray traversal", JCGT 2(2)), as pbrt-v3
    /// applies it: scaling the far slab distance by 1 + 2 gamma(3),
    /// gamma(n) = n eps / (1 - n eps) with eps = 2^-24, makes the rounded
    /// slab test conservative, so a box is never missed when a triangle
    /// inside it is hit.
    BVH_SLAB_PAD: f32 = {
        let eps = f32::EPSILON * 0.5;
        1.0 + 2.0 * (3.0 * eps / (1.0 - 3.0 * eps))
    };
    /// Entries of the wide traversal stack (CPU and GPU): a node visited
    /// pushes at most `WIDTH - 1` children (the nearest is visited at
    /// once), and at most `MAX_WIDE_DEPTH + 1` nodes lie on the path to the
    /// current one (`bvh::wide`).
    BVH4_STACK_SIZE: usize = 72;
    /// A 4-wide node's empty child slot.
    BVH4_SLOT_EMPTY: u32 = u32::MAX;
    /// A 4-wide node's child reference to a leaf: bits 0..27 its first
    /// triangle, bits 27..31 its count - 1.
    BVH4_LEAF_BIT: u32 = 1 << 31;
    /// The first triangle's bits of a leaf reference.
    BVH4_LEAF_FIRST_MASK: u32 = (1 << 27) - 1;
    /// Veltkamp's splitting factor 2^12 + 1 for f32 (24-bit significands):
    /// the triangle test's exact products (`bvh::traverse::two_product`).
    VELTKAMP_SPLIT: f32 = 4097.0;
}

device_struct! {
    /// tinybvh's 32-byte node, read unchanged by the GPU as two `vec4`s (the
    /// integers in `.w` through `floatBitsToUint`). Leaf when `tri_count > 0`:
    /// triangles `[left_or_first, left_or_first + tri_count)` of the
    /// (reordered) triangle array. Interior: children `left_or_first` and
    /// `left_or_first + 1`. Node 0 is the root.
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct BvhNode as "BvhNode" {
        pub aabb_min: [f32; 3] => "vec4" "min_left",
        pub left_or_first: u32,
        pub aabb_max: [f32; 3] => "vec4" "max_count",
        pub tri_count: u32,
    }
}
const _: () = assert!(size_of::<BvhNode>() == 32);

device_struct! {
    /// One node of the 4-wide BVH: 128 bytes, two cache lines. Slot i's box is
    /// `(lo_x[i], lo_y[i], lo_z[i])..(hi_x[i], hi_y[i], hi_z[i])`, copied
    /// unchanged from the binary node it stands for; `child[i]` is a node
    /// index (bit 31 clear), a leaf reference ([`BVH4_LEAF_BIT`] set, see
    /// `bvh::wide::leaf_ref`) or [`BVH4_SLOT_EMPTY`]. Node 0 is the root.
    /// Empty slots have the empty box (+inf..-inf), and are masked out by
    /// their reference, not their box.
    #[repr(C, align(64))]
    #[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
    pub struct Bvh4Node as "Bvh4Node" {
        pub lo_x: [f32; 4],
        pub hi_x: [f32; 4],
        pub lo_y: [f32; 4],
        pub hi_y: [f32; 4],
        pub lo_z: [f32; 4],
        pub hi_z: [f32; 4],
        pub child: [u32; 4],
        /// Pads the node to two 64-byte cache lines; always zero.
        pub _pad: [u32; 4] => "uvec4" "pad",
    }
}
const _: () = assert!(size_of::<Bvh4Node>() == 128);

// ---------------------------------------------------------------- materials

device_constants! { MATERIAL_CONSTANTS;
    /// `GpuMaterial::kind` tags, one per BSDF the kernel dispatches on.
    KIND_DIFFUSE: u32 = 0;
    KIND_CONDUCTOR: u32 = 1;
    KIND_DIELECTRIC: u32 = 2;
    KIND_METALLIC: u32 = 3;
    KIND_COATED: u32 = 4;
    KIND_PLASTIC: u32 = 5;
    KIND_THIN_DIELECTRIC: u32 = 6;
    KIND_ROUGH_PLASTIC: u32 = 7;
    /// Kinds are `0..KIND_COUNT`; the kernel counts a hit on any other as
    /// an error (NaN radiance, `bsdf.glsl`'s `bsdf_unknown`).
    KIND_COUNT: u32 = 8;
    /// `GpuMaterial::shadowing` bit 0 clear: height-correlated Smith G2.
    SHADOWING_CORRELATED: u32 = 0;
    /// `GpuMaterial::shadowing` bit 0: separable G1 G1.
    SHADOWING_SEPARABLE: u32 = 1;
    /// `GpuMaterial::shadowing` bit 1: `multiscatter` energy compensation.
    SHADOWING_MULTISCATTER: u32 = 2;
    /// Grid steps per unit of the clear coat normal's x and y
    /// (`bsdf::clearcoat::encode_coat_normal`): `GpuMaterial::extra.w` is
    /// 0, or 1 + qx STRIDE + qy with q = floor((x + 1) STEPS + 1/2) in
    /// [0, 2 STEPS].
    COAT_NORMAL_STEPS: u32 = 2047;
    /// Values of q per axis, 2 STEPS + 1.
    COAT_NORMAL_STRIDE: u32 = 2 * COAT_NORMAL_STEPS + 1;
}

device_struct! {
    /// The material record the GPU reads (std430, 128 bytes): 16 bytes of
    /// scalars, then `vec4`s.
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct GpuMaterial as "Material" {
        /// One of the `KIND_*` tags.
        pub kind: u32,
        /// Bit 0: separable G1 G1 (else height-correlated Smith G2); bit 1:
        /// `multiscatter` energy compensation.
        pub shadowing: u32,
        /// GGX alphas; the smooth (delta) form when max < SMOOTH_ALPHA_THRESHOLD.
        pub alpha_u: f32,
        pub alpha_v: f32,
        /// Diffuse reflectance (diffuse, metallic blend's base); `.w` = metallic
        /// weight. Dielectric: `specular_transmittance` (`bsdf::Tint`).
        pub reflectance: [f32; 4],
        /// Conductor eta (rgb); dielectric: `.x` = int_ior / ext_ior. `.w` of
        /// eta, k, specular: the conductor's F_avg (rgb) with `multiscatter`.
        pub eta: [f32; 4],
        /// Conductor k (rgb); dielectric: the interior's absorption sigma_a
        /// (rgb, `Material::absorption`).
        pub k: [f32; 4],
        /// Conductor specular_reflectance (rgb); dielectric: its
        /// `specular_reflectance` (`bsdf::Tint`).
        pub specular: [f32; 4],
        /// Emitted radiance (rgb); `.w` = 1 when emission leaves both faces.
        pub emission: [f32; 4],
        /// The non-metal's coat (coated, metallic blend): `KHR_materials_specular`
        /// scale (rgb), `.w` = the coat's IOR.
        pub coat: [f32; 4],
        /// The non-metal's `.x` = thin-walled transmission probability
        /// (`KHR_materials_transmission`); `.y` clear coat weight, `.z` its
        /// alpha (`KHR_materials_clearcoat`, over the coated and metallic
        /// kinds); `.w` its normal (`bsdf::clearcoat::encode_coat_normal`, 0:
        /// the shading normal).
        pub extra: [f32; 4],
    }
}
const _: () = assert!(size_of::<GpuMaterial>() == 128);

device_constants! { BSDF_CONSTANTS;
    /// GGX alphas below this are rendered as the smooth (delta) counterpart
    /// (pbrt-v4's choice; alpha = 0.01 is still rough).
    SMOOTH_ALPHA_THRESHOLD: f32 = 1e-3;
    /// A rough dielectric whose relative IOR is within this of 1 is
    /// rendered as the smooth interface (`bsdf::ETA_SMOOTH_THRESHOLD` says
    /// why).
    ETA_SMOOTH_THRESHOLD: f32 = 1e-2;
    /// Rough alphas are clamped to at least this (pbrt-v4's
    /// `TrowbridgeReitzDistribution` does the same) so that an anisotropic
    /// surface with one alpha near 0 and the other large stays finite.
    MIN_ALPHA: f32 = 1e-4;
    /// The clear coat's IOR (glTF `KHR_materials_clearcoat` fixes 1.5).
    CLEARCOAT_IOR: f32 = 1.5;
    /// The largest f32 below 1: what a lobe choice's rescaled random
    /// number is clamped to.
    ONE_MINUS_EPS: f32 = 1.0 - f32::EPSILON / 2.0;
    GLINT_PI: f32 = std::f32::consts::PI;
    GLINT_INV_PI: f32 = std::f32::consts::FRAC_1_PI;
}

device_constants! { TABLE_CONSTANTS;
    /// The conductor's energy tables (`bsdf::ms_tables`): MS_E[form] is
    /// MS_N x MS_N, MS_T[form] MS_T_N^3.
    MS_N: usize = 32;
    MS_T_N: usize = 24;
    /// Offsets into `bsdf::multiscatter::gpu_tables`, in floats: MS_E[0],
    /// MS_E[1], then MS_E_AVG[0], MS_E_AVG[1] (MS_N each), ...
    MS_OFF_E: usize = 0;
    MS_OFF_E_AVG: usize = 2 * MS_N * MS_N;
    /// ... MS_T[0], MS_T[1] (correlated, separable) ...
    MS_OFF_T: usize = MS_OFF_E_AVG + 2 * MS_N;
    /// ... the coat tables (`bsdf::coated`): E[sqrt x][sqrt alpha][mu^(1/4)],
    /// x = (eta - 1) / (eta + 1) (COAT_E_LEN floats), then E_avg[x][sqrt alpha] ...
    MS_OFF_COAT: usize = MS_OFF_T + 2 * MS_T_N * MS_T_N * MS_T_N;
    COAT_N_MU: usize = 64;
    COAT_N_ALPHA: usize = 64;
    COAT_N_ETA: usize = 32;
    COAT_E_LEN: usize = COAT_N_MU * COAT_N_ALPHA * COAT_N_ETA;
    COAT_E_AVG_LEN: usize = COAT_N_ALPHA * COAT_N_ETA;
    /// ... and `roughplastic`'s: T[form][sqrt x][sqrt alpha][mu] (RP_T_LEN
    /// floats per Smith form, correlated first), then R_int[form][sqrt x][sqrt alpha].
    MS_OFF_RP: usize = MS_OFF_COAT + COAT_E_LEN + COAT_E_AVG_LEN;
    RP_N_MU: usize = 64;
    RP_N_ALPHA: usize = 32;
    RP_N_ETA: usize = 32;
    RP_T_LEN: usize = RP_N_MU * RP_N_ALPHA * RP_N_ETA;
    RP_R_LEN: usize = RP_N_ALPHA * RP_N_ETA;
    /// The dielectric table's eta' grid: log-uniform over [1/3, 3].
    MS_T_ETA_MIN: f32 = 1.0 / 3.0;
    MS_T_ETA_MAX: f32 = 3.0;
}

// ---------------------------------------------------------------- lights

device_constants! { LIGHT_CONSTANTS;
    /// `GpuLight::kind`.
    LIGHT_POINT: u32 = 0;
    LIGHT_SPOT: u32 = 1;
    LIGHT_DIRECTIONAL: u32 = 2;
    /// Light sampling picks a point on an emissive triangle uniformly in
    /// the solid angle it subtends from the shading point when that is at
    /// least this (steradians), by area below it
    /// (`lights::spherical_sampling_angle`). Sampling by area spreads its
    /// weights over a triangle by about sqrt(omega) relative, which is lost
    /// in a path's other noise below this: on the bundled scenes at 1e-3
    /// (pbrt-v4 uses 3e-4) the Cornell box lost 22% per sample for no less
    /// error (`scripts/before_after.sh`, docs/benchmarks.md).
    SPHERICAL_SAMPLING_MIN: f32 = 0.1;
    /// ... and at most this: a triangle that covers nearly a hemisphere
    /// makes the spherical construction ill-conditioned (pbrt-v4's 6.22).
    SPHERICAL_SAMPLING_MAX: f32 = 6.22;
    /// ... and only when the spherical triangle is no sliver: its solid
    /// angle over its longest chord squared (`spherical::spherical_triangle_shape`;
    /// 0.43 for a small equilateral triangle) at least this. Slivers, seen
    /// edge-on or thin, lose the f32 sampler's accuracy: over 600 random
    /// configurations, 0 of those above this bound failed a chi-square test,
    /// 148 of all those above the solid-angle bound did.
    SPHERICAL_SAMPLING_SHAPE: f32 = 0.1;
    /// ... and only when the shading point is off the triangle's plane:
    /// its height over the plane at least this fraction of its distance to
    /// the farthest vertex. Closer to the plane the sampled directions
    /// graze it and f32 misplaces the points they hit (a chi-square test
    /// failed at 0.5% height, `cpu/tests/light_sampling.rs`).
    SPHERICAL_SAMPLING_HEIGHT: f32 = 0.05;
    /// The solid angle is not computed where a bound puts it below
    /// `SPHERICAL_SAMPLING_MIN` by this fraction or more
    /// (`lights::lanes::near_angle`: omega <= height / (2 d^3), d a lower
    /// bound on the distance to the triangle): the
    /// formula's own rounding (about 1e-6 relative at that size) cannot
    /// carry it back over the minimum, so the decisions are those of the
    /// solid angle itself.
    SOLID_ANGLE_BOUND_MARGIN: f32 = 1e-3;
    /// `spherical::atan2_nonneg` (Cephes' `atanf`, which both backends run
    /// instead of the library's `atan`): the range-reduction bounds
    /// tan(3 pi / 8) and tan(pi / 8) and the odd polynomial's coefficients
    /// of t^9, t^7, t^5, t^3.
    ATAN_TAN_3PI_8: f32 = 2.414_213_5;
    ATAN_TAN_PI_8: f32 = 0.414_213_57;
    ATAN_P9: f32 = 8.053_744_5e-2;
    ATAN_P7: f32 = -1.387_768_6e-1;
    ATAN_P5: f32 = 1.997_771_1e-1;
    ATAN_P3: f32 = -3.333_295e-1;
}

device_struct! {
    /// One emissive triangle in emitter order (`Triangle::light`), as the GPU
    /// reads it (std430, 32 bytes): `cdf` is the inclusive CDF of the power
    /// distribution at this entry, `pmf` its own probability.
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct GpuEmitter as "Emitter" {
        /// Index into the triangles.
        pub tri: u32,
        pub cdf: f32,
        pub pmf: f32,
        pub area: f32,
        /// The triangle's centroid and its distance to the farthest vertex:
        /// the bounding sphere light sampling's far exit reads
        /// (`lights::spherical_sampling_angle`), computed once.
        pub center: [f32; 3],
        pub radius: f32,
    }
}
const _: () = assert!(size_of::<GpuEmitter>() == 32);

device_struct! {
    /// A punctual light as the GPU reads it (std430, 48 bytes).
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct GpuLight as "Light" {
        /// Position (point, spot); unused for directional.
        pub position: [f32; 3],
        /// One of `LIGHT_*`.
        pub kind: u32,
        /// Spot: the direction the light points to; directional: the direction
        /// the light travels. Unit length.
        pub direction: [f32; 3],
        /// Spot: cos(outer cone angle).
        pub cos_outer: f32,
        /// Point, spot: radiant intensity; directional: irradiance.
        pub intensity: [f32; 3],
        /// Spot: cos(inner cone angle).
        pub cos_inner: f32,
    }
}
const _: () = assert!(size_of::<GpuLight>() == 48);

// ---------------------------------------------------------------- textures

device_constants! { TEXTURE_CONSTANTS;
    /// `TexRef::texture` of an absent texture.
    NO_TEXTURE: u32 = u32::MAX;
    /// `GpuTexture::flags` wrap modes (bits 0-1: S, bits 2-3: T).
    WRAP_REPEAT: u32 = 0;
    WRAP_CLAMP: u32 = 1;
    WRAP_MIRROR: u32 = 2;
    /// `GpuTexture::flags` bit: nearest filtering (else bilinear).
    TEX_NEAREST: u32 = 16;
    /// How a material's textures modify its BSDF (`MaterialTextures::mode`):
    /// not at all ...
    MAP_NONE: u32 = 0;
    /// ... glTF metallic-roughness mapping, recomputed per hit from the
    /// textured base colour, metallic and roughness ...
    MAP_GLTF: u32 = 1;
    /// ... or `extras.bsdf`: baseColorTexture multiplies a diffuse
    /// `reflectance` or a conductor's `specular_reflectance`.
    MAP_EXTRAS: u32 = 2;
}

device_struct! {
    /// One image in the texel array (std430 `struct Texture`, 16 bytes).
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct GpuTexture as "Texture" {
        /// First texel in the texel array.
        pub offset: u32,
        pub width: u32,
        pub height: u32,
        /// Bits 0-1: wrap S, bits 2-3: wrap T (`WRAP_*`), bit 4: [`TEX_NEAREST`].
        pub flags: u32,
    }
}
const _: () = assert!(size_of::<GpuTexture>() == 16);

device_struct! {
    /// A material's use of a texture (glTF `textureInfo` with
    /// `KHR_texture_transform`), 48 bytes.
    #[repr(C)]
    #[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
    pub struct TexRef as "TexRef" {
        /// Index into the texture table, or [`NO_TEXTURE`].
        pub texture: u32,
        /// Which TEXCOORD set (0 or 1).
        pub tex_coord: u32,
        /// normalTexture `scale` (1 elsewhere).
        pub scale: f32,
        pub _pad: u32 => "uint" "pad",
        /// UV transform rows: uv' = (r0.x u + r0.y v + r0.z, r1.x u + r1.y v + r1.z).
        pub transform: [[f32; 4]; 2],
    }
}
const _: () = assert!(size_of::<TexRef>() == 48);

device_struct! {
    /// One material's textures and the factors they multiply (std430, 560 B).
    #[repr(C)]
    #[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
    pub struct MaterialTextures as "MaterialTextures" {
        /// `MAP_*`.
        pub mode: u32,
        /// alphaMode MASK: geometry with alpha below this is not there; a
        /// negative value: opaque.
        pub alpha_cutoff: f32,
        /// baseColorFactor's alpha.
        pub base_alpha: f32,
        /// 1: alphaMode BLEND, as stochastic transparency (a hit is kept with
        /// probability alpha, `texture::blend_random`); 0 otherwise.
        pub blend: u32,
        /// baseColorFactor rgb (MAP_GLTF).
        pub base_factor: [f32; 4],
        /// metallicFactor, roughnessFactor, transmissionFactor, ior (MAP_GLTF).
        pub mr_factor: [f32; 4],
        /// clearcoatFactor, clearcoatRoughnessFactor, specularFactor, unused
        /// (MAP_GLTF; the factors the coat textures multiply).
        pub coat_factor: [f32; 4],
        /// specularColorFactor rgb (MAP_GLTF).
        pub specular_color_factor: [f32; 4],
        pub base_color: TexRef,
        pub metallic_roughness: TexRef,
        pub normal: TexRef,
        pub emissive: TexRef,
        /// `transmissionTexture` (R x transmissionFactor).
        pub transmission: TexRef,
        /// `clearcoatTexture` (R x clearcoatFactor).
        pub clearcoat: TexRef,
        /// `clearcoatRoughnessTexture` (G x clearcoatRoughnessFactor).
        pub clearcoat_roughness: TexRef,
        /// `specularTexture` (A x specularFactor).
        pub specular: TexRef,
        /// `specularColorTexture` (sRGB rgb x specularColorFactor).
        pub specular_color: TexRef,
        /// `clearcoatNormalTexture` (its `scale` in the TexRef), on the
        /// unmapped shading frame (`texture::clearcoat_normal`).
        pub clearcoat_normal: TexRef,
    }
}
const _: () = assert!(size_of::<MaterialTextures>() == 560);

device_struct! {
    /// A triangle's texture coordinates (std430, 64 bytes): `uv[k]` holds
    /// vertex k's TEXCOORD_0 in `.xy` and TEXCOORD_1 in `.zw`; `extra.x` is
    /// the bitangent sign for normal mapping (B = sign * cross(N, T)).
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct TriangleUv as "TriangleUv" {
        pub uv: [[f32; 4]; 3],
        pub extra: [f32; 4],
    }
}
const _: () = assert!(size_of::<TriangleUv>() == 64);

// ---------------------------------------------------------------- integrator

device_constants! { INTEGRATOR_CONSTANTS;
    /// Mitsuba's default `rr_depth`.
    RR_DEPTH: u32 = 5;
    /// Largest survival probability of Russian roulette (Mitsuba's 0.95).
    RR_MAX_PROB: f32 = 0.95;
    /// pbrt-v4's gamma(7) = 7 u / (1 - 7 u), u = 2^-24 (the unit roundoff):
    /// the error bound factor of a point interpolated from three vertices.
    RAY_ERR_GAMMA: f32 = 4.172_326_8e-7;
    /// Relative margin for the watertight triangle test's own rounding: a ray
    /// leaving a triangle at a grazing angle meets its plane again at a t
    /// whose rounding error is a few tens of ulps of the triangle's size.
    /// The test also rejects t below its own conservative error bound
    /// (pbrt-v4's deltaT), which covers steep rays far from the origin
    /// where this fixed margin did not (a 1e5-sized triangle 1e6 away was
    /// re-hit at t = 0.49); the margin keeps what it always covered. 64 unit
    /// roundoffs.
    RAY_ERR_TRI: f32 = 3.814_697_3e-6;
    /// pbrt-v4's gamma(2), gamma(3) and gamma(5): the triangle test's
    /// conservative bound on its own t error (`bvh::traverse::t_error`),
    /// under which a hit is not reported (pbrt-v4 sec. 6.8.4).
    TRI_GAMMA2: f32 = {
        let eps = f32::EPSILON * 0.5;
        2.0 * eps / (1.0 - 2.0 * eps)
    };
    TRI_GAMMA3: f32 = {
        let eps = f32::EPSILON * 0.5;
        3.0 * eps / (1.0 - 3.0 * eps)
    };
    TRI_GAMMA5: f32 = {
        let eps = f32::EPSILON * 0.5;
        5.0 * eps / (1.0 - 5.0 * eps)
    };
    /// Shadow rays stop this fraction of their length short of the light
    /// point (pbrt-v4's `ShadowEpsilon`).
    SHADOW_EPS: f32 = 1e-4;
    /// `GpuParams::mis` (`Mis::code`).
    MIS_POWER: u32 = 0;
    MIS_BALANCE: u32 = 1;
    MIS_NONE: u32 = 2;
    /// `GpuParams::sampler` (`SamplerKind::code`).
    SAMPLER_INDEPENDENT: u32 = 0;
    SAMPLER_SOBOL: u32 = 1;
    /// Salt of the Sobol pair seeds' hash (keeps them apart from `Rng`'s
    /// stream; `sobol`).
    SOBOL_SALT: u32 = 0x5f3c_9a1d;
    /// Sample indices per Sobol sequence: the direction tables' 16 bits.
    SOBOL_BLOCK_BITS: u32 = 16;
    /// Sobol pairs per bounce.
    PAIRS_PER_BOUNCE: u32 = 4;
}

device_constants! { FEATURE_CONSTANTS;
    /// The kernel's feature bits (`features::Features`, specialization
    /// constant 0): diffuse BSDFs (and the metallic blend's base) ...
    F_DIFFUSE: u32 = 1 << 0;
    /// ... smooth or rough conductors ...
    F_CONDUCTOR: u32 = 1 << 1;
    /// ... smooth or rough dielectrics ...
    F_DIELECTRIC: u32 = 1 << 2;
    /// ... the glTF metallic blend ...
    F_METALLIC: u32 = 1 << 3;
    /// ... any rough (microfacet) lobe ...
    F_ROUGH: u32 = 1 << 4;
    /// ... alpha_u != alpha_v somewhere ...
    F_ANISOTROPIC: u32 = 1 << 5;
    /// ... height-correlated and separable Smith forms ...
    F_SMITH_CORRELATED: u32 = 1 << 6;
    F_SMITH_SEPARABLE: u32 = 1 << 7;
    /// ... emissive triangles, point and spot lights, directional lights,
    /// a background (constant or environment map) ...
    F_AREA_LIGHTS: u32 = 1 << 8;
    F_POINT_SPOT: u32 = 1 << 9;
    F_DIRECTIONAL: u32 = 1 << 10;
    F_BACKGROUND: u32 = 1 << 11;
    /// ... paths longer than the camera ray's first hit, next-event
    /// estimation ...
    F_BOUNCES: u32 = 1 << 12;
    F_NEE: u32 = 1 << 13;
    /// ... the coated non-metal, the plastics, the thin dielectric ...
    F_COATED: u32 = 1 << 14;
    F_PLASTIC: u32 = 1 << 15;
    F_THIN_DIELECTRIC: u32 = 1 << 16;
    /// ... a normal map somewhere (the fold, `bsdf::fold`) ...
    F_NORMAL_MAP: u32 = 1 << 17;
    /// ... textures (`Params.textured`: the per-hit material, textured
    /// emission) and alpha masks (`Params.masked`: the alpha test in
    /// traversal).
    F_TEXTURES: u32 = 1 << 18;
    F_ALPHA_MASKS: u32 = 1 << 19;
    /// ... and the KHR extensions' textures (transmission, clear coat, its
    /// roughness and normal, specular, specular colour).
    F_EXTENSION_TEXTURES: u32 = 1 << 20;
    /// Every feature.
    F_ALL: u32 = (1 << 21) - 1;
}

device_struct! {
    /// The path tracer's `uniform Params` (binding 0, std140: the `vec4`s
    /// first, then scalars, so std140 and C agree).
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct GpuParams as "ParamsBlock" {
        /// Camera origin (xyz), see `PinholeCamera`.
        pub cam_origin: [f32; 4],
        /// Camera right axis scaled by tan(yfov/2) * aspect.
        pub cam_right: [f32; 4],
        /// Camera up axis scaled by tan(yfov/2).
        pub cam_up: [f32; 4],
        /// Camera viewing direction (the camera's -Z).
        pub cam_forward: [f32; 4],
        /// Constant background radiance (rgb).
        pub background: [f32; 4],
        pub width: u32,
        pub height: u32,
        /// Total samples per pixel of the render (dispatches cover sub-ranges).
        pub spp: u32,
        /// Mitsuba's max_depth, unbounded (-1) as 0xffffffff.
        pub max_depth: u32,
        /// `sampling::seed_key(seed)`.
        pub seed_key: u32,
        pub triangle_count: u32,
        pub bvh_node_count: u32,
        pub emitter_count: u32,
        pub light_count: u32,
        /// 1: next-event estimation on (`RenderOptions::nee`).
        pub nee: u32,
        /// `MIS_*`.
        pub mis: u32,
        /// `SAMPLER_*`.
        pub sampler: u32 => "uint" "sampler_kind",
        /// Light category probabilities (see `lights`).
        pub p_area: f32,
        pub p_punctual: f32,
        pub p_background: f32,
        /// Samples per variance batch (`RenderOptions::batch`, `Film::batch`).
        pub variance_batch: u32,
        /// 1: some material has textures (bindings 9-12 hold them).
        pub textured: u32,
        /// 1: some material has an alpha mask (traversal tests it).
        pub masked: u32,
        /// Environment map size (0: none; bindings 13-14 hold it).
        pub env_width: u32,
        pub env_height: u32,
        /// The environment map's rotation about +Y.
        pub env_rot_sin: f32,
        pub env_rot_cos: f32,
        /// 1: emissive triangles sampled by solid angle where it pays
        /// (`RenderOptions::light_sampling`), 0: by area everywhere.
        pub solid_angle: u32,
        pub env_pad: u32,
    }
}
const _: () = assert!(size_of::<GpuParams>() == 176);

device_struct! {
    /// The path tracer's push constants: a dispatch renders samples
    /// `[sample_start, sample_start + sample_count)` of every pixel.
    #[repr(C)]
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct SamplePush as "SamplePush" {
        pub sample_start: u32,
        pub sample_count: u32,
    }
}

// ---------------------------------------------------------------- bindings

/// What a binding holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Resource {
    /// A uniform buffer of one device struct (std140).
    Uniform,
    /// A read-only storage buffer (std430).
    Storage,
    /// A storage buffer the kernel writes.
    StorageWrite,
    /// A top-level acceleration structure.
    AccelerationStructure,
}

/// One binding of descriptor set 0.
#[derive(Clone, Copy, Debug)]
pub struct Binding {
    pub binding: u32,
    /// The GLSL variable (for a uniform, its instance name).
    pub name: &'static str,
    /// The element type (the block's type for a uniform).
    pub ty: &'static str,
    pub resource: Resource,
    /// Only in the hardware-traversal kernels (`--traversal hardware`: the
    /// ray-query kernel, `GLINT_RAY_QUERY`, and the ray tracing pipeline,
    /// `GLINT_RAY_TRACING`).
    pub hardware: bool,
    pub doc: &'static str,
}

const fn binding(
    binding: u32,
    name: &'static str,
    ty: &'static str,
    resource: Resource,
    doc: &'static str,
) -> Binding {
    Binding {
        binding,
        name,
        ty,
        resource,
        hardware: false,
        doc,
    }
}

const fn hardware(b: Binding) -> Binding {
    Binding {
        hardware: true,
        ..b
    }
}

use Resource::{AccelerationStructure, Storage, StorageWrite, Uniform};

/// The path tracer's binding table (descriptor set 0), in binding order.
/// Arrays may hold one dummy element (Vulkan buffers cannot be empty): the
/// counts in `params` are the truth.
pub const PATH_TRACER_BINDINGS: &[Binding] = &[
    binding(
        0,
        "params",
        GpuParams::TYPE,
        Uniform,
        "the render's parameters",
    ),
    binding(1, "triangles", Triangle::TYPE, Storage, "BVH leaf order"),
    binding(
        2,
        "bvh_nodes",
        Bvh4Node::TYPE,
        Storage,
        "the 4-wide BVH (one dummy with ray queries)",
    ),
    binding(
        3,
        "shading",
        "vec4",
        Storage,
        "packed normals and tangents of the triangles that have them (Triangle flags)",
    ),
    binding(
        4,
        "materials",
        GpuMaterial::TYPE,
        Storage,
        "Scene::materials",
    ),
    binding(5, "emitters", GpuEmitter::TYPE, Storage, "emitter order"),
    binding(6, "lights", GpuLight::TYPE, Storage, "punctual lights"),
    binding(
        7,
        "accum",
        "vec4",
        StorageWrite,
        "4 per pixel: sum, sum of squares, variance batch running sum, sum of squared batch sums (Film); continued sample by sample (the host zeroes it)",
    ),
    binding(
        8,
        "ray_counts",
        "uint",
        StorageWrite,
        "1 per pixel, added to",
    ),
    binding(
        9,
        "texels",
        "uint",
        Storage,
        "RGBA8 (9-12: one dummy element when params.textured == 0)",
    ),
    binding(
        10,
        "textures",
        GpuTexture::TYPE,
        Storage,
        "the texture table",
    ),
    binding(
        11,
        "material_textures",
        MaterialTextures::TYPE,
        Storage,
        "per material",
    ),
    binding(
        12,
        "triangle_uvs",
        TriangleUv::TYPE,
        Storage,
        "triangle order",
    ),
    binding(
        13,
        "env_texels",
        "vec4",
        Storage,
        "environment map radiance, row 0 the top (13-14: one dummy when params.env_width == 0)",
    ),
    binding(
        14,
        "env_dist",
        "float",
        Storage,
        "EnvMap::marginal then EnvMap::conditional",
    ),
    binding(
        15,
        "ms_tables",
        "float",
        Storage,
        "bsdf::multiscatter::gpu_tables",
    ),
    binding(
        16,
        "active_pixels",
        "uint",
        Storage,
        "1 per pixel: 0 skips the pixel (--adaptive; all 1 otherwise)",
    ),
    hardware(binding(
        17,
        "tri_map",
        "uint",
        Storage,
        "the acceleration structure's geometries' triangles (one dummy without alpha tests)",
    )),
    hardware(binding(
        18,
        "tlas",
        "accelerationStructureEXT",
        AccelerationStructure,
        "the scene's top-level acceleration structure",
    )),
];

/// The bindings of the software-traversal kernel (`hardware`: false) or
/// of the hardware-traversal ones (true), in binding order.
pub fn path_tracer_bindings(hardware: bool) -> impl Iterator<Item = &'static Binding> {
    PATH_TRACER_BINDINGS
        .iter()
        .filter(move |b| hardware || !b.hardware)
}

// ---------------------------------------------------------------- the generator

/// Every device struct, in declaration order (a struct after the ones it
/// contains).
fn structs() -> [(&'static str, &'static str, &'static [Field], usize); 12] {
    fn s<T: DeviceStruct>() -> (&'static str, &'static str, &'static [Field], usize) {
        (T::RUST, T::TYPE, T::FIELDS, size_of::<T>())
    }
    [
        s::<Triangle>(),
        s::<BvhNode>(),
        s::<Bvh4Node>(),
        s::<GpuMaterial>(),
        s::<GpuEmitter>(),
        s::<GpuLight>(),
        s::<GpuTexture>(),
        s::<TexRef>(),
        s::<MaterialTextures>(),
        s::<TriangleUv>(),
        s::<GpuParams>(),
        s::<SamplePush>(),
    ]
}

fn constant_groups() -> [&'static [(&'static str, Constant)]; 9] {
    [
        TRIANGLE_CONSTANTS,
        BVH_CONSTANTS,
        MATERIAL_CONSTANTS,
        BSDF_CONSTANTS,
        TABLE_CONSTANTS,
        LIGHT_CONSTANTS,
        TEXTURE_CONSTANTS,
        INTEGRATOR_CONSTANTS,
        FEATURE_CONSTANTS,
    ]
}

/// std430 (alignment, size) of a scalar or vector type; `None` for others.
fn vector_layout(ty: &str) -> Option<(usize, usize)> {
    Some(match ty {
        "uint" | "int" | "float" => (4, 4),
        "vec2" | "uvec2" | "ivec2" => (8, 8),
        "vec3" | "uvec3" | "ivec3" => (16, 12),
        "vec4" | "uvec4" | "ivec4" => (16, 16),
        _ => return None,
    })
}

/// The GLSL text of a constant; panics where GLSL would read another value.
fn constant_glsl(name: &str, c: Constant) -> String {
    match c {
        Constant::u32(v) => format!("{v}u"),
        Constant::usize(v) => {
            assert!(v <= u32::MAX as usize, "{name} = {v} does not fit a uint");
            format!("{v}u")
        }
        Constant::f32(v) => {
            assert!(v.is_finite(), "{name} = {v}");
            // Rust's shortest round-trip form; glslang reads it as a double
            // and rounds to float, which must give the same bits.
            let s = format!("{v:?}");
            let back = s.parse::<f64>().expect("a float literal") as f32;
            assert_eq!(
                back.to_bits(),
                v.to_bits(),
                "{name}: {s} reads back as {back}"
            );
            s
        }
    }
}

/// The GLSL of every device struct and constant (`glint_abi.glsl`).
/// Panics, failing the build, where a struct's std430 layout is not its
/// Rust layout.
pub fn glsl_types() -> String {
    let mut out = String::from(
        "// Generated by build.rs from cpu/src/abi.rs (glint_cpu::abi): do not edit.\n\
         #ifndef GLINT_ABI_GLSL\n#define GLINT_ABI_GLSL\n\n",
    );
    for group in constant_groups() {
        for &(name, c) in group {
            writeln!(out, "#define {name} {}", constant_glsl(name, c)).unwrap();
        }
        out.push('\n');
    }
    let mut layouts: Vec<(&str, (usize, usize))> = Vec::new();
    for (rust, glsl, fields, size) in structs() {
        if glsl == GpuParams::TYPE || glsl == SamplePush::TYPE {
            continue; // blocks, declared with the bindings
        }
        let (align, members) = struct_layout(rust, fields, size, &layouts);
        writeln!(
            out,
            "// glint_cpu::abi::{rust} ({size} bytes)\nstruct {glsl} {{"
        )
        .unwrap();
        out.push_str(&members);
        out.push_str("};\n\n");
        layouts.push((glsl, (align, size)));
    }
    out.push_str("#endif\n");
    out
}

/// The members of a struct (one line each) and its std430 alignment,
/// checked against the Rust offsets.
fn struct_layout(
    rust: &str,
    fields: &[Field],
    size: usize,
    known: &[(&str, (usize, usize))],
) -> (usize, String) {
    let layout_of = |ty: &str| {
        vector_layout(ty)
            .or_else(|| known.iter().find(|(n, _)| *n == ty).map(|(_, l)| *l))
            .unwrap_or_else(|| panic!("{rust}: no std430 layout for GLSL type {ty}"))
    };
    let mut members = String::new();
    let (mut offset, mut align_max, mut end) = (0usize, 4usize, 0usize);
    for f in fields {
        if f.offset < end {
            assert!(
                f.offset + f.size <= end,
                "{rust}.{}: straddles the end of the GLSL member before it",
                f.name
            );
            continue;
        }
        let g = f.glsl;
        let (align, elem) = layout_of(g.ty);
        let bytes = if g.array > 0 {
            elem.next_multiple_of(align) * g.array
        } else {
            elem
        };
        offset = offset.next_multiple_of(align);
        assert_eq!(
            offset, f.offset,
            "{rust}.{}: std430 puts GLSL {} {} at {offset}, Rust at {}",
            f.name, g.ty, g.name, f.offset
        );
        let array = if g.array > 0 {
            format!("[{}]", g.array)
        } else {
            String::new()
        };
        writeln!(members, "    {} {}{array};", g.ty, g.name).unwrap();
        offset += bytes;
        end = offset;
        align_max = align_max.max(align);
    }
    assert_eq!(
        offset.next_multiple_of(align_max),
        size,
        "{rust}: std430 size {offset} (aligned to {align_max}), Rust size {size}"
    );
    (align_max, members)
}

/// The GLSL of the path tracer's binding table and push constants
/// (`glint_bindings.glsl`; needs `glint_abi.glsl` first).
pub fn glsl_bindings() -> String {
    let mut out = String::from(
        "// Generated by build.rs from cpu/src/abi.rs (glint_cpu::abi::PATH_TRACER_BINDINGS): do not edit.\n\
         #ifndef GLINT_BINDINGS_GEN_GLSL\n#define GLINT_BINDINGS_GEN_GLSL\n\n",
    );
    // Scalars and vectors only, where std140 and std430 agree.
    let block = |rust: &str, fields: &[Field], size: usize| {
        assert!(
            fields.iter().all(|f| f.glsl.array == 0),
            "{rust}: an array in a block"
        );
        struct_layout(rust, fields, size, &[]).1
    };
    for b in PATH_TRACER_BINDINGS {
        if b.hardware {
            out.push_str("#if defined(GLINT_RAY_QUERY) || defined(GLINT_RAY_TRACING)\n");
        }
        writeln!(out, "// binding {}: {}", b.binding, b.doc).unwrap();
        let n = b.binding;
        match b.resource {
            Uniform => {
                assert_eq!(
                    b.ty,
                    GpuParams::TYPE,
                    "binding {n}: the one uniform is GpuParams"
                );
                writeln!(
                    out,
                    "layout(std140, set = 0, binding = {n}) uniform {} {{\n{}}} {};",
                    b.ty,
                    block(GpuParams::RUST, GpuParams::FIELDS, size_of::<GpuParams>()),
                    b.name
                )
                .unwrap();
            }
            Storage | StorageWrite => {
                let ro = if b.resource == Storage {
                    "readonly "
                } else {
                    ""
                };
                writeln!(
                    out,
                    "layout(std430, set = 0, binding = {n}) {ro}buffer Binding{n} {{ {} {}[]; }};",
                    b.ty, b.name
                )
                .unwrap();
            }
            AccelerationStructure => {
                writeln!(
                    out,
                    "layout(set = 0, binding = {n}) uniform {} {};",
                    b.ty, b.name
                )
                .unwrap();
            }
        }
        if b.hardware {
            out.push_str("#endif\n");
        }
    }
    writeln!(
        out,
        "\nlayout(push_constant) uniform {} {{\n{}}} push;\n\n#endif",
        SamplePush::TYPE,
        block(
            SamplePush::RUST,
            SamplePush::FIELDS,
            size_of::<SamplePush>()
        )
    )
    .unwrap();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_binding_table_is_in_order_and_complete() {
        for (i, b) in PATH_TRACER_BINDINGS.iter().enumerate() {
            assert_eq!(b.binding as usize, i, "{}", b.name);
        }
        assert_eq!(path_tracer_bindings(false).count(), 17);
        assert_eq!(path_tracer_bindings(true).count(), 19);
    }

    #[test]
    fn the_generator_accepts_every_struct() {
        let types = glsl_types();
        assert!(types.contains("struct Material {\n    uint kind;\n"));
        assert!(types.contains("#define KIND_ROUGH_PLASTIC 7u\n"));
        assert!(types.contains("#define BVH_SLAB_PAD 1.0000004\n"));
        let b = glsl_bindings();
        assert!(b.contains("buffer Binding7 { vec4 accum[]; };"));
    }

    #[test]
    #[should_panic(expected = "std430 puts")]
    fn a_layout_mismatch_fails() {
        // A vec3 then a vec4: std430 puts the vec4 at 16, a packed Rust
        // struct at 12.
        let fields = [
            Field {
                name: "a",
                offset: 0,
                size: 12,
                glsl: GlslField {
                    ty: "vec3",
                    name: "a",
                    array: 0,
                },
            },
            Field {
                name: "b",
                offset: 12,
                size: 16,
                glsl: GlslField {
                    ty: "vec4",
                    name: "b",
                    array: 0,
                },
            },
        ];
        struct_layout("T", &fields, 28, &[]);
    }
}
