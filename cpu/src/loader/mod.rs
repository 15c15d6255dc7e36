//! glTF 2.0 loading into [`crate::Scene`].
//!
//! [`parse`] reads a `.gltf` (external or data-URI buffers) or `.glb` file
//! and flattens its default scene to world-space triangles, materials,
//! cameras and punctual lights; [`load`] then builds the BVH. Every problem
//! with the input is one [`LoadError`] naming the file; nothing here panics
//! on bad input or allocates more than the file's own bytes justify.
//!
//! Choices where glTF or the contract leave room (also in README.md):
//! - The scene rendered is `scene`, else scene 0; a file with no scene at
//!   all is an error (there is nothing to render).
//! - Triangles come from modes 4 (triangles, the default), 5 (strips) and
//!   6 (fans); points and lines are skipped with a warning. Skins and morph
//!   targets are ignored (the rest pose is rendered), with a warning.
//! - What glint skips or substitutes is a warning in `Scene::warnings`
//!   (the CLI prints them, `--strict` makes them errors): points and lines,
//!   skins, morph targets, extensions used but not supported.
//! - Buffer and image URIs must stay inside the scene's folder (no absolute
//!   paths, no `..` leaving it; `file:` URIs alike) unless
//!   [`LoadOptions::allow_any_path`].
//! - A primitive without a material gets the glTF default material (spec
//!   3.9.6: baseColor 1, metallic 1, roughness 1), i.e. a GGX conductor with
//!   F0 = 0.999 and alpha 1, appended after the file's materials.
//! - Textures (`loader::texture`, conventions in [`crate::texture`]):
//!   baseColor, metallicRoughness, normal and emissive, PNG or JPEG; an
//!   image that cannot be used is a warning and its factor alone is used.
//!   alphaMode MASK cuts geometry; BLEND is stochastic transparency (a hit
//!   is kept with probability alpha).
//! - Cameras are listed in depth-first node order; orthographic cameras are
//!   an error. Without a camera, [`default_camera`] frames the scene.
//! - KHR_lights_punctual `range` is ignored (lights fall off as 1/r^2).
//! - Limits: 2 GiB per file, 2^24 triangles per scene.

mod accessor;
mod graph;
mod material;
mod source;
mod texture;

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::{Mat4, Vec3};
use serde_json::Value;

pub use graph::{MAX_TRIANGLES, dpdu};
pub use material::{
    DEFAULT_ALPHA, DEFAULT_EXT_IOR, DEFAULT_INT_IOR, DEFAULT_REFLECTANCE, bsdf_from_extras,
    conductor_from_f0, gltf_default_material,
};
pub use source::{
    LoadOptions, MAX_FILE_BYTES, SUPPORTED_EXTENSIONS, SUPPORTED_REQUIRED_EXTENSIONS,
};

use crate::bvh::Bvh4;
use crate::scene::{Camera, Scene};

/// One clear error naming the file and the problem.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    #[error("{path}: {message}")]
    Invalid { path: PathBuf, message: String },
}

/// Load the default scene of a .gltf/.glb file, flatten it to world-space
/// triangles and build the BVH.
pub fn load(path: &Path) -> Result<Scene, LoadError> {
    load_with(path, LoadOptions::default())
}

/// [`load`] with explicit [`LoadOptions`].
pub fn load_with(path: &Path, options: LoadOptions) -> Result<Scene, LoadError> {
    let mut scene = parse_with(path, options)?;
    scene.build_bvh();
    Ok(scene)
}

/// [`load`] without the BVH: the scene's triangles in traversal order,
/// emitters numbered ([`Scene::assign_emitters`]) and `bvh` empty.
pub fn parse(path: &Path) -> Result<Scene, LoadError> {
    parse_with(path, LoadOptions::default())
}

/// [`parse`] with explicit [`LoadOptions`].
pub fn parse_with(path: &Path, options: LoadOptions) -> Result<Scene, LoadError> {
    parse_inner(path, options)
        .map(|(scene, _)| scene)
        .map_err(|message| LoadError::Invalid {
            path: path.to_path_buf(),
            message,
        })
}

