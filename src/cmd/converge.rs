//! `glint converge`: error against time. Each variant (a set of render
//! options laid over the shared ones) renders at each sample count or time
//! budget; every image is measured against a reference with
//! `glint_cpu::metrics`; the table, the per-variant efficiency, the
//! equal-time view and the log-log chart are written to DIR.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result, anyhow, bail};
use clap::Parser;
use glam::Vec3;
use glint::backend::{Backend, BackendRender};
use glint::cache::{KeyScope, SourceKey, render_key};
use glint::chart::{ChartSpec, Curve};
use glint::cpu::exr_file::{RadianceImage, RenderMeta};
use glint::cpu::metrics::{self, ImageRef, Metrics};
use glint::cpu::{Film, OutputFormat, RenderOptions, Scene};

use super::outputs::Outputs;
use super::{TIME_LIMIT_MAX_SPP, check_opts, encode, render_on, render_options};
use crate::cli::{ControlOpts, ConvergeArgs, RenderOpts, VariantCli};

/// The reference's seed: independent of every variant's stream.
const REFERENCE_SEED_XOR: u64 = 0x5851_f42d_4c95_7f2d;

/// One parsed `--variant NAME=OPTIONS`.
#[derive(Clone, Debug)]
pub struct Variant {
    pub name: String,
    pub backend: Backend,
    pub opts: RenderOpts,
    /// `--target-error` / `--adaptive`: each `--spp` budget is the cap.
    pub control: ControlOpts,
}

/// A variant's resolved backend, and its own scene and key where its
/// options load the scene differently from the shared ones.
type VariantScene = (Backend, Option<(Scene, SourceKey)>);

/// Parse `NAME=OPTIONS` with OPTIONS laid over the shared options.
pub fn parse_variant(spec: &str, shared: &RenderOpts) -> Result<Variant> {
    let Some((name, options)) = spec.split_once('=') else {
        bail!("--variant '{spec}': expected NAME=OPTIONS, e.g. 'gpu=--backend gpu'");
    };
    let name = name.trim();
    if name.is_empty()
        || !name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_.+".contains(c))
    {
        bail!("--variant '{spec}': the name must be letters, digits and - _ . + (it names files)");
    }
    let v = overlay(shared, options).map_err(|e| anyhow!("--variant '{spec}': {e}"))?;
    if v.opts.time_limit.is_some() {
        bail!("--variant '{spec}': --time-limit is converge's own (use --time)");
    }
    super::render::check_control(&v.control, false, false)
        .map_err(|e| anyhow!("--variant '{spec}': {e}"))?;
    Ok(Variant {
        name: name.to_string(),
        backend: v.backend,
        opts: v.opts,
        control: v.control,
    })
}

/// `options` (render's, and `--backend`, `--target-error`, `--adaptive`)
/// laid over `shared`; an error is clap's first line.
pub fn overlay(shared: &RenderOpts, options: &str) -> Result<VariantCli> {
    let mut argv = shared.to_args()?;
    argv.extend(options.split_whitespace().map(str::to_string));
    VariantCli::try_parse_from(&argv).map_err(|e| {
        let text = e.to_string();
        let first = text
            .lines()
            .next()
            .unwrap_or("")
            .trim_start_matches("error: ");
        anyhow!("{first}")
    })
}

/// What each render of a variant is given: a sample count or a budget.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    Spp(u32),
    Seconds(f64),
}

impl Budget {
    fn file_tag(self) -> String {
        match self {
            Budget::Spp(n) => n.to_string(),
            Budget::Seconds(t) => format!("{t}s"),
        }
    }
}

/// One measured render.
#[derive(Clone, Debug)]
pub struct Row {
    pub variant: String,
    pub backend: Backend,
    /// Samples per pixel reached: the mean over pixels (an adaptive render
    /// stops pixels early; a target-error one stops at a whole pass).
    pub spp: f64,
    pub seconds: f64,
    pub metrics: Metrics,
}

pub const CSV_HEADER: &str =
    "variant,backend,spp,seconds,relmse,relmse_trim,rmse,flip,mean_r,mean_g,mean_b";

pub fn csv(rows: &[Row]) -> String {
    let mut s = String::from(CSV_HEADER);
    s.push('\n');
    for r in rows {
        let m = &r.metrics;
        let _ = writeln!(
            s,
            "{},{},{},{:.6},{:.6e},{:.6e},{:.6e},{:.6},{:.6e},{:.6e},{:.6e}",
            r.variant,
            r.backend.name(),
            r.spp,
            r.seconds,
            m.relmse,
            m.relmse_trim,
            m.rmse,
            m.flip,
            m.mean.x,
            m.mean.y,
            m.mean.z
        );
    }
    s
}

