//! One module per verb, and what they share: loading a scene with the
//! render options settled, progress bars, output files.

pub mod bench;
pub mod compare;
pub mod converge;
pub mod detect;
pub mod diff;
pub mod export;
pub mod info;
pub mod merge;
pub mod outputs;
pub mod render;
pub mod report;
pub mod shard;
pub mod stability;
pub mod test;

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use anyhow::{Result, anyhow, bail};
use glam::Vec3;
use glint::backend::{self, Backend, BackendRender, GpuOptions};
use glint::cpu::exr_file::{RadianceImage, RenderMeta};
use glint::cpu::prepare::{PrepareOptions, Prepared};
use glint::cpu::{Film, OutputFormat, RenderOptions, Scene};
use indicatif::{ProgressBar, ProgressStyle};

use crate::cli::{OnOff, RenderOpts, SceneArgs};

/// Largest image side accepted (the library's, one constant for every check).
pub const MAX_SIZE: u32 = glint::cpu::film::MAX_IMAGE_SIDE;
/// Width used when neither --width nor --height is given.
pub const DEFAULT_WIDTH: u32 = 512;
/// Samples per pixel when --spp is not given.
pub const DEFAULT_SPP: u32 = 64;
/// The most samples a time-limited render takes when --spp is not given.
pub const TIME_LIMIT_MAX_SPP: u32 = 1 << 24;

