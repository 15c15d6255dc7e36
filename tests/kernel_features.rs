//! Kernels specialised to a scene's features (`--kernel specialized`)
//! against the generic kernel, and the persistent pipeline cache.
//!
//! With the same seed both kernels trace the same paths (the specialised
//! one only lacks code the scene never reaches), so almost every pixel must
//! agree to float rounding, for the bundled scenes but two and for variants
//! that switch single features off (no bounces, no NEE). `textured.gltf` and
//! `materials.gltf` are left out: their specialised kernels cost minutes of
//! cold LLVM compilation each on a fresh lavapipe machine (measured: the
//! test ran past 18 minutes with them); their kernels are checked against
//! the CPU per image by `tests/gpu_images.rs` and per call by
//! `tests/gpu_bsdf.rs`.

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

#[test]
fn the_glsl_feature_bits_are_the_rust_ones() {
    let src = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders/features.glsl"),
    )
    .unwrap();
    let rust = [
        ("F_DIFFUSE", Features::DIFFUSE),
        ("F_CONDUCTOR", Features::CONDUCTOR),
        ("F_DIELECTRIC", Features::DIELECTRIC),
        ("F_METALLIC", Features::METALLIC),
        ("F_ROUGH", Features::ROUGH),
        ("F_ANISOTROPIC", Features::ANISOTROPIC),
        ("F_SMITH_CORRELATED", Features::SMITH_CORRELATED),
        ("F_SMITH_SEPARABLE", Features::SMITH_SEPARABLE),
        ("F_AREA_LIGHTS", Features::AREA_LIGHTS),
        ("F_POINT_SPOT", Features::POINT_SPOT),
        ("F_DIRECTIONAL", Features::DIRECTIONAL),
        ("F_BACKGROUND", Features::BACKGROUND),
        ("F_BOUNCES", Features::BOUNCES),
        ("F_NEE", Features::NEE),
        ("F_COATED", Features::COATED),
        ("F_PLASTIC", Features::PLASTIC),
        ("F_THIN_DIELECTRIC", Features::THIN_DIELECTRIC),
        ("F_NORMAL_MAP", Features::NORMAL_MAP),
    ];
    let mut defined = 0;
    for line in src.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        if w.len() == 3 && w[0] == "#define" && w[1].starts_with("F_") {
            let v: u32 = w[2].trim_end_matches('u').parse().unwrap();
            let (_, want) = rust
                .iter()
                .find(|(n, _)| *n == w[1])
                .unwrap_or_else(|| panic!("{} has no Rust twin", w[1]));
            assert_eq!(v, *want, "{}", w[1]);
            defined += 1;
        }
    }
    assert_eq!(defined, rust.len());
    let all = rust.iter().fold(0, |a, (_, b)| a | b);
    assert_eq!(Features::ALL.0, all);
}

#[test]
fn specialised_and_generic_kernels_give_the_same_image() {
    let ctx = common::context();
    let cases: [(&str, i32, bool); 10] = [
        ("cornell.gltf", -1, true),
        ("dielectric.gltf", 1, true),
        ("diffuse.gltf", -1, true),
        ("diffuse.gltf", 3, false),
        ("conductor.gltf", 3, true),
        ("roughconductor.gltf", -1, true),
        ("dielectric.gltf", -1, true),
        ("roughdielectric.gltf", 4, true),
        ("bunny.glb", 2, true),
        // Normal-mapped: the fold (feature normal-map) on both kernels.
        ("textured.gltf", -1, true),
    ];
    for (file, max_depth, nee) in cases {
        let mut scene = glint::cpu::loader::load(&asset(file)).unwrap();
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