/// Efficiency = 1 / (relMSE x seconds) (contract).
pub fn efficiency(relmse: f64, seconds: f64) -> f64 {
    1.0 / (relmse * seconds)
}

/// The error at time `t` on the log-log line through a variant's points
/// (sorted by time): interpolated inside, extended along the nearest
/// segment outside, along 1/t with a single point.
pub fn error_at(points: &[(f64, f64)], t: f64) -> f64 {
    let mut p: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
        .collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0));
    match p.len() {
        0 => f64::NAN,
        1 => p[0].1 * p[0].0 / t,
        n => {
            let i = p.windows(2).position(|w| t <= w[1].0).unwrap_or(n - 2);
            let ((t0, e0), (t1, e1)) = (p[i], p[i + 1]);
            if t1 <= t0 {
                return e0;
            }
            let s = (t.ln() - t0.ln()) / (t1.ln() - t0.ln());
            (e0.ln() + s * (e1.ln() - e0.ln())).exp()
        }
    }
}

/// The markdown report: the table, per-variant efficiency and the
/// equal-time view.
pub fn markdown(title: &str, command: &str, rows: &[Row], variants: &[Variant]) -> String {
    let mut s = format!("# glint converge: {title}\n\n`{command}`\n\n");
    s.push_str("| variant | backend | spp | seconds | relMSE | relMSE (trimmed) | RMSE | FLIP | efficiency 1/(relMSE s) |\n");
    s.push_str("|---|---|---:|---:|---:|---:|---:|---:|---:|\n");
    for r in rows {
        let m = &r.metrics;
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.3} | {:.3e} | {:.3e} | {:.3e} | {:.4} | {:.3e} |",
            r.variant,
            r.backend.name(),
            r.spp,
            r.seconds,
            m.relmse,
            m.relmse_trim,
            m.rmse,
            m.flip,
            efficiency(m.relmse, r.seconds)
        );
    }
    let pts = |v: &Variant| -> Vec<(f64, f64)> {
        rows.iter()
            .filter(|r| r.variant == v.name)
            .map(|r| (r.seconds, r.metrics.relmse))
            .collect()
    };
    // The slowest variant's smallest time: every variant has reached it.
    let t_eq = variants
        .iter()
        .filter_map(|v| pts(v).iter().map(|p| p.0).reduce(f64::min))
        .reduce(f64::max)
        .unwrap_or(f64::NAN);
    let _ = write!(
        s,
        "\n## Each variant\n\nEfficiency at the largest budget, and relMSE at equal time \
         ({t_eq:.3} s, the slowest variant's shortest render), interpolated on the log-log \
         line through its points.\n\n\
         | variant | efficiency (last point) | relMSE at {t_eq:.3} s | vs first variant |\n\
         |---|---:|---:|---:|\n"
    );
    let first = variants.first().map(|v| error_at(&pts(v), t_eq));
    for v in variants {
        let p = pts(v);
        let last = rows.iter().rfind(|r| r.variant == v.name);
        let eff = last.map_or(f64::NAN, |r| efficiency(r.metrics.relmse, r.seconds));
        let e = error_at(&p, t_eq);
        let ratio = first.map_or(f64::NAN, |f| f / e);
        let _ = writeln!(
            s,
            "| {} | {:.3e} | {:.3e} | {:.2}x |",
            v.name, eff, e, ratio
        );
    }
    s.push_str(
        "\n`vs first variant`: the first variant's relMSE over this one's at equal time \
         (above 1: this variant is ahead).\n\nrelMSE = mean over pixels and channels of \
         (x - r)^2 / (r^2 + 0.01); the trimmed form drops the 0.1% of pixels with the largest \
         error; FLIP is NVIDIA's FLIP of the 8-bit sRGB images; seconds are the render's \
         `render_seconds` (sampling alone).\n",
    );
    s
}

/// The reference's cache key: one exact render ([`KeyScope::Render`]).
pub fn reference_key(source: SourceKey, scene: &Scene, opts: &RenderOptions) -> String {
    render_key(source, scene, opts, KeyScope::Render)
}

/// Read a linear RGB EXR (or any image the `image` crate decodes).
/// A reference EXR's size and means: a regular file whose header the file
/// backs (`RadianceImage::read`), every value finite. A NaN or infinite
/// reference would put NaN in every row of the table: refused, exit 2.
pub fn read_exr(path: &Path) -> Result<(u32, u32, Vec<Vec3>)> {
    let img = read_reference(path)?;
    Ok((img.width, img.height, img.mean))
}

