//! `glint export SCENE -o DIR`: the prepared scene as Mitsuba 3 XML and PLY
//! meshes. What the peer renders must be what glint renders: every triangle
//! once, the emitters on their own meshes, the camera looking where glint's
//! looks, Mitsuba's own BSDFs written exactly, and a warning line for each
//! approximation (the rendered comparison is `scripts/mitsuba_bench.py`).

use std::path::{Path, PathBuf};
use std::process::Command;

use glam::{Mat4, Vec4};

fn glint() -> Command {
    Command::new(env!("CARGO_BIN_EXE_glint"))
}

fn asset(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(name)
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("glint-export-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// (vertex count, face count, has normals) of a binary PLY's header, after
/// checking the body's length.
fn ply(path: &Path) -> (usize, usize, bool) {
    let bytes = std::fs::read(path).unwrap();
    let end = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    let header = std::str::from_utf8(&bytes[..end]).unwrap();
    let count = |what: &str| -> usize {
        header
            .lines()
            .find_map(|l| l.strip_prefix(&format!("element {what} ")))
            .unwrap()
            .parse()
            .unwrap()
    };
    let (v, f) = (count("vertex"), count("face"));
    let normals = header.contains("property float nx");
    let stride = if normals { 24 } else { 12 };
    assert_eq!(bytes.len() - end, v * stride + f * 13, "{}", path.display());
    (v, f, normals)
}

fn export(scene: &Path, dir: &Path) -> String {
    let out = glint()
        .arg("export")
        .arg(scene)
        .arg("-o")
        .arg(dir)
        .args(["--width", "64", "--spp", "16", "--max-depth", "7"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{stderr}");
    stderr
}

#[test]
fn cornell_is_written_exactly_with_every_triangle_once() {
    let dir = scratch("cornell");
    let stderr = export(&asset("cornell.gltf"), &dir);
    let scene = glint::cpu::loader::parse(&asset("cornell.gltf")).unwrap();
    let xml = std::fs::read_to_string(dir.join("scene.xml")).unwrap();
    let doc = roxmltree::Document::parse(&xml).unwrap();
    let root = doc.root_element();
    assert_eq!(root.attribute("version"), Some("3.0.0"));

    // Every triangle once, in meshes of one material each; the emitter's
    // own mesh carries the area light.
    let mut faces = 0;
    let mut emitters = 0;
    for shape in root.children().filter(|n| n.has_tag_name("shape")) {
        let file = shape
            .children()
            .find(|n| n.attribute("name") == Some("filename"))
            .and_then(|n| n.attribute("value"))
            .unwrap();
        let (v, f, _) = ply(&dir.join(file));
        assert_eq!(v, 3 * f);
        faces += f;
        let bsdfs: Vec<_> = shape
            .children()
            .filter(|n| n.has_tag_name("bsdf"))
            .collect();
        assert_eq!(bsdfs.len(), 1);
        if let Some(e) = shape.children().find(|n| n.has_tag_name("emitter")) {
            assert_eq!(e.attribute("type"), Some("area"));
            emitters += 1;
        }
    }
    assert_eq!(faces, scene.triangles.len());
    assert_eq!(emitters, 1);

    // Mitsuba's own models, by name, with glint's parameters.
    let types: Vec<&str> = root
        .descendants()
        .filter(|n| n.has_tag_name("bsdf"))
        .filter_map(|n| n.attribute("type"))
        .collect();
    for t in [
        "diffuse",
        "conductor",
        "roughconductor",
        "dielectric",
        "roughdielectric",
    ] {
        assert!(types.contains(&t), "{t} in {types:?}");
    }
    assert!(!types.contains(&"principled"), "{types:?}");
    let int_ior: Vec<f32> = root
        .descendants()
        .filter(|n| n.attribute("name") == Some("int_ior"))
        .map(|n| n.attribute("value").unwrap().parse().unwrap())
        .collect();
    assert!(
        int_ior
            .iter()
            .all(|&v| (v - 1.5046 / 1.000277).abs() < 1e-4),
        "{int_ior:?}"
    );

    // The integrator's depth, the film, a box filter.
    let value = |tag: &str, name: &str| {
        root.descendants()
            .find(|n| n.has_tag_name(tag) && n.attribute("name") == Some(name))
            .and_then(|n| n.attribute("value"))
            .unwrap()
            .to_string()
    };
    assert_eq!(value("integer", "max_depth"), "7");
    assert_eq!(value("integer", "width"), "64");
    assert_eq!(value("integer", "sample_count"), "16");
    assert!(
        root.descendants()
            .any(|n| n.has_tag_name("rfilter") && n.attribute("type") == Some("box"))
    );

    // Mitsuba's camera looks down its +Z: the matrix sends +Z to glint's
    // forward and the origin to glint's eye.
    let matrix = root
        .descendants()
        .find(|n| n.has_tag_name("matrix"))
        .and_then(|n| n.attribute("value"))
        .unwrap();
    let m: Vec<f32> = matrix
        .split_whitespace()
        .map(|v| v.parse().unwrap())
        .collect();
    let m = Mat4::from_cols_array(&m.try_into().unwrap()).transpose();
    let cam = glint::cpu::camera::PinholeCamera::new(
        &glint::cpu::camera::scene_camera(&scene, 0),
        64,
        64,
    );
    let fwd = (m * Vec4::new(0.0, 0.0, 1.0, 0.0)).truncate();
    let eye = (m * Vec4::new(0.0, 0.0, 0.0, 1.0)).truncate();
    assert!(
        (fwd - cam.forward).length() < 1e-5,
        "{fwd} vs {}",
        cam.forward
    );
    assert!(
        (eye - cam.origin).length() < 1e-5,
        "{eye} vs {}",
        cam.origin
    );
    // Image x: Mitsuba's +X is its left, so -X is glint's right.
    let right = (m * Vec4::new(-1.0, 0.0, 0.0, 0.0)).truncate();
    assert!(right.dot(cam.right) > 0.0 && right.dot(cam.up).abs() < 1e-5);

    // The approximations: glint's default height-correlated shadowing and
    // the anisotropic copper's tangent frame.
    let warnings: Vec<&str> = stderr.lines().filter(|l| l.contains("warning")).collect();
    assert!(
        !warnings.is_empty()
            && warnings
                .iter()
                .all(|l| l.contains("separable") || l.contains("anisotropic")),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn approximations_each_get_a_warning_and_bad_input_one_line() {
    let dir = scratch("materials");
    let stderr = export(&asset("materials.gltf"), &dir);
    assert!(stderr.contains("principled"), "{stderr}");
    let dir2 = scratch("textured");
    let stderr = export(&asset("textured.gltf"), &dir2);
    assert!(stderr.contains("textures are not written"), "{stderr}");
    let out = glint()
        .arg("export")
        .arg(asset("no-such.gltf"))
        .arg("-o")
        .arg(&dir2)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.lines().count() == 1, "{err}");
    for d in [dir, dir2] {
        let _ = std::fs::remove_dir_all(&d);
    }
}
