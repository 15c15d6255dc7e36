//! What the GPU path tracer reads besides the scene's own arrays: the
//! `Params` uniform (binding 0 of `abi::PATH_TRACER_BINDINGS`), the emitter
//! table (binding 5) and the punctual lights (binding 6).

use super::{RenderError, depth_limit, validate_options};
use crate::camera::{PinholeCamera, scene_camera};
use crate::film::{LightSampling, RenderOptions};
use crate::lights::Lights;
use crate::lights::{GpuEmitter, GpuLight};
use crate::sampling::seed_key;
use crate::scene::{GpuMaterial, Scene};
use crate::texture::{GpuTexture, MaterialTextures, TriangleUv};

pub use crate::abi::GpuParams;

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
/// `scene` with `opts`, from the constructors the CPU path tracer sets
/// itself up with (the camera, the light distributions, the seed key).
pub fn gpu_scene_data(scene: &Scene, opts: &RenderOptions) -> Result<GpuSceneData, RenderError> {
    validate_options(scene, opts)?;
    let c = &PinholeCamera::new(&scene_camera(scene, opts.camera), opts.width, opts.height);
    let lights = Lights::new(scene);
    let params = GpuParams {
        cam_origin: v4(c.origin),
        cam_right: v4(c.right),
        cam_up: v4(c.up),
        cam_forward: v4(c.forward),
        background: v4(lights.background),
        width: opts.width,
        height: opts.height,
        spp: opts.spp,
        max_depth: depth_limit(opts.max_depth),
        seed_key: seed_key(opts.seed),
        triangle_count: scene.triangles.len() as u32,
        bvh_node_count: scene.bvh.nodes.len() as u32,
        emitter_count: lights.emitters.len() as u32,
        light_count: lights.punctual.len() as u32,
        nee: opts.nee as u32,
        mis: opts.mis.code(),
        sampler: opts.sampler.code(),
        p_area: lights.probs.area,
        p_punctual: lights.probs.punctual,
        p_background: lights.probs.background,
        variance_batch: opts.batch(),
        textured: !scene.textures.is_empty() as u32,
        masked: scene.textures.has_masks() as u32,
        env_width: scene.envmap.as_ref().map_or(0, |e| e.width),
        env_height: scene.envmap.as_ref().map_or(0, |e| e.height),
        env_rot_sin: scene.envmap.as_ref().map_or(0.0, |e| e.rotation.sin()),
        env_rot_cos: scene.envmap.as_ref().map_or(1.0, |e| e.rotation.cos()),
        solid_angle: (opts.light_sampling == LightSampling::SolidAngle) as u32,
        env_pad: 0,
    };
    Ok(GpuSceneData {
        params,
        materials: padded(scene.materials.iter().map(GpuMaterial::from).collect()),
        emitters: padded(lights.emitters.clone()),
        lights: padded(lights.punctual.clone()),
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
