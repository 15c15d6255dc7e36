//! The command line (clap derive), per the contract's table.

use std::path::PathBuf;

use clap::{Parser, Subcommand, ValueEnum};
use glint::backend::Backend;
use glint::cpu::{LightSampling, Mis, SamplerKind};
use serde::Serialize;

#[derive(Parser, Debug)]
#[command(
    name = "glint",
    version,
    long_version = glint::build_id::long_version(),
    about = "Headless physically based renderer: Vulkan compute path tracer with a CPU reference",
    // A later option overrides an earlier one (converge's variants append
    // their options to the shared ones).
    args_override_self = true
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
    /// Error against time: render variants (sets of render options) at
    /// several sample counts or time budgets, measure each image against a
    /// reference, write DIR/converge.csv, .md, .svg and .png.
    Converge(ConvergeArgs),
    /// What a scene holds and what glint will use: cameras, materials and
    /// the models they map to, textures, lights, triangles, bounds, kernel
    /// features, GPU memory, warnings.
    Info(InfoArgs),
    /// Write the prepared scene for a peer renderer: Mitsuba 3 XML and PLY
    /// meshes (exact for Mitsuba's own models, lights and camera; what is
    /// approximated gets a warning line).
    Export(ExportArgs),

    /// Sweep each BSDF through its failure points (grazing angles, alpha
    /// to 0, eta to 1, extreme k and anisotropy) on both backends; write
    /// DIR/stability.md, .csv and a pass/fail map (.svg, .png).
    Stability(StabilityArgs),
    /// Compare two EXRs: relMSE, RMSE, FLIP, mean ratio; with variance in
    /// both, the statistical verdict (exit 0 agree, 1 differ, 2 bad input).
    Diff(DiffArgs),
    /// Combine shards (render --shard I/N) into one image exactly.
    Merge(MergeArgs),
    /// Run an image-regression suite (SUITE.toml): render each scene, diff
    /// it against its reference (exit 0 all agree, 1 any differs, 2 bad
    /// input); --update rewrites the references.
    Test(TestArgs),
}

/// The verbs, for messages ("missing command: ...").
pub const VERBS: &[&str] = &[
    "render",
    "compare",
    "bench",
    "converge",
    "diff",
    "merge",
    "info",
    "stability",
    "test",
];

#[derive(clap::Args, Debug)]
pub struct InfoArgs {
    /// The scene: a glTF 2.0 file.
    #[arg(value_name = "SCENE")]
    pub scene: PathBuf,

    /// Let buffer and image URIs name files outside the scene's folder.
    #[arg(long)]
    pub allow_any_path: bool,

    /// Constant radiance R,G,B replacing the scene's background.
    #[arg(long, value_name = "R,G,B", value_parser = parse_rgb)]
    pub background: Option<[f32; 3]>,

    /// Energy compensation for every rough model, as `render` takes it
    /// (a material's own extras.bsdf `multiscatter` wins).
    #[arg(long, value_enum, value_name = "on|off", default_value_t = OnOff::Off)]
    pub multiscatter: OnOff,

    #[command(flatten)]
    pub env: EnvmapArgs,

    /// Every warning is an error.
    #[arg(long)]
    pub strict: bool,
}

/// `--nee on|off`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "kebab-case")] // clap's value names (`to_args`)
pub enum OnOff {
    On,
    Off,
}

/// `--mis power|balance|none`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "kebab-case")] // clap's value names (`to_args`)
pub enum MisArg {
    /// Power heuristic, beta 2 (Mitsuba 3's choice).
    Power,
    /// Balance heuristic.
    Balance,
    /// Light sampling alone for area lights and the background.
    None,
}

impl From<MisArg> for Mis {
    fn from(m: MisArg) -> Self {
        match m {
            MisArg::Power => Mis::Power,
            MisArg::Balance => Mis::Balance,
            MisArg::None => Mis::None,
        }
    }
}

/// `--light-sampling solid-angle|area`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "kebab-case")] // clap's value names (`to_args`)
pub enum LightSamplingArg {
    /// Uniform in the solid angle an emissive triangle subtends where
    /// that is large (0.1 to 6.22 sr) and well conditioned, by area
    /// elsewhere.
    SolidAngle,
    /// Uniform by area on every emissive triangle.
    Area,
}

