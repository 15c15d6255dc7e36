//! Hostile inputs and shared folders (issue 21), end to end through the
//! binary: links that leave the scene's folder, planted temporaries, device
//! nodes and FIFOs as outputs or inputs, outputs that name inputs, EXR
//! headers that lie about their size, non-finite images, the CPU film's
//! memory check, deterministic EXR bytes, warnings for non-finite lights and
//! texels, option values that name their option, and `--backend auto`.
//! Every case is one line on stderr (or a warning) and never a hang, a
//! panic or an abort. Images are tiny and rendered on the CPU, except where
//! the GPU's pipeline cache is the subject.

use std::ffi::CString;
use std::os::unix::fs::{FileTypeExt, symlink};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use glam::Vec3;
use glint::cpu::exr_file::{RadianceImage, RenderMeta};

fn glint() -> Command {
    Command::new(env!("CARGO_BIN_EXE_glint"))
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Failure with exactly one line on stderr that mentions every needle.
#[track_caller]
fn one_error_line(o: &Output, needles: &[&str]) {
    let err = stderr(o);
    assert!(!o.status.success(), "expected a failure, stderr: {err}");
    assert_ne!(o.status.code(), Some(101), "a panic: {err}");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "one line on stderr, got {err:?}");
    for n in needles {
        assert!(lines[0].contains(n), "{:?} should mention {n:?}", lines[0]);
    }
}

#[track_caller]
fn ok(o: &Output) {
    assert!(o.status.success(), "{}", stderr(o));
}

/// Run `cmd`, killing it (and failing) if it takes longer than `limit`: a
/// FIFO opened for reading would otherwise hang the test.
fn run_bounded(mut cmd: Command, limit: Duration) -> Output {
    let mut child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            return child.wait_with_output().unwrap();
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let o = child.wait_with_output().unwrap();
            panic!("hung for {limit:?}; stderr so far: {}", stderr(&o));
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn mkfifo(p: &Path) {
    let c = CString::new(p.to_str().unwrap()).unwrap();
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0, "mkfifo");
}

fn is_root() -> bool {
    // SAFETY: geteuid has no preconditions.
    unsafe { libc::geteuid() == 0 }
}

/// Every name in `dir` (temporaries included).
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[track_caller]
fn no_temporaries(dir: &Path) {
    let left: Vec<String> = names(dir)
        .into_iter()
        .filter(|n| n.contains(".tmp-"))
        .collect();
    assert!(left.is_empty(), "temporaries left behind: {left:?}");
}

/// The bytes of the scene's buffer: a floor quad and an emissive quad.
fn buffer_bytes() -> Vec<u8> {
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
    let uv: [[f32; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    let idx: [u16; 12] = [0, 1, 2, 0, 2, 3, 0, 1, 2, 0, 2, 3];
    let mut b: Vec<u8> = pos.iter().flatten().flat_map(|f| f.to_le_bytes()).collect();
    b.extend(idx.iter().flat_map(|i| i.to_le_bytes()));
    b.extend(uv.iter().flatten().flat_map(|f| f.to_le_bytes()));
    b
}

/// What varies between the test scenes.
struct SceneSpec<'a> {
    buffer_uri: &'a str,
    /// A baseColorTexture on the floor.
    texture_uri: Option<&'a str>,
    /// A point light's colour (times intensity 3e38).
    light_color: Option<f32>,
    aspect: f32,
}

impl Default for SceneSpec<'_> {
    fn default() -> Self {
        Self {
            buffer_uri: "scene.bin",
            texture_uri: None,
            light_color: None,
            aspect: 1.5,
        }
    }
}

