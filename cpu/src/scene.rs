//! The scene model shared by both backends.
//!
//! Geometry is flattened to world-space triangles at load time. The
//! `#[repr(C)]` records uploaded to the GPU unchanged ([`Triangle`],
//! [`GpuMaterial`]) are declared in [`crate::abi`], which generates their
//! GLSL; their methods are here.

use glam::{Mat4, Vec3};

use std::mem::size_of;

use bytemuck::{Pod, Zeroable};

use crate::abi;
use crate::bsdf::clearcoat::encode_coat_normal;
use crate::bsdf::{Bsdf, ConductorParams, Shadowing};
use crate::bvh::Bvh4;

pub use crate::abi::{
    GpuMaterial, NO_LIGHT, TRI_DOUBLE_SIDED, TRI_NORMALS, TRI_SHADING_SHIFT, TRI_TANGENTS, Triangle,
};

impl Triangle {
    pub fn vertices(&self) -> [Vec3; 3] {
        [self.p0.into(), self.p1.into(), self.p2.into()]
    }
    /// Unnormalised geometric normal (p1 - p0) x (p2 - p0): counter-clockwise
    /// winding faces the viewer, so it points to a dielectric's outside.
    pub fn geometric_normal(&self) -> Vec3 {
        let [a, b, c] = self.vertices();
        (b - a).cross(c - a)
    }
    pub fn area(&self) -> f32 {
        0.5 * self.geometric_normal().length()
    }
}

/// One triangle's shading data as the loader makes it and
/// [`Scene::shading_of`] gives it back. `.w` of each normal is 1 when the
/// mesh had NORMAL (0: use the geometric normal); `.w` of each tangent is
/// 1 when a tangent is known (TANGENT, or dP/du from TEXCOORD_0), else 0
/// and the frame is built from the normal. The scene stores only what is
/// known ([`Scene::set_shading`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TriangleShading {
    pub n: [[f32; 4]; 3],
    pub t: [[f32; 4]; 3],
}
const _: () = assert!(size_of::<TriangleShading>() == 96);

/// A glTF material as glint renders it.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    pub bsdf: Bsdf,
    /// Emitted radiance (emissiveFactor x KHR_materials_emissive_strength).
    pub emission: Vec3,
    /// glTF `doubleSided`: emission leaves both faces.
    pub double_sided: bool,
    /// Beer-Lambert absorption coefficient sigma_a (rgb, per scene unit) of
    /// the interior a closed mesh of this material bounds
    /// (`KHR_materials_volume`: -ln(attenuationColor) / attenuationDistance);
    /// read with the solid `Dielectric` BSDF only. A path segment that
    /// reaches a surface of the material from its back face (it travelled
    /// inside) is weighted by exp(-sigma_a t).
    pub absorption: Vec3,
}

impl Material {
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }
}

/// The non-metal's coat as the record's `coat` (specular scale, IOR) and
/// `extra` (transmission, clear coat weight, alpha and encoded normal).
fn coat_record(coat: &crate::bsdf::coated::CoatParams) -> ([f32; 4], [f32; 4]) {
    (
        vec4(coat.specular, coat.eta),
        [
            coat.transmission,
            coat.clearcoat,
            coat.clearcoat_alpha,
            encode_coat_normal(coat.clearcoat_normal),
        ],
    )
}

/// `GpuMaterial::shadowing`: bit 0 separable, bit 1 multiscatter.
fn shadowing_bits(r: &crate::bsdf::Roughness) -> u32 {
    (r.shadowing == Shadowing::Separable) as u32 | (r.multiscatter as u32) << 1
}

fn vec4(v: Vec3, w: f32) -> [f32; 4] {
    [v.x, v.y, v.z, w]
}

