//! `glint`: the command line. Every failure ends with one line on stderr
//! naming the file and the problem, a non-zero status, and no output file
//! left behind.

mod cli;
mod stats;

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result, anyhow, bail};
use clap::Parser;
use indicatif::{ProgressBar, ProgressStyle};

use cli::{Backend, BenchArgs, Cli, Command, CompareArgs, RenderArgs, SceneArgs};
use glint::cpu::film::{OutputFormat, temp_path_for};
use glint::cpu::{Film, RenderOptions, Scene};
use stats::{Stats, cpu_device_name};

/// Largest image side accepted.
const MAX_SIZE: u32 = 16384;
/// Width used when neither --width nor --height is given.
const DEFAULT_WIDTH: u32 = 512;

fn main() -> ExitCode {
    // Last resort: a bug must still end in one line, not a backtrace.
    std::panic::set_hook(Box::new(|info| {
        let msg = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown panic".into());
        let at = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()))
            .unwrap_or_default();
        eprintln!("glint: internal error: {}{at}", one_line(&msg));
    }));

    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) {
                let _ = e.print();
                return ExitCode::SUCCESS;
            }
            if e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
                eprintln!("glint: missing command: render or compare (see glint --help)");
                return ExitCode::from(2);
            }
            // clap's first paragraph is the error itself (a list of
            // missing arguments may follow its first line); then usage.
            let text = e.to_string();
            let first: Vec<&str> = text
                .lines()
                .take_while(|l| !l.trim().is_empty())
                .map(str::trim)
                .collect();
            eprintln!(
                "glint: {} (see glint --help)",
                first.join(" ").trim_start_matches("error: ")
            );
            return ExitCode::from(2);
        }
    };
    // A panic unwinds through `Outputs::drop` (removing partial files), is
    // reported by the hook above, and ends here with status 101.
    let result = match cli.command {
        Command::Render(args) => std::panic::catch_unwind(|| run_render(&args)),
        Command::Compare(args) => std::panic::catch_unwind(|| run_compare(&args)),
        Command::Bench(args) => std::panic::catch_unwind(|| run_bench(&args)),
    };
    match result {
        Ok(Ok(())) => ExitCode::SUCCESS,
        Ok(Err(e)) => {
            eprintln!("glint: {}", one_line(&format!("{e:#}")));
            ExitCode::FAILURE
        }
        Err(_) => ExitCode::from(101),
    }
}

fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Output files in two phases: temporaries beside each final path are
/// created up front (so an unwritable destination fails before any
/// rendering), filled at the end, then renamed. Dropping the set without
/// `commit` removes every temporary and every file already renamed.
struct Outputs {
    finals: Vec<PathBuf>,
    temps: Vec<PathBuf>,
    renamed: usize,
    committed: bool,
}

impl Outputs {
    fn new() -> Self {
        Self {
            finals: Vec::new(),
            temps: Vec::new(),
            renamed: 0,
            committed: false,
        }
    }

    /// Reserve `path`: create its temporary now.
    fn reserve(&mut self, path: &Path) -> Result<usize> {
        if let Some(i) = self.finals.iter().position(|p| p == path) {
            return Ok(i);
        }
        if path.is_dir() {
            bail!("{}: is a directory", path.display());
        }
        let tmp = temp_path_for(path);
        std::fs::File::create(&tmp).with_context(|| format!("{}: cannot write", path.display()))?;
        self.finals.push(path.to_path_buf());
        self.temps.push(tmp);
        Ok(self.finals.len() - 1)
    }

    fn write(
        &self,
        i: usize,
        f: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> Result<()>,
    ) -> Result<()> {
        let path = &self.finals[i];
        let file = std::fs::File::create(&self.temps[i])
            .with_context(|| format!("{}: cannot write", path.display()))?;
        let mut w = std::io::BufWriter::new(file);
        f(&mut w).with_context(|| format!("{}", path.display()))?;
        let file = w
            .into_inner()
            .map_err(|e| anyhow!("{}: {}", path.display(), e.error()))?;
        file.sync_all()
            .with_context(|| format!("{}: cannot write", path.display()))?;
        Ok(())
    }