/// Write `scene.gltf` (and `scene.bin` unless the URI names another file)
/// into `dir`.
fn write_scene(dir: &Path, spec: &SceneSpec) -> PathBuf {
    let bytes = buffer_bytes();
    if spec.buffer_uri == "scene.bin" {
        std::fs::write(dir.join("scene.bin"), &bytes).unwrap();
    }
    let (tex, textures, images, samplers) = match spec.texture_uri {
        Some(u) => (
            r#", "baseColorTexture": { "index": 0 }"#.to_string(),
            r#""textures": [ { "source": 0, "sampler": 0 } ],"#.to_string(),
            format!(r#""images": [ {{ "uri": "{u}" }} ],"#),
            r#""samplers": [ {} ],"#.to_string(),
        ),
        None => Default::default(),
    };
    let (light_node, lights, ext) = match spec.light_color {
        Some(c) => (
            r#", { "translation": [0, 2, 0], "extensions": { "KHR_lights_punctual": { "light": 0 } } }"#
                .to_string(),
            format!(
                r#""extensions": {{ "KHR_lights_punctual": {{ "lights": [ {{ "type": "point", "color": [{c}, {c}, {c}], "intensity": 3e38 }} ] }} }},"#
            ),
            r#", "KHR_lights_punctual""#,
        ),
        None => (String::new(), String::new(), ""),
    };
    let nodes = if spec.light_color.is_some() {
        "[0, 1, 2, 3]"
    } else {
        "[0, 1, 2]"
    };
    let gltf = format!(
        r#"{{
  "asset": {{ "version": "2.0" }},
  "scene": 0,
  "scenes": [ {{ "nodes": {nodes} }} ],
  "nodes": [
    {{ "mesh": 0 }},
    {{ "mesh": 1 }},
    {{ "camera": 0, "translation": [0, 1, 3] }}{light_node}
  ],
  {lights}
  "cameras": [ {{ "type": "perspective",
                  "perspective": {{ "yfov": 0.8, "aspectRatio": {aspect}, "znear": 0.01 }} }} ],
  "meshes": [
    {{ "primitives": [ {{ "attributes": {{ "POSITION": 0, "TEXCOORD_0": 4 }}, "indices": 2, "material": 0 }} ] }},
    {{ "primitives": [ {{ "attributes": {{ "POSITION": 1 }}, "indices": 3, "material": 1 }} ] }}
  ],
  "materials": [
    {{ "name": "floor", "pbrMetallicRoughness": {{ "baseColorFactor": [0.8, 0.8, 0.8, 1], "metallicFactor": 0{tex} }} }},
    {{ "name": "light", "emissiveFactor": [1, 1, 1],
       "extensions": {{ "KHR_materials_emissive_strength": {{ "emissiveStrength": 4 }} }} }}
  ],
  {textures}
  {images}
  {samplers}
  "extensionsUsed": [ "KHR_materials_emissive_strength"{ext} ],
  "buffers": [ {{ "uri": "{uri}", "byteLength": {len} }} ],
  "bufferViews": [
    {{ "buffer": 0, "byteOffset": 0, "byteLength": 48 }},
    {{ "buffer": 0, "byteOffset": 48, "byteLength": 48 }},
    {{ "buffer": 0, "byteOffset": 96, "byteLength": 12 }},
    {{ "buffer": 0, "byteOffset": 108, "byteLength": 12 }},
    {{ "buffer": 0, "byteOffset": 120, "byteLength": 32 }}
  ],
  "accessors": [
    {{ "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3" }},
    {{ "bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3" }},
    {{ "bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR" }},
    {{ "bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR" }},
    {{ "bufferView": 4, "componentType": 5126, "count": 4, "type": "VEC2" }}
  ]
}}"#,
        aspect = spec.aspect,
        uri = spec.buffer_uri,
        len = bytes.len(),
    );
    let p = dir.join("scene.gltf");
    std::fs::write(&p, gltf).unwrap();
    p
}

/// `glint render SCENE -o OUT --backend cpu --width 16 --spp 1 EXTRA`.
fn render(scene: &Path, out: &Path, extra: &[&str]) -> Output {
    render_cmd(scene, out, extra).output().unwrap()
}

fn render_cmd(scene: &Path, out: &Path, extra: &[&str]) -> Command {
    let mut c = glint();
    c.arg("render")
        .arg(scene)
        .arg("-o")
        .arg(out)
        .args(["--backend", "cpu", "--width", "16", "--spp", "1", "--quiet"])
        .args(extra);
    c
}

fn write_png(p: &Path) {
    image::RgbImage::from_pixel(2, 2, image::Rgb([200, 100, 50]))
        .save(p)
        .unwrap();
}

