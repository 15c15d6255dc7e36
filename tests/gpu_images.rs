//! Every scene in assets/ rendered by both backends and compared with the
//! statistical block test of `glint_cpu::compare` (Welch's z on 8x8 block
//! means, Sidak-corrected local test plus a binomial global test).
//!
//! The two renders use different seeds, so their noise is independent, as
//! Welch's test assumes (with equal seeds the backends trace the same paths:
//! that stronger, path-by-path agreement is tests/pathtrace_kernel.rs).
//! Seeds are fixed, so the outcome is deterministic for a given build.
//!
//! The test of the test: the same comparison must fail when one material
//! is perturbed by 5% on the GPU side only.
//!
//! On failure the two images and their difference are written to
//! `$CARGO_TARGET_TMPDIR/gpu_images/` for a person to look at.

mod common;

use std::path::{Path, PathBuf};

use glam::Vec3;
use glint::cpu::compare::{CompareReport, compare_films};
use glint::cpu::{Bsdf, Film, RenderOptions, Scene};
use glint::gpu::render::render_on;

/// Small and few samples: lavapipe is slow and CI has 2 cores; the block
/// test still has 36 blocks x 3 channels at this size.
const SIZE: u32 = 48;
const SPP: u32 = 64;

fn asset(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(name)
}

fn options(seed: u64) -> RenderOptions {
    RenderOptions {
        spp: SPP,
        max_depth: -1,
        seed,
        ..RenderOptions::new(SIZE, SIZE)
    }
}

fn gpu_film(ctx: &common::ValidatedContext, scene: &Scene) -> Film {
    render_on(ctx, scene, &options(2), &|_, _| {})
        .unwrap_or_else(|e| panic!("GPU render failed: {e}"))
        .film
}

fn cpu_film(scene: &Scene) -> Film {
    glint::cpu::render(scene, &options(1), &|_, _| {})
        .unwrap_or_else(|e| panic!("CPU render failed: {e}"))
        .0
}

/// Write both images and |difference| for inspection; returns the folder.
fn save_failure(name: &str, gpu: &Film, cpu: &Film) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("gpu_images");
    let _ = std::fs::create_dir_all(&dir);
    let mut diff = Film::new(gpu.width, gpu.height);
    diff.spp = 1;
    diff.sum = (0..gpu.sum.len())
        .map(|i| (gpu.mean(i) - cpu.mean(i)).abs())
        .collect();
    diff.sum_sq = vec![Vec3::ZERO; diff.sum.len()];
    for (film, suffix) in [(gpu, "gpu"), (cpu, "cpu"), (&diff, "difference")] {
        let _ = film.write_image(&dir.join(format!("{name}-{suffix}.exr")));
        let _ = film.write_image(&dir.join(format!("{name}-{suffix}.png")));
    }
    dir
}

/// Leave the scene as the file has it.
fn as_is(_: &mut Scene) {}

/// A bare mesh with no lights renders black on both backends, which
/// compares nothing: light it with a white background instead.
fn lit_by_background(scene: &mut Scene) {
    scene.background = Vec3::ONE;
}

/// The glass made an absorbing solid (KHR_materials_volume's
/// Beer-Lambert interior, read from the dielectric's k on the GPU).
fn absorbing_glass(scene: &mut Scene) {
    for m in &mut scene.materials {
        if matches!(m.bsdf, Bsdf::Dielectric { .. }) {
            m.absorption = Vec3::new(0.2, 0.8, 2.0);
        }
    }
}

