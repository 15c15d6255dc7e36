//! `glint bench`.

use anyhow::{Result, bail};
use glint::backend::{Backend, BackendRender, Traversal};

use super::outputs::Outputs;
use super::{check_params, load_scene, render_on};
use crate::cli::{BenchArgs, RayTracingArg, RenderOpts, TraversalArg};

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
    let rows = render_rows(args, &scene, &opts)?;
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
        "{:<8} {:<20} {:>9} {:>10} {:>14} {:>14}  device",
        "backend", "traversal", "setup s", "render s", "samples/s", "rays/s"
    );
    let mut json = Vec::new();
    let sps = |r: &BackendRender| pixels * r.film.spp as f64 / r.render_seconds.max(1e-9);
    for (backend, r) in &rows {
        let rps = r.rays as f64 / r.render_seconds.max(1e-9);
        let traversal = r.traversal.map_or("-".to_string(), traversal_label);
        println!(
            "{:<8} {:<20} {:>9.3} {:>10.3} {:>14.0} {:>14.0}  {}",
            backend.name(),
            traversal,
            r.setup_seconds,
            r.render_seconds,
            sps(r),
            rps,
            r.device
        );
        let mut row = serde_json::json!({
            "backend": backend.name(), "device": r.device, "driver": r.driver,
            "setup_seconds": r.setup_seconds, "render_seconds": r.render_seconds,
            "samples_per_second": sps(r), "rays_per_second": rps, "rays": r.rays,
        });
        if let Some(t) = r.traversal {
            row["traversal"] = serde_json::json!(t.name());
            if let Some(api) = t.api() {
                row["ray_tracing"] = serde_json::json!(api);
            }
        }
        json.push(row);
    }
    let cpu = &rows[rows.len() - 1].1;
    let ratio = sps(&rows[0].1) / sps(cpu).max(1e-9);
    println!("gpu/cpu samples/s ratio: {ratio:.3}");
    // With every traversal: each hardware API over software, on the GPU.
    let by = |t: Traversal| {
        rows.iter()
            .find(|(_, r)| r.traversal == Some(t))
            .map(|(_, r)| sps(r))
    };
    let mut hw_over_sw = serde_json::Map::new();
    if let (true, Some(s)) = (args.compare_traversals, by(Traversal::Software)) {
        for t in [Traversal::RayQuery, Traversal::Pipeline] {
            if let (Some(h), Some(api)) = (by(t), t.api()) {
                let x = h / s.max(1e-9);
                println!("gpu hardware ({api})/software traversal samples/s ratio: {x:.3}");
                hw_over_sw.insert(api.to_string(), serde_json::json!(x));
            }
        }
    }
    if let Some(json_slot) = json_slot {
        let doc = serde_json::json!({
            "scene": args.scene.scene.display().to_string(),
            "width": opts.width, "height": opts.height, "spp": opts.spp,
            "max_depth": opts.max_depth, "triangles": scene.triangles.len(),
            "bvh_nodes": bvh.nodes.len(), "bvh_depth": bvh.depth(),
            "bvh_build_seconds": bvh_seconds,
            "backends": json, "gpu_over_cpu_samples_per_second": ratio,
        });
        let mut doc = doc;
        if !hw_over_sw.is_empty() {
            doc["hardware_over_software_samples_per_second"] = hw_over_sw.into();
        }
        let slot = json_slot;
        outputs.write(slot, |w| {
            serde_json::to_writer_pretty(&mut *w, &doc)?;
            Ok(())
        })?;
        outputs.commit()?;
    }
    Ok(())
}

/// "software", or "hardware (query)" / "hardware (pipeline)".
fn traversal_label(t: Traversal) -> String {
    match t.api() {
        Some(api) => format!("{} ({api})", t.name()),
        None => t.name().to_string(),
    }
}

/// The rows of the table, each the fastest of `--repeat` renders: the GPU
/// with the options' traversal (with `--compare-traversals`: software,
/// then hardware by each API the device has), then the CPU.
fn render_rows(
    args: &BenchArgs,
    scene: &glint::cpu::Scene,
    opts: &glint::cpu::RenderOptions,
) -> Result<Vec<(Backend, BackendRender)>> {
    let given = (args.scene.opts.traversal, args.scene.opts.ray_tracing);
    let mut runs = vec![(Backend::Gpu, given)];
    if args.compare_traversals {
        runs[0].1 = (TraversalArg::Software, RayTracingArg::Auto);
        let rt = glint::gpu::context::ray_tracing_support(args.scene.opts.device.as_deref())?;
        for (has, api) in [
            (rt.query, RayTracingArg::Query),
            (rt.pipeline.is_some(), RayTracingArg::Pipeline),
        ] {
            if has {
                runs.push((Backend::Gpu, (TraversalArg::Hardware, api)));
            } else {
                eprintln!("warning: the device has no {api:?} ray tracing: its row is left out");
            }
        }
    }
    runs.push((Backend::Cpu, given));
    let mut rows = Vec::new();
    for (backend, (traversal, ray_tracing)) in runs {
        let ro = RenderOpts {
            traversal,
            ray_tracing,
            ..args.scene.opts.clone()
        };
        let mut best: Option<BackendRender> = None;
        for _ in 0..args.repeat {
            let r = render_on(backend, &args.scene.scene, &ro, scene, opts)?;
            if best
                .as_ref()
                .is_none_or(|b| r.render_seconds < b.render_seconds)
            {
                best = Some(r);
            }
        }
        rows.push((backend, best.expect("repeat >= 1")));
    }
    Ok(rows)
}