fn write_exr(p: &Path, w: u32, mean: Vec3, variance: Option<Vec3>, seed: u64) {
    let n = (w * w) as usize;
    RadianceImage {
        width: w,
        height: w,
        mean: vec![mean; n],
        variance: variance.map(|v| vec![v; n]),
        meta: Some(RenderMeta {
            spp: 64,
            seed,
            sampler: "independent".into(),
            shard: "0/1".into(),
            version: "0".into(),
            build: None,
            samples: vec![(0, 64)],
            scene: Some("k".into()),
            files: None,
            variance_batch: 1,
        }),
    }
    .write_file(p)
    .unwrap();
}

// ---- 1. Links that leave the scene's folder; file://HOST ----

#[test]
fn links_out_of_the_scene_folder_are_refused_and_named() {
    let root = tempfile::tempdir().unwrap();
    let (dir, outside) = (root.path().join("scene"), root.path().join("outside"));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::create_dir_all(&outside).unwrap();
    // A real buffer outside, so that following the link would render.
    std::fs::write(outside.join("secret.bin"), buffer_bytes()).unwrap();
    symlink(outside.join("secret.bin"), dir.join("p.bin")).unwrap();
    let scene = write_scene(
        &dir,
        &SceneSpec {
            buffer_uri: "p.bin",
            ..Default::default()
        },
    );
    let out = dir.join("out.exr");
    let o = render(&scene, &out, &[]);
    one_error_line(
        &o,
        &["p.bin", "symbolic link", "outside the scene's folder"],
    );
    assert!(!out.exists());
    // --allow-any-path lifts it.
    ok(&render(&scene, &out, &["--allow-any-path"]));

    // A linked folder on the way.
    symlink(&outside, dir.join("sub")).unwrap();
    let scene = write_scene(
        &dir,
        &SceneSpec {
            buffer_uri: "sub/secret.bin",
            ..Default::default()
        },
    );
    one_error_line(&render(&scene, &out, &[]), &["sub", "symbolic link"]);

    // A link that stays inside is fine.
    std::fs::write(dir.join("real.bin"), buffer_bytes()).unwrap();
    symlink("real.bin", dir.join("inside.bin")).unwrap();
    let scene = write_scene(
        &dir,
        &SceneSpec {
            buffer_uri: "inside.bin",
            ..Default::default()
        },
    );
    ok(&render(&scene, &out, &[]));

    // A linked texture: refused with a warning naming the link, never read.
    write_png(&outside.join("t.png"));
    symlink(outside.join("t.png"), dir.join("t.png")).unwrap();
    let scene = write_scene(
        &dir,
        &SceneSpec {
            texture_uri: Some("t.png"),
            ..Default::default()
        },
    );
    let o = render(&scene, &out, &[]);
    ok(&o);
    let err = stderr(&o);
    assert!(
        err.contains("glint: warning:") && err.contains("t.png") && err.contains("symbolic link"),
        "{err}"
    );

    // file://HOST/... names another machine.
    let scene = write_scene(
        &dir,
        &SceneSpec {
            buffer_uri: "file://otherhost/etc/passwd",
            ..Default::default()
        },
    );
    let o = render(&scene, &out, &["--allow-any-path"]);
    one_error_line(&o, &["otherhost", "host"]);
}

// ---- 2. Planted temporaries ----

#[test]
fn a_planted_temporary_link_is_never_written_through() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_scene(d, &SceneSpec::default());
    std::fs::write(d.join("victim.txt"), "precious").unwrap();
    // The old temporary's name, `.out.exr.tmp-PID`, planted by a shell that
    // then becomes glint (same PID).
    let cmd = format!(
        "ln -s victim.txt .out.exr.tmp-$$ && ln -s victim.txt .out.png.tmp-$$ && exec '{}' render scene.gltf -o out.exr -o out.png --backend cpu --width 16 --spp 1 --quiet",
        env!("CARGO_BIN_EXE_glint")
    );
    let o = Command::new("sh")
        .arg("-c")
        .arg(&cmd)
        .current_dir(d)
        .output()
        .unwrap();
    ok(&o);
    assert_eq!(
        std::fs::read_to_string(d.join("victim.txt")).unwrap(),
        "precious"
    );
    for out in ["out.exr", "out.png"] {
        let m = std::fs::symlink_metadata(d.join(out)).unwrap();
        assert!(m.file_type().is_file(), "{out} is not a regular file");
    }
}

