//! Render options and the film both backends accumulate into.
//!
//! INTERFACE FIXED BY THE LEAD; owned by the integrator work (add image
//! output, methods; keep these fields).

use glam::Vec3;

/// What `glint render` asks of either backend (the contract's options).
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    /// Mitsuba's convention: 1 = emitters seen directly, 2 = direct lighting,
    /// -1 = unbounded (Russian roulette ends paths).
    pub max_depth: i32,
    pub seed: u64,
    /// Index into `Scene::cameras`; ignored when the scene has none (the
    /// documented default viewpoint is used).
    pub camera: usize,
}

/// Per-pixel sums over the samples, enough for the mean and for the
/// variance of the mean that statistical image comparisons need.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel accumulated.
    pub spp: u32,
    /// Row-major, top row first: sum of the radiance samples.
    pub sum: Vec<Vec3>,
    /// Sum of the squared radiance samples (per channel).
    pub sum_sq: Vec<Vec3>,
}

/// Counts and timings a backend reports for `--stats`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Rays traced (camera, continuation and shadow rays).
    pub rays: u64,
    pub render_seconds: f64,
}