impl From<LightSamplingArg> for LightSampling {
    fn from(m: LightSamplingArg) -> Self {
        match m {
            LightSamplingArg::SolidAngle => LightSampling::SolidAngle,
            LightSamplingArg::Area => LightSampling::Area,
        }
    }
}

/// `--sampler`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "kebab-case")] // clap's value names (`to_args`)
pub enum SamplerArg {
    /// Owen-scrambled Sobol points (Burley 2020), scrambled per pixel.
    Sobol,
    /// Independent uniform random numbers.
    Independent,
}

impl From<SamplerArg> for SamplerKind {
    fn from(s: SamplerArg) -> Self {
        match s {
            SamplerArg::Sobol => SamplerKind::Sobol,
            SamplerArg::Independent => SamplerKind::Independent,
        }
    }
}

/// `--kernel`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "kebab-case")] // clap's value names (`to_args`)
pub enum KernelArg {
    /// Built for the scene's features (Vulkan specialization constants).
    Specialized,
    /// The kernel that handles every scene.
    Generic,
}

impl From<KernelArg> for glint::backend::KernelChoice {
    fn from(k: KernelArg) -> Self {
        match k {
            KernelArg::Specialized => Self::Specialized,
            KernelArg::Generic => Self::Generic,
        }
    }
}

/// `--traversal`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "kebab-case")] // clap's value names (`to_args`)
pub enum TraversalArg {
    /// glint's BVH, walked in the compute kernel.
    Software,
    /// Vulkan ray tracing against acceleration structures built on the
    /// device (needs VK_KHR_acceleration_structure, and VK_KHR_ray_query or
    /// VK_KHR_ray_tracing_pipeline: --ray-tracing).
    Hardware,
}

/// `--ray-tracing`: which Vulkan API `--traversal hardware` traces with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum RayTracingArg {
    /// Ray queries where the device has them, else the pipeline.
    Auto,
    /// Ray queries in the compute kernel (VK_KHR_ray_query).
    Query,
    /// A ray tracing pipeline: ray generation, hit and miss shaders
    /// (VK_KHR_ray_tracing_pipeline).
    Pipeline,
}

/// The GPU traversal of `--traversal` and `--ray-tracing`.
pub fn traversal(t: TraversalArg, api: RayTracingArg) -> glint::backend::Traversal {
    use glint::backend::Traversal;
    match (t, api) {
        (TraversalArg::Software, _) => Traversal::Software,
        (TraversalArg::Hardware, RayTracingArg::Auto) => Traversal::Hardware,
        (TraversalArg::Hardware, RayTracingArg::Query) => Traversal::RayQuery,
        (TraversalArg::Hardware, RayTracingArg::Pipeline) => Traversal::Pipeline,
    }
}

/// Render options every verb shares (all but the scene, the sample count
/// and the outputs). [`RenderOpts::to_args`] writes them back as arguments
/// (from their serde form, whose names are clap's), so converge can lay a
/// variant's options over them.
#[derive(clap::Args, Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case")] // clap's long names
pub struct RenderOpts {
    /// Image width in pixels (1..=16384); alone, the height follows the
    /// camera's aspect ratio. Default 512.
    #[arg(long, value_name = "W", allow_negative_numbers = true, value_parser = parse_side)]
    pub width: Option<u32>,

    /// Image height in pixels (1..=16384); alone, the width follows the
    /// camera's aspect ratio.
    #[arg(long, value_name = "H", allow_negative_numbers = true, value_parser = parse_side)]
    pub height: Option<u32>,

    /// Longest path (Mitsuba's convention): 1 = emitters seen directly,
    /// 2 = direct lighting only, -1 = unbounded (Russian roulette ends paths).
    #[arg(long, value_name = "D", default_value_t = -1, allow_negative_numbers = true)]
    pub max_depth: i32,

    /// Random seed: same seed, scene, options and backend give the same image.
    #[arg(long, value_name = "S", default_value_t = 0, allow_negative_numbers = true, value_parser = parse_seed)]
    pub seed: u64,

    /// The glTF camera, by name or by index among the default scene's
    /// cameras. Default: the first.
    #[arg(long, value_name = "NAME|INDEX", allow_negative_numbers = true, value_parser = parse_camera)]
    pub camera: Option<String>,

    /// GPU backend: use the Vulkan device whose name contains NAME.
    #[arg(long, value_name = "NAME")]
    pub device: Option<String>,