// ---- 3. Outputs that are device nodes or FIFOs ----

#[test]
fn outputs_that_are_not_regular_files_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = write_scene(d, &SceneSpec::default());
    let fifo = d.join("stats.json");
    mkfifo(&fifo);
    let o = render(
        &scene,
        &d.join("out.exr"),
        &["--stats", fifo.to_str().unwrap()],
    );
    one_error_line(&o, &["stats.json", "named pipe"]);
    assert!(
        std::fs::symlink_metadata(&fifo)
            .unwrap()
            .file_type()
            .is_fifo()
    );
    assert!(!d.join("out.exr").exists());
    no_temporaries(d);

    // diff --json onto a FIFO: exit 2, the FIFO stays.
    let (a, b) = (d.join("a.exr"), d.join("b.exr"));
    write_exr(&a, 4, Vec3::ONE, Some(Vec3::splat(0.01)), 1);
    write_exr(&b, 4, Vec3::ONE, Some(Vec3::splat(0.01)), 2);
    let o = glint()
        .arg("diff")
        .args([&a, &b])
        .arg("--json")
        .arg(&fifo)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        std::fs::symlink_metadata(&fifo)
            .unwrap()
            .file_type()
            .is_fifo()
    );

    // A link to a device.
    symlink("/dev/null", d.join("null.json")).unwrap();
    let o = render_cmd(&scene, &d.join("out.exr"), &["--stats", "null.json"])
        .current_dir(d)
        .output()
        .unwrap();
    one_error_line(&o, &["null.json", "character device"]);
    assert!(
        std::fs::symlink_metadata(d.join("null.json"))
            .unwrap()
            .file_type()
            .is_symlink()
    );

    // A device node made here: only root can.
    if !is_root() {
        eprintln!("skipped the device-node case: mknod needs root");
        return;
    }
    let node = d.join("null");
    let c = CString::new(node.to_str().unwrap()).unwrap();
    // SAFETY: a valid path; makedev(1, 3) is /dev/null's number.
    let made = unsafe { libc::mknod(c.as_ptr(), libc::S_IFCHR | 0o666, libc::makedev(1, 3)) };
    if made != 0 {
        eprintln!("skipped the device-node case: mknod failed (a container without CAP_MKNOD)");
        return;
    }
    let o = render(
        &scene,
        &d.join("out.exr"),
        &["--stats", node.to_str().unwrap()],
    );
    one_error_line(&o, &["character device"]);
    assert!(
        std::fs::symlink_metadata(&node)
            .unwrap()
            .file_type()
            .is_char_device()
    );
}

// ---- 4. Outputs that name inputs ----

#[test]
fn outputs_that_name_an_input_or_each_other_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_png(&d.join("t.png"));
    let scene = write_scene(
        d,
        &SceneSpec {
            texture_uri: Some("t.png"),
            ..Default::default()
        },
    );
    let tex = std::fs::read(d.join("t.png")).unwrap();
    one_error_line(&render(&scene, &d.join("t.png"), &[]), &["t.png", "input"]);
    assert_eq!(std::fs::read(d.join("t.png")).unwrap(), tex);
    // By another spelling, beside a second output.
    let other = d.join("sub/../t.png");
    std::fs::create_dir_all(d.join("sub")).unwrap();
    let o = render(&scene, &d.join("out.exr"), &["-o", other.to_str().unwrap()]);
    one_error_line(&o, &["t.png", "input"]);
    assert_eq!(std::fs::read(d.join("t.png")).unwrap(), tex);

    // The environment map.
    let env = d.join("e.exr");
    write_exr(&env, 4, Vec3::splat(0.5), None, 0);
    let before = std::fs::read(&env).unwrap();
    one_error_line(
        &render(&scene, &env, &["--envmap", env.to_str().unwrap()]),
        &["e.exr", "input"],
    );
    assert_eq!(std::fs::read(&env).unwrap(), before);

    // The same output twice: refused before anything, the old file kept.
    let out = d.join("out.exr");
    std::fs::write(&out, "old").unwrap();
    let o = glint()
        .current_dir(d)
        .args(["render", "scene.gltf", "-o", "out.exr", "-o", "./out.exr"])
        .args(["--backend", "cpu", "--width", "16", "--spp", "1"])
        .output()
        .unwrap();
    one_error_line(&o, &["out.exr", "twice"]);
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "old");
    no_temporaries(d);
}