impl From<&Material> for GpuMaterial {
    fn from(m: &Material) -> Self {
        let mut g = GpuMaterial {
            emission: vec4(m.emission, if m.double_sided { 1.0 } else { 0.0 }),
            ..Default::default()
        };
        let conductor = |g: &mut GpuMaterial, c: &ConductorParams| {
            // With `multiscatter`, the .w's carry the Kulla-Conty lobe's
            // average Fresnel term F_avg (rgb), computed once here.
            let f_avg = if c.roughness.multiscatter {
                crate::bsdf::multiscatter::fresnel_conductor_avg(c.eta, c.k)
            } else {
                Vec3::ZERO
            };
            g.eta = vec4(c.eta, f_avg.x);
            g.k = vec4(c.k, f_avg.y);
            g.specular = vec4(c.specular_reflectance, f_avg.z);
            g.alpha_u = c.roughness.alpha_u;
            g.alpha_v = c.roughness.alpha_v;
            g.shadowing = shadowing_bits(&c.roughness);
        };
        match &m.bsdf {
            Bsdf::Diffuse { reflectance } => {
                g.kind = abi::KIND_DIFFUSE;
                g.reflectance = vec4(*reflectance, 0.0);
            }
            Bsdf::Conductor(c) => {
                g.kind = abi::KIND_CONDUCTOR;
                conductor(&mut g, c);
            }
            Bsdf::Dielectric {
                eta,
                roughness,
                tint,
            } => {
                g.kind = abi::KIND_DIELECTRIC;
                g.eta = [*eta, 0.0, 0.0, 0.0];
                // Mitsuba's specular_reflectance and _transmittance.
                g.specular = vec4(tint.reflect, 0.0);
                g.reflectance = vec4(tint.transmit, 0.0);
                // k is the interior's absorption sigma_a for a dielectric.
                g.k = vec4(m.absorption, 0.0);
                g.alpha_u = roughness.alpha_u;
                g.alpha_v = roughness.alpha_v;
                g.shadowing = shadowing_bits(roughness);
            }
            Bsdf::Plastic(p) => {
                // .w of reflectance: nonlinear. F_dr and the sampling weight
                // are computed per hit (a texture changes the diffuse part).
                g.kind = abi::KIND_PLASTIC;
                g.reflectance = vec4(p.diffuse, if p.nonlinear { 1.0 } else { 0.0 });
                g.specular = vec4(p.specular, 0.0);
                g.eta = [p.eta, 0.0, 0.0, 0.0];
            }
            Bsdf::RoughPlastic(rp) => {
                let p = &rp.plastic;
                g.kind = abi::KIND_ROUGH_PLASTIC;
                g.reflectance = vec4(p.diffuse, if p.nonlinear { 1.0 } else { 0.0 });
                g.specular = vec4(p.specular, 0.0);
                g.eta = [p.eta, 0.0, 0.0, 0.0];
                g.alpha_u = rp.roughness.alpha_u;
                g.alpha_v = rp.roughness.alpha_v;
                g.shadowing = shadowing_bits(&rp.roughness);
            }
            Bsdf::ThinDielectric { eta, tint } => {
                g.kind = abi::KIND_THIN_DIELECTRIC;
                g.eta = [*eta, 0.0, 0.0, 0.0];
                g.specular = vec4(tint.reflect, 0.0);
                g.k = vec4(tint.transmit, 0.0);
            }
            Bsdf::Coated {
                base,
                coat,
                roughness,
            } => {
                g.kind = abi::KIND_COATED;
                g.reflectance = vec4(*base, 0.0);
                (g.coat, g.extra) = coat_record(coat);
                g.alpha_u = roughness.alpha_u;
                g.alpha_v = roughness.alpha_v;
                g.shadowing = shadowing_bits(roughness);
            }
            Bsdf::Metallic {
                metallic,
                base,
                conductor: c,
                coat,
            } => {
                g.kind = abi::KIND_METALLIC;
                g.reflectance = vec4(*base, *metallic);
                (g.coat, g.extra) = coat_record(coat);
                conductor(&mut g, c);
            }
        }
        g
    }
}

/// KHR_lights_punctual, in the file's own units (no photometric conversion).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PunctualLight {
    /// `intensity`: radiant intensity per steradian (color x intensity).
    Point { position: Vec3, intensity: Vec3 },
    /// Cone falloff as the KHR_lights_punctual spec writes it: t = saturate of
    /// a linear ramp in cos(angle) from the outer (0) to the inner cone (1),
    /// attenuation t^2.
    Spot {
        position: Vec3,
        /// Unit direction the light points to (the node's -Z).
        direction: Vec3,
        intensity: Vec3,
        inner_cone_angle: f32,
        outer_cone_angle: f32,
    },
    /// `irradiance` on a surface facing the light; `direction` is the unit
    /// direction the light travels (the node's -Z).
    Directional { direction: Vec3, irradiance: Vec3 },
}

/// A perspective camera: `to_world` maps camera space (looking down -Z, +Y
/// up) to world space, without scale.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub name: Option<String>,
    /// The name of the node the camera hangs off (`--camera` matches
    /// either: exporters name the node, the camera object or both).
    pub node_name: Option<String>,
    pub to_world: Mat4,
    /// Vertical field of view in radians.
    pub yfov: f32,
    /// The file's aspect ratio (width / height), if it gave one.
    pub aspect_ratio: Option<f32>,
}

