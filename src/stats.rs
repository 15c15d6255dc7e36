//! `--stats` JSON: what a benchmark script needs to compare runs.

use serde_json::{Value, json};

/// Everything the stats file records.
#[derive(Clone, Debug)]
pub struct Stats {
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
}

impl Stats {
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
        if let Some(d) = &self.driver {
            v["driver"] = json!(d);
        }
        if let Some(t) = self.threads {
            v["threads"] = json!(t);
        }
        v
    }
}

/// The CPU's model name from /proc/cpuinfo (Linux), with the thread count
/// the renderer uses, e.g. "Intel(R) Xeon(R) Processor (2 threads)".
pub fn cpu_device_name(threads: usize) -> String {
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string());
    format!("{model} ({threads} threads)")
}
