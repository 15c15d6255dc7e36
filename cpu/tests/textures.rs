//! glTF textures against analytic expectations: texel lookup (nearest,
//! bilinear, wrap modes, UV transform, sRGB, UV origin), textured renders
//! (a 2x2 texture seen head-on, a normal map's cosine, an alpha mask's
//! shadow), and bad images.

#[path = "fixtures/gltf_builder.rs"]
mod builder;

use std::f32::consts::PI;

use builder::{Doc, png_bytes, temp_dir};
use glam::{Quat, Vec2, Vec3, Vec4};
use glint_cpu::bvh::Ray;
use glint_cpu::loader::{load, parse};
use glint_cpu::texture::{TexRef, srgb_to_linear, texture_sample};
use glint_cpu::{RenderOptions, Scene};
use serde_json::{Value, json};

const RED: [u8; 4] = [255, 0, 0, 255];
const GREEN: [u8; 4] = [0, 255, 0, 255];
const BLUE: [u8; 4] = [0, 0, 255, 255];
const WHITE: [u8; 4] = [255, 255, 255, 255];

/// 2x2: red top-left, green top-right, blue bottom-left, white bottom-right.
fn quad_texels() -> Vec<u8> {
    [RED, GREEN, BLUE, WHITE].concat()
}

fn c(t: [u8; 4]) -> Vec4 {
    Vec4::from_array(t.map(|x| x as f32 / 255.0))
}

fn close4(a: Vec4, b: Vec4) {
    assert!((a - b).abs().max_element() < 1e-5, "{a} != {b}");
}