// ---- 5. EXR headers that lie about their size ----

/// Rewrite the data and display windows of an EXR written by glint to
/// claim `w` x `h` pixels (the file keeps its few real bytes).
fn lie_about_size(p: &Path, w: i32, h: i32) {
    let mut b = std::fs::read(p).unwrap();
    for name in [&b"dataWindow\0box2i\0"[..], &b"displayWindow\0box2i\0"[..]] {
        let at = b
            .windows(name.len())
            .position(|x| x == name)
            .expect("window attribute")
            + name.len()
            + 4;
        for (i, v) in [0i32, 0, w - 1, h - 1].iter().enumerate() {
            b[at + 4 * i..at + 4 * i + 4].copy_from_slice(&v.to_le_bytes());
        }
    }
    std::fs::write(p, b).unwrap();
}

#[test]
fn exr_headers_claiming_more_than_the_file_holds_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (a, b) = (d.join("a.exr"), d.join("b.exr"));
    write_exr(&a, 4, Vec3::ONE, Some(Vec3::splat(0.01)), 1);
    write_exr(&b, 4, Vec3::ONE, Some(Vec3::splat(0.01)), 2);
    lie_about_size(&b, 100_000, 100_000);
    let o = glint().arg("diff").args([&a, &b]).output().unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    one_error_line(&o, &["b.exr", "100000x100000"]);
    // Within the side limit, but far more than the file's bytes.
    write_exr(&b, 4, Vec3::ONE, Some(Vec3::splat(0.01)), 2);
    lie_about_size(&b, 16000, 16000);
    let o = glint().arg("diff").args([&a, &b]).output().unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    one_error_line(&o, &["b.exr", "the file holds only"]);
    let o = glint()
        .arg("merge")
        .args([&a, &b])
        .arg("-o")
        .arg(d.join("m.exr"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    one_error_line(&o, &["b.exr"]);
    assert!(!d.join("m.exr").exists());
    no_temporaries(d);
}

// ---- 6. FIFOs as inputs ----

#[test]
fn fifo_inputs_are_refused_without_hanging() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = write_scene(d, &SceneSpec::default());
    let fifo = d.join("f.exr");
    mkfifo(&fifo);
    let mut c = render_cmd(
        &scene,
        &d.join("out.exr"),
        &["--envmap", fifo.to_str().unwrap()],
    );
    c.stdin(Stdio::null());
    let o = run_bounded(c, Duration::from_secs(60));
    one_error_line(&o, &["f.exr", "named pipe"]);
    let mut c = glint();
    c.arg("compare")
        .arg(&scene)
        .args(["--width", "8", "--spp", "2", "--envmap"])
        .arg(&fifo);
    let o = run_bounded(c, Duration::from_secs(60));
    one_error_line(&o, &["f.exr", "named pipe"]);
    // diff and merge inputs too.
    let a = d.join("a.exr");
    write_exr(&a, 4, Vec3::ONE, Some(Vec3::splat(0.01)), 1);
    let mut c = glint();
    c.arg("diff").args([&a, &fifo]);
    let o = run_bounded(c, Duration::from_secs(60));
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    no_temporaries(d);
}

/// The GPU's pipeline cache: a FIFO under its name is ignored with a
/// warning and left alone (this case needs a Vulkan device, lavapipe will
/// do).
#[test]
fn a_fifo_as_the_pipeline_cache_is_ignored() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = write_scene(d, &SceneSpec::default());
    mkfifo(&d.join("pipelines.bin"));
    let mut c = render_cmd(
        &scene,
        &d.join("out.png"),
        &["--backend", "gpu", "--width", "8"],
    );
    c.env("GLINT_CACHE_DIR", d);
    let o = run_bounded(c, Duration::from_secs(300));
    ok(&o);
    let err = stderr(&o);
    assert!(
        err.contains("pipelines.bin") && err.contains("named pipe"),
        "{err}"
    );
    let t = std::fs::symlink_metadata(d.join("pipelines.bin")).unwrap();
    assert!(t.file_type().is_fifo());
}