/// A loaded scene. Triangles and their shading data are in BVH leaf order
/// once [`Scene::build_bvh`] has run.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    pub triangles: Vec<Triangle>,
    /// Shading normals and tangents of the triangles that have them, packed
    /// (`Triangle::flags` says which and where; [`Scene::set_shading`]):
    /// a mesh without NORMAL, TANGENT or texture coordinates costs nothing
    /// here. The GPU's binding 3 unchanged.
    pub shading: Vec<[f32; 4]>,
    pub materials: Vec<Material>,
    pub lights: Vec<PunctualLight>,
    /// Cameras of the default scene, in depth-first node order.
    pub cameras: Vec<Camera>,
    /// `scene.extras.background`: constant radiance (default black).
    pub background: Vec3,
    /// The 4-wide BVH both backends traverse (`Bvh4::nodes` is the GPU's
    /// binding 2 unchanged).
    pub bvh: Bvh4,
    /// What the loader skipped or substituted, one line each (without the
    /// file name): the CLI prints them as `glint: warning: FILE: ...`.
    pub warnings: Vec<String>,
    /// Texture data (empty for an untextured scene).
    pub textures: crate::texture::SceneTextures,
    /// The environment light (`--envmap`); it replaces `background`.
    pub envmap: Option<std::sync::Arc<crate::envmap::EnvMap>>,
}

impl Scene {
    /// Build the BVH and reorder triangles and shading into leaf order, so
    /// leaves address contiguous ranges of the triangle array (the layout the
    /// GPU reads unchanged); then number the emitters in that final order.
    pub fn build_bvh(&mut self) {
        let (bvh, order) = Bvh4::build(&self.triangles);
        // Triangles and their packed shading data moved into leaf order
        // together, so neighbouring leaves read neighbouring shading data.
        // (What `set_shading` of the unpacked records in leaf order would
        // store, without the 96-byte record per triangle in between.)
        let mut packed = Vec::with_capacity(self.shading.len());
        let mut triangles = Vec::with_capacity(self.triangles.len());
        for &i in &order {
            let mut t = self.triangles[i as usize];
            let kept = 3
                * ((t.flags & TRI_NORMALS != 0) as usize + (t.flags & TRI_TANGENTS != 0) as usize);
            if kept > 0 {
                let from = (t.flags >> TRI_SHADING_SHIFT) as usize;
                let to = packed.len() as u32;
                packed.extend_from_slice(&self.shading[from..from + kept]);
                t.flags = (t.flags & ((1 << TRI_SHADING_SHIFT) - 1)) | (to << TRI_SHADING_SHIFT);
            }
            triangles.push(t);
        }
        self.triangles = triangles;
        self.shading = packed;
        if !self.textures.uvs.is_empty() {
            let uvs = &self.textures.uvs;
            self.textures.uvs = order.iter().map(|&i| uvs[i as usize]).collect();
        }
        self.bvh = bvh;
        self.assign_emitters();
    }

    /// Store per-triangle shading records (one per triangle, in triangle
    /// order) packed, with each triangle's flags saying what it kept and
    /// where. Kept: normals where `n[0].w` is 1 and they are not all the
    /// geometric normal (a flat face's vertex normals: interpolating them
    /// gives the geometric normal up to rounding, which the readers use
    /// without them); tangents where `t[0].w` is 1 and the material needs
    /// an orientation about the normal (an anisotropic rough lobe, or a
    /// normal map). An isotropic BSDF is the same in any frame rotated
    /// about its normal, so without them the readers' `Frame::from_normal`
    /// renders the same image in distribution.
    pub fn set_shading(&mut self, records: &[TriangleShading]) {
        assert_eq!(records.len(), self.triangles.len());
        let needs_tangent: Vec<bool> = (0..self.materials.len())
            .map(|m| self.material_needs_tangent(m))
            .collect();
        let mut packed = Vec::new();
        for (t, r) in self.triangles.iter_mut().zip(records) {
            let offset = packed.len();
            let mut bits = 0;
            let ng = t.geometric_normal().normalize_or_zero();
            let flat = r.n.iter().all(|n| {
                let n = Vec3::from_slice(&n[..3]);
                (n - ng).abs().max_element() <= 1e-6 || (n + ng).abs().max_element() <= 1e-6
            });
            if r.n[0][3] == 1.0 && !flat {
                packed.extend_from_slice(&r.n);
                bits |= TRI_NORMALS;
            }
            let tangent = needs_tangent
                .get(t.material as usize)
                .copied()
                .unwrap_or(true);
            if r.t[0][3] == 1.0 && tangent {
                packed.extend_from_slice(&r.t);
                bits |= TRI_TANGENTS;
            }
            // At most 6 vec4s for each of at most 2^24 triangles
            // (loader::MAX_TRIANGLES): far inside the 29 bits.
            assert!(
                offset < (1 << (32 - TRI_SHADING_SHIFT)),
                "shading offset overflow"
            );
            let offset = if bits == 0 { 0 } else { offset as u32 };
            t.flags = (t.flags & TRI_DOUBLE_SIDED) | bits | (offset << TRI_SHADING_SHIFT);
        }
        self.shading = packed;
    }

