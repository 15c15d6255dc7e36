//! The glTF material mapping pinned through the whole pipeline (file,
//! loader, per-hit textures, integrator): a plate facing the camera under a
//! constant white sky, seen head-on, shows its directional albedo at normal
//! incidence, which the contract fixes per extension:
//! - a white non-metal reflects 1 at every roughness (the coat's energy is
//!   taken from the base);
//! - a black non-metal shows only its coat: F0 = ((ior - 1)/(ior + 1))^2,
//!   scaled by `KHR_materials_specular`;
//! - a smooth metal shows baseColor (its F0); `metallicFactor` blends by
//!   probability, also when a metallicRoughness texture sets it;
//! - thin-walled `KHR_materials_transmission` shows R' + (1 - R') baseColor
//!   (the sky through the slab, tinted), R' = 2 F0 / (1 + F0);
//! - a smooth clear coat of weight c adds c F0 and dims what is under it by
//!   (1 - c F0)^2 (glint's layering, `bsdf/clearcoat.rs`);
//! - each extension's texture multiplies its factor from the channel glTF
//!   names (transmission R, clearcoat R, clearcoatRoughness G, specular A,
//!   specularColor sRGB rgb), per hit (`texture::textured_coat`);
//! - a smooth clear coat over a surface that reflects nothing (black,
//!   specularFactor 0) shows c F(cos t), t the angle between its normal and
//!   the view: tilted by clearcoatNormalTexture, untilted (c F0) under the
//!   base's normal map alone.

#[path = "fixtures/gltf_builder.rs"]
mod builder;

use builder::{Doc, temp_dir};
use glam::Vec3;
use glint_cpu::RenderOptions;
use glint_cpu::features::Features;
use glint_cpu::loader::load;
use serde_json::{Value, json};

/// The plate's mean radiance, `material` its glTF material (a 1x1
/// metallicRoughness texture of (_, G, B) when `mr_texel` is given).
fn plate(test: &str, material: Value, mr_texel: Option<[u8; 3]>) -> Vec3 {
    let textures: Vec<(&str, &str, [u8; 4])> = match mr_texel {
        Some(t) => vec![(
            "pbrMetallicRoughness",
            "metallicRoughnessTexture",
            [t[0], t[1], t[2], 255],
        )],
        None => Vec::new(),
    };
    textured_plate(test, material, &textures)
}

/// [`plate`] with 1x1 textures: each (object, slot, texel) puts a texture
/// of that RGBA texel in `material[object][slot]`, the object a key of
/// the material (`pbrMetallicRoughness`), of its `extensions`, or "" for
/// the material itself.
fn textured_plate(test: &str, material: Value, textures: &[(&str, &str, [u8; 4])]) -> Vec3 {
    let mut d = Doc::new();
    let mut material = material;
    for (object, slot, t) in textures {
        let tex = d.png_texture(1, 1, t, Value::Null);
        let obj = if object.is_empty() {
            &mut material
        } else if *object == "pbrMetallicRoughness" {
            &mut material[*object]
        } else {
            &mut material["extensions"][*object]
        };
        obj[*slot] = json!({ "index": tex });
    }
    let m = d.material(material);
    let q = d.uv_quad(1.0, 0.0, Some(m));
    d.node(json!({ "mesh": q }));
    // The plate fills a narrow view head-on: every pixel sees it at
    // mu_o ~ 1 (within 0.2 degrees).
    d.json["cameras"] =
        json!([{ "type": "perspective", "perspective": { "yfov": 0.01, "znear": 0.01 } }]);
    d.node(json!({ "camera": 0, "translation": [0, 0, 2] }));
    d.json["scenes"][0]["extras"] = json!({ "background": [1, 1, 1] });
    let s = load(&d.write_gltf(&temp_dir(test), "scene")).unwrap();
    let o = RenderOptions {
        spp: 1024,
        max_depth: 3,
        ..RenderOptions::new(4, 4)
    };
    // The GPU kernel compiles the KHR extensions' texture slots only with
    // this feature: it must be set exactly where such a slot is filled.
    let khr = textures
        .iter()
        .any(|(object, ..)| object.starts_with("KHR_"));
    assert_eq!(
        Features::of(&s, &o).has(Features::EXTENSION_TEXTURES),
        khr,
        "{test}: extension-textures"
    );
    let f = glint_cpu::render(&s, &o, &|_, _| {}).unwrap().0;
    let mut sum = Vec3::ZERO;
    for y in 0..4 {
        for x in 0..4 {
            sum += f.mean(f.index(x, y));
        }
    }
    sum / 16.0
}

fn assert_near(got: Vec3, want: Vec3, tol: f32, what: &str) {
    assert!(
        (got - want).abs().max_element() <= tol,
        "{what}: {got} vs {want}"
    );
}

fn pbr(base: [f32; 3], metallic: f32, roughness: f32) -> Value {
    json!({ "pbrMetallicRoughness": {
        "baseColorFactor": [base[0], base[1], base[2], 1], "metallicFactor": metallic,
        "roughnessFactor": roughness } })
}