    /// Next-event estimation (light sampling); off: BSDF sampling alone.
    #[arg(long, value_enum, value_name = "on|off", default_value_t = OnOff::On)]
    pub nee: OnOff,

    /// Multiple importance sampling of light and BSDF samples.
    #[arg(long, value_enum, default_value_t = MisArg::Power)]
    pub mis: MisArg,

    /// How light sampling picks a point on an emissive triangle.
    #[arg(long, value_enum, default_value_t = LightSamplingArg::SolidAngle)]
    pub light_sampling: LightSamplingArg,

    /// Energy compensation (multiple scattering) for every rough model,
    /// glTF-derived ones included; a material's own extras.bsdf
    /// `multiscatter` wins.
    #[arg(long, value_enum, value_name = "on|off", default_value_t = OnOff::Off)]
    pub multiscatter: OnOff,

    /// Where the random numbers come from.
    #[arg(long, value_enum, default_value_t = SamplerArg::Sobol)]
    pub sampler: SamplerArg,

    /// GPU: the kernel built for what the scene uses, or the one that
    /// handles every scene.
    #[arg(long, value_enum, default_value_t = KernelArg::Specialized)]
    pub kernel: KernelArg,

    /// GPU: glint's BVH in the compute kernel, or Vulkan ray tracing
    /// against acceleration structures (a device without it is an error).
    #[arg(long, value_enum, default_value_t = TraversalArg::Software)]
    pub traversal: TraversalArg,

    /// GPU, --traversal hardware: ray queries in the compute kernel or a
    /// ray tracing pipeline (auto: ray queries where the device has them).
    #[arg(long, value_enum, default_value_t = RayTracingArg::Auto)]
    pub ray_tracing: RayTracingArg,

    /// GPU, --traversal hardware: split the scene's triangles into this many
    /// bottom-level acceleration structures (contiguous clusters in BVH
    /// order, one instance each), as one per mesh would; 1 (the default)
    /// builds one over the whole flattened scene, which measured faster.
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub blas_parts: u32,

    /// Stop at the last whole sample pass that fits this many seconds of
    /// sampling (--spp, when given, caps the samples; --stats reports the
    /// spp reached).
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    pub time_limit: Option<f64>,

    /// Constant radiance R,G,B from every direction, replacing the
    /// scene's background.
    #[arg(long, value_name = "R,G,B", value_parser = parse_rgb)]
    pub background: Option<[f32; 3]>,

    #[command(flatten)]
    #[serde(flatten)]
    pub env: EnvmapArgs,

    /// Every warning is an error.
    #[arg(long)]
    pub strict: bool,

    /// Let buffer and image URIs name files outside the scene's folder
    /// (absolute paths, `..`).
    #[arg(long)]
    pub allow_any_path: bool,
}

/// `R,G,B`: three finite numbers >= 0.
pub fn parse_rgb(s: &str) -> Result<[f32; 3], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(format!("'{s}' is not R,G,B (three numbers)"));
    }
    let mut c = [0.0f32; 3];
    for (ci, p) in c.iter_mut().zip(&parts) {
        *ci = p
            .parse::<f32>()
            .ok()
            .filter(|x| x.is_finite() && *x >= 0.0)
            .ok_or_else(|| format!("'{s}': each of R,G,B must be a finite number >= 0"))?;
    }
    Ok(c)
}

/// `--width`, `--height`: a whole number of pixels, said so for "-5"
/// (clap's "unexpected argument '-5'" named no option; its error now reads
/// "invalid value '-5' for '--width <W>': ...").
/// (The range itself, 0 included, is checked with the other parameters.)
fn parse_side(s: &str) -> Result<u32, String> {
    s.trim().parse::<u32>().map_err(|_| {
        format!(
            "an image side is a whole number of pixels from 1 to {}",
            crate::cmd::MAX_SIZE
        )
    })
}

/// A count (`--spp`, `--repeat`, `--reference-spp`): a whole number, said
/// so for "-5" (0 is refused with the other parameter checks).
fn parse_count(s: &str) -> Result<u32, String> {
    s.trim()
        .parse::<u32>()
        .map_err(|_| format!("a whole number from 1 to {}", u32::MAX))
}

/// `--seed`: a whole number 0..=2^64-1, said so for "-1" rather than
/// clap's "unexpected argument".
fn parse_seed(s: &str) -> Result<u64, String> {
    s.trim()
        .parse::<u64>()
        .map_err(|_| format!("a seed is a whole number from 0 to {}", u64::MAX))
}

