//! Bad input: every case is one `LoadError` whose text starts with the file's
//! path and names the problem; never a panic, never a runaway allocation.

#[path = "fixtures/gltf_builder.rs"]
mod builder;

use glint_cpu::sampling::Pcg32;
use std::path::{Path, PathBuf};

use builder::{Doc, temp_dir};
use glint_cpu::loader::{LoadError, parse};
use serde_json::{Value, json};

/// Parse `path`, expect an error that names the file and contains `needle`.
fn expect_err(path: &Path, needle: &str) -> String {
    let err = match parse(path) {
        Ok(_) => panic!("{} loaded but should fail with '{needle}'", path.display()),
        Err(e) => e,
    };
    let LoadError::Invalid { path: p, .. } = &err;
    assert_eq!(p, path);
    let text = err.to_string();
    assert!(
        text.starts_with(&format!("{}: ", path.display())),
        "error does not start with the path: {text}"
    );
    assert!(text.contains(needle), "error lacks '{needle}': {text}");
    assert!(!text.contains('\n'), "one line: {text}");
    text
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// A valid one-triangle document to break.
fn good() -> Doc {
    let mut d = Doc::new();
    let m = d.triangle_mesh(None);
    d.node(json!({ "mesh": m }));
    d
}

fn doc_err(test: &str, d: &Doc, needle: &str) -> String {
    let dir = temp_dir(test);
    expect_err(&d.write_gltf(&dir, "bad"), needle)
}

/// A document whose one material is `m`.
fn material_err(test: &str, m: Value, needle: &str) -> String {
    let mut d = Doc::new();
    d.material(m);
    let mesh = d.triangle_mesh(Some(0));
    d.node(json!({ "mesh": mesh }));
    doc_err(test, &d, needle)
}

fn bsdf_err(test: &str, bsdf: Value, needle: &str) -> String {
    material_err(
        test,
        json!({ "name": "broken", "extras": { "bsdf": bsdf } }),
        needle,
    )
}

#[test]
fn missing_file() {
    let dir = temp_dir("missing");
    expect_err(&dir.join("nope.gltf"), "cannot open");
    expect_err(&dir, "a directory, not a regular file");
}

#[test]
fn not_gltf_at_all() {
    let dir = temp_dir("not_gltf");
    expect_err(
        &write(&dir, "image.gltf", b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR"),
        "not a glTF file",
    );
    expect_err(&write(&dir, "empty.glb", b""), "not a glTF file");
    expect_err(
        &write(&dir, "array.gltf", b"[1, 2, 3]"),
        "not a valid glTF document",
    );
    expect_err(
        &write(&dir, "noasset.gltf", b"{\"scenes\": []}"),
        "missing field `asset`",
    );
}

#[test]
fn json_syntax_errors_and_truncated_gltf() {
    let dir = temp_dir("json_syntax");
    let e = expect_err(
        &write(&dir, "comma.gltf", b"{\"asset\": {\"version\": \"2.0\"},}"),
        "JSON",
    );
    assert!(e.contains("line 1"), "{e}");
    let full = std::fs::read(good().write_gltf(&dir, "full")).unwrap();
    expect_err(
        &write(&dir, "cut.gltf", &full[..full.len() / 2]),
        "JSON EOF",
    );
}

#[test]
fn truncated_and_malformed_glb() {
    let dir = temp_dir("glb");
    let glb = good().glb_bytes();
    expect_err(&write(&dir, "header.glb", &glb[..10]), "truncated GLB");
    expect_err(
        &write(&dir, "half.glb", &glb[..glb.len() / 2]),
        "truncated GLB",
    );
    // A header claiming 4 GB is refused without allocating it.
    let mut huge = glb.clone();
    huge[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
    expect_err(
        &write(&dir, "huge.glb", &huge),
        "header says 4294967295 bytes",
    );
    let mut v1 = glb.clone();
    v1[4] = 1;
    expect_err(&write(&dir, "v1.glb", &v1), "GLB version 1");
    // A chunk length running past the end.
    let mut chunk = glb.clone();
    chunk[12..16].copy_from_slice(&1_000_000u32.to_le_bytes());
    expect_err(&write(&dir, "chunk.glb", &chunk), "claims 1000000 bytes");
    let mut kind = glb.clone();
    kind[16..20].copy_from_slice(b"BIN\0");
    expect_err(&write(&dir, "kind.glb", &kind), "first chunk is not JSON");
    let mut small = glb;
    small[8..12].copy_from_slice(&8u32.to_le_bytes());
    expect_err(&write(&dir, "small.glb", &small), "malformed GLB");
}

#[test]
fn out_of_range_accessor_index() {
    let mut d = good();
    d.json["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(99);
    doc_err(
        "accessor_index",
        &d,
        "attributes[\"POSITION\"]: accessor 99 does not exist",
    );
    let mut d = good();
    d.json["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = json!(42);
    doc_err("normal_index", &d, "invalid glTF");
    let mut d = good();
    d.json["nodes"][0]["mesh"] = json!(5);
    doc_err("mesh_index", &d, "nodes[0].mesh");
}

#[test]
fn vertex_index_out_of_range() {
    let mut d = Doc::new();
    let pos = d.floats(&[0., 0., 0., 1., 0., 0., 0., 1., 0.], "VEC3");
    let idx = d.indices_u16(&[0, 1, 7]);
    let m = d.mesh(vec![
        json!({ "attributes": { "POSITION": pos }, "indices": idx }),
    ]);
    d.node(json!({ "mesh": m }));
    doc_err(
        "vertex_index",
        &d,
        "index 7 (at position 2) is out of range: 3 vertices",
    );
}

#[test]
fn absurd_counts_are_refused_before_allocating() {
    let mut d = good();
    d.json["accessors"][0]["count"] = json!(3000);
    doc_err(
        "big_count",
        &d,
        "3000 elements of 12 bytes (stride 12) at offset 0 do not fit",
    );
    // Counted against the triangle limit before any read.
    let mut d = good();
    d.json["accessors"][0]["count"] = json!(3_000_000_000u64);
    doc_err("huge_count", &d, "1000000000 triangles");
    // Indices too: a huge index count over a tiny buffer.
    let mut d = good();
    let view = d.view(&[0, 1, 2, 0]);
    let idx = d.accessor(
        json!({ "bufferView": view, "componentType": 5121, "count": 3_000_000, "type": "SCALAR" }),
    );
    d.json["meshes"][0]["primitives"][0]["indices"] = json!(idx);
    doc_err("huge_indices", &d, "3000000 elements of 1 bytes");
    // A sparse accessor without a buffer view: implicit zeros, bounded
    // separately since no buffer bounds them.
    let mut d = good();
    let iv = d.view(&[0, 0]);
    let vv = d.view(&[0; 12]);
    let n = d.accessor(json!({ "componentType": 5126, "count": 4_000_000_000u64, "type": "VEC3",
        "sparse": { "count": 1, "indices": { "bufferView": iv, "componentType": 5123 }, "values": { "bufferView": vv } } }));
    d.json["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = json!(n);
    doc_err(
        "implicit_count",
        &d,
        "4000000000 elements without a buffer view",
    );
    // A buffer view past the end of its buffer.
    let mut d = good();
    d.json["bufferViews"][0]["byteLength"] = json!(4096);
    doc_err("view_past_end", &d, "runs past the end of buffer 0");
    // A byteStride smaller than the element.
    let mut d = good();
    d.json["bufferViews"][0]["byteStride"] = json!(4);
    doc_err(
        "stride",
        &d,
        "byteStride 4 is smaller than the 12-byte element",
    );
}

#[test]
fn triangle_limit_is_checked_before_generating() {
    // 2,000 instances of an 8,400-triangle mesh: 16.8 million triangles,
    // just over the 2^24 limit, from a file of a few hundred KB.
    let mut d = Doc::new();
    let pos = d.floats(&[0., 0., 0., 1., 0., 0., 0., 1., 0.], "VEC3");
    let bytes: Vec<u8> = (0..8400 * 3).map(|i| (i % 3) as u8).collect();
    let view = d.view(&bytes);
    let idx = d.accessor(json!({ "bufferView": view, "componentType": 5121, "count": bytes.len(), "type": "SCALAR" }));
    let m = d.mesh(vec![
        json!({ "attributes": { "POSITION": pos }, "indices": idx }),
    ]);
    for _ in 0..2000 {
        d.node(json!({ "mesh": m }));
    }
    doc_err(
        "triangle_cap",
        &d,
        "16800000 triangles, more than glint's limit of 16777216",
    );
}

#[test]
fn non_finite_positions_and_transforms() {
    let mut d = Doc::new();
    let pos = d.floats(&[0., 0., 0., f32::NAN, 0., 0., 0., 1., 0.], "VEC3");
    let m = d.mesh(vec![json!({ "attributes": { "POSITION": pos } })]);
    d.node(json!({ "mesh": m }));
    doc_err("nan_position", &d, "POSITION 1 is not finite");

    let mut d = Doc::new();
    let pos = d.floats(&[0., 0., 0., f32::INFINITY, 0., 0., 0., 1., 0.], "VEC3");
    let m = d.mesh(vec![json!({ "attributes": { "POSITION": pos } })]);
    d.node(json!({ "mesh": m }));
    doc_err("inf_position", &d, "is not finite");

    // 1e39 overflows f32 to infinity.
    let mut d = good();
    d.json["nodes"][0]["translation"] = json!([0, 1e39, 0]);
    doc_err("inf_translation", &d, "non-finite");
    let mut d = good();
    d.json["nodes"][0]["matrix"] = json!([1, 0, 0, 0, 0, 1e39, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]);
    doc_err("inf_matrix", &d, "matrix has a non-finite value");
    let mut d = good();
    d.json["nodes"][0]["matrix"] = json!([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 1, 0, 0, 0, 1]);
    doc_err("projective", &d, "not affine");
    // Finite factors whose product overflows.
    let mut d = good();
    let child = d.json["nodes"][0].clone();
    d.json["nodes"][0] = json!({ "scale": [3e38, 3e38, 3e38], "children": [1] });
    d.child(json!({ "scale": [3e38, 3e38, 3e38], "children": [] , "mesh": child["mesh"] }));
    doc_err("overflow", &d, "non-finite");
    let mut d = good();
    d.json["nodes"][0]["rotation"] = json!([0, 0, 0, 0]);
    doc_err("zero_quat", &d, "zero length");
    let mut d = Doc::new();
    let pos = d.floats(&[0., 0., 0., 1., 0., 0., 0., 1., 0.], "VEC3");
    let nrm = d.floats(&[0., 0., 1., f32::NAN, 0., 1., 0., 0., 1.], "VEC3");
    let m = d.mesh(vec![
        json!({ "attributes": { "POSITION": pos, "NORMAL": nrm } }),
    ]);
    d.node(json!({ "mesh": m }));
    doc_err("nan_normal", &d, "NORMAL 1 is not finite");
}

#[test]
fn bad_attributes() {
    let mut d = good();
    d.json["meshes"][0]["primitives"][0]["attributes"] = json!({ "NORMAL": 0 });
    doc_err("no_position", &d, "attributes[\"POSITION\"]: Missing data");
    let mut d = good();
    d.json["accessors"][0]["type"] = json!("VEC2");
    d.json["accessors"][0]["count"] = json!(4);
    doc_err(
        "vec2_position",
        &d,
        "type is VEC2, expected a 3-component vector",
    );
    let mut d = Doc::new();
    let pos = d.floats(&[0., 0., 0., 1., 0., 0., 0., 1., 0.], "VEC3");
    let nrm = d.floats(&[0., 0., 1., 0., 0., 1.], "VEC3");
    let m = d.mesh(vec![
        json!({ "attributes": { "POSITION": pos, "NORMAL": nrm } }),
    ]);
    d.node(json!({ "mesh": m }));
    doc_err(
        "normal_count",
        &d,
        "NORMAL has 2 elements but POSITION has 3",
    );
}

#[test]
fn unknown_bsdf_type_and_parameters() {
    bsdf_err(
        "bsdf_type",
        json!({ "type": "velvet" }),
        "unknown BSDF type \"velvet\"",
    );
    let e = bsdf_err(
        "bsdf_type_name",
        json!({ "type": "velvet" }),
        "material 0 ('broken')",
    );
    assert!(e.contains("extras.bsdf"), "{e}");
    bsdf_err(
        "bsdf_no_type",
        json!({ "reflectance": 0.5 }),
        "has no \"type\"",
    );
    bsdf_err("bsdf_not_object", json!("diffuse"), "must be an object");
    bsdf_err(
        "bsdf_typo",
        json!({ "type": "roughconductor", "alpha_x": 0.1 }),
        "no parameter \"alpha_x\"",
    );
    bsdf_err(
        "bsdf_smooth_alpha",
        json!({ "type": "conductor", "alpha": 0.1 }),
        "no parameter \"alpha\"",
    );
    bsdf_err(
        "bsdf_distribution",
        json!({ "type": "roughconductor", "distribution": "beckmann" }),
        "\"distribution\" must be \"ggx\"",
    );
    bsdf_err(
        "bsdf_shadowing",
        json!({ "type": "roughdielectric", "shadowing": "smith" }),
        "\"shadowing\" must be",
    );
    bsdf_err(
        "bsdf_both_alphas",
        json!({ "type": "roughdielectric", "alpha": 0.1, "alpha_u": 0.2, "alpha_v": 0.2 }),
        "either \"alpha\"",
    );
    bsdf_err(
        "bsdf_half_alpha",
        json!({ "type": "roughdielectric", "alpha_u": 0.2 }),
        "must be given together",
    );
    bsdf_err(
        "bsdf_eta_only",
        json!({ "type": "conductor", "eta": [1, 1, 1] }),
        "must be given together",
    );
    bsdf_err(
        "bsdf_both_metal",
        json!({ "type": "conductor", "material": "Au", "eta": [1, 1, 1], "k": [1, 1, 1] }),
        "not both",
    );
    bsdf_err(
        "bsdf_zero_metal",
        json!({ "type": "conductor", "eta": [0, 1, 1], "k": [0, 1, 1] }),
        "both 0",
    );
}

#[test]
fn unknown_metal_and_ior_names() {
    bsdf_err(
        "metal_name",
        json!({ "type": "conductor", "material": "Unobtainium" }),
        "unknown metal \"Unobtainium\"",
    );
    bsdf_err(
        "ior_name",
        json!({ "type": "dielectric", "int_ior": "glassy" }),
        "unknown IOR name \"glassy\" for \"int_ior\"",
    );
    bsdf_err(
        "ior_type",
        json!({ "type": "dielectric", "ext_ior": [1.0] }),
        "\"ext_ior\" must be a number or a name",
    );
}

#[test]
fn bad_numbers_in_extras() {
    bsdf_err(
        "neg_alpha",
        json!({ "type": "roughconductor", "alpha": -0.1 }),
        "\"alpha\" must be a finite number in [0, inf]",
    );
    bsdf_err(
        "inf_alpha",
        json!({ "type": "roughconductor", "alpha_u": 1e39, "alpha_v": 0.1 }),
        "\"alpha_u\" must be a finite number",
    );
    bsdf_err(
        "str_alpha",
        json!({ "type": "roughconductor", "alpha": "rough" }),
        "\"alpha\" must be a number",
    );
    bsdf_err(
        "neg_ior",
        json!({ "type": "dielectric", "int_ior": -1.5 }),
        "\"int_ior\" must be a finite number > 0",
    );
    bsdf_err(
        "zero_ior",
        json!({ "type": "roughdielectric", "ext_ior": 0 }),
        "\"ext_ior\" must be a finite number > 0",
    );
    bsdf_err(
        "neg_refl",
        json!({ "type": "diffuse", "reflectance": [0.5, -0.1, 0.5] }),
        "\"reflectance\" values must be finite and in [0, 1]",
    );
    bsdf_err(
        "big_refl",
        json!({ "type": "diffuse", "reflectance": 1.5 }),
        "in [0, 1]",
    );
    bsdf_err(
        "short_refl",
        json!({ "type": "diffuse", "reflectance": [0.5, 0.5] }),
        "must be [r, g, b] (3 numbers), got 2 values",
    );
    bsdf_err(
        "long_k",
        json!({ "type": "conductor", "eta": [1, 1, 1], "k": [1, 1, 1, 1] }),
        "\"k\" must be [r, g, b] (3 numbers), got 4 values",
    );
    bsdf_err(
        "neg_eta",
        json!({ "type": "conductor", "eta": [-1, 1, 1], "k": [1, 1, 1] }),
        "\"eta\" values must be finite and >= 0",
    );
    bsdf_err(
        "str_spec",
        json!({ "type": "conductor", "specular_reflectance": ["a", 1, 1] }),
        "must hold numbers",
    );
}

#[test]
fn bad_gltf_material_factors() {
    material_err(
        "base_color",
        json!({ "pbrMetallicRoughness": { "baseColorFactor": [2, 0, 0, 1] } }),
        "baseColorFactor must lie in [0, 1]",
    );
    material_err(
        "metallic",
        json!({ "pbrMetallicRoughness": { "metallicFactor": -1 } }),
        "metallicFactor must lie in [0, 1]",
    );
    material_err(
        "roughness",
        json!({ "pbrMetallicRoughness": { "roughnessFactor": 1.5 } }),
        "roughnessFactor",
    );
    material_err(
        "emissive",
        json!({ "emissiveFactor": [1, 2, 0] }),
        "emissiveFactor",
    );
    material_err(
        "strength",
        json!({ "emissiveFactor": [1, 1, 1], "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": -3 } } }),
        "emissiveStrength must be finite and >= 0",
    );
    material_err(
        "ior",
        json!({ "extensions": { "KHR_materials_transmission": { "transmissionFactor": 1 }, "KHR_materials_ior": { "ior": 0.5 } } }),
        "ior must be finite and >= 1",
    );
}

#[test]
fn required_extensions() {
    let mut d = good();
    d.json["extensionsUsed"] = json!(["KHR_draco_mesh_compression", "EXT_unknown_optional"]);
    d.json["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
    doc_err(
        "required",
        &d,
        "requires unsupported extension(s) KHR_draco_mesh_compression",
    );
    // Optional unknown extensions are ignored, even on objects.
    let mut d = good();
    d.json["extensionsUsed"] = json!(["EXT_unknown_optional"]);
    d.json["nodes"][0]["extensions"] = json!({ "EXT_unknown_optional": { "x": 1 } });
    let dir = temp_dir("optional");
    assert_eq!(parse(&d.write_gltf(&dir, "ok")).unwrap().triangles.len(), 1);
    // A supported one listed as required is fine.
    let mut d = good();
    d.json["extensionsRequired"] = json!(["KHR_materials_emissive_strength"]);
    assert_eq!(
        parse(&d.write_gltf(&dir, "ok2")).unwrap().triangles.len(),
        1
    );
}

#[test]
fn node_cycles_and_shared_children() {
    let mut d = good();
    d.json["nodes"][0]["children"] = json!([1]);
    d.child(json!({ "children": [0] }));
    doc_err("cycle", &d, "is reached twice");
    let mut d = good();
    d.json["nodes"][0]["children"] = json!([0]);
    doc_err("self", &d, "node 0 is reached twice");
    let mut d = good();
    let c = d.child(json!({}));
    d.node(json!({ "children": [c] }));
    d.node(json!({ "children": [c], "name": "second parent" }));
    doc_err("shared", &d, "a cycle or a shared child");
}

#[test]
fn deep_hierarchy_does_not_overflow_the_stack() {
    let mut d = good();
    let n = 100_000;
    for i in 1..n {
        d.child(json!({ "children": [i + 1], "translation": [0.0, 0.0, 1e-4] }));
    }
    let m = d.json["nodes"][0]["mesh"].clone();
    d.child(json!({ "mesh": m }));
    d.json["nodes"][0]["children"] = json!([1]);
    let dir = temp_dir("deep");
    let s = parse(&d.write_gltf(&dir, "deep")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.triangles.len(), 2);
}

#[test]
fn bad_buffers() {
    let mut d = good();
    d.json["bufferViews"][0]["byteOffset"] = json!(0);
    let dir = temp_dir("buffers");
    let p = d.write_gltf(&dir, "b64");
    let mut j: Value = serde_json::from_slice(&std::fs::read(&p).unwrap()).unwrap();
    j["buffers"][0]["uri"] = json!("data:application/octet-stream;base64,AAAA$$$$");
    let bad = write(&dir, "bad64.gltf", &serde_json::to_vec(&j).unwrap());
    expect_err(
        &bad,
        "buffer 0: data URI does not decode: invalid base64 character '$'",
    );
    j["buffers"][0]["uri"] = json!("data:application/octet-stream,plain");
    let plain = write(&dir, "plain.gltf", &serde_json::to_vec(&j).unwrap());
    expect_err(&plain, "not base64-encoded");
    j["buffers"][0]["uri"] = json!("missing.bin");
    let missing = write(&dir, "missing.gltf", &serde_json::to_vec(&j).unwrap());
    expect_err(&missing, "buffer 0: ");
    expect_err(&missing, "missing.bin: cannot open");
    j["buffers"][0]["uri"] = json!("https://example.invalid/x.bin");
    let web = write(&dir, "web.gltf", &serde_json::to_vec(&j).unwrap());
    expect_err(&web, "URI scheme 'https:' is not supported");
    j["buffers"][0]["uri"] = json!("data:application/octet-stream;base64,AAAA");
    let short = write(&dir, "short.gltf", &serde_json::to_vec(&j).unwrap());
    expect_err(&short, "buffer 0 declares 36 bytes but holds only 3");
    // A .glb whose buffer has no uri but no BIN chunk either.
    let mut d = good();
    d.bin.clear();
    let glb = d.write_glb(&dir, "nobin");
    expect_err(&glb, "no GLB BIN chunk");
}

#[test]
fn no_scene() {
    let mut d = good();
    d.json.as_object_mut().unwrap().remove("scene");
    d.json["scenes"] = json!([]);
    doc_err("no_scene", &d, "the file has no scene to render");
}

#[test]
fn bad_cameras() {
    let mut d = good();
    d.json["cameras"] = json!([{ "type": "orthographic", "orthographic": { "xmag": 1, "ymag": 1, "zfar": 10, "znear": 0.1 } }]);
    d.node(json!({ "camera": 0 }));
    doc_err("ortho", &d, "orthographic cameras are not supported");
    let mut d = good();
    d.json["cameras"] =
        json!([{ "type": "perspective", "perspective": { "yfov": 0, "znear": 0.1 } }]);
    d.node(json!({ "camera": 0 }));
    doc_err("yfov", &d, "yfov must lie in (0, pi)");
    let mut d = good();
    d.json["cameras"] = json!([{ "type": "perspective", "perspective": { "yfov": 1, "aspectRatio": -1, "znear": 0.1 } }]);
    d.node(json!({ "camera": 0 }));
    doc_err("aspect", &d, "aspectRatio must be finite and > 0");
    let mut d = good();
    d.json["cameras"] =
        json!([{ "type": "perspective", "perspective": { "yfov": 1, "znear": 0.1 } }]);
    d.node(json!({ "camera": 0, "scale": [1, 0, 0] }));
    doc_err("cam_scale", &d, "degenerate");
}

#[test]
fn bad_lights_and_background() {
    let light_doc = |light: Value| {
        let mut d = good();
        d.json["extensions"] = json!({ "KHR_lights_punctual": { "lights": [light] } });
        d.node(json!({ "extensions": { "KHR_lights_punctual": { "light": 0 } } }));
        d
    };
    doc_err(
        "neg_intensity",
        &light_doc(json!({ "type": "point", "intensity": -1 })),
        "intensity must be finite and >= 0",
    );
    doc_err(
        "neg_color",
        &light_doc(json!({ "type": "point", "color": [1, -1, 1] })),
        "color must be finite",
    );
    doc_err(
        "cone",
        &light_doc(
            json!({ "type": "spot", "spot": { "innerConeAngle": 0.5, "outerConeAngle": 0.4 } }),
        ),
        "innerConeAngle < outerConeAngle",
    );
    doc_err(
        "light_type",
        &light_doc(json!({ "type": "area" })),
        "invalid glTF",
    );
    let mut d = good();
    d.node(json!({ "extensions": { "KHR_lights_punctual": { "light": 3 } } }));
    doc_err("light_index", &d, "invalid glTF");
    let mut d = good();
    d.json["scenes"][0]["extras"] = json!({ "background": [0.1, 0.2] });
    doc_err("bg_len", &d, "extras.background: must be [r, g, b]");
    let mut d = good();
    d.json["scenes"][0]["extras"] = json!({ "background": [0.1, -0.2, 0] });
    doc_err("bg_neg", &d, "values must be finite and >= 0");
}

#[test]
fn mutated_files_never_panic() {
    // A document touching most of the loader: indices, normals, UVs,
    // materials with extras, a camera, a light, a hierarchy.
    let mut d = Doc::new();
    d.material(json!({ "extras": { "bsdf": { "type": "roughdielectric", "alpha": 0.2 } }, "emissiveFactor": [1, 1, 1] }));
    let pos = d.floats(&[0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.], "VEC3");
    let nrm = d.floats(&[0., 0., 1., 0., 0., 1., 0., 0., 1., 0., 0., 1.], "VEC3");
    let uv = d.floats(&[0., 0., 1., 0., 1., 1., 0., 1.], "VEC2");
    let idx = d.indices_u16(&[0, 1, 2, 0, 2, 3]);
    let m = d.mesh(vec![json!({ "attributes": { "POSITION": pos, "NORMAL": nrm, "TEXCOORD_0": uv }, "indices": idx, "material": 0 })]);
    d.json["cameras"] =
        json!([{ "type": "perspective", "perspective": { "yfov": 0.8, "znear": 0.1 } }]);
    d.json["extensions"] =
        json!({ "KHR_lights_punctual": { "lights": [{ "type": "spot", "spot": {} }] } });
    let child = d.child(json!({ "mesh": m, "scale": [1, 2, 3] }));
    d.node(json!({ "children": [child], "camera": 0, "translation": [1, 2, 3] }));
    d.node(json!({ "extensions": { "KHR_lights_punctual": { "light": 0 } }, "rotation": glam::Quat::from_rotation_y(1.0).to_array() }));
    let dir = temp_dir("mutate");
    let glb = d.glb_bytes();
    let gltf = std::fs::read(d.write_gltf(&dir, "seed")).unwrap();
    assert!(parse(&write(&dir, "seed.glb", &glb)).is_ok());
    let mut rng = Pcg32::from_state(0x9E37_79B9_7F4A_7C15);
    let mut failures = 0;
    for round in 0..6000 {
        let (mut bytes, ext) = if round % 2 == 0 {
            (glb.clone(), "glb")
        } else {
            (gltf.clone(), "gltf")
        };
        for _ in 0..1 + rng.below(3) {
            let at = rng.below(bytes.len());
            match rng.below(4) {
                // Digits keep JSON parseable while changing numbers and indices.
                0 | 1 => bytes[at] = b"0123456789"[rng.below(10)],
                2 => bytes[at] = rng.next_u64() as u8,
                _ => bytes.truncate(at.max(1)),
            }
        }
        let path = write(&dir, &format!("m{round}.{ext}"), &bytes);
        let outcome = std::panic::catch_unwind(|| parse(&path).map(|s| s.triangles.len()));
        match outcome {
            Err(_) => panic!("parse panicked on {} (round {round})", path.display()),
            Ok(Err(e)) => {
                failures += 1;
                assert!(e.to_string().starts_with(&path.display().to_string()));
            }
            Ok(Ok(_)) => {}
        }
        std::fs::remove_file(&path).unwrap();
    }
    eprintln!("{failures} of 6000 mutated files were refused");
    // Sanity: the mutations do break files (the test exercises error paths).
    assert!(
        failures > 1200,
        "only {failures} of 6000 mutations failed to load"
    );
}

#[test]
fn uris_leaving_the_folder_are_refused() {
    use glint_cpu::loader::{LoadOptions, parse_with};
    let root = temp_dir("escape");
    let inner = root.join("scene");
    std::fs::create_dir_all(inner.join("sub")).unwrap();
    let d = good();
    // The buffer beside the scene's folder, named four ways.
    std::fs::write(root.join("outside.bin"), &d.bin).unwrap();
    std::fs::write(inner.join("sub").join("inside.bin"), &d.bin).unwrap();
    let p = d.write_gltf(&inner, "base");
    let j: Value = serde_json::from_slice(&std::fs::read(&p).unwrap()).unwrap();
    let abs = root.join("outside.bin").display().to_string();
    for (name, uri) in [
        ("dotdot", "../outside.bin".to_string()),
        ("deep", "sub/../../outside.bin".to_string()),
        ("abs", abs.clone()),
        ("fileuri", format!("file://{abs}")),
    ] {
        let mut j = j.clone();
        j["buffers"][0]["uri"] = json!(uri);
        let path = write(
            &inner,
            &format!("{name}.gltf"),
            &serde_json::to_vec(&j).unwrap(),
        );
        let text = expect_err(&path, "outside the scene's folder");
        assert!(text.contains("--allow-any-path"), "{text}");
        let allowed = parse_with(
            &path,
            LoadOptions {
                allow_any_path: true,
                ..Default::default()
            },
        )
        .unwrap_or_else(|e| panic!("{name} with allow_any_path: {e}"));
        assert_eq!(allowed.triangles.len(), 1);
    }
    // `..` that stays inside the folder is fine.
    let mut j = j.clone();
    j["buffers"][0]["uri"] = json!("sub/../sub/inside.bin");
    let path = write(&inner, "inside.gltf", &serde_json::to_vec(&j).unwrap());
    assert_eq!(parse(&path).unwrap().triangles.len(), 1);
}

#[test]
fn index_counts_and_empty_meshes() {
    let mut d = Doc::new();
    let pos = d.floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0], "VEC3");
    let idx = d.indices_u16(&[0, 1, 2, 0]);
    let m = d.mesh(vec![
        json!({ "attributes": { "POSITION": pos }, "indices": idx }),
    ]);
    d.node(json!({ "mesh": m }));
    doc_err("idx4", &d, "index count 4 is not a multiple of 3");
    let mut d = Doc::new();
    let pos = d.floats(&[0.0; 12], "VEC3");
    let m = d.mesh(vec![json!({ "attributes": { "POSITION": pos } })]);
    d.node(json!({ "mesh": m }));
    doc_err("vert4", &d, "vertex count 4 is not a multiple of 3");
    let mut d = Doc::new();
    let m = d.mesh(vec![]);
    d.node(json!({ "mesh": m }));
    doc_err("noprims", &d, "has no primitives");
}