/// [`read_exr`]'s checked image, with what glint recorded in it.
fn read_reference(path: &Path) -> Result<RadianceImage> {
    let img = RadianceImage::read(path)
        .map_err(|e| anyhow!("{}: cannot read the image: {e}", path.display()))?;
    if let Some(at) = super::first_non_finite(img.width, &img.mean) {
        return Err(super::BadInput(format!(
            "{}: a non-finite value (NaN or infinite) at {at}; no error can be measured against it",
            path.display()
        ))
        .into());
    }
    Ok(img)
}

/// The CPU reference at `spp` for `base` (an independent seed), from the
/// cache when a render with the same key is there; written to the cache
/// whole or not at all. Cache problems only cost a re-render (a warning).
fn reference_image(
    path: &Path,
    source: SourceKey,
    scene: &Scene,
    base: &RenderOptions,
    spp: u32,
    shared: &RenderOpts,
) -> Result<(u32, u32, Vec<Vec3>)> {
    let opts = RenderOptions {
        spp,
        seed: base.seed ^ REFERENCE_SEED_XOR,
        time_limit: None,
        sample_start: 0,
        nee: true,
        mis: glint::cpu::Mis::Power,
        light_sampling: glint::cpu::LightSampling::default(),
        ..base.clone()
    };
    let key = reference_key(source, scene, &opts);
    let cached = glint::cache::cache_dir().map(|d| d.join("references").join(format!("{key}.exr")));
    if let Some(c) = &cached
        && c.is_file()
    {
        match read_exr(c) {
            Ok(img) if (img.0, img.1) == (opts.width, opts.height) => {
                eprintln!(
                    "glint: converge: reference from the cache ({})",
                    c.display()
                );
                return Ok(img);
            }
            _ => eprintln!(
                "glint: warning: {}: unreadable cached reference; rendering it again",
                c.display()
            ),
        }
    }
    eprintln!(
        "glint: converge: rendering the reference ({}x{}, {spp} spp, CPU)",
        opts.width, opts.height
    );
    let r = render_on(Backend::Cpu, path, shared, scene, &opts)?;
    if let Some(c) = &cached {
        let stored = c
            .parent()
            .map(std::fs::create_dir_all)
            .transpose()
            .map_err(|e| e.to_string())
            .and_then(|_| {
                // Through a temporary, so a crash leaves no half-written entry.
                let meta = super::shard::render_meta(
                    source,
                    scene,
                    &opts,
                    super::shard::Shard::WHOLE,
                    r.film.spp,
                );
                let mut bytes = std::io::Cursor::new(Vec::new());
                RadianceImage::from_film(&r.film, false, Some(meta))
                    .write(&mut bytes)
                    .map_err(|e| e.to_string())
                    .and_then(|_| {
                        glint::cpu::safe_fs::write_atomic(c, bytes.get_ref())
                            .map_err(|e| e.to_string())
                    })
            });
        if let Err(e) = stored {
            eprintln!("glint: warning: cannot cache the reference: {e}");
        }
    }
    Ok((opts.width, opts.height, r.film.means()))
}

fn title(path: &Path, rows: &[(Backend, String)]) -> String {
    let scene = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut devices: Vec<String> = Vec::new();
    for (_, d) in rows {
        if !devices.contains(d) {
            devices.push(d.clone());
        }
    }
    format!("{scene}: {}", devices.join(" / "))
}

pub fn run(args: &ConvergeArgs) -> Result<()> {
    // Everything that needs no file first: a bad command line reads and
    // creates nothing.
    let budgets: Vec<Budget> = match &args.time {
        Some(ts) => {
            if ts.is_empty() || ts.iter().any(|t| !(*t > 0.0 && t.is_finite())) {
                bail!("--time: every budget must be a positive number of seconds");
            }
            ts.iter().map(|&t| Budget::Seconds(t)).collect()
        }
        None => {
            if args.spp.is_empty() || args.spp.contains(&0) {
                bail!("--spp: every sample count must be at least 1");
            }
            args.spp.iter().map(|&n| Budget::Spp(n)).collect()
        }
    };
    if args.opts.time_limit.is_some() {
        bail!("--time-limit: use --time for converge's time budgets");
    }
    if args.reference_spp == Some(0) {
        bail!("--reference-spp must be at least 1");
    }
    check_opts(1, &args.opts)?;
    let specs: Vec<String> = if args.variants.is_empty() {
        vec!["gpu=--backend gpu".into(), "cpu=--backend cpu".into()]
    } else {
        args.variants.clone()
    };
    let variants: Vec<Variant> = specs
        .iter()
        .map(|s| parse_variant(s, &args.opts))
        .collect::<Result<_>>()?;
    for (i, v) in variants.iter().enumerate() {
        check_opts(1, &v.opts).map_err(|e| anyhow!("--variant {}: {e}", v.name))?;
        if variants[..i].iter().any(|w| w.name == v.name) {
            bail!("--variant {}: the name is used twice", v.name);
        }
    }
    if let Some(r) = &args.reference
        && !r.is_file()
    {
        bail!("{}: no such file", r.display());
    }

    // The folder and every output reserved before any rendering.
    let dir = &args.dir;
    let created = !dir.exists();
    if dir.exists() && !dir.is_dir() {
        bail!("{}: exists and is not a folder", dir.display());
    }
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    let result = run_in(args, &budgets, &variants, dir);
    if result.is_err() && created {
        // Only succeeds when nothing was left in it.
        let _ = std::fs::remove_dir(dir);
    }
    result
}