/// `--camera`: a name, or an index from 0.
fn parse_camera(s: &str) -> Result<String, String> {
    match s.trim().parse::<i64>() {
        Ok(i) if i < 0 => Err("camera indices start at 0 (or give the camera's name)".into()),
        _ => Ok(s.to_string()),
    }
}

impl RenderOpts {
    /// These options as command-line arguments, every one explicit: each
    /// field of the serde form as `--name value` (`--name` alone for a
    /// true flag, nothing for an unset option or a false flag; arrays as
    /// `a,b,c`). The names are clap's (kebab-case fields and values), so
    /// an option added to the struct is serialised with no code here.
    pub fn to_args(&self) -> anyhow::Result<Vec<String>> {
        use serde_json::Value;
        let Value::Object(fields) = serde_json::to_value(self)? else {
            anyhow::bail!("render options do not serialise to a map");
        };
        let text = |v: &Value| match v {
            Value::String(s) => Ok(s.clone()),
            Value::Number(n) => Ok(n.to_string()),
            other => Err(anyhow::anyhow!("unexpected option value {other}")),
        };
        let mut args = Vec::new();
        for (name, value) in fields {
            match value {
                Value::Null | Value::Bool(false) => {}
                Value::Bool(true) => args.push(format!("--{name}")),
                Value::Array(items) => {
                    let items: anyhow::Result<Vec<String>> = items.iter().map(text).collect();
                    args.extend([format!("--{name}"), items?.join(",")]);
                }
                v => args.extend([format!("--{name}"), text(&v)?]),
            }
        }
        Ok(args)
    }
}

/// The environment map, as `render` and `info` take it.
#[derive(clap::Args, Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case")] // clap's long names
pub struct EnvmapArgs {
    /// Equirectangular environment light (.exr or .hdr, linear RGB, +Y up),
    /// importance sampled; replaces the scene's background.
    #[arg(long, value_name = "FILE")]
    pub envmap: Option<PathBuf>,

    /// Multiplies the environment map's radiance.
    #[arg(
        long,
        value_name = "S",
        default_value_t = 1.0,
        allow_negative_numbers = true
    )]
    pub envmap_scale: f32,

    /// Turns the environment map about +Y by this many degrees.
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub envmap_rotate: f32,
}

impl EnvmapArgs {
    /// The options' own rules, with whether `--background` is given too:
    /// not both; a finite scale >= 0 and a finite turn.
    pub fn check(&self, background: bool) -> anyhow::Result<()> {
        if self.envmap.is_some() && background {
            anyhow::bail!(
                "give --background or --envmap, not both (the environment map is the background)"
            );
        }
        if !(self.envmap_scale.is_finite() && self.envmap_scale >= 0.0) {
            anyhow::bail!(
                "--envmap-scale {} is out of range (a finite number >= 0)",
                self.envmap_scale
            );
        }
        if !self.envmap_rotate.is_finite() {
            anyhow::bail!(
                "--envmap-rotate {} is not a finite number of degrees",
                self.envmap_rotate
            );
        }
        Ok(())
    }

    /// What the scene preparation takes.
    pub fn source(&self) -> Option<glint::cpu::prepare::EnvmapSource> {
        self.envmap
            .as_ref()
            .map(|path| glint::cpu::prepare::EnvmapSource {
                path: path.clone(),
                scale: self.envmap_scale,
                rotate_degrees: self.envmap_rotate,
            })
    }
}

/// What `render`, `compare` and `bench` take: the scene, the sample count
/// and the shared render options.
#[derive(clap::Args, Debug)]
pub struct SceneArgs {
    /// The scene: a glTF 2.0 file (.gltf with external or embedded buffers, or .glb).
    #[arg(value_name = "SCENE")]
    pub scene: PathBuf,

    /// Samples per pixel (at least 1). Default 64; with --time-limit and no
    /// --spp, as many as fit.
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = parse_count)]
    pub spp: Option<u32>,

    #[command(flatten)]
    pub opts: RenderOpts,
}