fn f0(ior: f32) -> f32 {
    ((ior - 1.0) / (ior + 1.0)).powi(2)
}

#[test]
fn white_non_metal_reflects_one_black_shows_its_coat() {
    for r in [0.0f32, 0.5, 1.0] {
        let got = plate(&format!("white_{r}"), pbr([1.0; 3], 0.0, r), None);
        assert_near(
            got,
            Vec3::ONE,
            0.01,
            &format!("white non-metal roughness {r}"),
        );
    }
    let got = plate("black", pbr([0.0; 3], 0.0, 0.0), None);
    assert_near(got, Vec3::splat(f0(1.5)), 1e-4, "black non-metal, ior 1.5");
    // The "black disc" of the old mapping: a black non-metal is never 0.
    let rough = plate("black_rough", pbr([0.0; 3], 0.0, 0.6), None);
    assert!(rough.min_element() > 0.02, "{rough}");
}

#[test]
fn ior_and_specular_scale_the_coat() {
    let mut m = pbr([0.0; 3], 0.0, 0.0);
    m["extensions"] = json!({ "KHR_materials_ior": { "ior": 2.0 } });
    assert_near(plate("ior2", m, None), Vec3::splat(f0(2.0)), 1e-4, "ior 2");
    let mut m = pbr([0.0; 3], 0.0, 0.0);
    m["extensions"] = json!({ "KHR_materials_specular": {
        "specularFactor": 0.5, "specularColorFactor": [1, 0.5, 0] } });
    let want = Vec3::new(0.5, 0.25, 0.0) * f0(1.5);
    assert_near(plate("specular", m, None), want, 1e-4, "specular");
    // A white base under a reduced coat still reflects 1 (the base takes
    // what the coat gives up).
    let mut m = pbr([1.0; 3], 0.0, 0.4);
    m["extensions"] = json!({ "KHR_materials_specular": { "specularFactor": 0.3 } });
    assert_near(
        plate("specular_white", m, None),
        Vec3::ONE,
        0.01,
        "white, specular 0.3",
    );
}

#[test]
fn metals_and_the_blend_by_probability() {
    let base = [0.9f32, 0.5, 0.1];
    let metal = plate("metal", pbr(base, 1.0, 0.0), None);
    assert_near(metal, Vec3::from(base), 2e-3, "smooth metal = baseColor");
    let non = plate("non", pbr(base, 0.0, 0.0), None);
    let blend = plate("blend", pbr(base, 0.3, 0.0), None);
    assert_near(blend, 0.3 * metal + 0.7 * non, 0.01, "metallic 0.3");
    // metallicRoughness B = 0 makes the metal factor's surface a non-metal
    // per hit; B = 255 keeps it metal.
    let tex_non = plate("tex_non", pbr(base, 1.0, 1.0), Some([0, 0, 0]));
    assert_near(tex_non, non, 0.01, "texture metallic 0");
    let tex_metal = plate("tex_metal", pbr(base, 1.0, 1.0), Some([0, 0, 255]));
    assert_near(tex_metal, metal, 2e-3, "texture metallic 1, roughness 0");
}

#[test]
fn thin_walled_transmission_is_tinted_by_base_colour() {
    let tint = Vec3::new(1.0, 0.5, 0.25);
    let mut m = pbr(tint.to_array(), 0.0, 0.0);
    m["extensions"] = json!({ "KHR_materials_transmission": { "transmissionFactor": 1 } });
    let r = 2.0 * f0(1.5) / (1.0 + f0(1.5));
    let want = Vec3::splat(r) + (1.0 - r) * tint;
    assert_near(
        plate("thin", m.clone(), None),
        want,
        2e-3,
        "thin-walled, smooth",
    );
    // Half transmission: half the thin slab, half the opaque non-metal.
    m["extensions"]["KHR_materials_transmission"]["transmissionFactor"] = json!(0.5);
    let opaque = plate("thin_opaque", pbr(tint.to_array(), 0.0, 0.0), None);
    assert_near(
        plate("thin_half", m, None),
        0.5 * want + 0.5 * opaque,
        0.01,
        "transmission 0.5",
    );
}

#[test]
fn clearcoat_adds_its_reflection_and_dims_the_rest() {
    let c = 0.8f32;
    let ext = json!({ "KHR_materials_clearcoat": { "clearcoatFactor": c, "clearcoatRoughnessFactor": 0 } });
    let w = 1.0 - c * f0(1.5);
    let mut black = pbr([0.0; 3], 0.0, 0.0);
    black["extensions"] = ext.clone();
    let want = Vec3::splat(c * f0(1.5) + w * w * f0(1.5));
    assert_near(
        plate("cc_black", black, None),
        want,
        1e-4,
        "clear-coated black non-metal",
    );
    let base = [0.9f32, 0.5, 0.1];
    let mut metal = pbr(base, 1.0, 0.0);
    metal["extensions"] = ext;
    let want = Vec3::splat(c * f0(1.5)) + w * w * Vec3::from(base);
    assert_near(
        plate("cc_metal", metal, None),
        want,
        2e-3,
        "clear-coated smooth metal",
    );
}

