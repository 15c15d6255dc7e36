//! `glint export SCENE -o DIR`: the prepared scene as Mitsuba 3 XML and PLY
//! meshes. What the peer renders must be what glint renders: every triangle
//! once, the emitters on their own meshes, the camera looking where glint's
//! looks, Mitsuba's own BSDFs written exactly, and a warning line for each
//! approximation (the rendered comparison is `scripts/mitsuba_bench.py`).

#[path = "../cpu/tests/fixtures/gltf_builder.rs"]
mod builder;

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
    let (v, f, normals, _) = ply_body(path);
    (v, f, normals)
}

/// [`ply`] and the vertices' texture coordinates (empty where none).
fn ply_body(path: &Path) -> (usize, usize, bool, Vec<[f32; 2]>) {
    let (v, f, normals, _, uvs) = ply_vertices(path);
    (v, f, normals, uvs)
}

/// [`ply_body`] with the vertices' positions.
#[allow(clippy::type_complexity)]
fn ply_vertices(path: &Path) -> (usize, usize, bool, Vec<[f32; 3]>, Vec<[f32; 2]>) {
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
    let uv = header.contains("property float u\nproperty float v\n");
    let stride = 12 + if normals { 12 } else { 0 } + if uv { 8 } else { 0 };
    assert_eq!(bytes.len() - end, v * stride + f * 13, "{}", path.display());
    let f32_at = |o: usize| f32::from_le_bytes(bytes[o..o + 4].try_into().unwrap());
    let positions = (0..v)
        .map(|i| {
            let o = end + i * stride;
            [f32_at(o), f32_at(o + 4), f32_at(o + 8)]
        })
        .collect();
    let uvs = if uv {
        (0..v)
            .map(|i| {
                let o = end + i * stride + stride - 8;
                [f32_at(o), f32_at(o + 4)]
            })
            .collect()
    } else {
        Vec::new()
    };
    (v, f, normals, positions, uvs)
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
    assert!(stderr.contains("Mitsuba's tangent frame"), "{stderr}");
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

/// The shape element of mesh `id` and its file.
fn shape<'a>(root: roxmltree::Node<'a, 'a>, id: &str) -> (roxmltree::Node<'a, 'a>, String) {
    let shape = root
        .children()
        .find(|n| n.has_tag_name("shape") && n.attribute("id") == Some(id))
        .unwrap_or_else(|| panic!("no shape {id}"));
    let file = shape
        .children()
        .find(|n| n.attribute("name") == Some("filename"))
        .and_then(|n| n.attribute("value"))
        .unwrap()
        .to_string();
    (shape, file)
}

/// The bitmap named `name` under `node`: its texels (rgb, row by row).
fn bitmap(dir: &Path, node: roxmltree::Node, name: &str) -> (u32, u32, Vec<[f32; 3]>) {
    let tex = node
        .descendants()
        .find(|n| n.has_tag_name("texture") && n.attribute("name") == Some(name))
        .unwrap_or_else(|| panic!("no texture {name}"));
    assert_eq!(tex.attribute("type"), Some("bitmap"));
    let file = tex
        .children()
        .find(|n| n.attribute("name") == Some("filename"))
        .and_then(|n| n.attribute("value"))
        .unwrap();
    let img = image::open(dir.join(file)).unwrap().into_rgb32f();
    let px = img.pixels().map(|p| p.0).collect();
    (img.width(), img.height(), px)
}

