//! `--stats` JSON: what a benchmark script needs to compare runs.

use glint::cpu::RenderOptions;
use serde_json::{Value, json};

/// Everything the stats file records.
#[derive(Clone, Debug)]
pub struct Stats<'a> {
    pub backend: &'static str,
    pub device: String,
    /// Vulkan driver name and version (GPU backend only).
    pub driver: Option<String>,
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub max_depth: i32,
    pub seed: u64,
    pub camera: Option<String>,
    pub triangles: usize,
    pub emitters: usize,
    pub lights: usize,
    pub threads: Option<usize>,
    pub setup_seconds: f64,
    pub render_seconds: f64,
    pub rays: u64,
    /// The methods (nee, mis, sampler, time limit, sample range).
    pub options: &'a RenderOptions,
    /// GPU: the kernel that rendered ("specialized" or "generic").
    pub kernel: Option<&'static str>,
    /// GPU: "software" (glint's BVH) or "hardware" (Vulkan ray tracing).
    pub traversal: Option<&'static str>,
    /// GPU, hardware traversal: its API, "query" or "pipeline".
    pub ray_tracing: Option<&'static str>,
    /// What the scene uses.
    pub features: Vec<&'static str>,
}

impl Stats<'_> {
    pub fn samples(&self) -> u64 {
        self.width as u64 * self.height as u64 * self.spp as u64
    }

    pub fn to_json(&self) -> Value {
        let per_second = |n: f64| {
            if self.render_seconds > 0.0 {
                n / self.render_seconds
            } else {
                0.0
            }
        };
        let mut v = json!({
            "glint_version": env!("CARGO_PKG_VERSION"),
            // The executable's build ID (null where none was found).
            "glint_build": glint::build_id::build_id(),
            "backend": self.backend,
            "device": self.device,
            "scene": self.scene,
            "width": self.width,
            "height": self.height,
            "spp": self.spp,
            "max_depth": self.max_depth,
            "seed": self.seed,
            "camera": self.camera,
            "triangles": self.triangles,
            "emitters": self.emitters,
            "punctual_lights": self.lights,
            "setup_seconds": self.setup_seconds,
            "render_seconds": self.render_seconds,
            "samples": self.samples(),
            "rays": self.rays,
            "samples_per_second": per_second(self.samples() as f64),
            "rays_per_second": per_second(self.rays as f64),
        });
        v["nee"] = json!(self.options.nee);
        v["mis"] = json!(self.options.mis.name());
        v["light_sampling"] = json!(self.options.light_sampling.name());
        v["sampler"] = json!(self.options.sampler.name());
        v["sample_start"] = json!(self.options.sample_start);
        if let Some(t) = self.options.time_limit {
            v["time_limit"] = json!(t);
        }
        v["features"] = json!(self.features);
        if let Some(k) = self.kernel {
            v["kernel"] = json!(k);
        }
        if let Some(t) = self.traversal {
            v["traversal"] = json!(t);
        }
        if let Some(t) = self.ray_tracing {
            v["ray_tracing"] = json!(t);
        }
        if let Some(d) = &self.driver {
            v["driver"] = json!(d);
        }
        if let Some(t) = self.threads {
            v["threads"] = json!(t);
        }
        v
    }
}