    /// Rename every temporary over its final path.
    fn commit(mut self) -> Result<()> {
        for i in 0..self.finals.len() {
            std::fs::rename(&self.temps[i], &self.finals[i])
                .with_context(|| format!("{}: cannot write", self.finals[i].display()))?;
            self.renamed = i + 1;
        }
        self.committed = true;
        Ok(())
    }
}

impl Drop for Outputs {
    fn drop(&mut self) {
        if self.committed {
            return;
        }
        for (i, (t, f)) in self.temps.iter().zip(&self.finals).enumerate() {
            let _ = std::fs::remove_file(if i < self.renamed { f } else { t });
        }
    }
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
fn image_size(args: &SceneArgs, aspect: f32) -> Result<(u32, u32)> {
    let check = |name: &str, v: u32| -> Result<u32> {
        if (1..=MAX_SIZE).contains(&v) {
            Ok(v)
        } else {
            bail!("--{name} {v} is out of range (1..={MAX_SIZE})")
        }
    };
    let from = |v: u32, r: f32| ((v as f32 * r).round() as u32).clamp(1, MAX_SIZE);
    Ok(match (args.width, args.height) {
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

fn progress_bar() -> Option<ProgressBar> {
    if !std::io::stderr().is_terminal() {
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

/// Parameter checks that need no file: nothing is read or created for a
/// bad command line.
fn check_params(args: &SceneArgs) -> Result<()> {
    if args.spp == 0 {
        bail!("--spp must be at least 1");
    }
    if args.max_depth == 0 || args.max_depth < -1 {
        bail!(
            "--max-depth {} is out of range (-1 for unbounded, or at least 1)",
            args.max_depth
        );
    }
    Ok(())
}

/// Load the scene and settle the render options (camera, image size).
fn load_scene(args: &SceneArgs) -> Result<(Scene, RenderOptions)> {
    if !args.scene.is_file() {
        bail!("{}: no such file", args.scene.display());
    }
    let scene = glint::cpu::loader::load(&args.scene)?;
    let camera = resolve_camera(&scene, &args.scene, args.camera.as_deref())?;
    let aspect = scene
        .cameras
        .get(camera)
        .and_then(|c| c.aspect_ratio)
        .filter(|a| a.is_finite() && *a > 0.0)
        .unwrap_or(1.0);
    let (width, height) = image_size(args, aspect)?;
    let opts = RenderOptions {
        width,
        height,
        spp: args.spp,
        max_depth: args.max_depth,
        seed: args.seed,
        camera,
    };
    glint::cpu::integrator::validate_options(&scene, &opts)
        .map_err(|e| anyhow!("{}: {e}", args.scene.display()))?;
    Ok((scene, opts))
}

/// A finished render on either backend.
struct BackendRender {
    film: Film,
    rays: u64,
    render_seconds: f64,
    /// Backend set-up after loading (device, pipelines, upload; CPU: lights).
    setup_seconds: f64,
    device: String,
    driver: Option<String>,
    threads: Option<usize>,
}

fn render_on(
    backend: Backend,
    args: &SceneArgs,
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
    let r = match backend {
        Backend::Cpu => {
            let start = Instant::now();
            let pt = glint::cpu::PathTracer::new(scene, opts)
                .map_err(|e| anyhow!("{}: {e}", args.scene.display()))?;
            let setup_seconds = start.elapsed().as_secs_f64();
            let (film, st) = pt.render(opts.spp, &progress);
            let threads = rayon::current_num_threads();
            BackendRender {
                film,
                rays: st.rays,
                render_seconds: st.render_seconds,
                setup_seconds,
                device: cpu_device_name(threads),
                driver: None,
                threads: Some(threads),
            }
        }
        Backend::Gpu => {
            let r = glint::gpu::render(scene, opts, args.device.as_deref(), &progress)
                .map_err(|e| anyhow!("{}: GPU backend: {e}", args.scene.display()))?;
            BackendRender {
                film: r.film,
                rays: r.stats.rays,
                render_seconds: r.stats.render_seconds,
                setup_seconds: r.setup_seconds,
                device: r.device,
                driver: Some(r.driver),
                threads: None,
            }
        }
    };
    if let Some(pb) = pb {
        pb.finish_and_clear();
    }
    Ok(r)
}

fn run_render(args: &RenderArgs) -> Result<()> {
    let start = Instant::now();
    check_params(&args.scene)?;
    let mut formats = Vec::new();
    for o in &args.outputs {
        match OutputFormat::from_path(o) {
            Some(f) => formats.push(f),
            None => bail!(
                "{}: unsupported output format (use .exr or .png)",
                o.display()
            ),
        }
    }
    if let Some(s) = &args.stats
        && args.outputs.contains(s)
    {
        bail!("{}: given both as an image and as --stats", s.display());
    }
    if !args.scene.scene.is_file() {
        bail!("{}: no such file", args.scene.scene.display());
    }

    let mut outputs = Outputs::new();
    let image_slots: Vec<usize> = args
        .outputs
        .iter()
        .map(|o| outputs.reserve(o))
        .collect::<Result<_>>()?;
    let stats_slot = args
        .stats
        .as_ref()
        .map(|s| outputs.reserve(s))
        .transpose()?;

    let (scene, opts) = load_scene(&args.scene)?;
    let load_seconds = start.elapsed().as_secs_f64();
    let r = render_on(args.backend, &args.scene, &scene, &opts)?;

    for (&slot, &format) in image_slots.iter().zip(&formats) {
        outputs.write(slot, |w| encode(&r.film, w, format))?;
    }
    if let Some(slot) = stats_slot {
        let st = Stats {
            backend: args.backend.name(),
            device: r.device,
            driver: r.driver,
            scene: args.scene.scene.display().to_string(),
            width: opts.width,
            height: opts.height,
            spp: opts.spp,
            max_depth: opts.max_depth,
            seed: opts.seed,
            camera: scene
                .cameras
                .get(opts.camera)
                .map(|c| c.name.clone().unwrap_or_else(|| opts.camera.to_string())),
            triangles: scene.triangles.len(),
            emitters: scene.emitter_triangles().len(),
            lights: scene.lights.len(),
            threads: r.threads,
            setup_seconds: load_seconds + r.setup_seconds,
            render_seconds: r.render_seconds,
            rays: r.rays,
        };
        outputs.write(slot, |w| {
            serde_json::to_writer_pretty(&mut *w, &st.to_json())?;
            use std::io::Write;
            writeln!(w)?;
            Ok(())
        })?;
    }
    outputs.commit()
}

/// The CPU's seed in `glint compare`: any value other than the GPU's.
fn cpu_seed(seed: u64) -> u64 {
    seed ^ 0x9e37_79b9_7f4a_7c15
}

/// `glint compare`: both backends on one scene, the statistical test of
/// glint_cpu::compare, one line of verdict on stdout.
fn run_compare(args: &CompareArgs) -> Result<()> {
    check_params(&args.scene)?;
    if !(args.alpha > 0.0 && args.alpha < 1.0) {
        bail!("--alpha {} is out of range (0, 1)", args.alpha);
    }
    if args.scene.spp < 2 {
        bail!("--spp must be at least 2 to estimate the variance");
    }
    let (scene, opts) = load_scene(&args.scene)?;
    // Independent seeds: with the same seed both backends trace the same
    // paths (one random stream), and the Welch test assumes independence.
    let gpu = render_on(Backend::Gpu, &args.scene, &scene, &opts)?;
    let cpu_opts = RenderOptions {
        seed: cpu_seed(opts.seed),
        ..opts.clone()
    };
    let cpu = render_on(Backend::Cpu, &args.scene, &scene, &cpu_opts)?;
    let report =
        glint::cpu::compare::compare_films_masked(&gpu.film, &cpu.film, &|_, _| true, args.alpha)
            .map_err(|e| anyhow!("{}: {e}", args.scene.scene.display()))?;
    println!(
        "{}: gpu ({}) vs cpu: {report}",
        args.scene.scene.display(),
        gpu.device
    );
    if report.pass {
        Ok(())
    } else {
        bail!(
            "{}: the backends differ (see the report above)",
            args.scene.scene.display()
        )
    }
}

/// `glint bench`: the same scene and options on both backends, in one run
/// on one machine, so the figures compare; the fastest of `--repeat` renders
/// per backend counts. Prints a table and the GPU/CPU ratio.
fn run_bench(args: &BenchArgs) -> Result<()> {
    check_params(&args.scene)?;
    if args.repeat == 0 {
        bail!("--repeat must be at least 1");
    }
    let (scene, opts) = load_scene(&args.scene)?;
    let samples = opts.width as f64 * opts.height as f64 * opts.spp as f64;
    let mut rows = Vec::new();
    for backend in [Backend::Gpu, Backend::Cpu] {
        let mut best: Option<BackendRender> = None;
        for _ in 0..args.repeat {
            let r = render_on(backend, &args.scene, &scene, &opts)?;
            if best
                .as_ref()
                .is_none_or(|b| r.render_seconds < b.render_seconds)
            {
                best = Some(r);
            }
        }
        rows.push((backend, best.expect("repeat >= 1")));
    }
    println!(
        "{}: {}x{}, {} spp, max depth {}, {} triangles",
        args.scene.scene.display(),
        opts.width,
        opts.height,
        opts.spp,
        opts.max_depth,
        scene.triangles.len()
    );
    println!(
        "{:<8} {:>9} {:>10} {:>14} {:>14}  device",
        "backend", "setup s", "render s", "samples/s", "rays/s"
    );
    let mut json = Vec::new();
    for (backend, r) in &rows {
        let sps = samples / r.render_seconds.max(1e-9);
        let rps = r.rays as f64 / r.render_seconds.max(1e-9);
        println!(
            "{:<8} {:>9.3} {:>10.3} {:>14.0} {:>14.0}  {}",
            backend.name(),
            r.setup_seconds,
            r.render_seconds,
            sps,
            rps,
            r.device
        );
        json.push(serde_json::json!({
            "backend": backend.name(), "device": r.device, "driver": r.driver,
            "setup_seconds": r.setup_seconds, "render_seconds": r.render_seconds,
            "samples_per_second": sps, "rays_per_second": rps, "rays": r.rays,
        }));
    }
    let ratio = rows[1].1.render_seconds / rows[0].1.render_seconds.max(1e-9);
    println!("gpu/cpu samples/s ratio: {ratio:.3}");
    if let Some(path) = &args.json {
        let doc = serde_json::json!({
            "scene": args.scene.scene.display().to_string(),
            "width": opts.width, "height": opts.height, "spp": opts.spp,
            "max_depth": opts.max_depth, "triangles": scene.triangles.len(),
            "backends": json, "gpu_over_cpu_samples_per_second": ratio,
        });
        let mut outputs = Outputs::new();
        let slot = outputs.reserve(path)?;
        outputs.write(slot, |w| {
            serde_json::to_writer_pretty(&mut *w, &doc)?;
            Ok(())
        })?;
        outputs.commit()?;
    }
    Ok(())
}

fn encode(
    film: &Film,
    w: &mut std::io::BufWriter<std::fs::File>,
    format: OutputFormat,
) -> Result<()> {
    film.encode(w, format).map_err(|e| anyhow!("{e}"))
}
