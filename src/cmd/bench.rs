//! `glint bench`.

use anyhow::{Result, bail};
use glint::backend::{Backend, BackendRender, Traversal};

use super::outputs::Outputs;
use super::{check_params, load_scene, render_on};
use crate::cli::{BenchArgs, RenderOpts, TraversalArg};

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
        "{:<8} {:<9} {:>9} {:>10} {:>14} {:>14}  device",
        "backend", "traversal", "setup s", "render s", "samples/s", "rays/s"
    );
    let mut json = Vec::new();
    let sps = |r: &BackendRender| pixels * r.film.spp as f64 / r.render_seconds.max(1e-9);
    for (backend, r) in &rows {
        let rps = r.rays as f64 / r.render_seconds.max(1e-9);
        let traversal = r.traversal.map_or("-", |t| t.name());
        println!(
            "{:<8} {:<9} {:>9.3} {:>10.3} {:>14.0} {:>14.0}  {}",
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
        }
        json.push(row);
    }
    let cpu = &rows[rows.len() - 1].1;
    let ratio = sps(&rows[0].1) / sps(cpu).max(1e-9);
    println!("gpu/cpu samples/s ratio: {ratio:.3}");
    // With both traversals: hardware over software, on the GPU.
    let by = |t: Traversal| {
        rows.iter()
            .find(|(_, r)| r.traversal == Some(t))
            .map(|(_, r)| sps(r))
    };
    let hw_over_sw = match (by(Traversal::Hardware), by(Traversal::Software)) {
        (Some(h), Some(s)) if args.compare_traversals => Some(h / s.max(1e-9)),
        _ => None,
    };
    if let Some(x) = hw_over_sw {
        println!("gpu hardware/software traversal samples/s ratio: {x:.3}");
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
        if let Some(x) = hw_over_sw {
            doc["hardware_over_software_samples_per_second"] = serde_json::json!(x);
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

/// The rows of the table, each the fastest of `--repeat` renders: the GPU
/// with the options' traversal (then the other one, with
/// `--compare-traversals`), then the CPU.
fn render_rows(
    args: &BenchArgs,
    scene: &glint::cpu::Scene,
    opts: &glint::cpu::RenderOptions,
) -> Result<Vec<(Backend, BackendRender)>> {
    let given = args.scene.opts.traversal;
    let mut runs = vec![(Backend::Gpu, given)];
    if args.compare_traversals {
        for t in [TraversalArg::Software, TraversalArg::Hardware] {
            if t != given {
                runs.push((Backend::Gpu, t));
            }
        }
    }
    runs.push((Backend::Cpu, given));
    let mut rows = Vec::new();
    for (backend, traversal) in runs {
        let ro = RenderOpts {
            traversal,
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
