//! What the GPU path tracer reads besides the scene's own arrays: the
//! `Params` uniform (binding 0 of `shaders/bindings.glsl`), the emitter
//! table (binding 5) and the punctual lights (binding 6).

use std::mem::{offset_of, size_of};

use bytemuck::{Pod, Zeroable};

use super::{PathTracer, RenderError};
use crate::film::RenderOptions;
use crate::lights::{GpuEmitter, GpuLight};
use crate::scene::{GpuMaterial, Scene};
use crate::texture::{GpuTexture, MaterialTextures, TriangleUv};

/// Mirror of `uniform Params` in `shaders/bindings.glsl` (std140: the
/// `vec4`s first, then scalars in groups of four, so std140 and C agree).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuParams {
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
    /// `Mis::code`: 0 power, 1 balance, 2 none.
    pub mis: u32,
    /// `SamplerKind::code`.
    pub sampler: u32,
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
    pub env_pad: [u32; 2],
}
const _: () = assert!(size_of::<GpuParams>() == 176);
const _: () = assert!(offset_of!(GpuParams, textured) == 144);
const _: () = assert!(offset_of!(GpuParams, env_rot_sin) == 160);
const _: () = assert!(offset_of!(GpuParams, background) == 64);
const _: () = assert!(offset_of!(GpuParams, width) == 80);
const _: () = assert!(offset_of!(GpuParams, seed_key) == 96);
const _: () = assert!(offset_of!(GpuParams, light_count) == 112);
const _: () = assert!(offset_of!(GpuParams, p_area) == 128);

/// Everything `gpu_scene_data` prepares for the host to upload.
#[derive(Clone, Debug)]
pub struct GpuSceneData {
    pub params: GpuParams,
    /// Binding 4. Never empty (a zeroed entry pads an empty list: Vulkan
    /// buffers cannot be empty); the real count is `Scene::materials.len()`.
    pub materials: Vec<GpuMaterial>,
    /// Binding 5, `params.emitter_count` real entries, padded to >= 1.
    pub emitters: Vec<GpuEmitter>,
    /// Binding 6, `params.light_count` real entries, padded to >= 1.
    pub lights: Vec<GpuLight>,
    /// Bindings 9-12 (`SceneTextures`), each padded to >= 1.
    pub texels: Vec<u32>,
    pub textures: Vec<GpuTexture>,
    pub material_textures: Vec<MaterialTextures>,
    pub uvs: Vec<TriangleUv>,
    /// Bindings 13-14 (`EnvMap` texels; marginal then conditional
    /// distribution), each padded to >= 1.
    pub env_texels: Vec<[f32; 4]>,
    pub env_dist: Vec<f32>,
}

fn v4(v: glam::Vec3) -> [f32; 4] {
    [v.x, v.y, v.z, 0.0]
}

fn padded<T: Default + Clone>(mut v: Vec<T>) -> Vec<T> {
    if v.is_empty() {
        v.push(T::default());
    }
    v
}

/// The uniform parameters and the light tables for a GPU render of
/// `scene` with `opts`, exactly as the CPU path tracer sets itself up.
pub fn gpu_scene_data(scene: &Scene, opts: &RenderOptions) -> Result<GpuSceneData, RenderError> {
    let pt = PathTracer::new(scene, opts)?;
    let c = &pt.camera;
    let params = GpuParams {
        cam_origin: v4(c.origin),
        cam_right: v4(c.right),
        cam_up: v4(c.up),
        cam_forward: v4(c.forward),
        background: v4(pt.lights.background),
        width: opts.width,
        height: opts.height,
        spp: opts.spp,
        max_depth: pt.max_depth,
        seed_key: pt.key,
        triangle_count: scene.triangles.len() as u32,
        bvh_node_count: scene.bvh.nodes.len() as u32,
        emitter_count: pt.lights.emitters.len() as u32,
        light_count: pt.lights.punctual.len() as u32,
        nee: opts.nee as u32,
        mis: opts.mis.code(),
        sampler: opts.sampler.code(),
        p_area: pt.lights.probs.area,
        p_punctual: pt.lights.probs.punctual,
        p_background: pt.lights.probs.background,
        variance_batch: pt.batch,
        textured: !scene.textures.is_empty() as u32,
        masked: scene.textures.has_masks() as u32,
        env_width: scene.envmap.as_ref().map_or(0, |e| e.width),
        env_height: scene.envmap.as_ref().map_or(0, |e| e.height),
        env_rot_sin: scene.envmap.as_ref().map_or(0.0, |e| e.rotation.sin()),
        env_rot_cos: scene.envmap.as_ref().map_or(1.0, |e| e.rotation.cos()),
        env_pad: [0; 2],
    };
    Ok(GpuSceneData {
        params,
        materials: padded(scene.materials.iter().map(GpuMaterial::from).collect()),
        emitters: padded(pt.lights.emitters.clone()),
        lights: padded(pt.lights.punctual.clone()),
        texels: padded(scene.textures.texels.clone()),
        textures: padded(scene.textures.table.clone()),
        material_textures: padded(scene.textures.materials.clone()),
        uvs: padded(scene.textures.uvs.clone()),
        env_texels: padded(
            scene
                .envmap
                .as_ref()
                .map_or(Vec::new(), |e| e.texels.clone()),
        ),
        env_dist: padded(scene.envmap.as_ref().map_or(Vec::new(), |e| {
            [e.marginal.clone(), e.conditional.clone()].concat()
        })),
    })
}
