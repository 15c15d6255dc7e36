//! glTF textures as both backends read them: every image's texels as packed
//! RGBA8 (`u32`, R in the low byte) in one array, a table of images
//! ([`GpuTexture`]), per-material texture slots ([`MaterialTextures`]) and
//! per-triangle texture coordinates ([`TriangleUv`]). `shaders/texture.glsl`
//! mirrors every function here under the same name.
//!
//! Conventions (glTF 2.0, section 3.8 and the contract's "Materials"):
//! - UV (0, 0) is the image's top-left corner; `v` grows downward, so texel
//!   row `floor(v * height)` is read, row 0 being the image's first row.
//! - Filtering is bilinear (texel centres at half-integers), or nearest when
//!   the sampler's `magFilter` is NEAREST; no mipmaps.
//! - Wrap modes REPEAT, CLAMP_TO_EDGE and MIRRORED_REPEAT per axis.
//! - sRGB images (baseColor, emissive) are decoded to linear per texel,
//!   before filtering; alpha is linear.
//! - 8 bits per channel: 16-bit PNGs are reduced to 8 bits on load.

use std::mem::size_of;

use glam::{Vec2, Vec3, Vec4};

use crate::bsdf::coated::CoatParams;
use crate::bsdf::{Bsdf, Roughness, Shadowing};
use crate::frame::Frame;
use crate::loader::conductor_from_f0;

/// Largest image side glint decodes (checked from the header, before
/// decoding).
pub const MAX_TEXTURE_SIDE: u32 = 16384;
/// The most texels all of a scene's images may hold together (4 GiB of
/// RGBA8 would not fit a GPU buffer binding; 2^28 texels is 1 GiB).
pub const MAX_TEXELS: u64 = 1 << 28;

pub use crate::abi::{
    GpuTexture, MAP_EXTRAS, MAP_GLTF, MAP_NONE, MaterialTextures, NO_TEXTURE, TEX_NEAREST, TexRef,
    TriangleUv, WRAP_CLAMP, WRAP_MIRROR, WRAP_REPEAT,
};

impl Default for TexRef {
    fn default() -> Self {
        TexRef {
            texture: NO_TEXTURE,
            tex_coord: 0,
            scale: 1.0,
            _pad: 0,
            transform: [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]],
        }
    }
}

impl TexRef {
    pub fn is_some(&self) -> bool {
        self.texture != NO_TEXTURE
    }

    /// KHR_texture_transform: uv' = T * R * S * uv, with R as the sample
    /// model TextureTransformTest, Blender, Babylon.js and three.js agree
    /// on: u' = cos(r) sx u + sin(r) sy v + ox, v' = -sin(r) sx u + cos(r)
    /// sy v + oy. The GLSL listing in the extension's text has the
    /// opposite sign (KhronosGroup/glTF#1563); following it turns the
    /// sample's arrow to its red "error" marker.
    pub fn set_transform(&mut self, offset: Vec2, rotation: f32, scale: Vec2) {
        let (s, c) = rotation.sin_cos();
        self.transform = [
            [c * scale.x, s * scale.y, offset.x, 0.0],
            [-s * scale.x, c * scale.y, offset.y, 0.0],
        ];
    }

    pub fn apply(&self, uv: Vec2) -> Vec2 {
        let [r0, r1] = self.transform;
        Vec2::new(
            r0[0] * uv.x + r0[1] * uv.y + r0[2],
            r1[0] * uv.x + r1[1] * uv.y + r1[2],
        )
    }
}

impl Default for MaterialTextures {
    fn default() -> Self {
        MaterialTextures {
            mode: MAP_NONE,
            alpha_cutoff: -1.0,
            base_alpha: 1.0,
            blend: 0,
            base_factor: [1.0; 4],
            mr_factor: [0.0, 1.0, 0.0, 1.5],
            coat_factor: [0.0, 0.0, 1.0, 0.0],
            specular_color_factor: [1.0; 4],
            base_color: TexRef::default(),
            metallic_roughness: TexRef::default(),
            normal: TexRef::default(),
            emissive: TexRef::default(),
            transmission: TexRef::default(),
            clearcoat: TexRef::default(),
            clearcoat_roughness: TexRef::default(),
            specular: TexRef::default(),
            specular_color: TexRef::default(),
            clearcoat_normal: TexRef::default(),
        }
    }
}

