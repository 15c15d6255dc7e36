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
use crate::cli::RenderArgs;
use crate::stats::Stats;

pub fn run(args: &RenderArgs) -> Result<()> {
    let start = Instant::now();
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
    let shard = args.shard.unwrap_or(Shard::WHOLE);
    if args.shard.is_some() && args.scene.opts.time_limit.is_some() {
        bail!(
            "--shard and --time-limit cannot be combined (a shard's samples are fixed in advance)"
        );
    }
    if args.variance && !formats.contains(&OutputFormat::Exr) {
        eprintln!("glint: warning: --variance: no .exr output to hold it");
    }
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

    let (scene, inputs) = load_with_inputs(&args.scene.scene, &args.scene.opts)?;
    // Before anything renders: no output may overwrite what the scene read
    // (its buffers and images, the environment map).
    outputs.refuse_inputs(&inputs)?;
    let mut opts = render_options(
        &scene,
        &args.scene.scene,
        spp_of(args.scene.spp, &args.scene.opts),
        &args.scene.opts,
    )?;
    if args.shard.is_some() {
        shard::apply(&mut opts, shard)?;
    }
    let load_seconds = start.elapsed().as_secs_f64();
    let r = render_on(
        args.backend,
        &args.scene.scene,
        &args.scene.opts,
        &scene,
        &opts,
    )?;

    let meta = shard::render_meta(&scene, &opts, shard, r.film.spp);
    for (&slot, &format) in image_slots.iter().zip(&formats) {
        outputs.write(slot, |w| encode(&r.film, w, format, &meta, args.variance))?;
    }
    if let Some(slot) = stats_slot {
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
            options: &opts,
            kernel: r.kernel.map(|k| k.name()),
            traversal: r.traversal.map(|t| t.name()),
            features: r.features.names(),
        };
        outputs.write(slot, |w| {
            serde_json::to_writer_pretty(&mut *w, &st.to_json())?;
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