/// The textured scene's textures as Mitsuba reads them: every texel of
/// each bitmap is glint's decoded texel with its factor (base colour), its
/// channel (metallic B, roughness G), the normal map's scale or the alpha
/// cutoff applied; each mesh carries the texture coordinates glint
/// interpolates; normal map and mask wrap the model, two-sided where the
/// material is double-sided.
#[test]
fn textured_materials_write_their_textures() {
    use glint::cpu::texture::texture_fetch;
    let dir = scratch("textures");
    // The bundled scene with factors that are not 1, for the texels to
    // carry: the checker's colour, the metal's roughness and metallic, the
    // bumps' normal scale.
    let mut gltf: serde_json::Value =
        serde_json::from_slice(&std::fs::read(asset("textured.gltf")).unwrap()).unwrap();
    let mats = &mut gltf["materials"];
    mats[0]["pbrMetallicRoughness"]["baseColorFactor"] = serde_json::json!([0.5, 0.8, 0.25, 1.0]);
    mats[1]["pbrMetallicRoughness"]["roughnessFactor"] = serde_json::json!(0.6);
    mats[1]["pbrMetallicRoughness"]["metallicFactor"] = serde_json::json!(0.9);
    mats[2]["normalTexture"]["scale"] = serde_json::json!(0.7);
    let file = scratch("textures-scene.gltf");
    std::fs::write(&file, serde_json::to_vec(&gltf).unwrap()).unwrap();
    export(&file, &dir);
    let scene = glint::cpu::loader::parse(&file).unwrap();
    let st = &scene.textures;
    let xml = std::fs::read_to_string(dir.join("scene.xml")).unwrap();
    let doc = roxmltree::Document::parse(&xml).unwrap();
    let root = doc.root_element();
    // Texel (x, y) of texture ref `r`, decoded as glint reads it.
    let texel = |r: &glint::cpu::texture::TexRef, i: usize, w: u32, srgb: bool| {
        let t = st.table[r.texture as usize];
        assert_eq!(w, t.width);
        let (x, y) = ((i as u32 % w) as i32, (i as u32 / w) as i32);
        texture_fetch(&st.texels, &t, x, y, srgb)
    };
    let bsdf_types = |n: roxmltree::Node| -> Vec<String> {
        n.descendants()
            .filter(|n| n.has_tag_name("bsdf"))
            .map(|n| n.attribute("type").unwrap().to_string())
            .collect()
    };
    let mut checked = 0;
    for (m, mt) in st.materials.iter().enumerate() {
        if !mt.is_used() {
            continue;
        }
        let (node, file) = shape(root, &format!("m{m}"));
        let types = bsdf_types(node);
        let double_sided = scene.materials[m].double_sided;
        assert_eq!(
            types.contains(&"twosided".to_string()),
            double_sided,
            "m{m}: {types:?}"
        );
        if mt.base_color.is_some() {
            let (w, _, px) = bitmap(&dir, node, "base_color");
            let factor = glam::Vec3::from_slice(&mt.base_factor[..3]);
            for (i, p) in px.iter().enumerate() {
                let want = factor * texel(&mt.base_color, i, w, true).truncate();
                assert_eq!(*p, want.to_array(), "m{m} base colour texel {i}");
            }
            checked += 1;
        }
        if mt.metallic_roughness.is_some() {
            let r = &mt.metallic_roughness;
            for (name, k, factor) in [
                ("metallic", 2, mt.mr_factor[0]),
                ("roughness", 1, mt.mr_factor[1]),
            ] {
                let (w, _, px) = bitmap(&dir, node, name);
                for (i, p) in px.iter().enumerate() {
                    let want = factor * texel(r, i, w, false)[k];
                    assert_eq!(*p, [want; 3], "m{m} {name} texel {i}");
                }
            }
            checked += 1;
        }
        if mt.normal.is_some() {
            assert_eq!(types[0], "normalmap", "m{m}: {types:?}");
            let (w, _, px) = bitmap(&dir, node, "normalmap");
            for (i, p) in px.iter().enumerate().step_by(7) {
                let c = texel(&mt.normal, i, w, false).truncate() * 2.0 - glam::Vec3::ONE;
                let got = glam::Vec3::from(*p) * 2.0 - glam::Vec3::ONE;
                let want = glam::Vec3::new(c.x * mt.normal.scale, c.y * mt.normal.scale, c.z);
                assert!(
                    (got - want).abs().max_element() < 1e-6,
                    "m{m} normal texel {i}"
                );
            }
            checked += 1;
        }
        if mt.has_alpha_test() {
            assert_eq!(types[0], "mask", "m{m}: {types:?}");
            let (w, _, px) = bitmap(&dir, node, "opacity");
            for (i, p) in px.iter().enumerate() {
                let a = mt.base_alpha * texel(&mt.base_color, i, w, false).w;
                let want = if a >= mt.alpha_cutoff { 1.0 } else { 0.0 };
                assert_eq!(*p, [want; 3], "m{m} opacity texel {i}");
            }
            checked += 1;
        }
        // The mesh's texture coordinates: its triangles' (the export's
        // triangle order may be another's, so as sorted triples).
        let (_, f, _, uvs) = ply_body(&dir.join(&file));
        let key = |t: &[[f32; 2]]| t.iter().flatten().map(|v| v.to_bits()).collect::<Vec<_>>();
        let mut got: Vec<Vec<u32>> = uvs.chunks(3).map(key).collect();
        let mut want: Vec<Vec<u32>> = scene
            .triangles
            .iter()
            .enumerate()
            .filter(|(_, t)| t.material == m as u32)
            .map(|(i, _)| key(&st.uvs[i].uv.map(|c| [c[0], c[1]])))
            .collect();
        got.sort();
        want.sort();
        assert_eq!(uvs.len(), 3 * f, "m{m}");
        assert_eq!(got, want, "m{m}");
    }
    // Base colour (checker, leaf), metallic-roughness, normal map, mask.
    assert_eq!(checked, 5);
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_file(&file);
}