/// The render options of variant `v` at budget `b`: a sample count, or a
/// time budget (not with `--target-error` / `--adaptive`, which stop on the
/// error); the image must be the reference's size.
fn variant_options(
    scene: &Scene,
    path: &Path,
    v: &Variant,
    b: Budget,
    (rw, rh): (u32, u32),
    ref_name: &str,
) -> Result<RenderOptions> {
    let (spp, time_limit) = match b {
        Budget::Spp(n) => (n, None),
        Budget::Seconds(t) => (TIME_LIMIT_MAX_SPP, Some(t)),
    };
    if time_limit.is_some() && (v.control.target_error.is_some() || v.control.adaptive.is_some()) {
        bail!(
            "variant {}: --target-error and --adaptive stop on the error, not the clock: \
             give --spp budgets (each the cap), not --time",
            v.name
        );
    }
    let mut opts = render_options(scene, path, spp, &v.opts)?;
    opts.time_limit = time_limit;
    opts.target_error = v.control.target_error;
    opts.adaptive = v.control.adaptive;
    if (opts.width, opts.height) != (rw, rh) {
        bail!(
            "{ref_name} is {rw}x{rh} but variant {} renders {}x{} (set --width/--height to match)",
            v.name,
            opts.width,
            opts.height
        );
    }
    Ok(opts)
}

/// The chart of relMSE against render time, one curve per variant.
fn chart_spec(title: &str, rows: &[Row], variants: &[Variant]) -> ChartSpec {
    ChartSpec {
        title: title.to_string(),
        x_label: "render time (seconds, log)".into(),
        y_label: "relMSE (log)".into(),
        curves: variants
            .iter()
            .map(|v| Curve {
                label: v.name.clone(),
                points: rows
                    .iter()
                    .filter(|r| r.variant == v.name)
                    .map(|r| (r.seconds, r.metrics.relmse))
                    .collect(),
            })
            .collect(),
        guides: true,
    }
}

/// A warning where `--reference`'s recorded scene key (a glint EXR's)
/// is not the key of the shared options' image at its size: made from
/// other scene files or with other image options, it may not be the
/// image the variants converge to. Another renderer's EXR records none.
fn warn_on_reference_key(
    path: &Path,
    reference: &RadianceImage,
    source: SourceKey,
    scene: &Scene,
    base: &RenderOptions,
) {
    let Some(there) = &reference.meta else {
        return;
    };
    if there.scene.is_none() || (reference.width, reference.height) != (base.width, base.height) {
        return;
    }
    let here = super::shard::render_meta(source, scene, base, super::shard::Shard::WHOLE, 1);
    if let Some(why) = super::shard::key_mismatch(Some(&here), Some(there)) {
        eprintln!("glint: warning: {}: {why}", path.display());
    }
}

/// Each variant's own scene where its options change what the file loads
/// into (`--multiscatter`, `--background`, `--envmap`), with its key (the
/// reference stays the shared options' scene); None where it renders the
/// shared one. The files they read join `inputs`. A variant's GPU-only
/// options on the CPU backend are warned of here, once, and each variant's
/// backend resolved (`auto` asks Vulkan for a GPU once, not once a budget).
fn variant_scenes(
    args: &ConvergeArgs,
    variants: &[Variant],
    inputs: &mut Vec<std::path::PathBuf>,
) -> Result<Vec<VariantScene>> {
    let mut own = Vec::with_capacity(variants.len());
    for v in variants {
        let backend = super::check_gpu_only(&args.scene, &v.opts, v.backend)?
            .resolve(v.opts.device.as_deref());
        own.push((
            backend,
            if super::prepare_options(&v.opts) != super::prepare_options(&args.opts) {
                let (s, files) = super::load_with_inputs(&args.scene, &v.opts)?;
                let key = super::source_key(&files, &v.opts)?;
                inputs.extend(files);
                Some((s, key))
            } else {
                None
            },
        ));
    }
    Ok(own)
}

