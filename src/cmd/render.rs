//! `glint render`.

use std::time::Instant;

use anyhow::{Result, bail};
use glint::cpu::OutputFormat;

use super::outputs::Outputs;
use super::shard::{self, Shard};
use super::{
    check_params, check_scene_path, encode, load_with_inputs, render_on, render_options, same_file,
    spp_of,
};
use crate::cli::{ControlOpts, RenderArgs};
use crate::stats::Stats;

/// `--target-error` and `--adaptive`: positive numbers, and neither with
/// `--shard` or `--time-limit` (one line each saying why).
pub fn check_control(c: &ControlOpts, shard: bool, time_limit: bool) -> Result<()> {
    for (name, v) in [
        ("--target-error", c.target_error),
        ("--adaptive", c.adaptive),
    ] {
        let Some(v) = v else { continue };
        let refuse = |m: String| Err(super::BadInput(m).into());
        if !(v > 0.0 && v.is_finite()) {
            return refuse(format!("{name} {v} is out of range (a positive number)"));
        }
        if shard {
            return refuse(format!(
                "{name} and --shard cannot be combined (a shard cannot stop on the whole render's error: its samples are fixed in advance)"
            ));
        }
        if time_limit {
            return refuse(format!(
                "{name} and --time-limit cannot be combined (the error, not the clock, decides when it stops)"
            ));
        }
    }
    Ok(())
}

/// `--stats` of a controlled render: `estimated_relmse`, `mean_spp` (and
/// `spp`, the most any pixel reached), the samples actually taken.
fn control_stats(
    mut v: serde_json::Value,
    film: &glint::cpu::Film,
    opts: &glint::cpu::RenderOptions,
) -> serde_json::Value {
    if opts.target_error.is_none() && opts.adaptive.is_none() {
        return v;
    }
    let relmse = glint::cpu::adaptive::estimated_relmse(film);
    v["estimated_relmse"] = serde_json::json!(relmse);
    v["mean_spp"] = serde_json::json!(film.mean_spp());
    if let Some(e) = opts.target_error {
        v["target_error"] = serde_json::json!(e);
    }
    if let Some(t) = opts.adaptive {
        v["adaptive"] = serde_json::json!(t);
        let samples = (film.mean_spp() * film.sum.len() as f64).round();
        v["samples"] = serde_json::json!(samples as u64);
        let secs = v["render_seconds"].as_f64().unwrap_or(0.0);
        if secs > 0.0 {
            v["samples_per_second"] = serde_json::json!(samples / secs);
        }
    }
    v
}

/// Everything about the arguments that can be refused before the scene is
/// read; the output formats, in `args.outputs`' order.
fn check_args(args: &RenderArgs) -> Result<Vec<OutputFormat>> {
    check_params(&args.scene)?;
    for o in args.outputs.iter().chain(&args.stats) {
        if super::outputs::names_same(o, &args.scene.scene) || same_file(o, &args.scene.scene) {
            bail!(
                "{}: is the input scene; refusing to overwrite it",
                o.display()
            );
        }
    }
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
    check_scene_path(&args.scene.scene)?;
    if args.shard.is_some() && args.scene.opts.time_limit.is_some() {
        bail!(
            "--shard and --time-limit cannot be combined (a shard's samples are fixed in advance)"
        );
    }
    check_control(
        &args.control,
        args.shard.is_some(),
        args.scene.opts.time_limit.is_some(),
    )?;
    if args.variance && !formats.contains(&OutputFormat::Exr) {
        eprintln!("glint: warning: --variance: no .exr output to hold it");
    }
    Ok(formats)
}

/// The `--stats` record of a finished render.
fn stats_json(
    args: &RenderArgs,
    scene: &glint::cpu::Scene,
    opts: &glint::cpu::RenderOptions,
    r: &glint::backend::BackendRender,
    load_seconds: f64,
) -> serde_json::Value {
    let st = Stats {
        // The backend that ran (`auto` resolved).
        backend: r.backend.name(),
        device: r.device.clone(),
        driver: r.driver.clone(),
        scene: args.scene.scene.display().to_string(),
        width: opts.width,
        height: opts.height,
        spp: r.film.spp,
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
        options: opts,
        kernel: r.kernel.map(|k| k.name()),
        traversal: r.traversal.map(|t| t.name()),
        ray_tracing: r.traversal.and_then(|t| t.api()),
        features: r.features.names(),
    };
    control_stats(st.to_json(), &r.film, opts)
}

pub fn run(args: &RenderArgs) -> Result<()> {
    let start = Instant::now();
    let formats = check_args(args)?;
    let shard = args.shard.unwrap_or(Shard::WHOLE);
    super::QUIET.store(args.quiet, std::sync::atomic::Ordering::Relaxed);

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

    let backend = super::check_gpu_only(&args.scene.scene, &args.scene.opts, args.backend)?;
    let (scene, inputs) = load_with_inputs(&args.scene.scene, &args.scene.opts)?;
    // Before anything renders: no output may overwrite what the scene read
    // (its buffers and images, the environment map).
    outputs.refuse_inputs(&inputs)?;
    // Only an EXR records what it was rendered from; its scene key hashes
    // every file the scene read (the textures' too), so a PNG skips it.
    let source = formats
        .contains(&OutputFormat::Exr)
        .then(|| super::source_key(&inputs, &args.scene.opts))
        .transpose()?;
    let mut opts = render_options(
        &scene,
        &args.scene.scene,
        spp_of(args.scene.spp, &args.scene.opts),
        &args.scene.opts,
    )?;
    if args.shard.is_some() {
        shard::apply(&mut opts, shard)?;
    }
    opts.target_error = args.control.target_error;
    opts.adaptive = args.control.adaptive;
    let load_seconds = start.elapsed().as_secs_f64();
    let r = render_on(backend, &args.scene.scene, &args.scene.opts, &scene, &opts)?;

    let meta = source.map(|s| shard::render_meta(s, &scene, &opts, shard, r.film.spp));
    for (&slot, &format) in image_slots.iter().zip(&formats) {
        outputs.write(slot, |w| {
            encode(&r.film, w, format, meta.as_ref(), args.variance)
        })?;
    }
    if let Some(slot) = stats_slot {
        let json = stats_json(args, &scene, &opts, &r, load_seconds);
        outputs.write(slot, |w| {
            serde_json::to_writer_pretty(&mut *w, &json)?;
            use std::io::Write;
            writeln!(w)?;
            Ok(())
        })?;
    }
    outputs.commit()?;
    if !args.quiet {
        let names: Vec<String> = args
            .outputs
            .iter()
            .chain(&args.stats)
            .map(|p| p.display().to_string())
            .collect();
        let part = if args.shard.is_some() {
            format!(
                ", shard {shard}: samples {}..{}",
                opts.sample_start,
                opts.sample_start + r.film.spp
            )
        } else {
            String::new()
        };
        eprintln!(
            "glint: wrote {} ({} spp{part}, {:.2} s)",
            names.join(", "),
            r.film.spp,
            start.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