/// Whitespace (newlines included) folded to single spaces; any other
/// control character (a NUL from a file name or URI) escaped, so a message
/// stays one printable line.
pub fn one_line(s: &str) -> String {
    s.split_whitespace()
        .map(|w| {
            w.chars()
                .flat_map(|c| {
                    let e: Vec<char> = if c.is_control() {
                        c.escape_debug().collect()
                    } else {
                        vec![c]
                    };
                    e
                })
                .collect::<String>()
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// A refusal of bad input that the verb reports with exit status 2
/// (`diff`, `merge`, and `converge`'s non-finite reference): the contract's
/// "2 on bad input".
#[derive(Debug)]
pub struct BadInput(pub String);

impl std::fmt::Display for BadInput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BadInput {}

/// The first pixel of `values` that is not finite, as "(x, y)", for a
/// refusal naming the file.
pub fn first_non_finite(width: u32, values: &[glam::Vec3]) -> Option<String> {
    let i = values.iter().position(|v| !v.is_finite())?;
    let w = width.max(1) as usize;
    Some(format!("pixel ({}, {})", i % w, i / w))
}

/// Pick the camera (the loader's rule: a name first, then an index).
fn resolve_camera(scene: &Scene, path: &Path, camera: Option<&str>) -> Result<usize> {
    match camera {
        None => Ok(0),
        Some(c) => glint::cpu::loader::select_camera(scene, c)
            .map_err(|e| anyhow!("{}: {e}", path.display())),
    }
}

/// The image size: both given, or one given and the other from the
/// camera's aspect ratio (glTF `aspectRatio`, else 1:1), or 512 wide.
/// A side that the aspect ratio pushes past [`MAX_SIZE`] is clamped, with a
/// line in `warnings`.
fn image_size(opts: &RenderOpts, aspect: f32, warnings: &mut Vec<String>) -> Result<(u32, u32)> {
    let check = |name: &str, v: u32| -> Result<u32> {
        if (1..=MAX_SIZE).contains(&v) {
            Ok(v)
        } else {
            bail!("--{name} {v} is out of range (1..={MAX_SIZE})")
        }
    };
    let mut from = |v: u32, r: f32| {
        let side = (v as f64 * r as f64).round();
        if !(1.0..=MAX_SIZE as f64).contains(&side) {
            warnings.push(format!(
                "the camera's aspectRatio {aspect} makes the other side {side} pixels; \
                 clamped to 1..={MAX_SIZE} (give both --width and --height)"
            ));
        }
        (side as u32).clamp(1, MAX_SIZE)
    };
    Ok(match (opts.width, opts.height) {
        (Some(w), Some(h)) => (check("width", w)?, check("height", h)?),
        (Some(w), None) => {
            let w = check("width", w)?;
            (w, from(w, 1.0 / aspect))
        }
        (None, Some(h)) => {
            let h = check("height", h)?;
            (from(h, aspect), h)
        }
        (None, None) => (DEFAULT_WIDTH, from(DEFAULT_WIDTH, 1.0 / aspect)),
    })
}

/// `--quiet`: no progress bar (set once, before rendering).
pub static QUIET: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

pub fn progress_bar() -> Option<ProgressBar> {
    if QUIET.load(std::sync::atomic::Ordering::Relaxed) || !std::io::stderr().is_terminal() {
        return None;
    }
    let pb = ProgressBar::new(1);
    if let Ok(style) =
        ProgressStyle::with_template("{elapsed_precise} [{wide_bar}] {percent:>3}% eta {eta}")
    {
        pb.set_style(style.progress_chars("=> "));
    }
    Some(pb)
}

/// The samples per pixel a render takes: --spp, else the default, else
/// (time-limited) as many as fit.
pub fn spp_of(spp: Option<u32>, opts: &RenderOpts) -> u32 {
    match (spp, opts.time_limit) {
        (Some(n), _) => n,
        (None, Some(_)) => TIME_LIMIT_MAX_SPP,
        (None, None) => DEFAULT_SPP,
    }
}

/// Parameter checks that need no file: nothing is read or created for a
/// bad command line.
pub fn check_opts(spp: u32, opts: &RenderOpts) -> Result<()> {
    if spp == 0 {
        bail!("--spp must be at least 1");
    }
    if opts.max_depth == 0 || opts.max_depth < -1 {
        bail!(
            "--max-depth {} is out of range (-1 for unbounded, or at least 1)",
            opts.max_depth
        );
    }
    if let Some(t) = opts.time_limit
        && !(t > 0.0 && t.is_finite())
    {
        bail!("--time-limit {t} is out of range (a positive number of seconds)");
    }
    Ok(())
}

pub fn check_params(args: &SceneArgs) -> Result<()> {
    check_opts(spp_of(args.spp, &args.opts), &args.opts)
}

/// The scene file must be a regular file (or a link to one); anything else
/// is named for what it is. Only metadata is read: a FIFO is not opened
/// (which would wait for a writer).
pub fn check_scene_path(path: &Path) -> Result<()> {
    check_input_file(path, "a glTF file")
}

/// An input must be a regular file (or a link to one); anything else is
/// named for what it is, "not {kind}".
pub fn check_input_file(path: &Path, kind: &str) -> Result<()> {
    let p = path.display();
    let meta = match std::fs::metadata(path) {
        Ok(m) => m,
        // ELOOP: too many levels of symbolic links.
        Err(e) if e.raw_os_error() == Some(40) => {
            bail!("{p}: a symbolic link loop, not {kind}")
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            if std::fs::symlink_metadata(path).is_ok() {
                bail!("{p}: a symbolic link to a missing file");
            }
            bail!("{p}: no such file");
        }
        Err(e) => bail!("{p}: cannot read: {e}"),
    };
    let t = meta.file_type();
    if t.is_file() {
        return Ok(());
    }
    bail!("{p}: {}, not {kind}", glint::cpu::safe_fs::describe(t))
}

/// Whether `a` and `b` name the same existing file (links followed).
pub fn same_file(a: &Path, b: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (std::fs::metadata(a), std::fs::metadata(b)) {
        (Ok(x), Ok(y)) => (x.dev(), x.ino()) == (y.dev(), y.ino()),
        _ => false,
    }
}

/// Load the scene with the options that change what it holds
/// (`--allow-any-path`, `--background`), apply the contract's no-light rule,
/// then print its warnings (`glint: warning: FILE: ...`), or, with
/// `--strict`, fail on the first.
pub fn load(path: &Path, o: &RenderOpts) -> Result<Scene> {
    load_with_inputs(path, o).map(|(scene, _)| scene)
}

/// [`load`], and every file it read: the scene, its external buffers and
/// images (real paths) and the environment map. No output may name one.
pub fn load_with_inputs(path: &Path, o: &RenderOpts) -> Result<(Scene, Vec<PathBuf>)> {
    let prepared = prepare(path, o)?;
    report_warnings(path, &prepared.scene, o.strict)?;
    Ok((prepared.scene, prepared.inputs))
}

/// The key of the scene's files and of the options that change what they
/// load into ([`glint::cache::SourceKey`]), from [`load_with_inputs`]'s
/// files: what an EXR's scene key says of the scene.
pub fn source_key(inputs: &[PathBuf], o: &RenderOpts) -> Result<glint::cache::SourceKey> {
    glint::cache::SourceKey::of(inputs, &prepare_options(o))
        .map_err(|e| anyhow::anyhow!("reading the scene's files again for its key: {e}"))
}

/// The library's one scene preparation ([`glint::cpu::prepare`]) with the
/// options as the CLI gives them, checked first; warnings not printed.
pub fn prepare(path: &Path, o: &RenderOpts) -> Result<Prepared> {
    o.env.check(o.background.is_some())?;
    check_scene_path(path)?;
    Ok(glint::cpu::prepare::prepare(path, &prepare_options(o))?)
}

/// What of `o` changes the scene.
pub fn prepare_options(o: &RenderOpts) -> PrepareOptions {
    scene_options(o.allow_any_path, o.multiscatter, o.background, &o.env)
}

/// The scene preparation's options from the flags `render` and `info`
/// share.
pub fn scene_options(
    allow_any_path: bool,
    multiscatter: OnOff,
    background: Option<[f32; 3]>,
    env: &crate::cli::EnvmapArgs,
) -> PrepareOptions {
    PrepareOptions {
        allow_any_path,
        multiscatter: multiscatter == OnOff::On,
        background: background.map(Vec3::from),
        envmap: env.source(),
    }
}

/// The prepared scene of `path` with `options`, without printing the
/// warnings (they stay in `Scene::warnings`).
pub fn load_quiet(path: &Path, options: &PrepareOptions) -> Result<Prepared> {
    check_scene_path(path)?;
    Ok(glint::cpu::prepare::prepare(path, options)?)
}

/// Print each warning as `glint: warning: FILE: ...`; with `strict`, the
/// first one is the error instead.
pub fn report_warnings(path: &Path, scene: &Scene, strict: bool) -> Result<()> {
    if strict && let Some(w) = scene.warnings.first() {
        bail!("{}: {} (--strict)", path.display(), one_line(w));
    }
    for w in &scene.warnings {
        eprintln!("glint: warning: {}: {}", path.display(), one_line(w));
    }
    Ok(())
}

/// The GPU-only options (`--kernel`, `--traversal`, `--device`, and with
/// `--traversal hardware` `--ray-tracing` and `--blas-parts`) given to a
/// render on `backend` that runs on the CPU: one warning line saying they
/// are ignored (the error with `--strict`). `Auto` is resolved only when
/// such an option was given (it asks Vulkan for a GPU). Returns `backend`,
/// resolved where this resolved it, so that the render does not ask Vulkan
/// again.
pub fn check_gpu_only(path: &Path, o: &RenderOpts, backend: Backend) -> Result<Backend> {
    use crate::cli::{KernelArg, RayTracingArg, TraversalArg};
    let hardware = o.traversal == TraversalArg::Hardware;
    let given: Vec<&str> = [
        (o.kernel != KernelArg::Specialized, "--kernel"),
        (hardware, "--traversal"),
        (o.device.is_some(), "--device"),
        (
            hardware && o.ray_tracing != RayTracingArg::Auto,
            "--ray-tracing",
        ),
        (hardware && o.blas_parts != 1, "--blas-parts"),
    ]
    .into_iter()
    .filter_map(|(g, name)| g.then_some(name))
    .collect();
    if given.is_empty() {
        return Ok(backend);
    }
    let backend = backend.resolve(o.device.as_deref());
    if backend != Backend::Cpu {
        return Ok(backend);
    }
    let w = format!(
        "{} {} to the GPU backend only: ignored on the CPU backend",
        given.join(", "),
        if given.len() == 1 { "applies" } else { "apply" }
    );
    if o.strict {
        bail!("{}: {w} (--strict)", path.display());
    }
    eprintln!("glint: warning: {}: {w}", path.display());
    Ok(backend)
}

/// Settle the render options for `scene` (camera, image size, methods).
pub fn render_options(
    scene: &Scene,
    path: &Path,
    spp: u32,
    o: &RenderOpts,
) -> Result<RenderOptions> {
    let camera = resolve_camera(scene, path, o.camera.as_deref())?;
    let aspect = scene
        .cameras
        .get(camera)
        .and_then(|c| c.aspect_ratio)
        .filter(|a| a.is_finite() && *a > 0.0)
        .unwrap_or(1.0);
    let mut warnings = Vec::new();
    let (width, height) = image_size(o, aspect, &mut warnings)?;
    if o.traversal == crate::cli::TraversalArg::Software
        && (o.ray_tracing != crate::cli::RayTracingArg::Auto || o.blas_parts != 1)
    {
        warnings.push(
            "--ray-tracing and --blas-parts apply to --traversal hardware only: ignored".into(),
        );
    }
    if o.strict
        && let Some(w) = warnings.first()
    {
        bail!("{}: {} (--strict)", path.display(), one_line(w));
    }
    for w in &warnings {
        eprintln!("glint: warning: {}: {}", path.display(), one_line(w));
    }
    let opts = RenderOptions {
        spp,
        max_depth: o.max_depth,
        seed: o.seed,
        camera,
        nee: o.nee == OnOff::On,
        mis: o.mis.into(),
        light_sampling: o.light_sampling.into(),
        sampler: o.sampler.into(),
        time_limit: o.time_limit,
        ..RenderOptions::new(width, height)
    };
    glint::cpu::integrator::validate_options(scene, &opts)
        .map_err(|e| anyhow!("{}: {e}", path.display()))?;
    Ok(opts)
}

/// Load the scene and settle the render options.
pub fn load_scene(args: &SceneArgs) -> Result<(Scene, RenderOptions)> {
    let scene = load(&args.scene, &args.opts)?;
    let opts = render_options(
        &scene,
        &args.scene,
        spp_of(args.spp, &args.opts),
        &args.opts,
    )?;
    Ok((scene, opts))
}

/// Render with a progress bar on a terminal; errors name the scene.
pub fn render_on(
    backend: Backend,
    path: &Path,
    ro: &RenderOpts,
    scene: &Scene,
    opts: &RenderOptions,
) -> Result<BackendRender> {
    let pb = progress_bar();
    let progress = |done: u32, total: u32| {
        if let Some(pb) = &pb {
            pb.set_length(total as u64);
            pb.set_position(done as u64);
        }
    };
    let gpu = GpuOptions {
        device: ro.device.clone(),
        kernel: ro.kernel.into(),
        traversal: crate::cli::traversal(ro.traversal, ro.ray_tracing),
        blas_parts: ro.blas_parts,
        pipeline_cache: true,
    };
    let backend = backend.resolve(ro.device.as_deref());
    if backend == Backend::Cpu {
        glint::cpu::film::check_memory(opts.width, opts.height)
            .map_err(|e| anyhow!("{}: {e}", path.display()))?;
    }
    let r = backend::render(backend, scene, opts, &gpu, &progress)
        .map_err(|e| anyhow!("{}: {e}", path.display()))?;
    if let Some(pb) = pb {
        pb.finish_and_clear();
    }
    Ok(r)
}

/// Encode `film`: PNG through `Film::encode`; EXR with glint's header
/// attributes from `meta` (which only the EXR records), and the variance of
/// the mean when `variance`.
pub fn encode(
    film: &Film,
    w: &mut std::io::BufWriter<std::fs::File>,
    format: OutputFormat,
    meta: Option<&RenderMeta>,
    variance: bool,
) -> Result<()> {
    match format {
        OutputFormat::Exr => RadianceImage::from_film(film, variance, meta.cloned())
            .write_with(
                w,
                &glint::cpu::exr_file::samples_channel(film)
                    .into_iter()
                    .collect::<Vec<_>>(),
            )
            .map_err(|e| anyhow!("{e}")),
        OutputFormat::Png => film.encode(w, format).map_err(|e| anyhow!("{e}")),
    }
}
