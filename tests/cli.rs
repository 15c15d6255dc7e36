//! The `glint` binary end to end: outputs, stats, and the contract's error
//! behaviour (one line on stderr, non-zero status, no output file).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn glint() -> Command {
    Command::new(env!("CARGO_BIN_EXE_glint"))
}

/// A fresh, empty scratch directory for one test.
fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("glint-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A tiny glTF with an external buffer: a diffuse floor (y = 0), an
/// emissive quad facing the camera, and a camera at (0, 1, 3) looking down
/// -Z with aspectRatio 1.5.
fn write_scene(dir: &Path) -> PathBuf {
    let pos: [[f32; 3]; 8] = [
        [-2.0, 0.0, 2.0],
        [2.0, 0.0, 2.0],
        [2.0, 0.0, -2.0],
        [-2.0, 0.0, -2.0],
        [-0.5, 0.5, -1.0],
        [0.5, 0.5, -1.0],
        [0.5, 1.5, -1.0],
        [-0.5, 1.5, -1.0],
    ];
    let idx: [u16; 12] = [0, 1, 2, 0, 2, 3, 0, 1, 2, 0, 2, 3];
    let mut bytes: Vec<u8> = pos.iter().flatten().flat_map(|f| f.to_le_bytes()).collect();
    bytes.extend(idx.iter().flat_map(|i| i.to_le_bytes()));
    std::fs::write(dir.join("scene.bin"), &bytes).unwrap();
    let gltf = format!(
        r#"{{
  "asset": {{ "version": "2.0" }},
  "scene": 0,
  "scenes": [ {{ "nodes": [0, 1, 2] }} ],
  "nodes": [
    {{ "mesh": 0 }},
    {{ "mesh": 1 }},
    {{ "camera": 0, "name": "main", "translation": [0, 1, 3] }}
  ],
  "cameras": [ {{ "type": "perspective", "name": "main",
                  "perspective": {{ "yfov": 0.8, "aspectRatio": 1.5, "znear": 0.01 }} }} ],
  "meshes": [
    {{ "primitives": [ {{ "attributes": {{ "POSITION": 0 }}, "indices": 2, "material": 0 }} ] }},
    {{ "primitives": [ {{ "attributes": {{ "POSITION": 1 }}, "indices": 3, "material": 1 }} ] }}
  ],
  "materials": [
    {{ "name": "floor", "pbrMetallicRoughness": {{ "baseColorFactor": [0.8, 0.8, 0.8, 1], "metallicFactor": 0 }} }},
    {{ "name": "light", "emissiveFactor": [1, 1, 1],
       "extensions": {{ "KHR_materials_emissive_strength": {{ "emissiveStrength": 4 }} }} }}
  ],
  "extensionsUsed": [ "KHR_materials_emissive_strength" ],
  "buffers": [ {{ "uri": "scene.bin", "byteLength": {len} }} ],
  "bufferViews": [
    {{ "buffer": 0, "byteOffset": 0, "byteLength": 48 }},
    {{ "buffer": 0, "byteOffset": 48, "byteLength": 48 }},
    {{ "buffer": 0, "byteOffset": 96, "byteLength": 12 }},
    {{ "buffer": 0, "byteOffset": 108, "byteLength": 12 }}
  ],
  "accessors": [
    {{ "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
       "min": [-2, 0, -2], "max": [2, 0, 2] }},
    {{ "bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3",
       "min": [-0.5, 0.5, -1], "max": [0.5, 1.5, -1] }},
    {{ "bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR" }},
    {{ "bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR" }}
  ]
}}"#,
        len = bytes.len()
    );
    let path = dir.join("scene.gltf");
    std::fs::write(&path, gltf).unwrap();
    path
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// The contract's failure shape: non-zero status, exactly one non-empty
/// line on stderr, containing `needle`.
fn assert_one_line_error(out: &Output, needle: &str) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "expected failure, stderr: {err}");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "one line on stderr, got: {err:?}");
    assert!(
        lines[0].contains(needle),
        "stderr {:?} should mention {needle:?}",
        lines[0]
    );
    assert!(
        !err.contains("panicked") && !err.contains("backtrace"),
        "{err}"
    );
}

