//! Kernels specialised to a scene's features (`--kernel specialized`)
//! against the generic kernel, and the persistent pipeline cache.
//!
//! With the same seed both kernels trace the same paths (the specialised
//! one only lacks code the scene never reaches), so almost every pixel must
//! agree to float rounding, for every bundled scene and for variants that
//! switch single features off (no bounces, no NEE). (`materials.gltf` was
//! left out while its specialised kernel took minutes of cold LLVM
//! compilation on lavapipe; since its glTF models call each part once per
//! site it takes 19 s.)

mod common;

use std::path::{Path, PathBuf};

use ash::vk;
use glint::cpu::features::Features;
use glint::cpu::{Film, RenderOptions, Scene};
use glint::gpu::render::{KernelChoice, Traversal, render_with};

fn asset(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(name)
}

fn render(ctx: &common::ValidatedContext, s: &Scene, o: &RenderOptions, k: KernelChoice) -> Film {
    let r = render_with(
        ctx,
        s,
        o,
        (k, Traversal::Software),
        vk::PipelineCache::null(),
        &|_, _| {},
    )
    .unwrap();
    assert_eq!(r.kernel, k);
    assert_eq!(
        r.features,
        match k {
            KernelChoice::Specialized => Features::of(s, o),
            KernelChoice::Generic => Features::ALL,
        }
    );
    r.film
}

/// The feature bits are declared once (`glint_cpu::abi`'s F_*, from which
/// the GLSL `#define`s are generated); each has one name for `glint info`
/// and `--stats`, and together they are the generic kernel's set.
#[test]
fn every_feature_bit_has_one_name() {
    let names = Features::ALL.names();
    assert_eq!(names.len() as u32, Features::ALL.0.count_ones());
    for (i, n) in names.iter().enumerate() {
        assert!(!names[..i].contains(n), "{n} twice");
    }
    for b in 0..32 {
        let f = Features(1 << b);
        let want = usize::from(Features::ALL.has(1 << b));
        assert_eq!(f.names().len(), want, "bit {b}");
    }
}

/// The specialisation on textures and alpha masks is exact: the bits are
/// set where the kernel's `Params.textured` and `Params.masked` are, so a
/// kernel built without them never meets a scene that needs their code.
#[test]
fn texture_bits_are_the_params_the_kernel_reads() {
    let mut seen = [false; 2];
    for file in [
        "cornell.gltf",
        "conductor.gltf",
        "dielectric.gltf",
        "diffuse.gltf",
        "materials.gltf",
        "roughconductor.gltf",
        "roughdielectric.gltf",
        "textured.gltf",
        "bunny.glb",
    ] {
        let scene = glint::cpu::prepare::prepare_default(&asset(file)).unwrap();
        let o = RenderOptions::new(8, 8);
        let f = Features::of(&scene, &o);
        let p = glint::cpu::integrator::gpu_scene_data(&scene, &o)
            .unwrap()
            .params;
        assert_eq!(f.has(Features::TEXTURES), p.textured != 0, "{file}");
        assert_eq!(f.has(Features::ALPHA_MASKS), p.masked != 0, "{file}");
        seen[0] |= p.textured != 0;
        seen[1] |= p.masked != 0;
    }
    // Both bits are met set (textured.gltf has textures and an alpha mask).
    assert_eq!(seen, [true, true]);
}

#[test]
fn specialised_and_generic_kernels_give_the_same_image() {
    let ctx = common::context();
    let cases: [(&str, i32, bool); 11] = [
        ("cornell.gltf", -1, true),
        ("dielectric.gltf", 1, true),
        ("diffuse.gltf", -1, true),
        ("diffuse.gltf", 3, false),
        ("conductor.gltf", 3, true),
        ("roughconductor.gltf", -1, true),
        ("dielectric.gltf", -1, true),
        ("roughdielectric.gltf", 4, true),
        ("bunny.glb", 2, true),
        // Normal-mapped: the fold (feature normal-map) on both kernels;
        // textures and alpha masks.
        ("textured.gltf", -1, true),
        // The glTF coated non-metal and metallic blend side by side.
        ("materials.gltf", -1, true),
    ];
    for (file, max_depth, nee) in cases {
        let mut scene = glint::cpu::prepare::prepare_default(&asset(file)).unwrap();
        if scene.lights.is_empty() && scene.emitter_triangles().is_empty() {
            scene.background = glam::Vec3::ONE;
        }
        let o = RenderOptions {
            spp: 8,
            max_depth,
            nee,
            seed: 3,
            ..RenderOptions::new(32, 24)
        };
        let f = Features::of(&scene, &o);
        let what = format!("{file} depth {max_depth} nee {nee} ({:?})", f.names());
        let a = render(&ctx, &scene, &o, KernelChoice::Specialized);
        let b = render(&ctx, &scene, &o, KernelChoice::Generic);
        let close = (0..a.sum.len())
            .filter(|&i| {
                let (x, y) = (a.sum[i], b.sum[i]);
                (x - y).abs().max_element() <= 1e-3 * x.abs().max(y.abs()).max_element().max(1e-3)
            })
            .count();
        assert!(
            close as f64 >= 0.99 * a.sum.len() as f64,
            "{what}: only {close} of {} pixels agree",
            a.sum.len()
        );
        let lit = a.sum.iter().filter(|s| s.max_element() > 0.0).count();
        assert!(lit * 4 > a.sum.len(), "{what}: a dark image proves nothing");
    }
    assert!(ctx.finish().is_empty());
}

#[test]
fn pipeline_cache_survives_runs_and_corruption() {
    let dir = std::env::temp_dir().join(format!("glint-pcache-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let cache = dir.join("pipelines.bin");
    let run = || {
        std::process::Command::new(env!("CARGO_BIN_EXE_glint"))
            .env("GLINT_CACHE_DIR", &dir)
            .args(["render", asset("diffuse.gltf").to_str().unwrap(), "-o"])
            .arg(dir.join("x.png"))
            .args(["--backend", "gpu", "--width", "8", "--spp", "1"])
            .output()
            .unwrap()
    };
    let o = run();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let first = std::fs::read(&cache).expect("the cache is written");
    // A second run of the same scene compiles nothing new: the driver's
    // cache data does not grow, and the file is left as it was.
    let o = run();
    assert!(o.status.success());
    assert_eq!(std::fs::read(&cache).unwrap(), first);

    // Corrupt and truncated files: a warning, then a render as usual.
    let mut bad = first.clone();
    let mid = bad.len() / 2;
    bad[mid] ^= 0x5a;
    for contents in [bad, first[..first.len() - 3].to_vec(), b"garbage".to_vec()] {
        std::fs::write(&cache, &contents).unwrap();
        let o = run();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{err}");
        assert!(
            err.contains("warning") && err.contains("pipeline cache ignored"),
            "{err}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
