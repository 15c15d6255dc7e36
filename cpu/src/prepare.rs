//! One scene preparation: the steps between a glTF file and the scene a
//! render takes, in one order, for every verb of the binary and every test
//! that renders a file. Tests call [`prepare`] too, so they render exactly
//! what users render.
//!
//! The steps: load (glTF, textures, BVH; `loader`), the background the
//! user gives (a constant, or an environment map that replaces it), the
//! exact simplifications (`features::simplify`, so the specialised kernel
//! carries no more than the scene needs), the contract's default lighting
//! for a scene with no light (only when the user gave no background), and
//! the ray-offset precision warning. Warnings stay in `Scene::warnings`;
//! the caller prints them (or fails on them with `--strict`).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::Vec3;

use crate::envmap::EnvMap;
use crate::loader::{LoadError, LoadOptions};
use crate::scene::Scene;

/// An equirectangular environment map to light the scene with.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvmapSource {
    pub path: PathBuf,
    /// Multiplies its radiance (finite, >= 0).
    pub scale: f32,
    /// Turns it about +Y, in degrees.
    pub rotate_degrees: f32,
}

/// What changes the scene a file gives (the CLI's `--allow-any-path`,
/// `--multiscatter`, `--background`, `--envmap`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PrepareOptions {
    /// Let URIs name files outside the scene's folder.
    pub allow_any_path: bool,
    /// Energy compensation for every rough model (a material's own
    /// `extras.bsdf` `multiscatter` wins).
    pub multiscatter: bool,
    /// Constant radiance replacing the scene's background.
    pub background: Option<Vec3>,
    /// An environment map replacing the background (not with `background`).
    pub envmap: Option<EnvmapSource>,
}

/// A prepared scene.
#[derive(Clone, Debug)]
pub struct Prepared {
    pub scene: Scene,
    /// Every file read: the scene's external buffers and images (real
    /// paths, sorted), then the scene as named, then the environment map.
    /// No output may name one. The order does not depend on how the scene
    /// was named (relative, absolute, another name): the EXR's scene key
    /// hashes the files' bytes in it (`glint::cache::SourceKey`).
    pub inputs: Vec<PathBuf>,
    /// What the simplifications did, one line each (`glint info`).
    pub simplified: Vec<String>,
}

#[derive(Debug, thiserror::Error)]
pub enum PrepareError {
    #[error(transparent)]
    Load(#[from] LoadError),
    #[error("{path}: {message}")]
    Envmap { path: PathBuf, message: String },
    #[error(
        "give a background or an environment map, not both (the environment map is the background)"
    )]
    BackgroundAndEnvmap,
}

/// Load `path` and prepare it as every render does (see the module notes).
pub fn prepare(path: &Path, o: &PrepareOptions) -> Result<Prepared, PrepareError> {
    if o.background.is_some() && o.envmap.is_some() {
        return Err(PrepareError::BackgroundAndEnvmap);
    }
    let load = LoadOptions {
        allow_any_path: o.allow_any_path,
        multiscatter: o.multiscatter,
    };
    let (mut scene, mut inputs) = crate::loader::load_with_inputs(path, load)?;
    inputs.push(path.to_path_buf());
    if let Some(bg) = o.background {
        scene.background = bg;
    }
    if let Some(env) = &o.envmap {
        let (map, bad) =
            EnvMap::load_checked(&env.path, env.scale, env.rotate_degrees).map_err(|message| {
                PrepareError::Envmap {
                    path: env.path.clone(),
                    message,
                }
            })?;
        if bad > 0 {
            let scaled = if env.scale != 1.0 {
                ", after the scale"
            } else {
                ""
            };
            scene.warnings.push(format!(
                "{}: {bad} texel(s) not finite (NaN or infinite{scaled}); they emit nothing",
                env.path.display()
            ));
        }
        scene.background = Vec3::ZERO;
        scene.envmap = Some(Arc::new(map));
        inputs.push(env.path.clone());
    }
    let simplified = crate::features::simplify(&mut scene);
    // The default lighting applies to the file alone: a background the
    // user gives (even a black one, a dark scene) replaces it.
    if o.background.is_none() && o.envmap.is_none() {
        scene.light_if_unlit();
    }
    if let Some(w) = crate::integrator::precision_warning(&scene) {
        scene.warnings.push(w);
    }
    Ok(Prepared {
        scene,
        inputs,
        simplified,
    })
}

/// [`prepare`] with the default options: the scene `glint render FILE`
/// renders.
pub fn prepare_default(path: &Path) -> Result<Scene, PrepareError> {
    prepare(path, &PrepareOptions::default()).map(|p| p.scene)
}