#[test]
fn renders_png_and_exr_with_stats() {
    let dir = scratch("ok");
    let scene = write_scene(&dir);
    let (png, exr, stats) = (dir.join("a.png"), dir.join("a.exr"), dir.join("s.json"));
    let out = glint()
        .arg("render")
        .arg(&scene)
        .args(["-o"])
        .arg(&png)
        .args(["--output"])
        .arg(&exr)
        .args(["--backend", "cpu", "--spp", "4", "--width", "48", "--stats"])
        .arg(&stats)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // 48 wide, height from the camera's aspectRatio 1.5.
    let img = image::open(&png).unwrap();
    assert_eq!((img.width(), img.height()), (48, 32));
    let hdr = image::open(&exr).unwrap().into_rgb32f();
    assert_eq!((hdr.width(), hdr.height()), (48, 32));
    // The emitter is in the middle of the view: radiance 4 there, and the
    // PNG clamps it to 255.
    let centre = hdr.get_pixel(24, 14);
    assert!(
        centre.0.iter().all(|&c| (c - 4.0).abs() < 1e-4),
        "{centre:?}"
    );
    assert_eq!(img.to_rgb8().get_pixel(24, 14).0, [255, 255, 255]);
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
    for key in [
        "backend",
        "device",
        "width",
        "height",
        "spp",
        "max_depth",
        "triangles",
        "setup_seconds",
        "render_seconds",
        "samples_per_second",
        "rays_per_second",
    ] {
        assert!(v.get(key).is_some(), "stats lack {key}: {v}");
    }
    assert_eq!(v["backend"], "cpu");
    // The build the stats name is the one `--version` names (and the
    // EXR's glint.build, checked in cli_regression).
    let version = glint().arg("--version").output().unwrap();
    let version = String::from_utf8_lossy(&version.stdout).trim().to_string();
    assert!(
        version.starts_with(concat!("glint ", env!("CARGO_PKG_VERSION"))),
        "{version}"
    );
    match v["glint_build"].as_str() {
        Some(b) => assert!(
            version.ends_with(&format!("(build {b})")),
            "{version} / {b}"
        ),
        None => assert!(!version.contains("build"), "{version}"),
    }
    #[cfg(target_os = "linux")]
    assert!(v["glint_build"].is_string(), "{v}");
    assert_eq!(
        (v["width"].as_u64(), v["height"].as_u64()),
        (Some(48), Some(32))
    );
    assert_eq!(v["spp"], 4);
    assert_eq!(v["max_depth"], -1);
    assert_eq!(v["triangles"], 4);
    assert!(v["rays_per_second"].as_f64().unwrap() > 0.0);
    // Nothing but the inputs and the three outputs.
    assert_eq!(
        files_in(&dir),
        ["a.exr", "a.png", "s.json", "scene.bin", "scene.gltf"]
    );

    // Same seed: the same image; height alone keeps the aspect.
    let again = dir.join("b.exr");
    let out = glint()
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(&again)
        .args(["--backend", "cpu", "--spp", "4", "--height", "32"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(image::open(&again).unwrap().into_rgb32f(), hdr);
    // The camera by name and by index is the same camera; another seed
    // gives another image.
    for (camera, seed, same) in [("main", "0", true), ("0", "0", true), ("0", "9", false)] {
        let out = glint()
            .arg("render")
            .arg(&scene)
            .arg("-o")
            .arg(&again)
            .args(["--backend", "cpu", "--spp", "4", "--width", "48"])
            .args(["--camera", camera, "--seed", seed])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert_eq!(
            image::open(&again).unwrap().into_rgb32f() == hdr,
            same,
            "{camera} {seed}"
        );
    }

    // Without a camera in the default scene: the documented default
    // viewpoint, aspect 1.
    let text = std::fs::read_to_string(&scene).unwrap();
    let no_cam = dir.join("nocam.gltf");
    std::fs::write(
        &no_cam,
        text.replace(r#""nodes": [0, 1, 2]"#, r#""nodes": [0, 1]"#),
    )
    .unwrap();
    let out = glint()
        .arg("render")
        .arg(&no_cam)
        .arg("-o")
        .arg(&png)
        .args(["--backend", "cpu", "--spp", "2", "--width", "20"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let img = image::open(&png).unwrap().to_rgb8();
    assert_eq!((img.width(), img.height()), (20, 20));
    assert!(
        img.pixels().any(|p| p.0 != [0, 0, 0]),
        "the default view sees the scene"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_inputs_fail_with_one_line_and_no_output() {
    let dir = scratch("bad");
    let scene = write_scene(&dir);
    let bad_json = dir.join("broken.gltf");
    std::fs::write(&bad_json, "{ this is not json").unwrap();
    let out_png = dir.join("out.png");
    let s = |p: &Path| p.to_string_lossy().into_owned();
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec![s(&dir.join("missing.gltf")), "-o".into(), s(&out_png)],
            "missing.gltf",
        ),
        (vec![s(&bad_json), "-o".into(), s(&out_png)], "broken.gltf"),
        (
            vec![
                s(&scene),
                "-o".into(),
                s(&out_png),
                "--spp".into(),
                "0".into(),
            ],
            "spp",
        ),
        (
            vec![
                s(&scene),
                "-o".into(),
                s(&out_png),
                "--spp".into(),
                "many".into(),
            ],
            "spp",
        ),
        (
            vec![
                s(&scene),
                "-o".into(),
                s(&out_png),
                "--width".into(),
                "0".into(),
            ],
            "width",
        ),
        (
            vec![
                s(&scene),
                "-o".into(),
                s(&out_png),
                "--height".into(),
                "20000".into(),
            ],
            "height",
        ),
        (
            vec![
                s(&scene),
                "-o".into(),
                s(&out_png),
                "--max-depth".into(),
                "0".into(),
            ],
            "max-depth",
        ),
        (
            vec![
                s(&scene),
                "-o".into(),
                s(&out_png),
                "--max-depth".into(),
                "-2".into(),
            ],
            "max-depth",
        ),
        (
            vec![s(&scene), "-o".into(), s(&dir.join("out.jpg"))],
            "out.jpg",
        ),
        (
            vec![s(&scene), "-o".into(), s(&dir.join("no/such/dir/out.png"))],
            "out.png",
        ),
        (
            vec![
                s(&scene),
                "-o".into(),
                s(&out_png),
                "--camera".into(),
                "nosuch".into(),
            ],
            "nosuch",
        ),
        (
            vec![
                s(&scene),
                "-o".into(),
                s(&out_png),
                "--camera".into(),
                "7".into(),
            ],
            "scene.gltf",
        ),
        (
            vec![
                s(&scene),
                "-o".into(),
                s(&out_png),
                "--backend".into(),
                "tpu".into(),
            ],
            "tpu",
        ),
        // No Vulkan device has this name, whether or not Vulkan works here.
        (
            vec![
                s(&scene),
                "-o".into(),
                s(&out_png),
                "--backend".into(),
                "gpu".into(),
                "--device".into(),
                "no-such-device-xyzzy".into(),
            ],
            "scene.gltf",
        ),
        (vec![s(&scene)], "output"),
        // An output in a folder that is not there: said plainly, before
        // anything renders.
        (
            vec![s(&scene), "-o".into(), s(&dir.join("nodir").join("x.png"))],
            "cannot write: no folder",
        ),
    ];
    assert_one_line_error(&glint().output().unwrap(), "missing command");
    assert_one_line_error(&glint().arg("paint").output().unwrap(), "paint");
    // The compare verb validates the same way.
    for (args, needle) in [
        (vec!["--spp", "1"], "spp"),
        (vec!["--alpha", "2"], "alpha"),
        (vec!["--max-depth", "-5"], "max-depth"),
    ] {
        let out = glint()
            .arg("compare")
            .arg(&scene)
            .args(args)
            .output()
            .unwrap();
        assert_one_line_error(&out, needle);
    }
    for (args, needle) in cases {
        let mut full = vec!["render".to_string()];
        full.extend(args.iter().cloned());
        if !args.iter().any(|a| a == "--backend") {
            full.extend(["--backend".into(), "cpu".into()]);
        }
        if !args
            .iter()
            .any(|a| a == "--spp" || a == "--width" || a == "--height")
        {
            full.extend(["--spp".into(), "2".into(), "--width".into(), "16".into()]);
        }
        let out = glint().args(&full).output().unwrap();
        assert_one_line_error(&out, needle);
        assert_eq!(
            files_in(&dir),
            ["broken.gltf", "scene.bin", "scene.gltf"],
            "{args:?} left files behind"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn gpu_backend_renders_and_compare_finds_the_backends_agree() {
    let dir = scratch("compare");
    let scene = write_scene(&dir);
    let out = glint()
        .arg("compare")
        .arg(&scene)
        .args(["--spp", "8", "--width", "24"])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The verdict, then the metrics module's view of the same pair.
    assert_eq!(stdout.lines().count(), 2, "{stdout}");
    assert!(stdout.lines().next().unwrap().contains("pass"), "{stdout}");
    assert!(
        stdout.contains("relMSE") && stdout.contains("FLIP"),
        "{stdout}"
    );
    // Nothing written.
    assert_eq!(files_in(&dir), ["scene.bin", "scene.gltf"]);

    // Per-side options: another unbiased method agrees; a biased one (the
    // CPU without the floor's lighting, emitters only) is found, exit 1.
    let compare = |side: &str, extra: &str| {
        glint()
            .arg("compare")
            .arg(&scene)
            .args(["--spp", "8", "--width", "24", side, extra])
            .output()
            .unwrap()
    };
    let out = compare("--cpu-options", "--mis balance");
    assert!(
        out.status.success(),
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let out = compare("--cpu-options", "--max-depth 1");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stdout}{stderr}");
    assert!(stdout.lines().next().unwrap().contains("FAIL"), "{stdout}");
    assert!(stderr.contains("the backends differ"), "{stderr}");
    // What is not per side: one line.
    assert_one_line_error(&compare("--gpu-options", "--backend cpu"), "--gpu-options");
    assert_one_line_error(&compare("--cpu-options", "--max-depth 0"), "--cpu-options");

    // The GPU backend's stats name the device and driver.
    let (png, stats) = (dir.join("g.png"), dir.join("g.json"));
    let out = glint()
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(&png)
        .args(["--backend", "gpu", "--spp", "4", "--width", "24", "--stats"])
        .arg(&stats)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(image::open(&png).unwrap().height(), 16);
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
    assert_eq!(v["backend"], "gpu");
    assert!(v["driver"].as_str().is_some_and(|d| !d.is_empty()), "{v}");
    assert!(v["rays_per_second"].as_f64().unwrap() > 0.0);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bench_reports_both_backends_and_their_ratio() {
    let dir = scratch("bench");
    let scene = write_scene(&dir);
    let json = dir.join("bench.json");
    let out = glint()
        .args(["bench"])
        .arg(&scene)
        .args(["--width", "16", "--spp", "2", "--json"])
        .arg(&json)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.lines().any(|l| l.starts_with("gpu ")), "{text}");
    assert!(text.lines().any(|l| l.starts_with("cpu ")), "{text}");
    let doc: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let backends = doc["backends"].as_array().unwrap();
    assert_eq!(backends.len(), 2);
    let rate = |i: usize| backends[i]["samples_per_second"].as_f64().unwrap();
    // Both backends rendered the same 16x16x2 samples: equal ray counts
    // within the float noise of the paths, and the ratio is their quotient.
    let rays = |i: usize| backends[i]["rays"].as_f64().unwrap();
    assert!((rays(0) - rays(1)).abs() <= 0.01 * rays(1), "{doc}");
    let ratio = doc["gpu_over_cpu_samples_per_second"].as_f64().unwrap();
    assert!(
        (ratio - rate(0) / rate(1)).abs() <= 1e-6 * ratio.max(1.0),
        "{doc}"
    );

    let bad = glint()
        .args(["bench"])
        .arg(&scene)
        .args(["--repeat", "0"])
        .output()
        .unwrap();
    assert_one_line_error(&bad, "--repeat");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `write_scene` without its emitter: nothing lights it.
fn write_unlit_scene(dir: &Path) -> PathBuf {
    let path = write_scene(dir);
    let mut j: serde_json::Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    j["scenes"][0]["nodes"] = serde_json::json!([0, 2]);
    let unlit = dir.join("unlit.gltf");
    std::fs::write(&unlit, serde_json::to_vec(&j).unwrap()).unwrap();
    unlit
}

fn mean_of_exr(path: &Path) -> f32 {
    let img = image::open(path).unwrap().to_rgb32f();
    img.pixels().map(|p| p.0[1]).sum::<f32>() / (img.width() * img.height()) as f32
}

/// `glint render SCENE -o OUT` on the CPU at 12x8 and `spp`, plus `extra`.
fn render_unlit(scene: &Path, out: &Path, spp: u32, extra: &[&str]) -> Output {
    glint()
        .arg("render")
        .arg(scene)
        .args(["--backend", "cpu", "--spp", &spp.to_string()])
        .args(["--width", "12", "--height", "8", "-o"])
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}

#[test]
fn warnings_strict_background_and_the_no_light_rule() {
    let dir = scratch("warnings");
    let scene = write_unlit_scene(&dir);
    let render = |extra: &[&str], out: &str| render_unlit(&scene, &dir.join(out), 2, extra);
    // No light: rendered under a white sky, with one warning line.
    let out = render(&[], "white.exr");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    let warning = format!(
        "glint: warning: {}: the scene has no light",
        scene.display()
    );
    assert!(err.contains(&warning), "{err}");
    let white = mean_of_exr(&dir.join("white.exr"));
    assert!(white > 0.5, "{white}");
    // --strict: the warning is the error, and no image is left.
    let out = render(&["--strict"], "strict.exr");
    assert_one_line_error(&out, "the scene has no light");
    assert!(!dir.join("strict.exr").exists());
    // --background replaces it: no warning, a dimmer image.
    let out = render(&["--background", "0.1,0.1,0.1"], "dim.exr");
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("the scene has no light"), "{err}");
    let dim = mean_of_exr(&dir.join("dim.exr"));
    assert!((dim / white - 0.1).abs() < 0.03, "{dim} vs {white}");
    // --background 0,0,0 keeps the scene dark (contract, "Second additions").
    let out = render(&["--background", "0,0,0"], "dark.exr");
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("the scene has no light"), "{err}");
    assert_eq!(mean_of_exr(&dir.join("dark.exr")), 0.0);
    let out = render(&["--background", "1,2"], "bad.exr");
    assert_one_line_error(&out, "R,G,B");
    // The hardware traversal's options without it: a warning, not silence.
    let out = render(
        &["--background", "0.1,0.1,0.1", "--blas-parts", "4"],
        "parts.exr",
    );
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--blas-parts apply to --traversal hardware only: ignored"),
        "{err}"
    );
    let out = render(&["--blas-parts", "0"], "zero.exr");
    assert!(!out.status.success());
    // The GPU's options on the CPU backend: one warning naming them, and
    // with --strict the error, before anything is written.
    let out = render(
        &[
            "--background",
            "0.1,0.1,0.1",
            "--kernel",
            "generic",
            "--traversal",
            "hardware",
        ],
        "gpu-only.exr",
    );
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.matches("glint: warning:").count(), 1, "{err}");
    assert!(
        err.contains("--kernel, --traversal apply to the GPU backend only: ignored"),
        "{err}"
    );
    let out = render(
        &["--background", "0.1,0.1,0.1", "--device", "x", "--strict"],
        "gpu-only-strict.exr",
    );
    assert_one_line_error(&out, "--device applies to the GPU backend only");
    assert!(!dir.join("gpu-only-strict.exr").exists());
}

/// `glint info` of a bundled asset, which must succeed.
fn info_of(asset: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(asset);
    let out = glint().arg("info").arg(&path).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn info_describes_the_textured_asset() {
    let text = info_of("textured.gltf");
    for needle in [
        "cameras: 1",
        "materials: 4",
        "textures: 4",
        "checker 64x64 wrap repeat/repeat nearest",
        "roughness ramp 64x64",
        "alpha mask < 0.5",
        // A textured channel as "texture x factor", not the bare factor.
        "roughness texture 1.G x 1.0000",
        "baseColor texture 0 x 1.0000,1.0000,1.0000",
        "normal texture 2 x scale 1",
        // The kernel carries the fold for the normal-mapped material.
        "normal-map, textures",
        // The model each maps to (the glTF non-metal is the coated one).
        "glTF per texel: metal/coated non-metal blend",
        "coated non-metal (ggx coat alpha 1.0000 ior 1.5000 over diffuse base 0.7000,0.3000,0.2500)",
        "lights: 0 emissive triangles, 1 punctual",
        "directional toward",
        "triangles: 8",
        "texels: 65536 B",
        "warnings: 0",
    ] {
        assert!(text.contains(needle), "info lacks '{needle}':\n{text}");
    }
    let out = glint().args(["info", "missing.gltf"]).output().unwrap();
    assert_one_line_error(&out, "missing.gltf");
}

#[test]
fn info_bytes_per_triangle_match_the_uploaded_buffers() {
    // The per-triangle buffers the GPU path uploads (triangles, packed
    // shading, triangle uvs: glint::gpu::render::SceneBytes) against what
    // `glint info` reports: a mesh with normals alone (the bunny: no
    // tangent record), meshes with normals and texture coordinates
    // (Cornell), a textured scene.
    for (name, expect) in [
        ("bunny.glb", Some(96.0)),
        ("cornell.gltf", None),
        ("textured.gltf", None),
    ] {
        let asset = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("assets")
            .join(name);
        let text = info_of(name);
        let line = text
            .lines()
            .find(|l| l.starts_with("bytes per triangle: "))
            .unwrap_or_else(|| panic!("{name}: no bytes per triangle in\n{text}"));
        let reported: f64 = line["bytes per triangle: ".len()..]
            .split_whitespace()
            .next()
            .unwrap()
            .parse()
            .unwrap();
        let scene = glint::cpu::prepare::prepare_default(&asset).unwrap();
        let opts = glint::cpu::RenderOptions::new(8, 8);
        let data = glint::cpu::integrator::gpu_scene_data(&scene, &opts).unwrap();
        let b = glint::gpu::render::SceneBytes::new(&scene, &data);
        // An untextured scene's uv binding holds one dummy element (a
        // Vulkan buffer cannot be empty): not scene data, not counted.
        let uvs = if scene.textures.uvs.is_empty() {
            0
        } else {
            b.uvs.len()
        };
        let uploaded =
            (b.triangles.len() + b.shading.len() + uvs) as f64 / scene.triangles.len() as f64;
        assert!(
            (reported - uploaded).abs() < 0.05,
            "{name}: {line} vs {uploaded}"
        );
        if let Some(e) = expect {
            assert_eq!(uploaded, e, "{name}");
        }
        assert!(
            line.contains("with a shading record on every triangle"),
            "{line}"
        );
    }
}

#[test]
fn envmap_file_renders_like_the_same_constant_background() {
    let dir = scratch("envmap");
    let scene = write_unlit_scene(&dir);
    let env = dir.join("sky.exr");
    image::Rgb32FImage::from_pixel(16, 8, image::Rgb([0.5f32, 0.5, 0.5]))
        .save(&env)
        .unwrap();
    let render = |extra: &[&str], out: &str| render_unlit(&scene, &dir.join(out), 32, extra);
    let out = render(
        &["--envmap", env.to_str().unwrap(), "--envmap-rotate", "40"],
        "env.exr",
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!String::from_utf8_lossy(&out.stderr).contains("warning"));
    let out = render(&["--background", "0.5,0.5,0.5"], "bg.exr");
    assert!(out.status.success());
    let (a, b) = (
        mean_of_exr(&dir.join("env.exr")),
        mean_of_exr(&dir.join("bg.exr")),
    );
    assert!((a / b - 1.0).abs() < 0.03, "envmap {a} vs background {b}");
    let out = render(
        &["--envmap", env.to_str().unwrap(), "--background", "1,1,1"],
        "both.exr",
    );
    assert_one_line_error(&out, "not both");
    let out = render(&["--envmap", "missing.exr"], "missing.exr");
    assert_one_line_error(&out, "missing.exr");
}

/// `glint info` takes the options that change what a scene loads into as
/// `render` takes them: `--multiscatter` shows on every rough model, an
/// environment map as the background (its size and turn), and the same
/// rules hold (not both a background and an environment map, a file
/// that is not there).
#[test]
fn info_takes_the_scene_options_render_takes() {
    let dir = scratch("info-options");
    let env = dir.join("sky.exr");
    image::Rgb32FImage::from_pixel(16, 8, image::Rgb([0.5f32, 0.5, 0.5]))
        .save(&env)
        .unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/roughconductor.gltf");
    let info = |extra: &[&str]| {
        glint()
            .arg("info")
            .arg(&scene)
            .args(extra)
            .output()
            .unwrap()
    };
    let text = |out: &Output| {
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let plain = text(&info(&[]));
    assert!(
        plain.contains("alpha_u 0.3000 alpha_v 0.0500 eta"),
        "{plain}"
    );
    assert!(!plain.contains("multiscatter"), "{plain}");
    assert!(plain.contains("background 0.2000,0.2000,0.2500"), "{plain}");
    let with = text(&info(&[
        "--multiscatter",
        "on",
        "--envmap",
        env.to_str().unwrap(),
        "--envmap-rotate",
        "30",
    ]));
    assert!(
        with.contains("alpha_u 0.3000 alpha_v 0.0500 multiscatter eta"),
        "{with}"
    );
    assert!(
        with.contains("background an environment map of 16x8 texels turned 30.00 degrees about +Y"),
        "{with}"
    );
    let out = info(&["--envmap", env.to_str().unwrap(), "--background", "1,1,1"]);
    assert_one_line_error(&out, "not both");
    let out = info(&["--envmap-scale", "-1"]);
    assert_one_line_error(&out, "--envmap-scale -1 is out of range");
    let out = info(&["--envmap", "missing.exr"]);
    assert_one_line_error(&out, "missing.exr");
}

/// A closed standard output (`glint info scene | head -1`) ends glint as it
/// ends a Unix filter: quietly, status 141 (128 + SIGPIPE), not as an
/// internal error.
#[test]
fn a_closed_stdout_ends_quietly() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell.gltf");
    let mut child = glint()
        .arg("info")
        .arg(&scene)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Closed before glint has loaded the scene, so its first write fails.
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("internal error"), "{err}");
    assert!(
        matches!(out.status.code(), Some(141) | Some(0)),
        "{:?}: {err}",
        out.status
    );
}

/// An EXR's scene key is the scene's files and the options that change
/// what they load into, not glint's own form of the loaded scene: the same
/// files in another folder keep it (a moved suite keeps its references),
/// a changed byte of an external buffer or a scene option changes it.
#[test]
fn the_scene_key_follows_the_files_not_their_folder() {
    let key_from = |cwd: &Path, scene: &Path, dir: &Path, extra: &[&str]| {
        let out = dir.join("k.exr");
        let o = glint()
            .current_dir(cwd)
            .arg("render")
            .arg(scene)
            .args(["--backend", "cpu", "--width", "8", "--spp", "2", "--quiet"])
            .args(extra)
            .arg("-o")
            .arg(&out)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let img = glint_cpu::exr_file::RadianceImage::read(&out).unwrap();
        img.meta.unwrap().scene.expect("a scene key")
    };
    let key = |dir: &Path, extra: &[&str]| key_from(dir, &dir.join("scene.gltf"), dir, extra);
    let (a, b) = (scratch("key-a"), scratch("key-b"));
    write_scene(&a);
    write_scene(&b);
    let k = key(&a, &[]);
    assert_eq!(key(&b, &[]), k, "the same files in another folder");
    // The same file as a.gltf, named absolutely (its path sorts before its
    // buffer's, scene.bin) and relatively (after the buffer's real path).
    std::fs::copy(a.join("scene.gltf"), a.join("a.gltf")).unwrap();
    assert_eq!(key_from(&a, &a.join("a.gltf"), &a, &[]), k, "absolute");
    assert_eq!(key_from(&a, Path::new("a.gltf"), &a, &[]), k, "relative");
    let parent = a.parent().unwrap();
    let rel = Path::new(a.file_name().unwrap()).join("a.gltf");
    assert_eq!(key_from(parent, &rel, &a, &[]), k, "from the parent");
    assert_eq!(key(&a, &["--seed", "3"]), k, "samples are not the image");
    for extra in [
        &["--multiscatter", "on"][..],
        &["--background", "0,0,0"],
        &["--max-depth", "2"],
        &["--height", "6"],
    ] {
        assert_ne!(key(&a, extra), k, "{extra:?}");
    }
    // One vertex of the light moved in the external buffer.
    let bin = b.join("scene.bin");
    let mut bytes = std::fs::read(&bin).unwrap();
    bytes[4 * 3 * 5] ^= 1;
    std::fs::write(&bin, bytes).unwrap();
    assert_ne!(key(&b, &[]), k, "a changed external buffer");
    for d in [a, b] {
        let _ = std::fs::remove_dir_all(d);
    }
}