    /// Whether material `m`'s shading needs a tangent: an anisotropic rough
    /// lobe, or a normal map (tangent space).
    pub fn material_needs_tangent(&self, m: usize) -> bool {
        self.material_is_anisotropic(m)
            || self
                .textures
                .materials
                .get(m)
                .is_some_and(|t| t.normal.is_some())
    }

    /// Whether material `m` has an anisotropic rough lobe (oriented by the
    /// surface tangent).
    pub fn material_is_anisotropic(&self, m: usize) -> bool {
        let aniso = |r: &crate::bsdf::Roughness| !r.is_smooth() && r.alpha_u != r.alpha_v;
        match &self.materials[m].bsdf {
            Bsdf::Diffuse { .. }
            | Bsdf::Plastic(_)
            | Bsdf::RoughPlastic(_)
            | Bsdf::ThinDielectric { .. } => false,
            Bsdf::Coated { roughness, .. } => aniso(roughness),
            Bsdf::Conductor(c) => aniso(&c.roughness),
            Bsdf::Dielectric { roughness, .. } => aniso(roughness),
            Bsdf::Metallic { conductor, .. } => aniso(&conductor.roughness),
        }
    }

    /// Triangle `tri`'s shading record: what [`Scene::set_shading`] stored,
    /// the geometric normal (`.w` 0) where it stored no normals and zero
    /// tangents where it stored none.
    pub fn shading_of(&self, tri: usize) -> TriangleShading {
        let t = &self.triangles[tri];
        let mut off = (t.flags >> TRI_SHADING_SHIFT) as usize;
        let mut r = TriangleShading::default();
        if t.flags & TRI_NORMALS != 0 {
            r.n.copy_from_slice(&self.shading[off..off + 3]);
            off += 3;
        } else {
            let geo = t.geometric_normal().normalize_or_zero();
            r.n = [geo.extend(0.0).to_array(); 3];
        }
        if t.flags & TRI_TANGENTS != 0 {
            r.t.copy_from_slice(&self.shading[off..off + 3]);
        }
        r
    }

    /// Bytes per triangle of the GPU's per-triangle buffers (triangles,
    /// shading, and texture coordinates when textured), as uploaded.
    pub fn gpu_bytes_per_triangle(&self) -> f64 {
        let n = self.triangles.len().max(1) as f64;
        let bytes = self.triangles.len() * size_of::<Triangle>()
            + self.shading.len() * 16
            + self.textures.uvs.len() * size_of::<crate::texture::TriangleUv>();
        bytes as f64 / n
    }

    /// Set `Triangle::light` to 0, 1, 2, ... for the emissive triangles of
    /// non-zero area, in triangle order, and `NO_LIGHT` elsewhere; set the
    /// double-sided flag. The emitter list is then exactly
    /// `emitter_triangles()`, the same on both backends.
    pub fn assign_emitters(&mut self) {
        let mut next = 0u32;
        for t in &mut self.triangles {
            let m = &self.materials[t.material as usize];
            t.flags =
                (t.flags & !TRI_DOUBLE_SIDED) | if m.double_sided { TRI_DOUBLE_SIDED } else { 0 };
            let area = t.area();
            if m.is_emissive() && area > 0.0 && area.is_finite() {
                t.light = next;
                next += 1;
            } else {
                t.light = NO_LIGHT;
            }
        }
    }

    /// Indices of the emissive triangles, in emitter order.
    pub fn emitter_triangles(&self) -> Vec<u32> {
        (0..self.triangles.len() as u32)
            .filter(|&i| self.triangles[i as usize].light != NO_LIGHT)
            .collect()
    }

    /// Closest hit, alpha tests (MASK, BLEND) applied when the scene has any.
    pub fn intersect(&self, ray: &crate::bvh::Ray) -> Option<crate::bvh::Hit> {
        self.intersect_with(ray, self.textures.has_masks())
    }

