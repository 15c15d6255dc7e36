//! `glint bench`.

use anyhow::{Result, bail};
use glint::backend::{Backend, BackendRender};

use super::outputs::Outputs;
use super::{check_params, load_scene, render_on};
use crate::cli::BenchArgs;

/// `glint bench`: the same scene and options on both backends, in one run
/// on one machine, so the figures compare; the fastest of `--repeat` renders
/// per backend counts. Prints a table and the GPU/CPU ratio.
pub fn run(args: &BenchArgs) -> Result<()> {
    check_params(&args.scene)?;
    if args.repeat == 0 {
        bail!("--repeat must be at least 1");
    }
    // Output paths are checked (reserved) before any rendering.
    let mut outputs = Outputs::new();
    let json_slot = args.json.as_ref().map(|p| outputs.reserve(p)).transpose()?;
    let (scene, opts) = load_scene(&args.scene)?;
    let pixels = opts.width as f64 * opts.height as f64;
    // The BVH build again, timed alone (loading built it once already).
    let t = std::time::Instant::now();
    let (bvh, _) = glint::cpu::Bvh::build(&scene.triangles);
    let bvh_seconds = t.elapsed().as_secs_f64();
    let mut rows = Vec::new();
    for backend in [Backend::Gpu, Backend::Cpu] {
        let mut best: Option<BackendRender> = None;
        for _ in 0..args.repeat {
            let r = render_on(backend, &args.scene.scene, &args.scene.opts, &scene, &opts)?;
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
        "{}: {}x{}, {} spp, max depth {}, {} triangles; BVH {} nodes, depth {}, built in {:.4} s",
        args.scene.scene.display(),
        opts.width,
        opts.height,
        opts.spp,
        opts.max_depth,
        scene.triangles.len(),
        bvh.nodes.len(),
        bvh.depth(),
        bvh_seconds
    );
    println!(
        "{:<8} {:>9} {:>10} {:>14} {:>14}  device",
        "backend", "setup s", "render s", "samples/s", "rays/s"
    );
    let mut json = Vec::new();
    for (backend, r) in &rows {
        let sps = pixels * r.film.spp as f64 / r.render_seconds.max(1e-9);
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
    let sps = |r: &BackendRender| pixels * r.film.spp as f64 / r.render_seconds.max(1e-9);
    let ratio = sps(&rows[0].1) / sps(&rows[1].1).max(1e-9);
    println!("gpu/cpu samples/s ratio: {ratio:.3}");
    if let Some(json_slot) = json_slot {
        let doc = serde_json::json!({
            "scene": args.scene.scene.display().to_string(),
            "width": opts.width, "height": opts.height, "spp": opts.spp,
            "max_depth": opts.max_depth, "triangles": scene.triangles.len(),
            "bvh_nodes": bvh.nodes.len(), "bvh_depth": bvh.depth(),
            "bvh_build_seconds": bvh_seconds,
            "backends": json, "gpu_over_cpu_samples_per_second": ratio,
        });
        let slot = json_slot;
        outputs.write(slot, |w| {
            serde_json::to_writer_pretty(&mut *w, &doc)?;
            Ok(())
        })?;
        outputs.commit()?;
    }
    Ok(())
}
