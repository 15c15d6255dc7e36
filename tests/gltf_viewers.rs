//! Issue 20's rendered behaviours on both backends (GPU on lavapipe under
//! the validation layer, and the CPU reference), on small self-made scenes
//! (`cpu/tests/fixtures/viewer_scenes.rs`): the KHR_texture_transform
//! rotation convention, BLEND as stochastic transparency (camera and
//! shadow rays), and normal-mapped glossy spheres without black rims.

mod common;

#[path = "../cpu/tests/fixtures/gltf_builder.rs"]
mod builder;
#[path = "../cpu/tests/fixtures/viewer_scenes.rs"]
mod viewer;

use std::path::Path;

use glam::Vec3;
use glint::cpu::{Film, RenderOptions, Scene};
use glint::gpu::render::render_on;

fn options(size: u32, spp: u32, seed: u64) -> RenderOptions {
    RenderOptions {
        spp,
        max_depth: -1,
        seed,
        ..RenderOptions::new(size, size)
    }
}

/// The scene rendered by the GPU (seed `seed`) and the CPU (seed + 1).
fn both(
    ctx: &common::ValidatedContext,
    path: &Path,
    size: u32,
    spp: u32,
    seed: u64,
) -> [(&'static str, Film); 2] {
    let scene: Scene = glint::cpu::prepare::prepare_default(path).unwrap_or_else(|e| panic!("{e}"));
    let gpu = render_on(ctx, &scene, &options(size, spp, seed), &|_, _| {})
        .unwrap_or_else(|e| panic!("GPU render failed: {e}"))
        .film;
    let cpu = glint::cpu::render(&scene, &options(size, spp, seed + 1), &|_, _| {})
        .unwrap()
        .0;
    [("gpu", gpu), ("cpu", cpu)]
}

#[test]
fn texture_rotation_puts_each_quadrant_where_the_convention_does() {
    let ctx = common::context();
    let path = viewer::rotated_quadrants("rotation_both");
    let want = viewer::rotated_quadrant_colours();
    for (backend, f) in both(&ctx, &path, 8, 8, 0) {
        for (k, (x, y)) in [(1, 1), (6, 1), (1, 6), (6, 6)].into_iter().enumerate() {
            let p = f.mean(f.index(x, y));
            assert!(
                (p - want[k]).abs().max_element() < 0.02,
                "{backend}: pixel ({x}, {y}) = {p}, want {}",
                want[k]
            );
        }
    }
}

#[test]
fn blend_quad_of_alpha_0_3_transmits_70_percent_to_camera_and_shadow_rays() {
    let ctx = common::context();
    let path = viewer::blend_over_floor("blend_both");
    let (size, spp) = (16u32, 64u32);
    // Every sample is 0 or 1 (floor seen and lit, or not): a Bernoulli
    // mean of p = 0.49 over size^2 spp samples; 6 sigma.
    let n = (size * size * spp) as f32;
    let tol = 6.0 * (0.49f32 * 0.51 / n).sqrt();
    let mut means = Vec::new();
    for (backend, f) in both(&ctx, &path, size, spp, 7) {
        let m = (0..(size * size) as usize).map(|i| f.mean(i)).sum::<Vec3>() / (size * size) as f32;
        assert!(
            (m.x - 0.49).abs() < tol && (m.x - m.y).abs() < 1e-5,
            "{backend}: mean {m}, want 0.49 +- {tol}"
        );
        means.push(m.x);
    }
    assert!(
        (means[0] - means[1]).abs() < tol * std::f32::consts::SQRT_2,
        "gpu {} cpu {}",
        means[0],
        means[1]
    );
}

#[test]
fn normal_mapped_white_furnace_loses_nothing_on_either_backend() {
    let ctx = common::context();
    // A white Lambertian under a 60-degree map in a white sky: folded at
    // the geometric surface (glint_cpu::bsdf::fold, shaders/bsdf/fold.glsl)
    // it reflects everything, as the unmapped one does (0.998 on the CPU,
    // cpu/tests/gltf_viewers.rs); discarding what the tilted lobe sends
    // into the surface kept 0.882 (measured on the CPU).
    let path = viewer::mapped_sphere(
        "furnace_fold",
        viewer::white_diffuse(),
        Some(60f32.to_radians()),
    );
    let (size, spp) = (12u32, 16u32);
    let mut means = Vec::new();
    for (backend, f) in both(&ctx, &path, size, spp, 5) {
        let n = (f.width * f.height) as usize;
        let m = (0..n).map(|i| f.mean(i).x).sum::<f32>() / n as f32;
        let se = (0..n).map(|i| f.variance_of_mean(i).x).sum::<f32>().sqrt() / n as f32;
        assert!(
            (m - 1.0).abs() < 5.0 * se + 5e-3,
            "{backend}: furnace mean {m} (standard error {se})"
        );
        means.push(m);
    }
    eprintln!(
        "furnace under a 60-degree map: gpu {} cpu {}",
        means[0], means[1]
    );
}

#[test]
fn normal_mapped_glossy_sphere_has_no_black_rims_on_either_backend() {
    let ctx = common::context();
    // As cpu/tests/gltf_viewers.rs: the smooth metal keeps (nearly) all,
    // the rough one too, folded (darkest pixel at 8 spp 0.79 on both
    // backends; 0.25 was the bound when the part of the lobe below the
    // surface was discarded).
    for (name, r, least) in [("rims_smooth", 0.0, 0.95), ("rims_rough", 0.3, 0.55)] {
        let path = viewer::mapped_sphere(name, viewer::metal(r), Some(50f32.to_radians()));
        let mut means = Vec::new();
        for (backend, f) in both(&ctx, &path, 12, 8, 3) {
            let n = (f.width * f.height) as usize;
            for i in 0..n {
                let p = f.mean(i);
                assert!(p.min_element() > least, "{backend} {name}: pixel {i} = {p}");
            }
            means.push((0..n).map(|i| f.mean(i).x).sum::<f32>() / n as f32);
        }
        assert!(
            (means[0] - means[1]).abs() < 0.03,
            "{name}: gpu {} cpu {}",
            means[0],
            means[1]
        );
    }
}