impl MaterialTextures {
    /// Whether anything here needs a texture lookup or an alpha test.
    pub fn is_used(&self) -> bool {
        self.mode != MAP_NONE
            || self.is_masked()
            || self.is_blended()
            || self.normal.is_some()
            || self.emissive.is_some()
            || self.clearcoat_normal.is_some()
    }
    pub fn is_masked(&self) -> bool {
        self.alpha_cutoff >= 0.0
    }
    pub fn is_blended(&self) -> bool {
        self.blend != 0
    }
    /// Whether traversal must run this material's alpha test.
    pub fn has_alpha_test(&self) -> bool {
        self.is_masked() || self.is_blended()
    }
    /// Whether a texture modulates the coat (transmission, clear coat,
    /// specular): the glTF mapping is then recomputed per hit.
    pub fn has_coat_textures(&self) -> bool {
        [
            &self.transmission,
            &self.clearcoat,
            &self.clearcoat_roughness,
            &self.specular,
            &self.specular_color,
        ]
        .iter()
        .any(|r| r.is_some())
    }
}

impl TriangleUv {
    /// Interpolated texture coordinate set `set` at barycentrics (u, v).
    pub fn at(&self, set: u32, u: f32, v: f32) -> Vec2 {
        let w = 1.0 - u - v;
        let o = if set == 1 { 2 } else { 0 };
        let c = |k: usize| Vec2::new(self.uv[k][o], self.uv[k][o + 1]);
        w * c(0) + u * c(1) + v * c(2)
    }
}

/// A decoded image's name and size, for `glint info`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TextureInfo {
    pub name: String,
    pub width: u32,
    pub height: u32,
}

/// All of a scene's texture data. Empty (and never read) for a scene
/// without textures or alpha masks.
#[derive(Clone, Debug, Default)]
pub struct SceneTextures {
    pub texels: Vec<u32>,
    pub table: Vec<GpuTexture>,
    pub info: Vec<TextureInfo>,
    /// Per material (same indices as `Scene::materials`), or empty.
    pub materials: Vec<MaterialTextures>,
    /// Per triangle (same order as `Scene::triangles`), or empty.
    pub uvs: Vec<TriangleUv>,
}

impl SceneTextures {
    pub fn is_empty(&self) -> bool {
        self.materials.iter().all(|m| !m.is_used())
    }

    /// Whether some material has an alpha test (MASK or BLEND): traversal
    /// then runs [`SceneTextures::alpha_pass`].
    pub fn has_masks(&self) -> bool {
        self.materials.iter().any(|m| m.has_alpha_test())
    }

    /// Whether `material`'s emission is textured (`emissiveTexture`).
    pub fn has_emissive_texture(&self, material: u32) -> bool {
        self.material(material)
            .is_some_and(|m| m.emissive.is_some())
    }

    /// The material's textures, if it uses any.
    pub fn material(&self, material: u32) -> Option<&MaterialTextures> {
        self.materials
            .get(material as usize)
            .filter(|m| m.is_used())
    }

    /// Bytes the GPU holds for textures.
    pub fn bytes(&self) -> usize {
        self.texels.len() * 4
            + self.table.len() * size_of::<GpuTexture>()
            + self.materials.len() * size_of::<MaterialTextures>()
            + self.uvs.len() * size_of::<TriangleUv>()
    }

    /// `r` looked up at triangle `tri`, barycentrics (u, v); raw RGBA, or
    /// sRGB-decoded RGB with `srgb`.
    pub fn lookup(&self, r: &TexRef, tri: u32, u: f32, v: f32, srgb: bool) -> Vec4 {
        let uv = self.uvs[tri as usize].at(r.tex_coord, u, v);
        texture_sample(
            &self.texels,
            &self.table[r.texture as usize],
            r.apply(uv),
            srgb,
        )
    }