/// A scene of one textured quad per sampler; returns the loaded scene.
fn sampler_scene(test: &str, samplers: &[Value]) -> Scene {
    let mut d = Doc::new();
    for (k, s) in samplers.iter().enumerate() {
        let t = d.png_texture(2, 2, &quad_texels(), s.clone());
        let m = d.material(json!({
            "pbrMetallicRoughness": { "baseColorTexture": { "index": t }, "metallicFactor": 0 }
        }));
        let q = d.uv_quad(1.0, k as f32, Some(m));
        d.node(json!({ "mesh": q }));
    }
    let dir = temp_dir(test);
    parse(&d.write_gltf(&dir, "scene")).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn nearest_and_bilinear_with_the_origin_at_the_top_left() {
    let s = sampler_scene(
        "filters",
        &[json!({ "magFilter": 9728 }), json!({ "magFilter": 9729 })],
    );
    let st = &s.textures;
    assert_eq!(st.table.len(), 2);
    assert_eq!((st.info[0].width, st.info[0].height), (2, 2));
    let at =
        |t: usize, u: f32, v: f32| texture_sample(&st.texels, &st.table[t], Vec2::new(u, v), false);
    // Nearest: each quadrant is its texel; (0, 0) is the image's first row.
    close4(at(0, 0.25, 0.25), c(RED));
    close4(at(0, 0.75, 0.25), c(GREEN));
    close4(at(0, 0.25, 0.75), c(BLUE));
    close4(at(0, 0.99, 0.99), c(WHITE));
    close4(at(0, 0.45, 0.05), c(RED));
    // Bilinear: exact at texel centres, the mean of the four at the middle.
    close4(at(1, 0.25, 0.25), c(RED));
    close4(at(1, 0.5, 0.25), (c(RED) + c(GREEN)) / 2.0);
    close4(
        at(1, 0.5, 0.5),
        (c(RED) + c(GREEN) + c(BLUE) + c(WHITE)) / 4.0,
    );
    close4(at(1, 0.375, 0.25), 0.75 * c(RED) + 0.25 * c(GREEN));
}

#[test]
fn wrap_modes() {
    // REPEAT (default), CLAMP_TO_EDGE, MIRRORED_REPEAT, bilinear.
    let s = sampler_scene(
        "wraps",
        &[
            json!({ "wrapS": 10497, "wrapT": 10497 }),
            json!({ "wrapS": 33071, "wrapT": 33071 }),
            json!({ "wrapS": 33648, "wrapT": 33648 }),
            json!({ "wrapS": 33071, "wrapT": 10497, "magFilter": 9728 }),
        ],
    );
    let st = &s.textures;
    let at =
        |t: usize, u: f32, v: f32| texture_sample(&st.texels, &st.table[t], Vec2::new(u, v), false);
    let (r, g, b) = (c(RED), c(GREEN), c(BLUE));
    // Repeat: u = 0 blends the left and the (wrapped) right column.
    close4(at(0, 0.0, 0.25), (r + g) / 2.0);
    close4(at(0, 1.25, 0.25), r);
    close4(at(0, -0.25, 0.25), g);
    close4(at(0, 7.25, -2.75), r);
    // Clamp: the edge texel.
    close4(at(1, 0.0, 0.25), r);
    close4(at(1, 1.25, 0.25), g);
    close4(at(1, -0.25, 0.25), r);
    close4(at(1, 0.25, 5.0), b);
    // Mirror: u in (1, 2) runs backwards.
    close4(at(2, 0.0, 0.25), r);
    close4(at(2, 1.25, 0.25), g);
    close4(at(2, 1.75, 0.25), r);
    close4(at(2, -0.25, 0.25), r);
    // Per axis: S clamps, T repeats (nearest).
    close4(at(3, 1.5, 1.25), g);
    close4(at(3, -0.5, 1.75), b);
    // NaN reads as 0, no panic.
    let _ = at(0, f32::NAN, f32::INFINITY);
}

#[test]
fn uv_transform_and_tex_coord() {
    let mut d = Doc::new();
    let t = d.png_texture(2, 2, &quad_texels(), json!({ "magFilter": 9728 }));
    let m = d.material(json!({ "pbrMetallicRoughness": { "baseColorTexture": {
        "index": t, "texCoord": 0,
        "extensions": { "KHR_texture_transform": {
            "offset": [0.5, 0.25], "rotation": 0.5, "scale": [2.0, 3.0], "texCoord": 1 } } } } }));
    let q = d.uv_quad(1.0, 0.0, Some(m));
    d.node(json!({ "mesh": q }));
    d.json["extensionsUsed"] = json!(["KHR_texture_transform"]);
    let s = parse(&d.write_gltf(&temp_dir("transform"), "scene")).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let r = s.textures.materials[0].base_color;
    assert_eq!(r.tex_coord, 1, "the extension's texCoord overrides");
    // T(offset) R(rotation) S(scale), R by the sample model's (and
    // Blender's, three.js's) convention: u' = cos u + sin v, v' = -sin u +
    // cos v (the extension text's listing has the other sign).
    let uv = Vec2::new(0.3, 0.7);
    let (sn, cs) = 0.5f32.sin_cos();
    let want = Vec2::new(
        cs * 2.0 * uv.x + sn * 3.0 * uv.y + 0.5,
        -sn * 2.0 * uv.x + cs * 3.0 * uv.y + 0.25,
    );
    assert!(
        (r.apply(uv) - want).length() < 1e-5,
        "{} != {want}",
        r.apply(uv)
    );
    // An offset of half the image moves red onto green's place.
    let mut shift = TexRef {
        texture: 0,
        ..TexRef::default()
    };
    shift.set_transform(Vec2::new(0.5, 0.0), 0.0, Vec2::ONE);
    let st = &s.textures;
    close4(
        texture_sample(
            &st.texels,
            &st.table[0],
            shift.apply(Vec2::new(0.25, 0.25)),
            false,
        ),
        c(GREEN),
    );
}

#[test]
fn srgb_decode_of_base_color_and_emissive() {
    assert!((srgb_to_linear(128.0 / 255.0) - 0.2158).abs() < 1e-4);
    let mut d = Doc::new();
    let grey = [128u8, 128, 128, 255];
    let t = d.png_texture(1, 1, &grey, Value::Null);
    let m = d.material(json!({
        "pbrMetallicRoughness": { "baseColorTexture": { "index": t }, "metallicFactor": 0 },
        "emissiveTexture": { "index": t }, "emissiveFactor": [1, 1, 1]
    }));
    let q = d.uv_quad(1.0, 0.0, Some(m));
    d.node(json!({ "mesh": q }));
    let s = load(&d.write_gltf(&temp_dir("srgb"), "scene")).unwrap();
    let st = &s.textures;
    let mt = st.materials[0];
    let base = st.lookup(&mt.base_color, 0, 0.3, 0.3, true);
    let emit = st.lookup(&mt.emissive, 0, 0.3, 0.3, true);
    for x in [base.x, base.y, base.z, emit.x] {
        assert!((x - 0.2158).abs() < 1e-4, "{x}");
    }
    // The emitter's radiance is emission x texture, on both backends' path.
    let le = glint_cpu::lights::emitted(&s, 0, 0.3, 0.3, Vec3::Z).unwrap();
    assert!((le.x - 0.2158).abs() < 1e-4, "{le}");
}

/// Camera at (0, 0, dist) looking down -Z with yfov so the quad [-1, 1]^2
/// fills the image exactly.
fn head_on(d: &mut Doc, dist: f32) {
    let yfov = 2.0 * (1.0 / dist).atan();
    d.json["cameras"] =
        json!([{ "type": "perspective", "perspective": { "yfov": yfov, "znear": 0.01 } }]);
    d.node(json!({ "camera": 0, "translation": [0, 0, dist] }));
}

fn render(s: &Scene, size: u32, spp: u32, max_depth: i32) -> glint_cpu::Film {
    let o = RenderOptions {
        spp,
        max_depth,
        ..RenderOptions::new(size, size)
    };
    glint_cpu::render(s, &o, &|_, _| {}).unwrap().0
}

#[test]
fn two_by_two_texture_seen_head_on() {
    // A diffuse quad under a white sky of radiance 1 reflects exactly its
    // albedo (nothing else in the scene): each image quadrant is one
    // texel's sRGB-decoded colour.
    let mut d = Doc::new();
    let t = d.png_texture(2, 2, &quad_texels(), json!({ "magFilter": 9728 }));
    let m = d.material(json!({
        "pbrMetallicRoughness": { "baseColorTexture": { "index": t }, "metallicFactor": 0,
                                  "baseColorFactor": [0.5, 0.5, 0.5, 1] }
    }));
    let q = d.uv_quad(1.0, 0.0, Some(m));
    d.node(json!({ "mesh": q }));
    head_on(&mut d, 4.0);
    d.json["scenes"][0]["extras"] = json!({ "background": [1, 1, 1] });
    let s = load(&d.write_gltf(&temp_dir("headon"), "scene")).unwrap();
    let f = render(&s, 8, 64, 2);
    let px = |x: u32, y: u32| f.mean(f.index(x, y));
    // Pixel (1, 1) is in the top-left quadrant: red, times the factor.
    let want = [
        (1, 1, Vec3::X),
        (6, 1, Vec3::Y),
        (1, 6, Vec3::Z),
        (6, 6, Vec3::ONE),
    ];
    for (x, y, col) in want {
        let p = px(x, y);
        assert!(
            (p - 0.5 * col).abs().max_element() < 0.03,
            "pixel ({x}, {y}) = {p}, want {}",
            0.5 * col
        );
    }
}

/// A flat diffuse quad (facing +Z) with a constant normal map `rgb`,
/// lit by a directional light arriving from `from` (unit, toward the light).
fn normal_map_radiance(test: &str, rgb: [u8; 3], scale: f32, from: Vec3) -> f32 {
    let mut d = Doc::new();
    let t = d.png_texture(1, 1, &[rgb[0], rgb[1], rgb[2], 255], Value::Null);
    // A Lambertian (the normal map applies to every model; a glTF
    // non-metal's coat would add its Fresnel reflection).
    let m = d.material(json!({
        "extras": { "bsdf": { "type": "diffuse", "reflectance": 1 } },
        "normalTexture": { "index": t, "scale": scale }
    }));
    let q = d.uv_quad(1.0, 0.0, Some(m));
    d.node(json!({ "mesh": q }));
    head_on(&mut d, 4.0);
    // The light's -Z is its direction of travel: -from.
    let rot = Quat::from_rotation_arc(Vec3::NEG_Z, -from);
    d.json["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    d.json["extensions"] = json!({ "KHR_lights_punctual": { "lights": [
        { "type": "directional", "color": [1, 1, 1], "intensity": PI } ] } });
    d.node(json!({ "rotation": rot.to_array(), "extensions": { "KHR_lights_punctual": { "light": 0 } } }));
    let s = load(&d.write_gltf(&temp_dir(test), "scene")).unwrap();
    let f = render(&s, 4, 4, 2);
    // Direct light only, no noise: every pixel is rho/pi * E * cos.
    let p = f.mean(f.index(1, 1));
    assert!((p.x - p.y).abs() < 1e-5);
    p.x
}