// ---- 7. Non-finite images in diff, merge and converge ----

#[test]
fn non_finite_images_give_no_verdict() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (a, b, nan, inf) = (
        d.join("a.exr"),
        d.join("b.exr"),
        d.join("nan.exr"),
        d.join("inf.exr"),
    );
    write_exr(&a, 16, Vec3::ONE, None, 1);
    write_exr(&b, 16, Vec3::ONE, None, 2);
    write_exr(&nan, 16, Vec3::splat(f32::NAN), None, 3);
    write_exr(&inf, 16, Vec3::splat(f32::INFINITY), None, 4);
    let diff = |x: &Path, y: &Path, extra: &[&str]| {
        glint()
            .arg("diff")
            .args([x, y])
            .args(extra)
            .output()
            .unwrap()
    };
    // No variance: no verdict (2), unless a threshold decides.
    let o = diff(&a, &b, &[]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert_eq!(
        diff(&a, &b, &["--max-relmse", "1e-6"]).status.code(),
        Some(0)
    );
    for bad in [&nan, &inf] {
        let o = diff(bad, &b, &[]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        one_error_line(&o, &["non-finite"]);
        let o = diff(&a, bad, &["--max-relmse", "1e9"]);
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    }
    // merge: a non-finite shard is refused with 2; so is any refusal.
    let o = glint()
        .arg("merge")
        .args([&a, &nan])
        .arg("-o")
        .arg(d.join("m.exr"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    one_error_line(&o, &["nan.exr", "non-finite"]);
    let o = glint()
        .arg("merge")
        .arg(d.join("missing.exr"))
        .arg("-o")
        .arg(d.join("m.exr"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    // converge --reference NaN: 2, no table.
    let scene = write_scene(d, &SceneSpec::default());
    let nan_ref = d.join("nan-ref.exr");
    let h = 11; // 16 wide at aspect 1.5.
    RadianceImage {
        width: 16,
        height: h,
        mean: vec![Vec3::splat(f32::NAN); 16 * h as usize],
        variance: None,
        meta: None,
    }
    .write_file(&nan_ref)
    .unwrap();
    let out = d.join("conv");
    let o = glint()
        .arg("converge")
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .arg("--reference")
        .arg(&nan_ref)
        .args([
            "--spp",
            "1",
            "--width",
            "16",
            "--variant",
            "cpu=--backend cpu",
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("non-finite"), "{}", stderr(&o));
    assert!(!out.join("converge.csv").exists());
}

// ---- 8. The CPU film against the memory the machine can give ----

#[test]
fn a_film_larger_than_memory_is_refused_before_allocating() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_scene(d, &SceneSpec::default());
    // 4 GB of address space: a 16384 x 16384 film needs about 26 GB.
    let cmd = format!(
        "ulimit -v 4000000 && exec '{}' render scene.gltf -o out.exr --backend cpu --width 16384 --height 16384 --spp 1 --quiet",
        env!("CARGO_BIN_EXE_glint")
    );
    let o = Command::new("sh")
        .arg("-c")
        .arg(&cmd)
        .current_dir(d)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    one_error_line(&o, &["16384x16384", "GB", "--shard"]);
    assert!(!d.join("out.exr").exists());
    no_temporaries(d);
}

// ---- 9. Deterministic EXR bytes ----

#[test]
fn the_same_render_writes_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = write_scene(d, &SceneSpec::default());
    let mut files = Vec::new();
    for i in 0..3 {
        let out = d.join(format!("r{i}.exr"));
        ok(&render(&scene, &out, &["--variance", "--seed", "5"]));
        files.push(std::fs::read(&out).unwrap());
    }
    assert!(files.windows(2).all(|w| w[0] == w[1]), "EXR bytes differ");
    // And merge's output, too.
    let (a, b) = (d.join("m0.exr"), d.join("m1.exr"));
    for out in [&a, &b] {
        ok(&glint()
            .arg("merge")
            .arg(d.join("r0.exr"))
            .arg("-o")
            .arg(out)
            .output()
            .unwrap());
    }
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
}

// ---- 10. Warnings and messages ----

#[test]
fn non_finite_lights_and_texels_are_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = write_scene(
        d,
        &SceneSpec {
            light_color: Some(10.0),
            ..Default::default()
        },
    );
    let out = d.join("out.exr");
    let o = render(&scene, &out, &[]);
    ok(&o);
    assert!(
        stderr(&o).contains("glint: warning:") && stderr(&o).contains("punctual light"),
        "{}",
        stderr(&o)
    );
    // The rest of the scene still renders (the emissive quad is seen).
    let img = RadianceImage::read(&out).unwrap();
    assert!(img.mean.iter().all(|m| m.is_finite()));
    assert!(img.mean.iter().any(|m| m.max_element() > 0.0));
    one_error_line(&render(&scene, &out, &["--strict"]), &["punctual light"]);

    // NaN and infinite envmap texels.
    let env = d.join("env.exr");
    let mut texels = vec![Vec3::splat(0.5); 32];
    texels[3] = Vec3::splat(f32::NAN);
    texels[7] = Vec3::new(f32::INFINITY, 0.0, 0.0);
    RadianceImage {
        width: 8,
        height: 4,
        mean: texels,
        variance: None,
        meta: None,
    }
    .write_file(&env)
    .unwrap();
    let plain = write_scene(d, &SceneSpec::default());
    let o = render(&plain, &out, &["--envmap", env.to_str().unwrap()]);
    ok(&o);
    let err = stderr(&o);
    assert!(
        err.contains("env.exr") && err.contains("2 texel(s) not finite"),
        "{err}"
    );
}

#[test]
fn option_values_name_their_option_and_sizes_are_not_clamped_silently() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = write_scene(d, &SceneSpec::default());
    let out = d.join("out.exr");
    for (opt, v) in [
        ("--width", "-5"),
        ("--height", "-5"),
        ("--spp", "-2"),
        ("--envmap-scale", "-1"),
    ] {
        let o = glint()
            .arg("render")
            .arg(&scene)
            .arg("-o")
            .arg(&out)
            .args(["--backend", "cpu", opt, v])
            .output()
            .unwrap();
        one_error_line(&o, &[opt]);
    }
    // aspectRatio 1e-6: the height would be 2e6 pixels; clamped, with a
    // warning.
    let tall = write_scene(
        d,
        &SceneSpec {
            aspect: 1e-6,
            ..Default::default()
        },
    );
    let o = glint()
        .arg("render")
        .arg(&tall)
        .arg("-o")
        .arg(&out)
        .args(["--backend", "cpu", "--width", "1", "--spp", "1", "--quiet"])
        .output()
        .unwrap();
    ok(&o);
    assert!(stderr(&o).contains("aspectRatio"), "{}", stderr(&o));
    let img = RadianceImage::read(&out).unwrap();
    assert_eq!((img.width, img.height), (1, 16384));

    // A NUL in a URI is escaped, never echoed raw.
    let nul = write_scene(
        d,
        &SceneSpec {
            buffer_uri: "a\\u0000b.bin",
            ..Default::default()
        },
    );
    let o = render(&nul, &out, &[]);
    one_error_line(&o, &["\\0"]);
    assert!(!o.stderr.contains(&0u8));
}

// ---- --backend auto ----

#[test]
fn the_default_backend_is_a_gpu_when_one_exists_else_the_cpu() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = write_scene(d, &SceneSpec::default());
    let stats = d.join("s.json");
    let o = glint()
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(d.join("out.png"))
        .args(["--width", "8", "--spp", "1", "--quiet", "--stats"])
        .arg(&stats)
        .output()
        .unwrap();
    ok(&o);
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
    let want = if glint::gpu::context::gpu_available(None) {
        "gpu"
    } else {
        "cpu"
    };
    assert_eq!(v["backend"], want, "{v}");
}