/// Render `file` (after `prepare`, on both sides) with both backends; with
/// `perturb`, change the GPU's copy of the scene too.
fn compare_scene(
    file: &str,
    prepare: fn(&mut Scene),
    perturb: Option<&dyn Fn(&mut Scene)>,
) -> CompareReport {
    let ctx = common::context();
    let mut scene = glint::cpu::prepare::prepare_default(&asset(file))
        .unwrap_or_else(|e| panic!("{file}: {e}"));
    prepare(&mut scene);
    let cpu = cpu_film(&scene);
    let gpu = match perturb {
        None => gpu_film(&ctx, &scene),
        Some(f) => {
            let mut changed = scene.clone();
            f(&mut changed);
            gpu_film(&ctx, &changed)
        }
    };
    let report = compare_films(&gpu, &cpu).unwrap();
    if perturb.is_none() {
        eprintln!("{file}: {report}");
    }
    // Two black images would pass while proving nothing.
    let lit = (0..cpu.sum.len())
        .filter(|&i| cpu.mean(i).max_element() > 0.0)
        .count();
    assert!(
        lit * 4 >= cpu.sum.len(),
        "{file}: only {lit} of {} pixels see any light",
        cpu.sum.len()
    );
    if !report.pass && perturb.is_none() {
        let dir = save_failure(file, &gpu, &cpu);
        panic!(
            "{file}: GPU and CPU disagree: {report}\nimages in {}",
            dir.display()
        );
    }
    report
}

/// Every diffuse material made a smooth non-metal under a rough clear
/// coat (KHR_materials_clearcoat, roughness 0.5): the kernel needs its
/// rough code for the coat although the material under it is smooth.
fn rough_clearcoat(scene: &mut Scene) {
    for m in &mut scene.materials {
        if let Bsdf::Diffuse { reflectance } = m.bsdf {
            m.bsdf = Bsdf::Coated {
                base: reflectance,
                coat: glint::cpu::bsdf::coated::CoatParams {
                    clearcoat: 0.8,
                    clearcoat_alpha: 0.25,
                    ..glint::cpu::bsdf::coated::CoatParams::GLTF_DEFAULT
                },
                roughness: glint::cpu::bsdf::Roughness::SMOOTH,
            };
        }
    }
}

/// Clear coats on the textured scene: a smooth one over "bumps" (its
/// normal map tilts the base, not the coat, which keeps the unmapped
/// normal) and a rough one over the floor, tilted by the bumps' normal
/// texture as its clearcoatNormalTexture.
fn clearcoat_normals(scene: &mut Scene) {
    let index = |scene: &Scene, name: &str| {
        scene
            .materials
            .iter()
            .position(|m| m.name == name)
            .unwrap_or_else(|| panic!("no material {name}"))
    };
    let bumps = index(scene, "bumps");
    let floor = index(scene, "checker floor");
    let normal = scene.textures.materials[bumps].normal;
    assert!(normal.is_some(), "bumps has a normal texture");
    for (i, c, a) in [(bumps, 0.8, 0.0), (floor, 1.0, 0.09)] {
        match &mut scene.materials[i].bsdf {
            Bsdf::Coated { coat, .. } | Bsdf::Metallic { coat, .. } => {
                coat.clearcoat = c;
                coat.clearcoat_alpha = a;
            }
            other => panic!("{other:?} has no coat"),
        }
    }
    scene.textures.materials[floor].clearcoat_normal = normal;
}

macro_rules! scene_tests {
    ($($test:ident => $file:literal, $prepare:expr;)*) => {
        $(
            #[test]
            fn $test() {
                compare_scene($file, $prepare, None);
            }
        )*
        /// Every scene file in assets/ has a test above.
        #[test]
        fn every_asset_is_compared() {
            let covered = [$($file),*];
            let mut missing = Vec::new();
            for entry in std::fs::read_dir(asset("")).unwrap() {
                let name = entry.unwrap().file_name().to_string_lossy().into_owned();
                let scene = name.ends_with(".gltf") || name.ends_with(".glb");
                if scene && !covered.contains(&name.as_str()) {
                    missing.push(name);
                }
            }
            assert!(missing.is_empty(), "assets without a GPU/CPU comparison: {missing:?}");
        }
    };
}

