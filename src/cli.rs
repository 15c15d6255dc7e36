//! The command line (clap derive), per the contract's table.

use std::path::PathBuf;

use clap::{Parser, Subcommand, ValueEnum};

#[derive(Parser, Debug)]
#[command(
    name = "glint",
    version,
    about = "Headless physically based renderer: Vulkan compute path tracer with a CPU reference"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a glTF 2.0 scene to .exr (linear radiance) and/or .png (sRGB).
    Render(RenderArgs),
    /// Render a scene with both backends (independent random streams) and
    /// test statistically whether they agree (8x8-block Welch z-tests;
    /// exit status 1 when they differ).
    Compare(CompareArgs),
    /// Render a scene with both backends in one run and report samples/s,
    /// rays/s and the GPU/CPU ratio (same scene, options and machine).
    Bench(BenchArgs),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Backend {
    /// Vulkan compute (lavapipe where no GPU exists).
    Gpu,
    /// The CPU reference renderer.
    Cpu,
}

impl Backend {
    pub fn name(self) -> &'static str {
        match self {
            Backend::Gpu => "gpu",
            Backend::Cpu => "cpu",
        }
    }
}

/// What both `render` and `compare` take: the scene and the render options.
#[derive(clap::Args, Debug)]
pub struct SceneArgs {
    /// The scene: a glTF 2.0 file (.gltf with external or embedded buffers, or .glb).
    #[arg(value_name = "SCENE")]
    pub scene: PathBuf,

    /// Samples per pixel (at least 1).
    #[arg(long, value_name = "N", default_value_t = 64)]
    pub spp: u32,

    /// Image width in pixels (1..=16384); alone, the height follows the
    /// camera's aspect ratio. Default 512.
    #[arg(long, value_name = "W")]
    pub width: Option<u32>,

    /// Image height in pixels (1..=16384); alone, the width follows the
    /// camera's aspect ratio.
    #[arg(long, value_name = "H")]
    pub height: Option<u32>,

    /// Longest path (Mitsuba's convention): 1 = emitters seen directly,
    /// 2 = direct lighting only, -1 = unbounded (Russian roulette ends paths).
    #[arg(long, value_name = "D", default_value_t = -1, allow_negative_numbers = true)]
    pub max_depth: i32,

    /// Random seed: same seed, scene, options and backend give the same image.
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub seed: u64,

    /// The glTF camera, by name or by index among the default scene's
    /// cameras. Default: the first.
    #[arg(long, value_name = "NAME|INDEX")]
    pub camera: Option<String>,

    /// GPU backend: use the Vulkan device whose name contains NAME.
    #[arg(long, value_name = "NAME")]
    pub device: Option<String>,
}

#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: SceneArgs,

    /// Output image: .exr (linear RGB, 32-bit float) or .png (8-bit sRGB,
    /// clamped). May be given more than once.
    #[arg(short = 'o', long = "output", value_name = "FILE", required = true)]
    pub outputs: Vec<PathBuf>,

    /// Which renderer runs the path tracer.
    #[arg(long, value_enum, default_value_t = Backend::Gpu)]
    pub backend: Backend,

    /// Write timings and counts as JSON to this file.
    #[arg(long, value_name = "FILE.json")]
    pub stats: Option<PathBuf>,
}

#[derive(clap::Args, Debug)]
pub struct CompareArgs {
    #[command(flatten)]
    pub scene: SceneArgs,

    /// Overall significance of the test (the chance that two correct
    /// renderers are reported as differing).
    #[arg(long, value_name = "P", default_value_t = 1e-3)]
    pub alpha: f64,
}

#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    #[command(flatten)]
    pub scene: SceneArgs,

    /// Renders per backend; the fastest counts (the others absorb warm-up
    /// and noise from the rest of the machine).
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub repeat: u32,

    /// Also write the figures as JSON to this file.
    #[arg(long, value_name = "FILE.json")]
    pub json: Option<PathBuf>,
}