#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: SceneArgs,

    /// Output image: .exr (linear RGB, 32-bit float) or .png (8-bit sRGB,
    /// clamped). May be given more than once.
    #[arg(short = 'o', long = "output", value_name = "FILE", required = true)]
    pub outputs: Vec<PathBuf>,

    /// Which renderer runs the path tracer: auto (a GPU when Vulkan lists
    /// one, else the CPU backend), gpu (Vulkan; lavapipe where no GPU
    /// exists) or cpu.
    #[arg(long, value_enum, default_value_t = Backend::Auto)]
    pub backend: Backend,

    /// Write timings and counts as JSON to this file.
    #[arg(long, value_name = "FILE.json")]
    pub stats: Option<PathBuf>,

    /// The .exr outputs also hold variance.R, variance.G, variance.B: the
    /// variance of each pixel's mean (for glint diff and merge).
    #[arg(long)]
    pub variance: bool,

    /// Render only shard I of N (0-based): sample indices
    /// [floor(I spp/N), floor((I+1) spp/N)); glint merge combines them.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<crate::cmd::shard::Shard>,

    #[command(flatten)]
    pub control: ControlOpts,

    /// No progress bar and no success line.
    #[arg(long)]
    pub quiet: bool,
}

/// `--target-error` and `--adaptive`: what decides when a render stops
/// (render's, and a converge variant's).
#[derive(clap::Args, Debug, Clone, Default)]
pub struct ControlOpts {
    /// Render whole passes until the image's estimated relMSE (each
    /// pixel's variance of the mean in place of its squared error) is at
    /// most E; --spp is then the cap.
    #[arg(long, value_name = "E", allow_negative_numbers = true)]
    pub target_error: Option<f64>,

    /// Per-pixel adaptive sampling: a pixel stops once its estimated
    /// relative standard error is below T (after a minimum, neighbours
    /// kept alive); --spp is the per-pixel cap; .exr outputs gain a
    /// `samples` channel.
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    pub adaptive: Option<f64>,
}

#[derive(clap::Args, Debug)]
pub struct DiffArgs {
    /// The image under test (.exr).
    #[arg(value_name = "A.exr")]
    pub a: PathBuf,

    /// The reference (.exr).
    #[arg(value_name = "B.exr")]
    pub b: PathBuf,

    /// Write a false-colour difference image with a colour bar: per-pixel
    /// z where both carry variance, relative error otherwise.
    #[arg(long = "diff", value_name = "OUT.png")]
    pub diff: Option<PathBuf>,

    /// Write the figures and the verdict as JSON.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,

    /// Overall significance of the statistical test (the chance that two
    /// renders of the same image are reported as differing).
    #[arg(
        long,
        value_name = "P",
        default_value_t = 1e-3,
        allow_negative_numbers = true
    )]
    pub alpha: f64,

    /// Agree only if relMSE is at most X. Without variance in both files
    /// (or with a non-finite value, or sizes that differ) the thresholds
    /// decide 0 or 1 where diff would otherwise exit 2; with variance they
    /// must hold as well as the statistical test.
    #[arg(long, value_name = "X", allow_negative_numbers = true)]
    pub max_relmse: Option<f64>,

    /// Agree only if FLIP is at most X (as --max-relmse).
    #[arg(long, value_name = "X", allow_negative_numbers = true)]
    pub max_flip: Option<f64>,
}

#[derive(clap::Args, Debug)]
pub struct MergeArgs {
    /// The shards (.exr from render --shard I/N, with --variance to pool
    /// variances).
    #[arg(value_name = "SHARD.exr", required = true)]
    pub shards: Vec<PathBuf>,

    /// The merged image (.exr).
    #[arg(short = 'o', long = "output", value_name = "OUT.exr", required = true)]
    pub output: PathBuf,
}

#[derive(clap::Args, Debug)]
pub struct CompareArgs {
    #[command(flatten)]
    pub scene: SceneArgs,

    /// Overall significance of the test (the chance that two correct
    /// renderers are reported as differing).
    #[arg(
        long,
        value_name = "P",
        default_value_t = 1e-3,
        allow_negative_numbers = true
    )]
    pub alpha: f64,

    /// Further render options for the GPU side only, laid over the shared
    /// ones, e.g. '--mis balance' (not --backend, --spp, --target-error or
    /// --adaptive): compare two methods, or check a change is seen.
    #[arg(long, value_name = "OPTIONS", allow_hyphen_values = true)]
    pub gpu_options: Option<String>,

    /// As --gpu-options, for the CPU side (e.g. '--max-depth 2' must differ
    /// from the default on a scene with indirect light).
    #[arg(long, value_name = "OPTIONS", allow_hyphen_values = true)]
    pub cpu_options: Option<String>,
}