/// The normal a texel encodes, with glTF's convention (+Y up the image).
fn decoded(rgb: [u8; 3], scale: f32) -> Vec3 {
    let m = Vec3::from_array(rgb.map(|x| x as f32 / 255.0)) * 2.0 - Vec3::ONE;
    Vec3::new(m.x * scale, m.y * scale, m.z).normalize()
}

#[test]
fn normal_map_tilt_changes_radiance_by_the_cosine() {
    // Reflectance 1, E = pi -> L = cos.
    let tilt = 30f32.to_radians();
    let n = Vec3::new(0.0, tilt.sin(), tilt.cos());
    let rgb = ((n + Vec3::ONE) * 0.5 * 255.0)
        .round()
        .to_array()
        .map(|x| x as u8);
    let flat = [128u8, 128, 255];
    // Light from straight above: cos = n.z of the decoded normal.
    let above = Vec3::Z;
    let l_flat = normal_map_radiance("nm_flat", flat, 1.0, above);
    assert!(
        (l_flat - decoded(flat, 1.0).dot(above)).abs() < 1e-3,
        "{l_flat}"
    );
    let l = normal_map_radiance("nm_tilt", rgb, 1.0, above);
    let want = decoded(rgb, 1.0).dot(above);
    assert!((l - want).abs() < 1e-3, "{l} != {want}");
    assert!((want - tilt.cos()).abs() < 0.01);
    // Green is +Y (up the image, which is world +Y here): a light from the
    // +Y side at the tilt angle meets the tilted normal head-on.
    let from_up = Vec3::new(0.0, tilt.sin(), tilt.cos());
    let l_up = normal_map_radiance("nm_up", rgb, 1.0, from_up);
    let l_down = normal_map_radiance("nm_down", rgb, 1.0, Vec3::new(0.0, -tilt.sin(), tilt.cos()));
    assert!(
        (l_up - decoded(rgb, 1.0).dot(from_up)).abs() < 1e-3,
        "{l_up}"
    );
    assert!(l_up > 0.99 && l_down < 0.51, "up {l_up}, down {l_down}");
    // `scale` multiplies the tangent-space xy.
    let l_half = normal_map_radiance("nm_scale", rgb, 0.5, above);
    assert!(
        (l_half - decoded(rgb, 0.5).dot(above)).abs() < 1e-3,
        "{l_half}"
    );
}