/// An emissive texture goes on the area light: its bitmap is emissiveFactor
/// times the sRGB-decoded texels, on the emitter mesh's texture coordinates.
#[test]
fn an_emissive_texture_is_the_area_light_s_radiance() {
    use serde_json::json;
    let mut d = builder::Doc::new();
    let texels = [
        [255u8, 0, 0, 255],
        [0, 128, 0, 255],
        [0, 0, 64, 255],
        [255; 4],
    ]
    .concat();
    let t = d.png_texture(2, 2, &texels, json!({ "magFilter": 9728 }));
    let m = d.material(json!({
        "pbrMetallicRoughness": { "baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0 },
        "emissiveTexture": { "index": t }, "emissiveFactor": [1, 0.75, 0.5],
        "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 3 } }
    }));
    let q = d.uv_quad(1.0, 0.0, Some(m));
    d.node(json!({ "mesh": q }));
    let file = d.write_gltf(&builder::temp_dir("export-emissive"), "scene");
    let dir = scratch("emissive");
    export(&file, &dir);
    let scene = glint::cpu::loader::parse(&file).unwrap();
    let xml = std::fs::read_to_string(dir.join("scene.xml")).unwrap();
    let doc = roxmltree::Document::parse(&xml).unwrap();
    let (node, ply_file) = shape(doc.root_element(), "m0e");
    let emitter = node.children().find(|n| n.has_tag_name("emitter")).unwrap();
    let (w, h, px) = bitmap(&dir, emitter, "radiance");
    assert_eq!((w, h), (2, 2));
    assert!(
        xml.contains(r#"<string name="filter_type" value="nearest"/>"#),
        "{xml}"
    );
    let emission = scene.materials[0].emission;
    for (i, p) in px.iter().enumerate() {
        let c = &texels[4 * i..4 * i + 3];
        let want = emission
            * glam::Vec3::from_array(
                [0, 1, 2].map(|k| glint::cpu::texture::srgb_to_linear(c[k] as f32 / 255.0)),
            );
        assert!(
            (glam::Vec3::from(*p) - want).abs().max_element() < 1e-6,
            "texel {i}: {p:?} vs {want}"
        );
    }
    let (_, f, _, uvs) = ply_body(&dir.join(ply_file));
    assert_eq!((f, uvs.len()), (2, 6));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--envmap`: written as Mitsuba's `envmap`, its texels glint's (the
/// scale applied, a non-finite texel 0) and its turn about +Y, in place of
/// the constant background; the bilinear filter Mitsuba applies is warned
/// of. (Rendered against Mitsuba 3.9.1 when written: a camera seeing the
/// sky alone, relMSE 0.009 unturned and 0.011 turned by 30 degrees, 21-25
/// with the turn's sign flipped: docs/benchmarks.md.)
#[test]
fn the_environment_map_is_written_as_mitsubas_envmap() {
    let dir = scratch("envmap");
    std::fs::create_dir_all(&dir).unwrap();
    let sky = dir.join("sky.exr");
    let mut img = image::Rgb32FImage::from_fn(8, 4, |x, y| {
        image::Rgb([x as f32, y as f32 + 0.5, 1.0 + (x * y) as f32])
    });
    img.put_pixel(3, 1, image::Rgb([f32::NAN, 1.0, 1.0]));
    img.save(&sky).unwrap();
    let run = |out: &Path| {
        glint()
            .arg("export")
            .arg(asset("diffuse.gltf"))
            .arg("-o")
            .arg(out)
            .args(["--width", "16", "--envmap"])
            .arg(&sky)
            .args(["--envmap-scale", "2", "--envmap-rotate", "30"])
            .output()
            .unwrap()
    };
    let (out, again) = (dir.join("out"), dir.join("again"));
    let o = run(&out);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    // The same scene exports to the same bytes (the map's EXR included).
    assert!(run(&again).status.success());
    let bytes = |d: &Path| std::fs::read(d.join("textures/envmap.exr")).unwrap();
    assert_eq!(bytes(&out), bytes(&again));
    assert!(stderr.contains("Mitsuba filters it bilinearly"), "{stderr}");
    let xml = std::fs::read_to_string(out.join("scene.xml")).unwrap();
    let doc = roxmltree::Document::parse(&xml).unwrap();
    let emitters: Vec<_> = doc
        .root_element()
        .children()
        .filter(|n| n.has_tag_name("emitter"))
        .collect();
    let env = emitters
        .iter()
        .find(|n| n.attribute("type") == Some("envmap"))
        .expect("an envmap emitter");
    assert!(
        !emitters
            .iter()
            .any(|n| n.attribute("type") == Some("constant"))
    );
    let rotate = env
        .descendants()
        .find(|n| n.has_tag_name("rotate"))
        .unwrap();
    assert_eq!(rotate.attribute("y"), Some("1"));
    let angle: f32 = rotate.attribute("angle").unwrap().parse().unwrap();
    assert!((angle - 30.0).abs() < 1e-4, "{angle}");
    let file = env
        .children()
        .find(|n| n.attribute("name") == Some("filename"))
        .and_then(|n| n.attribute("value"))
        .unwrap();
    let written = image::open(out.join(file)).unwrap().into_rgb32f();
    assert_eq!(written.dimensions(), (8, 4));
    for (x, y, p) in written.enumerate_pixels() {
        let want = if (x, y) == (3, 1) {
            [0.0; 3]
        } else {
            img.get_pixel(x, y).0.map(|c| 2.0 * c)
        };
        assert_eq!(p.0, want, "texel ({x}, {y})");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Anisotropic lobes are oriented alike in both renderers: Mitsuba 3 takes
/// dP/du of a mesh's texture coordinates, or p1 - p0 without them (3.9.1
/// measured), so the export writes coordinates whose dP/du is glint's
/// tangent on every triangle, where one tangent per triangle says it
/// (dP/du of the file's TEXCOORD_0, or the first edge without one), and
/// warns where it cannot (a TANGENT that turns within a face).
#[test]
fn anisotropic_lobes_keep_glints_tangent_in_mitsuba() {
    use glam::{Vec2, Vec3};
    let mut d = builder::Doc::new();
    // A bent quad with smooth normals; its u runs along +y, across the
    // first edge (+x), so a PLY without coordinates would turn the lobe.
    let pos = d.floats(&[0., 0., 0., 1., 0., 0., 1., 1., 0.3, 0., 1., 0.], "VEC3");
    let nrm = d.floats(
        &[0., -0.3, 1., 0.2, -0.3, 1., 0.2, 0.3, 1., 0., 0.3, 1.],
        "VEC3",
    );
    let uv = d.floats(&[0., 0., 0., 1., 1., 1., 1., 0.], "VEC2");
    let tan = d.floats(
        &[
            1., 0., 0., 1., 0., 1., 0., 1., 1., 0., 0., 1., 0.7, 0.7, 0., 1.,
        ],
        "VEC4",
    );
    let idx = d.indices_u16(&[0, 1, 2, 0, 2, 3]);
    let mut prims = Vec::new();
    for attrs in [
        serde_json::json!({ "POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv }),
        serde_json::json!({ "POSITION": pos, "NORMAL": nrm }),
        serde_json::json!({ "POSITION": pos, "NORMAL": nrm, "TANGENT": tan }),
    ] {
        // Three materials (the loader merges equal ones).
        let alpha_u = 0.05 + 0.01 * prims.len() as f32;
        let m = d.material(serde_json::json!({ "extras": { "bsdf": {
            "type": "roughconductor", "material": "Au", "alpha_u": alpha_u, "alpha_v": 0.4,
            "shadowing": "separable" } } }));
        prims.push(serde_json::json!({ "attributes": attrs, "indices": idx, "material": m }));
    }
    let mesh = d.mesh(prims);
    d.node(serde_json::json!({ "mesh": mesh }));
    let dir = scratch("aniso");
    std::fs::create_dir_all(&dir).unwrap();
    let file = d.write_gltf(&dir, "aniso");
    let out = dir.join("out");
    let stderr = export(&file, &out);
    let warned = |m: usize| {
        stderr
            .lines()
            .any(|l| l.contains(&format!("material {m} ")) && l.contains("anisotropic"))
    };
    assert!(!warned(0) && !warned(1) && warned(2), "{stderr}");

    let scene = glint::cpu::loader::parse(&file).unwrap();
    for m in 0..2u32 {
        let (_, faces, _, positions, uvs) = ply_vertices(&out.join(format!("meshes/m{m}.ply")));
        assert_eq!(uvs.len(), 3 * faces, "material {m}: coordinates written");
        let tris: Vec<usize> = (0..scene.triangles.len())
            .filter(|&i| scene.triangles[i].material == m)
            .collect();
        assert_eq!(tris.len(), faces);
        for (f, &i) in tris.iter().enumerate() {
            // Mitsuba's dp_du of what was written (mesh.cpp).
            let p = [0, 1, 2].map(|k| Vec3::from(positions[3 * f + k]));
            let uv = [0, 1, 2].map(|k| Vec2::from(uvs[3 * f + k]));
            let (d0, d1) = (uv[1] - uv[0], uv[2] - uv[0]);
            let det = d0.x * d1.y - d0.y * d1.x;
            assert!(det != 0.0);
            let dp_du = ((d1.y * (p[1] - p[0]) - d0.y * (p[2] - p[0])) / det).normalize();
            for t in scene.shading_of(i).t {
                let t = Vec3::from_slice(&t[..3]).normalize();
                assert!(
                    t.dot(dp_du) > 0.9999,
                    "material {m}, face {f}: {t} vs {dp_du}"
                );
            }
            // Material 0's tangent is the file's dP/du (+y here), material
            // 1's its first edge.
            let want = if m == 0 {
                Vec3::Y
            } else {
                (p[1] - p[0]).normalize()
            };
            assert!(dp_du.dot(want) > 0.95, "material {m}: {dp_du} vs {want}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