scene_tests! {
    cornell => "cornell.gltf", as_is;
    diffuse => "diffuse.gltf", as_is;
    conductor => "conductor.gltf", as_is;
    roughconductor => "roughconductor.gltf", as_is;
    dielectric => "dielectric.gltf", as_is;
    roughdielectric => "roughdielectric.gltf", as_is;
    bunny => "bunny.glb", as_is;
    bunny_white_sky => "bunny.glb", lit_by_background;
    textured => "textured.gltf", as_is;
    materials => "materials.gltf", as_is;
    textured_envmap => "textured.gltf", with_envmap;
    dielectric_absorbing => "dielectric.gltf", absorbing_glass;
    diffuse_rough_clearcoat => "diffuse.gltf", rough_clearcoat;
    textured_clearcoat_normals => "textured.gltf", clearcoat_normals;
}

/// A procedural sky (a blue gradient with a small bright sun) as an
/// environment map, turned 30 degrees, in place of the background.
fn with_envmap(scene: &mut Scene) {
    let (w, h) = (32u32, 16u32);
    let mut rgb = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let t = y as f32 / h as f32;
            let sun = if (x, y) == (9, 4) { 40.0 } else { 0.0 };
            rgb.push([0.2 + 0.6 * t + sun, 0.3 + 0.4 * t + sun, 0.6 + sun]);
        }
    }
    scene.background = Vec3::ZERO;
    scene.envmap = Some(std::sync::Arc::new(glint::cpu::envmap::EnvMap::new(
        w,
        h,
        &rgb,
        0.8,
        std::f32::consts::FRAC_PI_6,
    )));
}

/// Scale material `name`'s reflectance (diffuse) or specular reflectance
/// (conductor) by 1.05, on the GPU side only.
fn brighten(scene: &mut Scene, name: &str) {
    let m = scene
        .materials
        .iter_mut()
        .find(|m| m.name == name)
        .unwrap_or_else(|| panic!("no material named {name}"));
    match &mut m.bsdf {
        Bsdf::Diffuse { reflectance } => *reflectance *= 1.05,
        Bsdf::Conductor(c) => c.specular_reflectance *= 1.05,
        // A dielectric has no albedo: its one parameter, the IOR.
        Bsdf::Dielectric { eta, .. } => *eta *= 1.05,
        other => panic!("material {name} is {other:?}"),
    }
}

/// `scene` rendered as is against `scene` with `material` perturbed by
/// `brighten`: the comparison must fail. `what` names the perturbation.
fn assert_perturbation_caught(scene: &str, material: &str, what: &str) {
    let report = compare_scene(scene, as_is, Some(&|s: &mut Scene| brighten(s, material)));
    eprintln!("{what}: {report}");
    assert!(!report.pass, "{what} went unnoticed: {report}");
}

#[test]
fn comparison_catches_a_5_percent_diffuse_error() {
    // The Cornell box's white walls, floor and ceiling.
    assert_perturbation_caught("cornell.gltf", "white", "a 5% brighter diffuse reflectance");
}

#[test]
fn comparison_catches_a_5_percent_conductor_error() {
    // The smooth gold sphere.
    assert_perturbation_caught("conductor.gltf", "conductor", "a 5% brighter conductor");
}

#[test]
fn comparison_catches_a_5_percent_error_on_a_small_object() {
    // The diffuse asset's sphere, about 17 px across at 48 px: a few 8x8
    // blocks. (The Cornell box's spheres are one block at 48 px and its
    // glass caustics make 64 spp too noisy there: z near 2 even at 96 px.)
    assert_perturbation_caught("diffuse.gltf", "diffuse", "a 5% brighter small sphere");
}

#[test]
fn comparison_catches_a_5_percent_dielectric_error() {
    // The dielectric asset's smooth glass sphere, its IOR 5% high.
    assert_perturbation_caught(
        "dielectric.gltf",
        "dielectric",
        "a 5% higher IOR on the glass sphere",
    );
}
