//! `glint render`.

use std::time::Instant;

use anyhow::{Result, bail};
use glint::cpu::OutputFormat;

use super::outputs::Outputs;
use super::{check_params, check_scene_path, encode, load_scene, render_on};
use crate::cli::RenderArgs;
use crate::stats::Stats;

pub fn run(args: &RenderArgs) -> Result<()> {
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
    check_scene_path(&args.scene.scene)?;

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
    let r = render_on(
        args.backend,
        &args.scene.scene,
        &args.scene.opts,
        &scene,
        &opts,
    )?;

    for (&slot, &format) in image_slots.iter().zip(&formats) {
        outputs.write(slot, |w| encode(&r.film, w, format))?;
    }
    if let Some(slot) = stats_slot {
        let st = Stats {
            backend: args.backend.name(),
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
            features: r.features.names(),
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