#[derive(clap::Args, Debug)]
pub struct ExportArgs {
    #[command(flatten)]
    pub scene: SceneArgs,

    /// Output folder: DIR/scene.xml and DIR/meshes/*.ply (created; files
    /// of the same names are replaced).
    #[arg(short = 'o', long = "output", value_name = "DIR")]
    pub dir: std::path::PathBuf,
}

#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    #[command(flatten)]
    pub scene: SceneArgs,

    /// Renders per backend; the fastest counts (the others absorb warm-up
    /// and noise from the rest of the machine).
    #[arg(long, value_name = "N", default_value_t = 1, allow_negative_numbers = true, value_parser = parse_count)]
    pub repeat: u32,

    /// Also write the figures as JSON to this file.
    #[arg(long, value_name = "FILE.json")]
    pub json: Option<PathBuf>,

    /// Render on the GPU with every traversal, glint's BVH and Vulkan ray
    /// tracing by each API the device has (ray queries, the pipeline), and
    /// report them side by side (a device without ray tracing is an error).
    #[arg(long)]
    pub compare_traversals: bool,
}

#[derive(clap::Args, Debug)]
#[command(group(clap::ArgGroup::new("reference_source").required(true).args(["reference", "reference_spp"])))]
pub struct ConvergeArgs {
    /// The scene: a glTF 2.0 file.
    #[arg(value_name = "SCENE")]
    pub scene: PathBuf,

    /// Output folder (created if missing): converge.csv, converge.md,
    /// converge.svg, converge.png (and NAME-SPP.exr with --keep-images).
    #[arg(short = 'o', long = "output", value_name = "DIR")]
    pub dir: PathBuf,

    /// The reference image (.exr, the render's size).
    #[arg(long, value_name = "REF.exr")]
    pub reference: Option<PathBuf>,

    /// Render the reference with the CPU backend at N spp (an independent
    /// seed), cached in the user's cache folder by scene content and options.
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = parse_count)]
    pub reference_spp: Option<u32>,

    /// Sample counts of each variant, comma-separated.
    #[arg(
        long,
        value_name = "N,N,...",
        value_delimiter = ',',
        default_value = "4,16,64,256"
    )]
    pub spp: Vec<u32>,

    /// Time budgets in seconds instead of sample counts, comma-separated
    /// (each render stops at the last whole sample pass that fits).
    #[arg(long, value_name = "S,S,...", value_delimiter = ',')]
    pub time: Option<Vec<f64>>,

    /// A variant: NAME=OPTIONS, the render options (quoted, space-separated)
    /// laid over the shared ones, e.g. 'gpu-balance=--backend gpu --mis balance'.
    /// May be given more than once. Default: gpu=--backend gpu and
    /// cpu=--backend cpu.
    #[arg(long = "variant", value_name = "NAME=OPTIONS")]
    pub variants: Vec<String>,

    /// Keep each image as DIR/NAME-SPP.exr (NAME-Ts.exr for time budgets).
    #[arg(long)]
    pub keep_images: bool,

    #[command(flatten)]
    pub opts: RenderOpts,
}

/// How a converge variant's options parse: the backend and the shared
/// render options.
#[derive(Parser, Debug)]
#[command(name = "variant", no_binary_name = true, args_override_self = true)]
pub struct VariantCli {
    /// Which renderer runs the path tracer (as render's --backend).
    #[arg(long, value_enum, default_value_t = Backend::Auto)]
    pub backend: Backend,

    #[command(flatten)]
    pub opts: RenderOpts,

    /// --target-error / --adaptive as render's: the variant stops on its
    /// error, each --spp budget its cap (not with --time).
    #[command(flatten)]
    pub control: ControlOpts,
}

#[derive(clap::Args, Debug)]
pub struct StabilityArgs {
    /// Output folder (created if missing).
    #[arg(short = 'o', long = "output", value_name = "DIR")]
    pub dir: PathBuf,

    /// The small sweep CI runs (fewer samples and queries per point).
    #[arg(long)]
    pub quick: bool,

    /// The sampling methods' sweep instead (Veach's plate roughness x
    /// light size, each technique at equal time): DIR/methods.md, .csv,
    /// .svg and .png.
    #[arg(long)]
    pub methods: bool,