fn run_in(args: &ConvergeArgs, budgets: &[Budget], variants: &[Variant], dir: &Path) -> Result<()> {
    let mut outputs = Outputs::new();
    let csv_slot = outputs.reserve(&dir.join("converge.csv"))?;
    let md_slot = outputs.reserve(&dir.join("converge.md"))?;
    let svg_slot = outputs.reserve(&dir.join("converge.svg"))?;
    let png_slot = outputs.reserve(&dir.join("converge.png"))?;
    let mut image_slots = Vec::new();
    if args.keep_images {
        for v in variants {
            for b in budgets {
                let p = dir.join(format!("{}-{}.exr", v.name, b.file_tag()));
                image_slots.push(outputs.reserve(&p)?);
            }
        }
    }

    let (scene, mut inputs) = super::load_with_inputs(&args.scene, &args.opts)?;
    let source = super::source_key(&inputs, &args.opts)?;
    let own = variant_scenes(args, variants, &mut inputs)?;
    inputs.extend(args.reference.clone());
    outputs.refuse_inputs(&inputs)?;
    let base = render_options(&scene, &args.scene, 1, &args.opts)?;
    let (rw, rh, reference) = match (&args.reference, args.reference_spp) {
        (Some(p), _) => {
            let r = read_reference(p)?;
            warn_on_reference_key(p, &r, source, &scene, &base);
            (r.width, r.height, r.mean)
        }
        (None, Some(n)) => reference_image(&args.scene, source, &scene, &base, n, &args.opts)?,
        (None, None) => unreachable!("clap requires one of --reference and --reference-spp"),
    };
    let ref_name = args
        .reference
        .as_ref()
        .map(|p| p.display().to_string())
        .unwrap_or_else(|| "the reference".into());
    let reference_img = ImageRef::new(rw, rh, &reference)?;

    let mut rows = Vec::new();
    let mut devices = Vec::new();
    let mut films: Vec<(Film, RenderMeta)> = Vec::new();
    for (v, (backend, own)) in variants.iter().zip(&own) {
        let (scene, source) = own.as_ref().map_or((&scene, source), |(s, k)| (s, *k));
        for &b in budgets {
            let opts = variant_options(scene, &args.scene, v, b, (rw, rh), &ref_name)?;
            let r: BackendRender = render_on(*backend, &args.scene, &v.opts, scene, &opts)?;
            let means = r.film.means();
            let img = ImageRef::new(opts.width, opts.height, &means)?;
            let m = metrics::compute(&img, &reference_img)?;
            eprintln!(
                "glint: converge: {} {} spp: relMSE {:.3e} in {:.3} s",
                v.name,
                r.film.mean_spp(),
                m.relmse,
                r.render_seconds
            );
            devices.push((r.backend, r.device.clone()));
            rows.push(Row {
                variant: v.name.clone(),
                backend: r.backend,
                spp: r.film.mean_spp(),
                seconds: r.render_seconds,
                metrics: m,
            });
            if args.keep_images {
                let meta = super::shard::render_meta(
                    source,
                    scene,
                    &opts,
                    super::shard::Shard::WHOLE,
                    r.film.spp,
                );
                films.push((r.film, meta));
            }
        }
    }

    let command = std::env::args().collect::<Vec<_>>().join(" ");
    let title = title(&args.scene, &devices);
    let spec = chart_spec(&title, &rows, variants);
    let md = markdown(&title, &command, &rows, variants);
    let svg = glint::chart::svg(&spec)?;
    let png = glint::chart::png(&spec)?;
    use std::io::Write;
    outputs.write(csv_slot, |w| Ok(w.write_all(csv(&rows).as_bytes())?))?;
    outputs.write(md_slot, |w| Ok(w.write_all(md.as_bytes())?))?;
    outputs.write(svg_slot, |w| Ok(w.write_all(svg.as_bytes())?))?;
    outputs.write(png_slot, |w| Ok(w.write_all(&png)?))?;
    for (slot, (film, meta)) in image_slots.iter().zip(&films) {
        outputs.write(*slot, |w| {
            encode(film, w, OutputFormat::Exr, Some(meta), false)
        })?;
    }
    outputs.commit()?;
    print!("{md}");
    Ok(())
}