/// An 8-bit texel value as the texture reads it.
fn unorm(x: u8) -> f32 {
    x as f32 / 255.0
}

#[test]
fn coat_textures_multiply_their_factors() {
    let f = f0(1.5);
    // clearcoatTexture R (G, B, A at 255 would give a different weight if
    // read instead) over a black smooth non-metal.
    let mut black = pbr([0.0; 3], 0.0, 0.0);
    black["extensions"] = json!({ "KHR_materials_clearcoat": {
        "clearcoatFactor": 0.9, "clearcoatRoughnessFactor": 1 } });
    let c = 0.9 * unorm(128);
    let w = 1.0 - c * f;
    // clearcoatRoughnessTexture G = 0 makes roughness factor 1 smooth; its
    // R and A (255) would leave it rough.
    let got = textured_plate(
        "cc_tex",
        black,
        &[
            (
                "KHR_materials_clearcoat",
                "clearcoatTexture",
                [128, 255, 255, 255],
            ),
            (
                "KHR_materials_clearcoat",
                "clearcoatRoughnessTexture",
                [255, 0, 255, 255],
            ),
        ],
    );
    assert_near(
        got,
        Vec3::splat(c * f + w * w * f),
        1e-4,
        "clearcoat textures",
    );

    // specularTexture A x specularFactor, specularColorTexture sRGB rgb x
    // specularColorFactor: the black non-metal shows their product x F0.
    let mut black = pbr([0.0; 3], 0.0, 0.0);
    black["extensions"] = json!({ "KHR_materials_specular": {
        "specularFactor": 0.8, "specularColorFactor": [1, 0.5, 1] } });
    let got = textured_plate(
        "spec_tex",
        black,
        &[
            (
                "KHR_materials_specular",
                "specularTexture",
                [255, 255, 255, 128],
            ),
            (
                "KHR_materials_specular",
                "specularColorTexture",
                [255, 128, 0, 255],
            ),
        ],
    );
    let srgb_128 = glint_cpu::texture::srgb_to_linear(unorm(128));
    let want = 0.8 * unorm(128) * Vec3::new(1.0, 0.5 * srgb_128, 0.0) * f;
    assert_near(got, want, 1e-4, "specular textures");

    // transmissionTexture R x transmissionFactor: that share of the thin
    // slab, the rest the opaque smooth non-metal (F0 + (1 - F0) tint, as
    // its white base reflects 1).
    let tint = Vec3::new(1.0, 0.5, 0.25);
    let mut m = pbr(tint.to_array(), 0.0, 0.0);
    m["extensions"] = json!({ "KHR_materials_transmission": { "transmissionFactor": 0.9 } });
    let got = textured_plate(
        "trans_tex",
        m,
        &[(
            "KHR_materials_transmission",
            "transmissionTexture",
            [64, 255, 255, 255],
        )],
    );
    let r = 2.0 * f / (1.0 + f);
    let thin = Vec3::splat(r) + (1.0 - r) * tint;
    let opaque = Vec3::splat(f) + (1.0 - f) * tint;
    let t = 0.9 * unorm(64);
    assert_near(
        got,
        t * thin + (1.0 - t) * opaque,
        0.01,
        "transmission texture",
    );
}

#[test]
fn clearcoat_normal_texture_tilts_the_coat_and_the_base_map_does_not() {
    // Black, specularFactor 0: only the smooth clear coat (c = 1) reflects,
    // the white sky in its mirror direction, so the plate shows F(cos t).
    let mut m = pbr([0.0; 3], 0.0, 0.0);
    m["extensions"] = json!({
        "KHR_materials_clearcoat": { "clearcoatFactor": 1, "clearcoatRoughnessFactor": 0 },
        "KHR_materials_specular": { "specularFactor": 0 } });
    // A normal texel tilted ~40 degrees along the tangent: the mirror
    // direction of the head-on view stays above the plate.
    let texel = [210u8, 128, 225, 255];
    let n = Vec3::new(
        2.0 * unorm(texel[0]) - 1.0,
        2.0 * unorm(texel[1]) - 1.0,
        2.0 * unorm(texel[2]) - 1.0,
    )
    .normalize();
    let f = |cos: f32| glint_cpu::bsdf::fresnel::fresnel_dielectric(cos, 1.5);
    let untilted = plate("ccn_none", m.clone(), None);
    assert_near(untilted, Vec3::splat(f0(1.5)), 1e-4, "untilted clear coat");
    let tilted = textured_plate(
        "ccn_tilted",
        m.clone(),
        &[("KHR_materials_clearcoat", "clearcoatNormalTexture", texel)],
    );
    assert!((f(n.z) - f0(1.5)) > 4e-3, "the tilt must show: {}", f(n.z));
    assert_near(tilted, Vec3::splat(f(n.z)), 5e-4, "clearcoatNormalTexture");
    // The base's normal map alone leaves the coat on the unmapped normal.
    let base_mapped = textured_plate("ccn_base", m, &[("", "normalTexture", texel)]);
    assert_near(
        base_mapped,
        Vec3::splat(f0(1.5)),
        5e-4,
        "normalTexture only",
    );
}
