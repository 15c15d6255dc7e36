//! shaders/pathtrace.comp against the CPU path tracer it mirrors.
//!
//! Both draw the same random numbers for a sample (with either sampler:
//! glint_cpu::sampling / shaders/integrator/rng.glsl, glint_cpu::sobol /
//! shaders/integrator/sobol.glsl), so
//! they trace the same paths up to float rounding: almost every pixel must
//! agree to 1e-3 relative, the ray counts nearly exactly, and the images
//! must pass the statistical comparison (which a systematic error in one
//! backend fails even where rounding makes paths diverge).

mod common;

use std::path::Path;

use glint::cpu::compare::compare_films;
use glint::cpu::integrator::gpu_scene_data;
use glint::cpu::{Film, RenderOptions, SamplerKind, Scene};
use glint::gpu::render::{SceneBytes, render_film};

fn gpu_render(ctx: &common::ValidatedContext, scene: &Scene, opts: &RenderOptions) -> (Film, u64) {
    let d = gpu_scene_data(scene, opts).unwrap();
    let bytes = SceneBytes::new(scene, &d);
    let r = render_film(
        ctx,
        "pathtrace",
        &bytes,
        opts.width,
        opts.height,
        opts.spp,
        &|_, _| {},
    )
    .unwrap();
    (r.film, r.stats.rays)
}

#[test]
fn gpu_kernel_traces_the_cpu_paths() {
    let ctx = common::context();
    let cases = [
        ("cornell.gltf", -1),
        ("cornell.gltf", 2),
        ("dielectric.gltf", -1),
        ("roughdielectric.gltf", -1),
        ("roughconductor.gltf", -1),
        ("conductor.gltf", 3),
        ("textured.gltf", -1),
    ];
    let samplers = [SamplerKind::Sobol, SamplerKind::Independent];
    // "+ms": every rough lobe energy-compensated (`multiscatter`).
    let cases = cases.into_iter().chain([
        ("roughconductor.gltf+ms", -1),
        ("roughdielectric.gltf+ms", -1),
    ]);
    for ((asset, max_depth), sampler) in cases.flat_map(|c| samplers.map(|s| (c, s))) {
        let (file, ms) = match asset.strip_suffix("+ms") {
            Some(f) => (f, true),
            None => (asset, false),
        };
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("assets")
            .join(file);
        let mut scene = glint::cpu::prepare::prepare_default(&path).unwrap();
        if ms {
            let mut rough = 0;
            for m in &mut scene.materials {
                let r = match &mut m.bsdf {
                    glint::cpu::Bsdf::Conductor(c) => &mut c.roughness,
                    glint::cpu::Bsdf::Dielectric { roughness, .. } => roughness,
                    glint::cpu::Bsdf::Metallic { conductor, .. } => &mut conductor.roughness,
                    glint::cpu::Bsdf::Coated { roughness, .. } => roughness,
                    glint::cpu::Bsdf::Diffuse { .. }
                    | glint::cpu::Bsdf::Plastic(_)
                    | glint::cpu::Bsdf::RoughPlastic(_)
                    | glint::cpu::Bsdf::ThinDielectric { .. } => continue,
                };
                if !r.is_smooth() {
                    r.multiscatter = true;
                    rough += 1;
                }
            }
            assert!(rough > 0, "{asset}: no rough lobe to compensate");
        }
        let opts = RenderOptions {
            spp: 16,
            max_depth,
            seed: 7,
            sampler,
            // Sobol films in variance batches of 4 (independent: 1).
            variance_batch: 4,
            ..RenderOptions::new(40, 32)
        };
        let (gpu, gpu_rays) = gpu_render(&ctx, &scene, &opts);
        let (cpu, cpu_stats) = glint::cpu::render(&scene, &opts, &|_, _| {}).unwrap();
        let what = format!("{asset} max_depth {max_depth} {}", sampler.name());

        let r = compare_films(&gpu, &cpu).unwrap();
        assert!(r.pass, "{what}: {r}");
        assert_eq!(
            (gpu.batch, cpu.batch),
            (opts.batch(), opts.batch()),
            "{what}"
        );
        let near = |a: glam::Vec3, b: glam::Vec3| {
            (a - b).abs().max_element() <= 1e-3 * a.abs().max(b.abs()).max_element().max(1e-3)
        };
        // The same paths give the same sums and the same batch sums.
        let close = (0..cpu.sum.len())
            .filter(|&i| near(gpu.sum[i], cpu.sum[i]) && near(gpu.batch_sq[i], cpu.batch_sq[i]))
            .count();
        assert!(
            close as f64 >= 0.99 * cpu.sum.len() as f64,
            "{what}: only {close} of {} pixels trace the same paths",
            cpu.sum.len()
        );
        let rel = (gpu_rays as f64 - cpu_stats.rays as f64).abs() / cpu_stats.rays as f64;
        assert!(rel < 0.01, "{what}: rays {gpu_rays} vs {}", cpu_stats.rays);
    }
    assert!(ctx.finish().is_empty());
}