/// [`load_with`], and the real paths of the files the scene's URIs named
/// (external buffers and images, each once): what an output must not
/// overwrite.
pub fn load_with_inputs(
    path: &Path,
    options: LoadOptions,
) -> Result<(Scene, Vec<PathBuf>), LoadError> {
    let (mut scene, inputs) = parse_inner(path, options).map_err(|message| LoadError::Invalid {
        path: path.to_path_buf(),
        message,
    })?;
    scene.build_bvh();
    Ok((scene, inputs))
}

/// [`load`] and the seconds it took (file reading and parsing, BVH build).
pub fn load_timed(path: &Path) -> Result<(Scene, f64), LoadError> {
    let start = Instant::now();
    let scene = load(path)?;
    Ok((scene, start.elapsed().as_secs_f64()))
}

fn parse_inner(path: &Path, options: LoadOptions) -> Result<(Scene, Vec<PathBuf>), String> {
    let mut warnings = Vec::new();
    let src = source::read(path, options, &mut warnings)?;
    accept_quiet_extensions(&mut warnings);
    let doc = &src.doc;
    let scene_index = match doc.default_scene() {
        Some(s) => s.index(),
        None if doc.scenes().len() > 0 => 0,
        None => return Err("the file has no scene to render".into()),
    };
    let mut materials = doc
        .materials()
        .map(|m| {
            let raw = &src.raw["materials"][m.index().unwrap_or(0)];
            material::convert(&m, raw, options.multiscatter, &mut warnings)
        })
        .collect::<Result<Vec<_>, _>>()?;
    let default_material = materials.len() as u32;
    // The default material is appended (and untextured) if used.
    let mut with_default = materials.clone();
    with_default.push(material::gltf_default_material());
    let textures = texture::collect(&src, &with_default, &mut warnings)?;
    let want_uvs = !textures.is_empty();
    let collected = graph::collect(&src, scene_index, default_material, want_uvs, &mut warnings)?;
    let mut textures = textures;
    if collected.uses_default_material {
        materials.push(material::gltf_default_material());
    } else if !textures.materials.is_empty() {
        textures.materials.truncate(materials.len());
    }
    if want_uvs {
        textures.uvs = collected.uvs;
    }
    let scene_json = &doc.as_json().scenes[scene_index];
    let background = background(scene_json.extras.as_deref())
        .map_err(|e| format!("scene {scene_index}: extras.background: {e}"))?;
    let mut scene = Scene {
        triangles: collected.triangles,
        shading: Vec::new(),
        materials,
        lights: collected.lights,
        cameras: collected.cameras,
        background,
        bvh: Bvh4::default(),
        warnings,
        textures,
        envmap: None,
    };
    scene.set_shading(&collected.shading);
    scene.assign_emitters();
    warn_non_finite_lights(&mut scene);
    let mut inputs = src.inputs.take();
    inputs.sort();
    inputs.dedup();
    Ok((scene, inputs))
}

/// A light whose colour x intensity overflows f32 made the whole image
/// black (the light table's total power is infinite): such lights are
/// dropped with a warning. An emission whose factor x strength overflows is
/// named in a warning.
fn warn_non_finite_lights(scene: &mut Scene) {
    use crate::scene::PunctualLight;
    let finite = |l: &PunctualLight| match l {
        PunctualLight::Point { intensity, .. } | PunctualLight::Spot { intensity, .. } => {
            intensity.is_finite()
        }
        PunctualLight::Directional { irradiance, .. } => irradiance.is_finite(),
    };
    let before = scene.lights.len();
    scene.lights.retain(finite);
    let bad_lights = before - scene.lights.len();
    if bad_lights > 0 {
        scene.warnings.push(format!(
            "{bad_lights} punctual light(s) with a colour x intensity beyond f32's range \
             (infinite); dropped, they light nothing"
        ));
    }
    let bad_emission: Vec<&str> = scene
        .materials
        .iter()
        .filter(|m| !m.emission.is_finite())
        .map(|m| m.name.as_str())
        .collect();
    if !bad_emission.is_empty() {
        scene.warnings.push(format!(
            "material(s) {} emit a radiance beyond f32's range (emissiveFactor x strength is infinite)",
            bad_emission.join(", ")
        ));
    }
}