    /// Any hit, alpha masks applied when the scene has any.
    pub fn occluded(&self, ray: &crate::bvh::Ray) -> bool {
        self.occluded_with(ray, self.textures.has_masks())
    }

    /// [`Scene::intersect`] with the scene's `has_masks()` answered by the
    /// caller, once per render rather than once per ray.
    pub fn intersect_with(&self, ray: &crate::bvh::Ray, masks: bool) -> Option<crate::bvh::Hit> {
        if masks {
            self.bvh
                .intersect_masked(&self.triangles, ray, |i, u, v| self.present(i, u, v, ray))
        } else {
            self.bvh.intersect(&self.triangles, ray)
        }
    }

    /// [`Scene::intersect_with`] of the rays in `live` (bit k: `rays[k]`),
    /// into `hits` (which starts all None; the other lanes stay so), in
    /// one packet traversal where they are alike
    /// ([`crate::bvh::Bvh4::intersect_packet`]); alpha-masked scenes trace
    /// them one at a time. (Written in place: the array returned was
    /// copied twice on its way.)
    #[inline]
    pub fn intersect_packet(
        &self,
        rays: &[crate::bvh::Ray; crate::bvh::PACKET],
        live: u8,
        masks: bool,
        hits: &mut [Option<crate::bvh::Hit>; crate::bvh::PACKET],
    ) {
        if masks {
            for k in crate::lanes::live_lanes(live) {
                hits[k] = self.intersect_with(&rays[k], true);
            }
            return;
        }
        self.bvh.intersect_packet(&self.triangles, rays, live, hits)
    }

    /// [`Scene::occluded`] with `has_masks()` answered by the caller.
    pub fn occluded_with(&self, ray: &crate::bvh::Ray, masks: bool) -> bool {
        if masks {
            self.bvh
                .occluded_masked(&self.triangles, ray, |i, u, v| self.present(i, u, v, ray))
        } else {
            self.bvh.occluded(&self.triangles, ray)
        }
    }

    /// The alpha test of triangle `tri` at barycentrics (u, v) for `ray`.
    fn present(&self, tri: u32, u: f32, v: f32, ray: &crate::bvh::Ray) -> bool {
        let m = self.triangles[tri as usize].material;
        self.textures.alpha_pass(m, tri, u, v, ray.o, ray.d)
    }

    /// Whether anything lights the scene by the contract's default-lighting
    /// rule ("Second additions"): a punctual light, a non-black background
    /// or an emitter of constant emission (an emissive material without
    /// `emissiveTexture`: a lamp, a light panel). Textured emission (a
    /// screen, a label, a helmet's glow map) still emits but does not count:
    /// a file lit only by it renders nearly black in every viewer's sense.
    pub fn has_light(&self) -> bool {
        self.background.max_element() > 0.0
            || self.envmap.is_some()
            || !self.lights.is_empty()
            || self
                .triangles
                .iter()
                .any(|t| t.light != NO_LIGHT && !self.textures.has_emissive_texture(t.material))
    }

    /// The number of emissive triangles whose emission is textured.
    pub fn textured_emitters(&self) -> usize {
        self.triangles
            .iter()
            .filter(|t| t.light != NO_LIGHT && self.textures.has_emissive_texture(t.material))
            .count()
    }

    /// The contract's default-lighting rule: a scene with no punctual
    /// light, no background and no emitter of constant emission is lit by a
    /// constant white background of radiance 1, with a warning that says
    /// which rule applied. Returns whether it applied.
    pub fn light_if_unlit(&mut self) -> bool {
        if self.has_light() {
            return false;
        }
        self.background = Vec3::ONE;
        let textured = self.textured_emitters();
        let why = if textured > 0 {
            format!(
                "the scene's only emitters ({textured} triangles) have textured emission \
                 (emissiveTexture), which does not count as lighting, and it has no punctual \
                 light or background"
            )
        } else {
            "the scene has no light (no emitter, punctual light or background)".to_string()
        };
        self.warnings.push(format!(
            "{why}; lit by a constant white background of radiance 1 (--background 0,0,0 keeps it dark)"
        ));
        true
    }

    /// World-space bounds of all geometry (min, max); (0, 0) for an empty scene.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for t in &self.triangles {
            for p in t.vertices() {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        if lo.x > hi.x {
            (Vec3::ZERO, Vec3::ZERO)
        } else {
            (lo, hi)
        }
    }
}