    /// Alpha test: whether the surface of `tri` at (u, v) is there for the
    /// ray (o, d). MASK: alpha >= alphaCutoff. BLEND: `xi < alpha`, `xi` the
    /// ray's uniform number for this triangle ([`blend_random`]), so a hit is kept
    /// with probability alpha and passed through with 1 - alpha: unbiased
    /// transparency for camera, bounce and shadow rays alike. Opaque
    /// materials (and scenes without alpha tests) always pass.
    pub fn alpha_pass(&self, material: u32, tri: u32, u: f32, v: f32, o: Vec3, d: Vec3) -> bool {
        let Some(m) = self.materials.get(material as usize) else {
            return true;
        };
        if !m.has_alpha_test() {
            return true;
        }
        let mut a = m.base_alpha;
        if m.base_color.is_some() {
            a *= self.lookup(&m.base_color, tri, u, v, false).w;
        }
        if m.is_blended() {
            blend_random(tri, o, d) < a
        } else {
            a >= m.alpha_cutoff
        }
    }
}

/// Chris Wellons' `lowbias32` integer hash (a full-avalanche 32-bit mix).
pub fn hash_u32(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^= x >> 16;
    x
}

/// The uniform number in [0, 1) that decides a BLEND hit of triangle `tri`
/// by the ray (o, d): a hash of the triangle index and the ray's origin and
/// direction bits. It needs no sampler dimension (traversal has none to
/// spare, and shadow rays would need their own), a ray asking twice about
/// one triangle gets one answer, and different rays (every sample jitters
/// the camera ray; every bounce starts elsewhere) get independent ones.
/// `shaders/texture.glsl` computes the same bits from the same inputs.
pub fn blend_random(tri: u32, o: Vec3, d: Vec3) -> f32 {
    let mut h = hash_u32(tri ^ 0x9e37_79b9);
    for x in [o.x, o.y, o.z, d.x, d.y, d.z] {
        h = hash_u32(h ^ x.to_bits());
    }
    (h >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// sRGB transfer function to linear (IEC 61966-2-1).
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// [`srgb_to_linear`] of every 8-bit value `b / 255`, as [`unpack_texel`]
/// makes it: the decode of a texel channel by table, the same bits as the
/// function (a test checks all 256), without its `powf` per channel and
/// fetch (four fetches of three channels per filtered lookup).
static SRGB_TO_LINEAR_8: std::sync::LazyLock<[f32; 256]> =
    std::sync::LazyLock::new(|| std::array::from_fn(|b| srgb_to_linear(b as f32 / 255.0)));

/// A packed RGBA8 texel as four values in [0, 1].
pub fn unpack_texel(t: u32) -> Vec4 {
    Vec4::new(
        (t & 255) as f32,
        ((t >> 8) & 255) as f32,
        ((t >> 16) & 255) as f32,
        (t >> 24) as f32,
    ) / 255.0
}

/// Integer texel coordinate `i` wrapped into [0, n) by `mode`.
pub fn wrap_texel(i: i32, n: i32, mode: u32) -> i32 {
    if (0..n).contains(&i) {
        // Inside the image every mode leaves it be (and most lookups are
        // inside): no integer division.
        return i;
    }
    match mode {
        WRAP_CLAMP => i.clamp(0, n - 1),
        WRAP_MIRROR => {
            let k = i.rem_euclid(2 * n);
            if k >= n { 2 * n - 1 - k } else { k }
        }
        _ => i.rem_euclid(n),
    }
}

/// A texture coordinate reduced to a small range with the same result
/// under `mode` (one period for repeat, two for mirror, [-1, 2] for clamp),
/// so texel indices fit an `i32`; NaN reads as 0.
pub fn reduce_coord(x: f32, mode: u32) -> f32 {
    let x = if x.is_nan() { 0.0 } else { x };
    match mode {
        WRAP_CLAMP => x.clamp(-1.0, 2.0),
        WRAP_MIRROR => x - 2.0 * (0.5 * x).floor(),
        _ => x - x.floor(),
    }
}

/// The texel at integer (x, y), wrapped; sRGB-decoded RGB with `srgb`.
pub fn texture_fetch(texels: &[u32], t: &GpuTexture, x: i32, y: i32, srgb: bool) -> Vec4 {
    let (w, h) = (t.width as i32, t.height as i32);
    let x = wrap_texel(x, w, t.flags & 3);
    let y = wrap_texel(y, h, (t.flags >> 2) & 3);
    fetch_wrapped(texels, t, x, y, srgb)
}

/// [`texture_fetch`] of a texel already inside the image.
#[inline]
fn fetch_wrapped(texels: &[u32], t: &GpuTexture, x: i32, y: i32, srgb: bool) -> Vec4 {
    let texel = texels[t.offset as usize + (y * t.width as i32 + x) as usize];
    let c = unpack_texel(texel);
    if srgb {
        let lut = &*SRGB_TO_LINEAR_8;
        Vec4::new(
            lut[(texel & 255) as usize],
            lut[((texel >> 8) & 255) as usize],
            lut[((texel >> 16) & 255) as usize],
            c.w,
        )
    } else {
        c
    }
}

/// Filtered lookup at `uv` (glTF: (0, 0) the image's top-left corner).
pub fn texture_sample(texels: &[u32], t: &GpuTexture, uv: Vec2, srgb: bool) -> Vec4 {
    let u = reduce_coord(uv.x, t.flags & 3);
    let v = reduce_coord(uv.y, (t.flags >> 2) & 3);
    let x = u * t.width as f32;
    let y = v * t.height as f32;
    if t.flags & TEX_NEAREST != 0 {
        return texture_fetch(texels, t, x.floor() as i32, y.floor() as i32, srgb);
    }
    let (x, y) = (x - 0.5, y - 0.5);
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let (ix, iy) = (x0 as i32, y0 as i32);
    // The two columns and two rows wrapped once each, not per texel.
    let (w, h) = (t.width as i32, t.height as i32);
    let [x0, x1] = [ix, ix + 1].map(|i| wrap_texel(i, w, t.flags & 3));
    let [y0, y1] = [iy, iy + 1].map(|i| wrap_texel(i, h, (t.flags >> 2) & 3));
    let a = fetch_wrapped(texels, t, x0, y0, srgb);
    let b = fetch_wrapped(texels, t, x1, y0, srgb);
    let c = fetch_wrapped(texels, t, x0, y1, srgb);
    let d = fetch_wrapped(texels, t, x1, y1, srgb);
    (a * (1.0 - fx) + b * fx) * (1.0 - fy) + (c * (1.0 - fx) + d * fx) * fy
}

/// A tangent-space normal-map texel (rgb in [0, 1]) applied to the frame
/// (n, t, b): ((2 rgb - 1) with xy times `scale`) in (t, b, n), normalised.
/// Returns `n` when the result is degenerate.
pub fn perturb_normal(rgb: Vec3, scale: f32, n: Vec3, t: Vec3, b: Vec3) -> Vec3 {
    let m = rgb * 2.0 - Vec3::ONE;
    let p = t * (m.x * scale) + b * (m.y * scale) + n * m.z;
    let len2 = p.length_squared();
    if len2 > 0.0 && len2.is_finite() {
        p / len2.sqrt()
    } else {
        n
    }
}

/// The BSDF at a textured hit: the material's BSDF with its textured
/// parameters. `MAP_GLTF` recomputes the glTF mapping (transmission, else
/// the metal/non-metal blend, as `loader::material` maps the factors) from
/// the textured base colour, metallic (B) and roughness (G); `MAP_EXTRAS`
/// multiplies a diffuse reflectance or a conductor's specular reflectance
/// by the base colour texture. (Inlined, so that its BSDF is made where
/// the caller keeps it, not copied there.)
#[inline(always)]
pub fn textured_bsdf(
    st: &SceneTextures,
    mt: &MaterialTextures,
    bsdf: &Bsdf,
    tri: u32,
    u: f32,
    v: f32,
) -> Bsdf {
    let base_tex = if mt.base_color.is_some() {
        st.lookup(&mt.base_color, tri, u, v, true).truncate()
    } else {
        Vec3::ONE
    };
    match mt.mode {
        MAP_GLTF => {
            let base = Vec3::from_slice(&mt.base_factor[..3]) * base_tex;
            let mut metallic = mt.mr_factor[0];
            let mut roughness = mt.mr_factor[1];
            if mt.metallic_roughness.is_some() {
                let c = st.lookup(&mt.metallic_roughness, tri, u, v, false);
                roughness *= c.y;
                metallic *= c.z;
            }
            let alpha = roughness * roughness;
            // The factors' model carries what no texture changes: the
            // coat's IOR and `--multiscatter`.
            let (mut coat, multiscatter) = match bsdf {
                Bsdf::Coated {
                    coat, roughness, ..
                } => (*coat, roughness.multiscatter),
                Bsdf::Metallic {
                    coat, conductor, ..
                } => (*coat, conductor.roughness.multiscatter),
                Bsdf::Conductor(c) => (CoatParams::GLTF_DEFAULT, c.roughness.multiscatter),
                Bsdf::Dielectric { roughness, .. } => {
                    (CoatParams::GLTF_DEFAULT, roughness.multiscatter)
                }
                Bsdf::Diffuse { .. }
                | Bsdf::Plastic(_)
                | Bsdf::RoughPlastic(_)
                | Bsdf::ThinDielectric { .. } => (CoatParams::GLTF_DEFAULT, false),
            };
            textured_coat(st, mt, &mut coat, tri, u, v);
            let rough = Roughness {
                alpha_u: alpha,
                alpha_v: alpha,
                shadowing: Shadowing::Correlated,
                multiscatter,
            };
            // A solid (KHR_materials_volume) transmissive material stays
            // the dielectric; thin-walled transmission rides in the coat.
            if matches!(bsdf, Bsdf::Dielectric { .. }) {
                Bsdf::Dielectric {
                    eta: mt.mr_factor[3],
                    roughness: rough,
                    tint: crate::bsdf::Tint::NONE,
                }
            } else {
                // Always the blend (the GPU's KIND_METALLIC: one kernel
                // path whatever the texel); metallic 0 and 1 are its ends.
                Bsdf::Metallic {
                    metallic,
                    base,
                    conductor: conductor_from_f0(base, rough),
                    coat,
                }
            }
        }
        MAP_EXTRAS => match *bsdf {
            Bsdf::Diffuse { reflectance } => Bsdf::Diffuse {
                reflectance: reflectance * base_tex,
            },
            Bsdf::Conductor(mut c) => {
                c.specular_reflectance *= base_tex;
                Bsdf::Conductor(c)
            }
            // A plastic's diffuse_reflectance is a diffuse reflectance.
            Bsdf::Plastic(mut p) => {
                p.diffuse *= base_tex;
                Bsdf::Plastic(p)
            }
            Bsdf::RoughPlastic(mut p) => {
                p.plastic.diffuse *= base_tex;
                Bsdf::RoughPlastic(p)
            }
            other => other,
        },
        _ => *bsdf,
    }
}

/// The coat's textured parameters (glTF MAP_GLTF): transmissionTexture.R,
/// clearcoatTexture.R, clearcoatRoughnessTexture.G, specularTexture.A and
/// specularColorTexture (sRGB) times their factors. Only the parameters
/// with a texture are replaced, so an untextured one keeps the loader's
/// value to the bit. The specular scale is clamped to 1 per channel, as
/// the loader clamps the factors (energy conservation).
pub fn textured_coat(
    st: &SceneTextures,
    mt: &MaterialTextures,
    coat: &mut CoatParams,
    tri: u32,
    u: f32,
    v: f32,
) {
    if mt.transmission.is_some() {
        coat.transmission = mt.mr_factor[2] * st.lookup(&mt.transmission, tri, u, v, false).x;
    }
    if mt.clearcoat.is_some() {
        coat.clearcoat = mt.coat_factor[0] * st.lookup(&mt.clearcoat, tri, u, v, false).x;
    }
    if mt.clearcoat_roughness.is_some() {
        let r = mt.coat_factor[1] * st.lookup(&mt.clearcoat_roughness, tri, u, v, false).y;
        coat.clearcoat_alpha = r * r;
    }
    if mt.specular.is_some() || mt.specular_color.is_some() {
        let mut factor = mt.coat_factor[2];
        if mt.specular.is_some() {
            factor *= st.lookup(&mt.specular, tri, u, v, false).w;
        }
        let mut color = Vec3::from_slice(&mt.specular_color_factor[..3]);
        if mt.specular_color.is_some() {
            color *= st.lookup(&mt.specular_color, tri, u, v, true).truncate();
        }
        coat.specular = (factor * color).min(Vec3::ONE);
    }
}

/// The shading normal after `mt`'s normal map, in the frame (ns, s, t)
/// of the hit (s the tangent, t = cross(ns, s)), seen from `wo`; `ns`
/// itself when there is no normal map or the result would face away from
/// `ng`. The mapped normal is then adapted ([`valid_reflection_normal`])
/// so that the mirror direction of `wo` about it stays above the
/// geometric surface: a glossy lobe about a strongly tilted normal would
/// otherwise point into the surface (black rims on every bump). What a
/// wider lobe still sends below, the integrator folds back up
/// ([`crate::bsdf::fold`]).
#[allow(clippy::too_many_arguments)]
pub fn normal_mapped(
    st: &SceneTextures,
    mt: &MaterialTextures,
    tri: u32,
    u: f32,
    v: f32,
    ng: Vec3,
    wo: Vec3,
    frame: &Frame,
) -> Vec3 {
    if !mt.normal.is_some() {
        return frame.n;
    }
    let n = mapped_normal(st, &mt.normal, tri, u, v, frame);
    if n.dot(ng) > 0.0 {
        valid_reflection_normal(ng, wo, n)
    } else {
        frame.n
    }
}

/// The tangent-space normal map `r` applied to `frame` (its bitangent
/// signed by the triangle's handedness).
fn mapped_normal(st: &SceneTextures, r: &TexRef, tri: u32, u: f32, v: f32, frame: &Frame) -> Vec3 {
    let c = st.lookup(r, tri, u, v, false).truncate();
    let sign = st.uvs[tri as usize].extra[0];
    perturb_normal(c, r.scale, frame.n, frame.s, frame.t * sign)
}

/// The clear coat's normal at a hit, in the shading frame `frame` (after
/// the base's normal map), as [`crate::bsdf::coated::CoatParams`] carries
/// it: glTF's `clearcoatNormalTexture` applied to the unmapped frame
/// `unmapped`, or without one the unmapped normal itself (glTF: the base's
/// normal map does not tilt the coat). ZERO (the shading normal) when
/// nothing tilts it, or when the coat's normal would face away from `ng`
/// or lie below the shading surface. On the grid of
/// [`crate::bsdf::clearcoat::decode_coat_normal`], as the GPU record holds it.
#[allow(clippy::too_many_arguments)]
pub fn clearcoat_normal(
    st: &SceneTextures,
    mt: &MaterialTextures,
    tri: u32,
    u: f32,
    v: f32,
    ng: Vec3,
    unmapped: &Frame,
    frame: &Frame,
) -> Vec2 {
    use crate::bsdf::clearcoat::{decode_coat_normal, encode_coat_normal};
    let n = if mt.clearcoat_normal.is_some() {
        mapped_normal(st, &mt.clearcoat_normal, tri, u, v, unmapped)
    } else {
        unmapped.n
    };
    let local = frame.to_local(n);
    if n.dot(ng) <= 0.0 || local.z <= 0.0 || n == frame.n {
        return Vec2::ZERO;
    }
    decode_coat_normal(encode_coat_normal(local.truncate()))
}

/// Cycles' `ensure_valid_specular_reflection` (Blender's
/// `kernel/closure/bsdf_util.h`): the shading normal `n` (on `ng`'s side)
/// turned toward the geometric normal `ng` just enough that the mirror
/// direction of `wo` about it rises at least min(0.9 cos_o, 0.01) above
/// the geometric surface (cos_o = |wo . ng|); `n` itself when it already
/// does. Worked on `wo`'s side of the surface, so a hit from behind
/// (transmission) is adapted the same way. Both unit vectors.
pub fn valid_reflection_normal(ng: Vec3, wo: Vec3, n: Vec3) -> Vec3 {
    let side = if wo.dot(ng) < 0.0 { -1.0 } else { 1.0 };
    let (ng, n) = (ng * side, n * side);
    let iz = wo.dot(ng);
    let r = 2.0 * n.dot(wo) * n - wo;
    let threshold = (0.9 * iz).min(0.01);
    if r.dot(ng) >= threshold {
        return n * side;
    }
    // Frame: ng as z, n in the x-z plane. The adapted n' = (nx, 0, nz)
    // solves 2 (n' . wo) n'.z - wo.z = threshold, a quadratic in nz^2 of
    // which one root is the valid one (Cycles' derivation).
    let x = (n - n.dot(ng) * ng).normalize_or_zero();
    let ix = wo.dot(x);
    let a = ix * ix + iz * iz;
    if a.is_nan() || a <= 0.0 || x == Vec3::ZERO {
        return ng * side;
    }
    let b = 2.0 * (a + iz * threshold);
    let c = (threshold + iz) * (threshold + iz);
    let disc = (b * b - 4.0 * a * c).max(0.0).sqrt();
    let nz2 = if ix < 0.0 {
        0.25 * (b + disc) / a
    } else {
        0.25 * (b - disc) / a
    };
    let nx = (1.0 - nz2).max(0.0).sqrt();
    let nz = nz2.max(0.0).sqrt();
    (nx * x + nz * ng).normalize_or_zero() * side
}

/// The emissive texture's factor at a hit (1 without one).
pub fn emission_factor(st: &SceneTextures, material: u32, tri: u32, u: f32, v: f32) -> Vec3 {
    match st.material(material) {
        Some(mt) if mt.emissive.is_some() => st.lookup(&mt.emissive, tri, u, v, true).truncate(),
        _ => Vec3::ONE,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wraps() {
        assert_eq!(wrap_texel(-1, 4, WRAP_REPEAT), 3);
        assert_eq!(wrap_texel(4, 4, WRAP_REPEAT), 0);
        assert_eq!(wrap_texel(-1, 4, WRAP_CLAMP), 0);
        assert_eq!(wrap_texel(9, 4, WRAP_CLAMP), 3);
        assert_eq!(wrap_texel(4, 4, WRAP_MIRROR), 3);
        assert_eq!(wrap_texel(-1, 4, WRAP_MIRROR), 0);
        assert_eq!(wrap_texel(8, 4, WRAP_MIRROR), 0);
    }

    #[test]
    fn wrap_texel_is_each_mode_s_rule() {
        for n in [1i32, 2, 3, 7] {
            for i in -3 * n..3 * n {
                let mirror = {
                    let k = i.rem_euclid(2 * n);
                    if k >= n { 2 * n - 1 - k } else { k }
                };
                assert_eq!(wrap_texel(i, n, WRAP_CLAMP), i.clamp(0, n - 1));
                assert_eq!(wrap_texel(i, n, WRAP_MIRROR), mirror, "{i} {n}");
                assert_eq!(wrap_texel(i, n, WRAP_REPEAT), i.rem_euclid(n));
            }
        }
    }

    #[test]
    fn srgb_table_is_the_function_bit_for_bit() {
        for b in 0..256u32 {
            let c = unpack_texel(b | b << 8 | b << 16);
            let want = srgb_to_linear(c.x);
            assert_eq!(
                SRGB_TO_LINEAR_8[b as usize].to_bits(),
                want.to_bits(),
                "{b}"
            );
            let got = texture_fetch(
                &[b | b << 8 | b << 16],
                &GpuTexture {
                    width: 1,
                    height: 1,
                    ..Default::default()
                },
                0,
                0,
                true,
            );
            assert_eq!(got.x.to_bits(), want.to_bits(), "{b}");
        }
    }

    #[test]
    fn srgb_128_is_0_2158() {
        assert!((srgb_to_linear(128.0 / 255.0) - 0.2158605).abs() < 1e-5);
    }
}