/// A quad at height 1 whose alpha is the 2x2 `alpha` mask (nearest) above
/// a floor; `mode` is the alphaMode.
fn masked_scene(test: &str, mode: &str) -> Scene {
    let mut d = Doc::new();
    // Top-left and bottom-right transparent (alpha 0), the others opaque.
    let texels = [
        [255, 255, 255, 0],
        [255, 255, 255, 255],
        [255, 255, 255, 255],
        [255, 255, 255, 0],
    ]
    .concat();
    let t = d.png_texture(2, 2, &texels, json!({ "magFilter": 9728 }));
    let m = d.material(json!({
        "pbrMetallicRoughness": { "baseColorTexture": { "index": t }, "metallicFactor": 0 },
        "alphaMode": mode, "alphaCutoff": 0.5
    }));
    let q = d.uv_quad(1.0, 1.0, Some(m));
    d.node(json!({ "mesh": q }));
    let floor = d.uv_quad(4.0, 0.0, None);
    d.node(json!({ "mesh": floor }));
    load(&d.write_gltf(&temp_dir(test), "scene")).unwrap()
}

#[test]
fn alpha_mask_casts_the_masks_shadow() {
    let s = masked_scene("mask", "MASK");
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    // Shadow rays straight up from a grid of floor points under the quad:
    // exactly the opaque half is blocked, quadrant by quadrant.
    let n = 40;
    let mut blocked = 0;
    for i in 0..n {
        for j in 0..n {
            let x = -1.0 + (i as f32 + 0.5) * 2.0 / n as f32;
            let y = -1.0 + (j as f32 + 0.5) * 2.0 / n as f32;
            let ray = Ray {
                o: Vec3::new(x, y, 1e-3),
                d: Vec3::Z,
                tmax: 10.0,
            };
            let hit = s.occluded(&ray);
            // Texel row 0 is +Y (the top); column 0 is -X.
            let opaque = (x > 0.0) == (y > 0.0);
            assert_eq!(hit, opaque, "shadow ray at ({x}, {y})");
            blocked += hit as u32;
            // Closest hits skip the cut-away part too.
            let down = Ray {
                o: Vec3::new(x, y, 2.0),
                d: Vec3::NEG_Z,
                tmax: 10.0,
            };
            let t = s.intersect(&down).unwrap().t;
            assert!((t - if opaque { 1.0 } else { 2.0 }).abs() < 1e-4, "{t}");
        }
    }
    assert_eq!(blocked, n * n / 2);
}