    /// Skip the GPU-vs-CPU half (no Vulkan device needed).
    #[arg(long)]
    pub cpu_only: bool,

    /// Use the Vulkan device whose name contains NAME.
    #[arg(long, value_name = "NAME")]
    pub device: Option<String>,
}

#[derive(clap::Args, Debug)]
pub struct TestArgs {
    /// The suite manifest (TOML: [defaults] and [[scene]] tables).
    #[arg(value_name = "SUITE.toml")]
    pub suite: PathBuf,

    /// (Re)write the references (with variance, more samples than the
    /// tests and another seed) instead of testing; exits 0.
    #[arg(long)]
    pub update: bool,

    /// Write JUnit XML: one testcase per scene.
    #[arg(long, value_name = "FILE.xml")]
    pub junit: Option<PathBuf>,

    /// Write DIR/index.html and the images beside it.
    #[arg(long, value_name = "DIR")]
    pub html: Option<PathBuf>,

    /// Scenes rendered at once.
    #[arg(long, value_name = "N", value_parser = parse_count)]
    pub jobs: Option<u32>,

    /// Only the scenes whose name contains NAME.
    #[arg(long, value_name = "NAME")]
    pub filter: Option<String>,

    /// Seed of the test renders (independent re-renders: other seeds).
    #[arg(long, value_name = "S", default_value_t = 1, value_parser = parse_seed)]
    pub seed: u64,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[String]) -> RenderOpts {
        VariantCli::try_parse_from(args)
            .unwrap_or_else(|e| panic!("{args:?}: {e}"))
            .opts
    }

    /// Every option, at its default and away from it, survives `to_args`
    /// and clap's parser unchanged: the serde names are clap's.
    #[test]
    fn render_opts_round_trip_through_their_arguments() {
        let defaults = parse(&[]);
        assert_eq!(parse(&defaults.to_args().unwrap()), defaults);
        let all = RenderOpts {
            width: Some(33),
            height: Some(17),
            max_depth: 4,
            seed: 123_456_789_012,
            camera: Some("side view".into()),
            device: Some("llvmpipe".into()),
            nee: OnOff::Off,
            mis: MisArg::Balance,
            light_sampling: LightSamplingArg::Area,
            multiscatter: OnOff::On,
            sampler: SamplerArg::Independent,
            kernel: KernelArg::Generic,
            traversal: TraversalArg::Hardware,
            ray_tracing: RayTracingArg::Pipeline,
            blas_parts: 16,
            time_limit: Some(2.5),
            background: Some([0.1, 0.25, 3.0]),
            env: EnvmapArgs {
                envmap: Some(PathBuf::from("sky dir/sky.hdr")),
                envmap_scale: 0.3,
                envmap_rotate: -45.5,
            },
            strict: true,
            allow_any_path: true,
        };
        let args = all.to_args().unwrap();
        assert_eq!(parse(&args), all, "{args:?}");
        // A variant's options laid over them win.
        let mut over = args.clone();
        over.extend(["--mis".into(), "none".into(), "--width".into(), "8".into()]);
        let o = parse(&over);
        assert_eq!((o.mis, o.width, o.seed), (MisArg::None, Some(8), all.seed));
    }

    /// The serde names of the value enums are clap's value names.
    #[test]
    fn value_enum_names_are_the_serde_names() {
        fn check<T: ValueEnum + Serialize>() {
            for v in T::value_variants() {
                let clap = v.to_possible_value().unwrap().get_name().to_string();
                assert_eq!(serde_json::to_value(v).unwrap(), clap);
            }
        }
        check::<OnOff>();
        check::<MisArg>();
        check::<SamplerArg>();
        check::<KernelArg>();
        check::<TraversalArg>();
        check::<RayTracingArg>();
    }

    /// The --width/--height help states the limit in prose (a doc comment
    /// cannot name a const): it must say MAX_SIZE's value.
    #[test]
    fn side_help_states_the_limit() {
        use clap::CommandFactory;
        let mut cmd = super::Cli::command();
        let render = cmd.find_subcommand_mut("render").unwrap();
        for name in ["width", "height"] {
            let arg = render.get_arguments().find(|a| a.get_id() == name).unwrap();
            let help = arg.get_help().unwrap().to_string();
            let limit = format!("1..={}", crate::cmd::MAX_SIZE);
            assert!(help.contains(&limit), "--{name}: {help}");
        }
    }
}