/// Extensions glint accepts without a warning although it reads nothing
/// from them: metadata alone (`KHR_xmp`, `KHR_xmp_json_ld`: authorship and
/// licence, no effect on the image) and `KHR_materials_variants`, whose
/// default (each primitive's own `material`) is what glint renders.
pub const QUIET_EXTENSIONS: &[&str] = &["KHR_xmp", "KHR_xmp_json_ld", "KHR_materials_variants"];

/// Drop the reader's "not supported" warning for [`QUIET_EXTENSIONS`].
fn accept_quiet_extensions(warnings: &mut Vec<String>) {
    warnings.retain(|w| {
        !QUIET_EXTENSIONS
            .iter()
            .any(|e| *w == format!("extension {e} is not supported; ignored"))
    });
}

fn background(extras: Option<&serde_json::value::RawValue>) -> Result<Vec3, String> {
    let Some(raw) = extras else {
        return Ok(Vec3::ZERO);
    };
    let v: Value = serde_json::from_str(raw.get()).map_err(|e| e.to_string())?;
    let Some(bg) = v.get("background") else {
        return Ok(Vec3::ZERO);
    };
    let arr = bg
        .as_array()
        .filter(|a| a.len() == 3)
        .ok_or_else(|| format!("must be [r, g, b] (3 numbers), got {bg}"))?;
    let mut c = [0.0f32; 3];
    for (ci, x) in c.iter_mut().zip(arr) {
        *ci = x
            .as_f64()
            .ok_or_else(|| format!("must hold numbers, got {bg}"))? as f32;
    }
    let c = Vec3::from(c);
    if c.is_finite() && c.min_element() >= 0.0 {
        Ok(c)
    } else {
        Err(format!("values must be finite and >= 0, got {bg}"))
    }
}

/// Vertical field of view of [`default_camera`]: 40 degrees.
pub const DEFAULT_YFOV: f32 = 40.0 * std::f32::consts::PI / 180.0;

/// The viewpoint used when the file has no camera: looking down -Z (+Y up)
/// at the centre of the bounding box from the +Z side, yfov 40 degrees,
/// aspect 1, far enough that the bounding sphere (the box's circumsphere)
/// exactly fills the vertical field of view. An empty scene is viewed from
/// (0, 0, 1 / sin(20 deg)) as if it were the unit sphere.
pub fn default_camera(scene: &Scene) -> Camera {
    let (lo, hi) = scene.bounds();
    let center = 0.5 * (lo + hi);
    let radius = 0.5 * (hi - lo).length();
    let radius = if radius > 0.0 && radius.is_finite() {
        radius
    } else {
        1.0
    };
    let distance = radius / (0.5 * DEFAULT_YFOV).sin();
    Camera {
        name: Some("default".into()),
        node_name: None,
        to_world: Mat4::from_translation(center + Vec3::Z * distance),
        yfov: DEFAULT_YFOV,
        aspect_ratio: Some(1.0),
    }
}

/// Resolve the CLI's `--camera NAME|INDEX`: a camera's name or its
/// node's name first (exact match; the first camera in node order that has
/// it), then a 0-based index into `scene.cameras`.
pub fn select_camera(scene: &Scene, name_or_index: &str) -> Result<usize, String> {
    let named = |c: &Camera| {
        c.name.as_deref() == Some(name_or_index) || c.node_name.as_deref() == Some(name_or_index)
    };
    if let Some(i) = scene.cameras.iter().position(named) {
        return Ok(i);
    }
    let n = scene.cameras.len();
    let names: Vec<String> = scene
        .cameras
        .iter()
        .enumerate()
        .map(|(i, c)| match (&c.name, &c.node_name) {
            (Some(name), Some(node)) if name != node => format!("{i} '{name}' (node '{node}')"),
            (Some(name), _) | (None, Some(name)) => format!("{i} '{name}'"),
            (None, None) => i.to_string(),
        })
        .collect();
    let available = if n == 0 {
        "the scene has no cameras".to_string()
    } else {
        format!("the scene's cameras: {}", names.join(", "))
    };
    match name_or_index.trim().parse::<usize>() {
        Ok(i) if i < n => Ok(i),
        Ok(i) => Err(format!("camera index {i} is out of range ({available})")),
        Err(_) => Err(format!("no camera named '{name_or_index}' ({available})")),
    }
}