#[test]
fn blend_with_alpha_zero_or_one_is_exact_and_not_warned_about() {
    // Stochastic transparency keeps a hit with probability alpha: 0 and 1
    // are certain (the fractional case: tests/gltf_viewers.rs).
    let s = masked_scene("blend", "BLEND");
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let ray = |x: f32, y: f32| Ray {
        o: Vec3::new(x, y, 1e-3),
        d: Vec3::Z,
        tmax: 10.0,
    };
    assert!(!s.occluded(&ray(-0.5, 0.5)));
    assert!(s.occluded(&ray(0.5, 0.5)));
}

fn doc_with_image(image: Value) -> Doc {
    let mut d = Doc::new();
    d.json["images"] = json!([image]);
    d.json["textures"] = json!([{ "source": 0 }]);
    let m = d.material(json!({ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }));
    let q = d.uv_quad(1.0, 0.0, Some(m));
    d.node(json!({ "mesh": q }));
    d
}

#[test]
fn bad_images_are_warnings_and_the_factor_is_used() {
    let dir = temp_dir("badimages");
    let png = png_bytes(2, 2, &quad_texels());
    // Truncated PNG, a missing file, a 0x0 and a 65536x65536 header, an
    // image URI leaving the folder: each a warning, the factor alone used.
    std::fs::write(dir.join("cut.png"), &png[..png.len() / 2]).unwrap();
    let mut huge = png_bytes(1, 1, &WHITE);
    // IHDR width/height at bytes 16..24 (the CRC is then wrong too).
    huge[16..20].copy_from_slice(&65536u32.to_be_bytes());
    huge[20..24].copy_from_slice(&65536u32.to_be_bytes());
    std::fs::write(dir.join("huge.png"), &huge).unwrap();
    let mut zero = png_bytes(1, 1, &WHITE);
    zero[16..24].copy_from_slice(&[0; 8]);
    std::fs::write(dir.join("zero.png"), &zero).unwrap();
    std::fs::write(dir.join("../outside.png"), &png).unwrap();
    for (name, uri, needle) in [
        ("cut", "cut.png", "image 0"),
        ("missing", "nope.png", "cannot open"),
        ("huge", "huge.png", "image 0"),
        ("zero", "zero.png", "image 0"),
        ("escape", "../outside.png", "outside the scene's folder"),
        ("text", "data:image/png;base64,AAAA", "image 0"),
    ] {
        let d = doc_with_image(json!({ "uri": uri }));
        let path = d.write_gltf(&dir, name);
        let s = parse(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        let w = s.warnings.join("\n");
        assert!(
            w.contains(needle) && w.contains("the factor alone is used"),
            "{name}: {w}"
        );
        assert!(!w.contains('\n') || s.warnings.len() > 1);
        assert!(s.textures.table.is_empty(), "{name}");
    }
    // A texture index out of range is a clear error.
    let mut d = doc_with_image(json!({ "uri": "cut.png" }));
    d.json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["index"] = json!(7);
    let path = d.write_gltf(&dir, "badindex");
    let e = parse(&path)
        .expect_err("texture 7 does not exist")
        .to_string();
    assert!(e.contains("baseColorTexture.index"), "{e}");
    assert!(!e.contains('\n'));
}
