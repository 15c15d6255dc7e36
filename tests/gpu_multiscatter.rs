//! Energy-compensated GGX (`multiscatter`) on the GPU: a white furnace of
//! the roughconductor and roughdielectric assets with every surface an
//! F = 1 rough conductor (or rough glass) under a background of radiance
//! 1 renders 1 on the objects' pixels with compensation, and visibly less
//! without it (the CPU crate bounds that loss from both sides against the
//! quadrature: cpu/tests/bsdf_multiscatter.rs); the GPU
//! image agrees with the CPU crate's (the per-call agreement is
//! tests/gpu_bsdf.rs, the per-path one tests/pathtrace_kernel.rs).

mod common;

use std::path::Path;

use glam::Vec3;
use glint::cpu::bsdf::{ConductorParams, Roughness, Shadowing};
use glint::cpu::compare::compare_films;
use glint::cpu::{Bsdf, Film, RenderOptions, Scene};
use glint::gpu::render::render_on;

/// The asset with every material replaced by `bsdf`, lights removed and
/// a white background. For glass only the asset's dielectric object stays
/// (a closed sphere): an open glass floor would trap light in its
/// unbounded "inside", which no furnace survives.
fn furnace(asset: &str, bsdf: Bsdf) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(asset);
    let mut s = glint::cpu::prepare::prepare_default(&path).unwrap();
    if matches!(bsdf, Bsdf::Dielectric { .. }) {
        let glass: Vec<bool> = s
            .materials
            .iter()
            .map(|m| matches!(m.bsdf, Bsdf::Dielectric { .. }))
            .collect();
        s.triangles.retain(|t| glass[t.material as usize]);
        assert!(!s.triangles.is_empty(), "{asset}: no glass object");
    }
    for m in &mut s.materials {
        m.bsdf = bsdf;
        m.emission = Vec3::ZERO;
    }
    s.lights.clear();
    s.background = Vec3::ONE;
    s.build_bvh();
    s
}

fn rough(alpha: f32, ms: bool) -> Roughness {
    Roughness {
        alpha_u: alpha,
        alpha_v: alpha,
        shadowing: Shadowing::Correlated,
        multiscatter: ms,
    }
}

/// The pixels the furnace measures: those that see only geometry (a
/// render of depth 1 shows the background, exactly 1, everywhere else,
/// and an emission-free surface as exactly 0). Averaging the background
/// in would dilute the error.
fn object_pixels(scene: &Scene, opts: &RenderOptions) -> Vec<usize> {
    let o = RenderOptions {
        max_depth: 1,
        spp: 16,
        ..opts.clone()
    };
    let f = glint::cpu::render(scene, &o, &|_, _| {}).unwrap().0;
    let px: Vec<usize> = (0..f.sum.len()).filter(|&i| f.mean(i).x == 0.0).collect();
    assert!(px.len() > f.sum.len() / 10, "{} object pixels", px.len());
    px
}

fn mean(f: &Film, px: &[usize]) -> f64 {
    px.iter().map(|&i| f.mean(i).x as f64).sum::<f64>() / px.len() as f64
}

#[test]
fn gpu_white_furnace_is_one_with_multiscatter() {
    let ctx = common::context();
    let opts = RenderOptions {
        spp: 64,
        seed: 5,
        ..RenderOptions::new(32, 32)
    };
    let white = |alpha, ms| {
        Bsdf::Conductor(ConductorParams {
            // eta = 1, k = 1e4: F = 1 - O(1e-8) at every angle.
            eta: Vec3::ONE,
            k: Vec3::splat(1e4),
            specular_reflectance: Vec3::ONE,
            roughness: rough(alpha, ms),
        })
    };
    let glass = |alpha, ms| Bsdf::Dielectric {
        eta: 1.5,
        roughness: rough(alpha, ms),
        tint: glint::cpu::bsdf::Tint::NONE,
    };
    // (scene, compensated, tolerance), over the objects' pixels: the glass
    // furnace compounds the tables' ~0.3% interpolation error over internal
    // bounces. On this asset's sphere (larger in frame than the CPU test's,
    // more internal bounces per pixel) both backends measure 2-2.5% low
    // (GPU 0.977, CPU 0.981 at 32x32, 64 spp): allowed 3%. The whole-image
    // average this test used to take, 43% background at exactly 1, hid it.
    let cases = [
        ("roughconductor.gltf", white(1.0, true), true, 0.01),
        ("roughconductor.gltf", white(0.5, true), true, 0.01),
        ("roughconductor.gltf", white(1.0, false), false, 0.0),
        ("roughdielectric.gltf", glass(1.0, true), true, 0.03),
        ("roughdielectric.gltf", glass(1.0, false), false, 0.0),
    ];
    for (asset, bsdf, ms, tol) in cases {
        let scene = furnace(asset, bsdf);
        let gpu = render_on(&ctx, &scene, &opts, &|_, _| {}).unwrap().film;
        // The CPU crate's image, another seed: the same statistically.
        let cpu = glint::cpu::render(
            &scene,
            &RenderOptions {
                seed: 6,
                ..opts.clone()
            },
            &|_, _| {},
        )
        .unwrap()
        .0;
        let px = object_pixels(&scene, &opts);
        let (m, mc) = (mean(&gpu, &px), mean(&cpu, &px));
        eprintln!("{asset} {bsdf:?}: furnace mean GPU {m:.4}, CPU {mc:.4}");
        if ms {
            assert!((m - 1.0).abs() < tol, "{asset} {bsdf:?}: {m}");
        } else {
            assert!(m < 0.9, "{asset} single scattering: {m}");
        }
        let r = compare_films(&gpu, &cpu).unwrap();
        assert!(r.pass, "{asset} {bsdf:?}: GPU vs CPU: {r}");
    }
    assert!(ctx.finish().is_empty());
}
