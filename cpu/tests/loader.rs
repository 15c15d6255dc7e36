//! The loader against the contract's scene conventions, one test per feature.
//! Scenes are generated into a temporary directory by `fixtures/gltf_builder.rs`.

#[path = "fixtures/gltf_builder.rs"]
mod builder;

use std::f32::consts::{FRAC_PI_2, FRAC_PI_4};
use std::path::Path;

use builder::{Doc, temp_dir};
use glam::{Mat3, Quat, Vec2, Vec3};
use glint_cpu::bsdf::coated::CoatParams;
use glint_cpu::bsdf::{Bsdf, Roughness, Shadowing, Tint};
use glint_cpu::loader::{
    self, DEFAULT_EXT_IOR, DEFAULT_INT_IOR, default_camera, parse, select_camera,
};
use glint_cpu::{PunctualLight, Scene, TRI_DOUBLE_SIDED};
use serde_json::json;

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() < 1e-5
}

fn assert_close(a: Vec3, b: Vec3) {
    assert!(close(a, b), "{a} != {b}");
}

fn parse_doc(doc: &Doc, test: &str) -> Scene {
    let dir = temp_dir(test);
    let path = doc.write_gltf(&dir, "scene");
    parse(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn parse_doc_err(doc: &Doc, test: &str) -> String {
    let dir = temp_dir(test);
    let path = doc.write_gltf(&dir, "scene");
    match parse(&path) {
        Ok(_) => panic!("{test}: loaded"),
        Err(e) => e.to_string(),
    }
}

fn tri_set(s: &Scene) -> Vec<[Vec3; 3]> {
    s.triangles.iter().map(|t| t.vertices()).collect()
}

#[test]
fn indexed_and_non_indexed_primitives() {
    let mut d = Doc::new();
    // A unit quad through 4 vertices and 6 u16 indices, and a lone triangle.
    let quad = d.floats(&[0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.], "VEC3");
    let idx = d.indices_u16(&[0, 1, 2, 0, 2, 3]);
    let tri = d.floats(&[5., 0., 0., 6., 0., 0., 5., 1., 0.], "VEC3");
    let idx32 = d.indices_u32(&[2, 1, 0]);
    let m = d.mesh(vec![
        json!({ "attributes": { "POSITION": quad }, "indices": idx }),
        json!({ "attributes": { "POSITION": tri } }),
        json!({ "attributes": { "POSITION": tri }, "indices": idx32 }),
        // Points have no area: skipped.
        json!({ "attributes": { "POSITION": tri }, "mode": 0 }),
    ]);
    d.node(json!({ "mesh": m }));
    let s = parse_doc(&d, "indexed");
    let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    assert_eq!(
        tri_set(&s),
        vec![
            [v(0., 0., 0.), v(1., 0., 0.), v(1., 1., 0.)],
            [v(0., 0., 0.), v(1., 1., 0.), v(0., 1., 0.)],
            [v(5., 0., 0.), v(6., 0., 0.), v(5., 1., 0.)],
            [v(5., 1., 0.), v(6., 0., 0.), v(5., 0., 0.)],
        ]
    );
    // No NORMAL, TANGENT or texture coordinates: no shading data at all.
    assert!(s.shading.is_empty());
    assert!(s.triangles.iter().all(|t| t.flags >> 1 == 0));
    assert!(s.bvh.nodes.is_empty(), "parse does not build the BVH");
}

#[test]
fn strips_and_fans_keep_one_facing() {
    let mut d = Doc::new();
    let strip = d.floats(
        &[0., 0., 0., 1., 0., 0., 0., 1., 0., 1., 1., 0., 0., 2., 0.],
        "VEC3",
    );
    let m = d.mesh(vec![
        json!({ "attributes": { "POSITION": strip }, "mode": 5 }),
        json!({ "attributes": { "POSITION": strip }, "mode": 6 }),
    ]);
    d.node(json!({ "mesh": m }));
    let s = parse_doc(&d, "strips");
    assert_eq!(s.triangles.len(), 3 + 3);
    for t in &s.triangles[..3] {
        assert!(
            t.geometric_normal().z > 0.0,
            "strip triangle faces -Z: {t:?}"
        );
    }
    assert_eq!(
        s.triangles[4].vertices()[2],
        Vec3::ZERO,
        "fans pivot on vertex 0"
    );
}

#[test]
fn trs_and_matrix_compose_down_the_hierarchy() {
    let mut d = Doc::new();
    let m = d.triangle_mesh(None);
    // child: a matrix translating by (0, 0, 3); grandchild: TRS.
    let grandchild = d.child(json!({ "mesh": m, "scale": [1, 2, 1], "translation": [1, 0, 0] }));
    let child = d.child(json!({
        "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,3,1], "children": [grandchild], "mesh": m
    }));
    let q = Quat::from_rotation_y(FRAC_PI_2);
    d.node(json!({
        "translation": [10, 0, 0], "rotation": q.to_array(), "scale": [2, 2, 2], "children": [child]
    }));
    let s = parse_doc(&d, "hierarchy");
    assert_eq!(s.triangles.len(), 2);
    let parent = glam::Mat4::from_scale_rotation_translation(Vec3::splat(2.0), q, Vec3::X * 10.0);
    let child_m = parent * glam::Mat4::from_translation(Vec3::Z * 3.0);
    let grand = child_m
        * glam::Mat4::from_scale_rotation_translation(
            Vec3::new(1., 2., 1.),
            Quat::IDENTITY,
            Vec3::X,
        );
    let local = [Vec3::ZERO, Vec3::X, Vec3::Y];
    for (tri, m) in s.triangles.iter().zip([child_m, grand]) {
        for (p, l) in tri.vertices().iter().zip(local) {
            assert_close(*p, m.transform_point3(l));
        }
    }
    // Spot check by hand: (0,0,3) in the child -> rotated 90 deg about Y
    // (z -> x), scaled 2, moved +10 x: (16, 0, 0).
    assert_close(s.triangles[0].vertices()[0], Vec3::new(16.0, 0.0, 0.0));
}

#[test]
fn normals_use_the_inverse_transpose_and_mark_w() {
    let mut d = Doc::new();
    let pos = d.floats(&[0., 0., 0., 1., 0., 0., 0., 1., 0.], "VEC3");
    let n = std::f32::consts::FRAC_1_SQRT_2;
    let nrm = d.floats(&[n, n, 0., n, n, 0., 0., 0., 2.], "VEC3");
    let with = d.mesh(vec![
        json!({ "attributes": { "POSITION": pos, "NORMAL": nrm } }),
    ]);
    let without = d.mesh(vec![json!({ "attributes": { "POSITION": pos } })]);
    d.node(json!({ "mesh": with, "scale": [2, 1, 1] }));
    d.node(json!({ "mesh": without, "scale": [2, 1, 1] }));
    let s = parse_doc(&d, "normals");
    let sh = &s.shading_of(0);
    // Non-uniform scale diag(2,1,1): normals go through diag(1/2, 1, 1).
    assert_close(
        Vec3::from_slice(&sh.n[0][..3]),
        Vec3::new(0.5, 1.0, 0.0).normalize(),
    );
    assert_close(Vec3::from_slice(&sh.n[2][..3]), Vec3::Z);
    assert!(sh.n.iter().all(|v| v[3] == 1.0));
    let plain = &s.shading_of(1);
    assert!(plain.n.iter().all(|v| v[3] == 0.0), "no NORMAL: w = 0");
    assert!(plain.t.iter().all(|v| v[3] == 0.0), "no tangent: w = 0");
}

#[test]
fn negative_determinant_keeps_the_outside() {
    let mut d = Doc::new();
    let pos = d.floats(&[0., 0., 0., 1., 0., 0., 0., 1., 0.], "VEC3");
    let nrm = d.floats(&[0., 0., 1., 0., 0., 1., 0., 0., 1.], "VEC3");
    let m = d.mesh(vec![
        json!({ "attributes": { "POSITION": pos, "NORMAL": nrm } }),
    ]);
    // Mirror z: the triangle's +Z side (its outside) becomes -Z.
    d.node(json!({ "mesh": m, "scale": [1, 1, -1] }));
    // Mirror x: the outside stays +Z, but the winding reverses.
    d.node(json!({ "mesh": m, "scale": [-1, 1, 1] }));
    let s = parse_doc(&d, "mirror");
    let gz = s.triangles[0].geometric_normal().normalize();
    assert_close(gz, -Vec3::Z);
    assert_close(Vec3::from_slice(&s.shading_of(0).n[0][..3]), -Vec3::Z);
    let gx = s.triangles[1].geometric_normal().normalize();
    assert_close(gx, Vec3::Z);
    assert_close(Vec3::from_slice(&s.shading_of(1).n[1][..3]), Vec3::Z);
    // Swapped vertices carry their own normals and positions along.
    let v = s.triangles[1].vertices();
    assert_eq!(v[0], Vec3::ZERO);
    assert_eq!(v[1], Vec3::Y);
    assert_eq!(v[2], -Vec3::X);
}

#[test]
fn tangent_attribute_is_transformed() {
    let mut d = Doc::new();
    let pos = d.floats(&[0., 0., 0., 1., 0., 0., 0., 1., 0.], "VEC3");
    let tan = d.floats(&[1., 0., 0., 1., 1., 0., 0., -1., 3., 0., 0., 1.], "VEC4");
    let uv = d.floats(&[0., 0., 0., 1., 1., 0.], "VEC2");
    // An anisotropic lobe needs the tangent (an isotropic one gets none).
    let aniso = d.material(anisotropic_material());
    let m = d.mesh(vec![
        json!({ "attributes": { "POSITION": pos, "TANGENT": tan, "TEXCOORD_0": uv }, "material": aniso }),
    ]);
    let q = Quat::from_rotation_z(FRAC_PI_2);
    d.node(json!({ "mesh": m, "rotation": q.to_array() }));
    let s = parse_doc(&d, "tangent");
    let t = s.shading_of(0).t;
    // TANGENT wins over TEXCOORD_0; x -> y under the rotation.
    assert_close(Vec3::from_slice(&t[0][..3]), Vec3::Y);
    assert_close(Vec3::from_slice(&t[2][..3]), Vec3::Y);
    assert!(t.iter().all(|v| v[3] == 1.0));
}

#[test]
fn texcoords_give_dp_du_tangents() {
    let mut d = Doc::new();
    let pos = d.floats(&[0., 0., 0., 2., 0., 0., 0., 3., 0.], "VEC3");
    // u runs along +y, v along +x.
    let uv = d.floats(&[0., 0., 0., 1., 1., 0.], "VEC2");
    let flat = d.floats(&[0., 0., 0., 0., 0., 0.], "VEC2");
    let aniso = d.material(anisotropic_material());
    let m = d.mesh(vec![
        json!({ "attributes": { "POSITION": pos, "TEXCOORD_0": uv }, "material": aniso }),
        json!({ "attributes": { "POSITION": pos, "TEXCOORD_0": flat }, "material": aniso }),
        json!({ "attributes": { "POSITION": pos, "TEXCOORD_0": uv } }),
    ]);
    d.node(json!({ "mesh": m, "translation": [0, 0, 5] }));
    let s = parse_doc(&d, "dpdu");
    for t in s.shading_of(0).t {
        assert_close(Vec3::from_slice(&t[..3]), Vec3::Y);
        assert_eq!(t[3], 1.0);
    }
    // Degenerate UVs: the first edge, as without them (Mitsuba's
    // fallback too).
    for t in s.shading_of(1).t {
        assert_close(Vec3::from_slice(&t[..3]), Vec3::X);
        assert_eq!(t[3], 1.0);
    }
    // The default (isotropic) material needs no orientation: no tangent
    // stored, and no shading data at all for this flat triangle.
    assert!(s.shading_of(2).t.iter().all(|t| t[3] == 0.0));
    assert_eq!(s.triangles[2].flags >> 1, 0);
}

#[test]
fn without_texcoords_the_tangent_is_the_files_first_edge() {
    // Mitsuba 3 (3.9.1) takes dp_du = p1 - p0 on a mesh without texture
    // coordinates, and pbrt-v4's default uv (0,0), (1,0), (1,1) gives the
    // same: the first edge in the file's vertex order, under a mirroring
    // node too (where glint swaps two of its own vertices).
    let mut d = Doc::new();
    let pos = d.floats(&[0., 0., 0., 2., 1., 0., 0., 3., 0.], "VEC3");
    let nrm = d.floats(&[0., 0.2, 1., 0.1, 0., 1., 0., 0., 1.], "VEC3");
    let aniso = d.material(anisotropic_material());
    let m = d.mesh(vec![
        json!({ "attributes": { "POSITION": pos, "NORMAL": nrm }, "material": aniso }),
    ]);
    let flat = d.mesh(vec![
        json!({ "attributes": { "POSITION": pos }, "material": aniso }),
    ]);
    d.node(json!({ "mesh": m }));
    d.node(json!({ "mesh": m, "scale": [-1, 1, 1], "translation": [0, 0, 1] }));
    d.node(json!({ "mesh": flat, "translation": [0, 0, 2] }));
    let s = parse_doc(&d, "first-edge");
    let mut seen = 0;
    for (i, tri) in s.triangles.iter().enumerate() {
        let z = tri.vertices()[0].z;
        let want = if z == 1.0 {
            Vec3::new(-2.0, 1.0, 0.0).normalize()
        } else {
            Vec3::new(2.0, 1.0, 0.0).normalize()
        };
        for t in s.shading_of(i).t {
            assert_close(Vec3::from_slice(&t[..3]), want);
            assert_eq!(t[3], 1.0);
        }
        seen += 1;
    }
    assert_eq!(seen, 3);
}

/// A rough conductor with alpha_u != alpha_v.
fn anisotropic_material() -> serde_json::Value {
    json!({ "extras": { "bsdf": { "type": "roughconductor", "eta": [1, 1, 1], "k": [2, 2, 2],
        "alpha_u": 0.05, "alpha_v": 0.3 } } })
}

#[test]
fn flat_faces_and_isotropic_materials_store_no_shading_data() {
    // A quad whose NORMALs all equal its face normal: interpolating them
    // gives the geometric normal, so none are stored; a bent one keeps
    // its normals. Bytes per triangle follow.
    let mut d = Doc::new();
    let pos = d.floats(&[0., 0., 0., 1., 0., 0., 0., 1., 0.], "VEC3");
    let up = d.floats(&[0., 0., 1., 0., 0., 1., 0., 0., 1.], "VEC3");
    let bent = d.floats(&[0., 0.6, 0.8, 0., 0., 1., 0.6, 0., 0.8], "VEC3");
    let m = d.mesh(vec![
        json!({ "attributes": { "POSITION": pos, "NORMAL": up } }),
        json!({ "attributes": { "POSITION": pos, "NORMAL": bent } }),
    ]);
    d.node(json!({ "mesh": m }));
    let s = parse_doc(&d, "flat");
    assert_eq!(s.triangles[0].flags & glint_cpu::TRI_NORMALS, 0);
    assert_close(Vec3::from_slice(&s.shading_of(0).n[0][..3]), Vec3::Z);
    assert_ne!(s.triangles[1].flags & glint_cpu::TRI_NORMALS, 0);
    assert_close(
        Vec3::from_slice(&s.shading_of(1).n[0][..3]),
        Vec3::new(0., 0.6, 0.8),
    );
    assert_eq!(s.shading.len(), 3);
    assert_eq!(s.gpu_bytes_per_triangle(), (2.0 * 48.0 + 48.0) / 2.0);
}

fn material_doc(materials: Vec<serde_json::Value>) -> Doc {
    let mut d = Doc::new();
    let n = materials.len();
    for m in materials {
        d.material(m);
    }
    for i in 0..n {
        let mesh = d.triangle_mesh(Some(i));
        d.node(json!({ "mesh": mesh }));
    }
    d
}

fn bsdfs(test: &str, extras: Vec<serde_json::Value>) -> Vec<Bsdf> {
    let d = material_doc(
        extras
            .into_iter()
            .map(|b| json!({ "extras": { "bsdf": b } }))
            .collect(),
    );
    parse_doc(&d, test)
        .materials
        .into_iter()
        .map(|m| m.bsdf)
        .collect()
}

fn rough(u: f32, v: f32, shadowing: Shadowing) -> Roughness {
    Roughness {
        alpha_u: u,
        alpha_v: v,
        shadowing,
        multiscatter: false,
    }
}

#[test]
fn extras_diffuse_and_conductors() {
    let b = bsdfs(
        "extras_conductor",
        vec![
            json!({ "type": "diffuse", "reflectance": [0.1, 0.2, 0.3] }),
            json!({ "type": "diffuse", "reflectance": 0.25 }),
            json!({ "type": "diffuse" }),
            json!({ "type": "conductor", "eta": [0.2, 0.4, 1.4], "k": [3.9, 2.4, 1.6],
                    "specular_reflectance": [0.9, 0.8, 0.7] }),
            json!({ "type": "roughconductor", "eta": [1, 1, 1], "k": [2, 2, 2], "alpha": 0.3,
                    "distribution": "ggx" }),
            json!({ "type": "roughconductor", "eta": [1, 1, 1], "k": [2, 2, 2], "alpha_u": 0.05,
                    "alpha_v": 0.4, "shadowing": "separable" }),
            json!({ "type": "roughconductor", "eta": [1, 1, 1], "k": [2, 2, 2] }),
            json!({ "type": "conductor" }),
        ],
    );
    assert_eq!(
        b[0],
        Bsdf::Diffuse {
            reflectance: Vec3::new(0.1, 0.2, 0.3)
        }
    );
    assert_eq!(
        b[1],
        Bsdf::Diffuse {
            reflectance: Vec3::splat(0.25)
        }
    );
    assert_eq!(
        b[2],
        Bsdf::Diffuse {
            reflectance: Vec3::splat(0.5)
        },
        "Mitsuba's default"
    );
    let Bsdf::Conductor(c) = b[3] else {
        panic!("{:?}", b[3])
    };
    assert_eq!(c.eta, Vec3::new(0.2, 0.4, 1.4));
    assert_eq!(c.k, Vec3::new(3.9, 2.4, 1.6));
    assert_eq!(c.specular_reflectance, Vec3::new(0.9, 0.8, 0.7));
    assert!(c.roughness.is_smooth());
    let Bsdf::Conductor(c) = b[4] else { panic!() };
    assert_eq!(c.roughness, rough(0.3, 0.3, Shadowing::Correlated));
    assert_eq!(c.specular_reflectance, Vec3::ONE);
    let Bsdf::Conductor(c) = b[5] else { panic!() };
    assert_eq!(c.roughness, rough(0.05, 0.4, Shadowing::Separable));
    let Bsdf::Conductor(c) = b[6] else { panic!() };
    assert_eq!(
        c.roughness,
        rough(0.1, 0.1, Shadowing::Correlated),
        "Mitsuba's default alpha"
    );
    // Mitsuba's default material "none": eta 0, k 1, a perfect mirror.
    let Bsdf::Conductor(c) = b[7] else { panic!() };
    assert_eq!((c.eta, c.k), (Vec3::ZERO, Vec3::ONE));
    for cos in [1.0f32, 0.5, 0.05] {
        let wo = Vec3::new((1.0 - cos * cos).sqrt(), 0.0, cos);
        let smp = b[7]
            .sample(wo, 0.5, Vec2::splat(0.5))
            .expect("mirror sample");
        assert!(
            close(smp.weight, Vec3::ONE),
            "mirror reflects {} at cos {cos}",
            smp.weight
        );
    }
}

#[test]
fn extras_named_metals() {
    let b = bsdfs(
        "extras_metals",
        ["Au", "Ag", "Cu", "Al", "Cr"]
            .iter()
            .map(|m| json!({ "type": "roughconductor", "material": m, "alpha": 0.2 }))
            .collect(),
    );
    for (bsdf, name) in b.iter().zip(["Au", "Ag", "Cu", "Al", "Cr"]) {
        let Bsdf::Conductor(c) = bsdf else { panic!() };
        let (eta, k) = glint_cpu::bsdf::named_metal(name).unwrap();
        assert_eq!((c.eta, c.k), (eta, k), "{name}");
        assert_eq!(c.roughness.alpha_u, 0.2);
    }
}

/// Mitsuba 3's `plastic` and `thindielectric` with their defaults
/// (plastic: diffuse 0.5, specular 1, int_ior 1.49 polypropylene, air
/// outside, nonlinear false; thindielectric: bk7 in air, both factors 1).
#[test]
fn extras_plastic_and_thindielectric() {
    use glint_cpu::bsdf::plastic::PlasticParams;
    let b = bsdfs(
        "extras_plastic",
        vec![
            json!({ "type": "plastic" }),
            json!({ "type": "plastic", "diffuse_reflectance": [0.1, 0.2, 0.3],
                    "specular_reflectance": 0.5, "int_ior": "water", "nonlinear": true }),
            json!({ "type": "thindielectric" }),
            json!({ "type": "thindielectric", "int_ior": 1.33, "ext_ior": 1.0,
                    "specular_reflectance": [1, 0.5, 0.25], "specular_transmittance": 0.5 }),
        ],
    );
    assert_eq!(
        b[0],
        Bsdf::Plastic(PlasticParams {
            diffuse: Vec3::splat(0.5),
            specular: Vec3::ONE,
            eta: 1.49 / DEFAULT_EXT_IOR,
            nonlinear: false,
        })
    );
    assert_eq!(
        b[1],
        Bsdf::Plastic(PlasticParams {
            diffuse: Vec3::new(0.1, 0.2, 0.3),
            specular: Vec3::splat(0.5),
            eta: 1.333 / DEFAULT_EXT_IOR,
            nonlinear: true,
        })
    );
    assert_eq!(
        b[2],
        Bsdf::ThinDielectric {
            eta: DEFAULT_INT_IOR / DEFAULT_EXT_IOR,
            tint: Tint::NONE,
        }
    );
    assert_eq!(
        b[3],
        Bsdf::ThinDielectric {
            eta: 1.33,
            tint: Tint {
                reflect: Vec3::new(1.0, 0.5, 0.25),
                transmit: Vec3::splat(0.5),
            },
        }
    );
    use glint_cpu::bsdf::roughplastic::RoughPlasticParams;
    let r = bsdfs(
        "extras_roughplastic",
        vec![
            json!({ "type": "roughplastic" }),
            json!({ "type": "roughplastic", "alpha": 0.3, "shadowing": "separable",
                    "distribution": "ggx", "diffuse_reflectance": 0.2 }),
        ],
    );
    assert_eq!(
        r[0],
        Bsdf::RoughPlastic(RoughPlasticParams {
            plastic: PlasticParams {
                diffuse: Vec3::splat(0.5),
                specular: Vec3::ONE,
                eta: 1.49 / DEFAULT_EXT_IOR,
                nonlinear: false,
            },
            roughness: rough(
                glint_cpu::loader::DEFAULT_ALPHA,
                glint_cpu::loader::DEFAULT_ALPHA,
                Shadowing::Correlated
            ),
        })
    );
    let Bsdf::RoughPlastic(p) = r[1] else {
        panic!("{:?}", r[1])
    };
    assert_eq!(p.roughness, rough(0.3, 0.3, Shadowing::Separable));
    assert_eq!(p.plastic.diffuse, Vec3::splat(0.2));
    for (bad, want) in [
        (
            json!({ "type": "roughplastic", "alpha_u": 0.1, "alpha_v": 0.2 }),
            "isotropic",
        ),
        (
            json!({ "type": "roughplastic", "multiscatter": true }),
            "multiscatter",
        ),
        (
            json!({ "type": "plastic", "alpha": 0.1 }),
            "takes no parameter \"alpha\"",
        ),
        (json!({ "type": "plastic", "int_ior": 0 }), "int_ior"),
        (json!({ "type": "plastic", "nonlinear": 1 }), "nonlinear"),
        (
            json!({ "type": "thindielectric", "specular_transmittance": 2 }),
            "specular_transmittance",
        ),
    ] {
        let d = material_doc(vec![json!({ "extras": { "bsdf": bad } })]);
        let e = parse_doc_err(&d, "bad_plastic");
        assert!(e.contains(want), "{e}");
    }
}

#[test]
fn sample_visible_is_taken_as_mitsuba_writes_it() {
    // Mitsuba's rough models take `sample_visible` (its glint export
    // writes it): either value gives the same BSDF, which samples the
    // visible normals.
    let plain = bsdfs(
        "sample_visible_plain",
        vec![
            json!({ "type": "roughconductor", "alpha": 0.2 }),
            json!({ "type": "roughdielectric", "alpha": 0.2 }),
            json!({ "type": "roughplastic", "alpha": 0.2 }),
        ],
    );
    for v in [true, false] {
        let b = bsdfs(
            "sample_visible",
            vec![
                json!({ "type": "roughconductor", "alpha": 0.2, "sample_visible": v }),
                json!({ "type": "roughdielectric", "alpha": 0.2, "sample_visible": v }),
                json!({ "type": "roughplastic", "alpha": 0.2, "sample_visible": v }),
            ],
        );
        assert_eq!(b, plain);
    }
    for (bad, want) in [
        (
            json!({ "type": "roughconductor", "sample_visible": 1 }),
            "\"sample_visible\" must be true or false",
        ),
        (
            json!({ "type": "conductor", "sample_visible": true }),
            "takes no parameter \"sample_visible\"",
        ),
    ] {
        let d = material_doc(vec![json!({ "extras": { "bsdf": bad } })]);
        let e = parse_doc_err(&d, "bad_sample_visible");
        assert!(e.contains(want), "{e}");
    }
}

#[test]
fn twosided_is_the_opaque_bsdf_it_wraps() {
    // Mitsuba 3 scenes wrap opaque BSDFs in `twosided`; glint's opaque
    // models reflect on both sides already.
    let inner = [
        json!({ "type": "diffuse", "reflectance": [0.2, 0.4, 0.6] }),
        json!({ "type": "roughconductor", "material": "Au", "alpha": 0.2 }),
        json!({ "type": "plastic", "diffuse_reflectance": 0.3 }),
    ];
    let plain = bsdfs("twosided_plain", inner.to_vec());
    let wrapped = bsdfs(
        "twosided",
        inner
            .iter()
            .enumerate()
            .map(|(i, b)| json!({ "type": "twosided", ["bsdf", "material", "x"][i]: b }))
            .collect(),
    );
    assert_eq!(wrapped, plain);
    for (bad, want) in [
        (
            json!({ "type": "twosided", "bsdf": { "type": "dielectric" } }),
            "opaque",
        ),
        (
            json!({ "type": "twosided", "front": { "type": "diffuse" }, "back": { "type": "diffuse" } }),
            "one nested BSDF",
        ),
        (json!({ "type": "twosided" }), "one nested BSDF"),
        (
            json!({ "type": "twosided", "bsdf": { "type": "diffuse", "alpha": 1 } }),
            "in \"twosided\": \"diffuse\" takes no parameter \"alpha\"",
        ),
    ] {
        let d = material_doc(vec![json!({ "extras": { "bsdf": bad } })]);
        let e = parse_doc_err(&d, "bad_twosided");
        assert!(e.contains(want), "{e}");
    }
}

#[test]
fn dielectrics_take_mitsubas_tints() {
    let b = bsdfs(
        "dielectric_tints",
        vec![
            json!({ "type": "dielectric", "specular_transmittance": [0.2, 0.5, 0.9] }),
            json!({ "type": "roughdielectric", "alpha": 0.2, "specular_reflectance": 0.5 }),
            json!({ "type": "dielectric" }),
        ],
    );
    let tint = |b: &Bsdf| match b {
        Bsdf::Dielectric { tint, .. } => *tint,
        other => panic!("{other:?}"),
    };
    assert_eq!(
        tint(&b[0]),
        Tint {
            reflect: Vec3::ONE,
            transmit: Vec3::new(0.2, 0.5, 0.9)
        }
    );
    assert_eq!(
        tint(&b[1]),
        Tint {
            reflect: Vec3::splat(0.5),
            transmit: Vec3::ONE
        }
    );
    assert_eq!(tint(&b[2]), Tint::NONE);
    let d = material_doc(vec![json!({ "extras": { "bsdf":
        { "type": "dielectric", "specular_reflectance": [1.5, 0, 0] } } })]);
    let e = parse_doc_err(&d, "bad_tint");
    assert!(e.contains("specular_reflectance"), "{e}");
}

#[test]
fn colours_take_mitsubas_dictionary_form() {
    // Mitsuba's Python scenes write colours as {"type": "rgb", "value": ...}.
    let b = bsdfs(
        "rgb_dict",
        vec![
            json!({ "type": "diffuse", "reflectance": { "type": "rgb", "value": [0.2, 0.25, 0.7] } }),
            json!({ "type": "diffuse", "reflectance": { "type": "rgb", "value": 0.3 } }),
        ],
    );
    assert_eq!(
        b[0],
        Bsdf::Diffuse {
            reflectance: Vec3::new(0.2, 0.25, 0.7)
        }
    );
    assert_eq!(
        b[1],
        Bsdf::Diffuse {
            reflectance: Vec3::splat(0.3)
        }
    );
    for (bad, want) in [
        (
            json!({ "type": "diffuse", "reflectance": { "type": "rgb", "value": [2, 0, 0] } }),
            "must be finite and in [0, 1]",
        ),
        (
            json!({ "type": "diffuse", "reflectance": { "type": "rgb" } }),
            "takes one \"value\"",
        ),
        (
            json!({ "type": "diffuse", "reflectance": { "type": "bitmap", "filename": "a.png" } }),
            "must be [r, g, b] or a number",
        ),
    ] {
        let d = material_doc(vec![json!({ "extras": { "bsdf": bad } })]);
        let e = parse_doc_err(&d, "bad_rgb_dict");
        assert!(e.contains(want), "{e}");
    }
}

#[test]
fn extras_dielectrics_with_defaults_and_names() {
    let b = bsdfs(
        "extras_dielectric",
        vec![
            json!({ "type": "dielectric" }),
            json!({ "type": "dielectric", "int_ior": 1.7, "ext_ior": 1.1 }),
            json!({ "type": "dielectric", "int_ior": "diamond", "ext_ior": "water" }),
            json!({ "type": "roughdielectric", "int_ior": "bk7", "ext_ior": "air", "alpha": 0.02 }),
            json!({ "type": "roughdielectric", "alpha_u": 0.1, "alpha_v": 0.3,
                    "shadowing": "separable", "distribution": "ggx" }),
            json!({ "type": "roughdielectric" }),
        ],
    );
    let eta = |b: &Bsdf| match b {
        Bsdf::Dielectric { eta, .. } => *eta,
        _ => panic!("{b:?}"),
    };
    let r = |b: &Bsdf| match b {
        Bsdf::Dielectric { roughness, .. } => *roughness,
        _ => panic!("{b:?}"),
    };
    assert_eq!(eta(&b[0]), DEFAULT_INT_IOR / DEFAULT_EXT_IOR);
    assert_eq!(DEFAULT_INT_IOR, 1.5046);
    assert_eq!(DEFAULT_EXT_IOR, 1.000277);
    assert!(r(&b[0]).is_smooth());
    assert_eq!(eta(&b[1]), 1.7 / 1.1);
    use glint_cpu::bsdf::named_ior;
    assert_eq!(
        eta(&b[2]),
        named_ior("diamond").unwrap() / named_ior("water").unwrap()
    );
    assert!((eta(&b[3]) - 1.5046 / 1.000277).abs() < 1e-6);
    assert_eq!(r(&b[3]), rough(0.02, 0.02, Shadowing::Correlated));
    assert_eq!(r(&b[4]), rough(0.1, 0.3, Shadowing::Separable));
    assert_eq!(r(&b[5]), rough(0.1, 0.1, Shadowing::Correlated));
}

#[test]
fn tiny_alpha_is_stored_and_renders_smooth() {
    let b = bsdfs(
        "tiny_alpha",
        vec![
            json!({ "type": "roughconductor", "material": "none", "alpha": 0.0005 }),
            json!({ "type": "roughdielectric", "alpha": 0.01 }),
        ],
    );
    let Bsdf::Conductor(c) = b[0] else { panic!() };
    assert_eq!(c.roughness.alpha_u, 0.0005);
    assert!(c.roughness.is_smooth());
    let Bsdf::Dielectric { roughness, .. } = b[1] else {
        panic!()
    };
    assert!(!roughness.is_smooth(), "alpha = 0.01 is still rough");
}

/// Fresnel reflectance of a conductor at normal incidence,
/// ((eta - 1)^2 + k^2) / ((eta + 1)^2 + k^2).
fn f0(eta: Vec3, k: Vec3) -> Vec3 {
    ((eta - 1.0) * (eta - 1.0) + k * k) / ((eta + 1.0) * (eta + 1.0) + k * k)
}

#[test]
fn gltf_core_materials_map_onto_the_bsdfs() {
    let base = [0.9, 0.5, 0.1, 1.0];
    let d = material_doc(vec![
        json!({ "pbrMetallicRoughness": { "baseColorFactor": [0.2, 0.4, 0.6, 1], "metallicFactor": 0 } }),
        json!({ "pbrMetallicRoughness": { "baseColorFactor": base, "metallicFactor": 1, "roughnessFactor": 0 } }),
        json!({ "pbrMetallicRoughness": { "baseColorFactor": base, "metallicFactor": 1, "roughnessFactor": 0.5 } }),
        json!({ "pbrMetallicRoughness": { "baseColorFactor": base, "metallicFactor": 0.25, "roughnessFactor": 0.3 } }),
        json!({ "pbrMetallicRoughness": { "baseColorFactor": [1, 1, 1, 1], "metallicFactor": 1, "roughnessFactor": 0 } }),
    ]);
    let s = parse_doc(&d, "core");
    let b: Vec<Bsdf> = s.materials.iter().map(|m| m.bsdf).collect();
    // A non-metal is the coated model (contract: a GGX dielectric coat of
    // IOR 1.5 over a Lambertian base), roughness 1 by default.
    assert_eq!(
        b[0],
        Bsdf::Coated {
            base: Vec3::new(0.2, 0.4, 0.6),
            coat: CoatParams::GLTF_DEFAULT,
            roughness: rough(1.0, 1.0, Shadowing::Correlated),
        }
    );
    let base3 = Vec3::new(0.9, 0.5, 0.1);
    let Bsdf::Conductor(c) = b[1] else {
        panic!("{:?}", b[1])
    };
    assert_eq!(c.eta, Vec3::ONE);
    assert!(
        close(f0(c.eta, c.k), base3),
        "F0 {} != baseColor",
        f0(c.eta, c.k)
    );
    assert!(c.roughness.is_smooth());
    assert_eq!(c.specular_reflectance, Vec3::ONE);
    // The BSDF's own Fresnel at normal incidence reproduces baseColor: a
    // smooth conductor reflects wo = +z into wi = +z with weight F(0).
    let smp = b[1]
        .sample(Vec3::Z, 0.5, Vec2::splat(0.5))
        .expect("mirror sample");
    assert!(smp.delta);
    assert!(
        close(smp.weight, base3),
        "Fresnel weight {} != {base3}",
        smp.weight
    );
    let Bsdf::Conductor(c) = b[2] else { panic!() };
    assert_eq!(
        c.roughness,
        rough(0.25, 0.25, Shadowing::Correlated),
        "alpha = roughness^2"
    );
    match b[3] {
        Bsdf::Metallic {
            metallic,
            base,
            conductor,
            coat,
        } => {
            assert_eq!(coat, CoatParams::GLTF_DEFAULT);
            assert_eq!(metallic, 0.25);
            assert_eq!(base, base3);
            assert!(close(f0(conductor.eta, conductor.k), base3));
            assert!((conductor.roughness.alpha_u - 0.09).abs() < 1e-6);
        }
        other => panic!("{other:?}"),
    }
    // F0 = 1 is clamped to 0.999 so k stays finite.
    let Bsdf::Conductor(c) = b[4] else { panic!() };
    assert!(c.k.is_finite());
    assert!(close(f0(c.eta, c.k), Vec3::splat(0.999)));
}

/// KHR_materials_ior and KHR_materials_specular reach the non-metal's coat
/// (and the blend's); a specular scale over 1 is clamped with a warning;
/// an IOR below 1 or a negative colour is one clear error.
#[test]
fn ior_and_specular_shape_the_coat() {
    let d = material_doc(vec![
        json!({ "pbrMetallicRoughness": { "metallicFactor": 0, "roughnessFactor": 0.5 },
                "extensions": { "KHR_materials_ior": { "ior": 1.33 },
                                "KHR_materials_specular": { "specularFactor": 0.5,
                                                            "specularColorFactor": [1, 0.5, 0.25] } } }),
        json!({ "pbrMetallicRoughness": { "metallicFactor": 0.5 },
                "extensions": { "KHR_materials_specular": { "specularColorFactor": [2, 1, 1] } } }),
    ]);
    let s = parse_doc(&d, "coat");
    let Bsdf::Coated {
        coat, roughness, ..
    } = s.materials[0].bsdf
    else {
        panic!("{:?}", s.materials[0].bsdf)
    };
    assert_eq!(coat.eta, 1.33);
    assert_eq!(coat.specular, Vec3::new(0.5, 0.25, 0.125));
    assert_eq!(roughness.alpha_u, 0.25);
    let Bsdf::Metallic { coat, .. } = s.materials[1].bsdf else {
        panic!("{:?}", s.materials[1].bsdf)
    };
    assert_eq!(coat.specular, Vec3::ONE, "clamped to 1");
    assert!(
        s.warnings.iter().any(|w| w.contains("clamped")),
        "{:?}",
        s.warnings
    );
    for (ext, want) in [
        (json!({ "KHR_materials_ior": { "ior": 0.5 } }), "ior"),
        (
            json!({ "KHR_materials_specular": { "specularColorFactor": [-1, 0, 0] } }),
            "specularColorFactor",
        ),
    ] {
        let d = material_doc(vec![
            json!({ "extensions": ext, "pbrMetallicRoughness": { "metallicFactor": 0 } }),
        ]);
        let e = parse_doc_err(&d, "bad coat");
        assert!(e.contains(want), "{e}");
    }
}

#[test]
fn a_solid_dielectric_takes_the_volumes_beer_lambert_absorption() {
    let glass = |volume: serde_json::Value| {
        json!({ "pbrMetallicRoughness": { "roughnessFactor": 0, "metallicFactor": 0 },
                "extensions": { "KHR_materials_transmission": { "transmissionFactor": 1 },
                                "KHR_materials_volume": volume } })
    };
    let d = material_doc(vec![
        glass(
            json!({ "thicknessFactor": 1, "attenuationColor": [0.5, 1, 0.25],
                      "attenuationDistance": 2 }),
        ),
        // No distance: infinite, a clear interior.
        glass(json!({ "thicknessFactor": 1, "attenuationColor": [0.5, 0.5, 0.5] })),
        // Thin-walled (no thickness): glTF ignores the volume.
        glass(
            json!({ "thicknessFactor": 0, "attenuationColor": [0.5, 0.5, 0.5],
                      "attenuationDistance": 1 }),
        ),
        // A black channel absorbs everything, finitely (no NaN from 0 t).
        glass(json!({ "thicknessFactor": 1, "attenuationColor": [0, 1, 1],
                      "attenuationDistance": 1 })),
    ]);
    let s = parse_doc(&d, "volume");
    assert!(
        s.warnings.iter().all(|w| !w.contains("attenuation")),
        "{:?}",
        s.warnings
    );
    let a = s.materials[0].absorption;
    let ln2 = std::f32::consts::LN_2;
    assert!(
        (a - Vec3::new(ln2 / 2.0, 0.0, 2.0 * ln2 / 2.0))
            .abs()
            .max_element()
            < 1e-6,
        "{a}"
    );
    assert!(matches!(s.materials[0].bsdf, Bsdf::Dielectric { .. }));
    assert_eq!(s.materials[1].absorption, Vec3::ZERO);
    assert_eq!(s.materials[2].absorption, Vec3::ZERO);
    assert!(!matches!(s.materials[2].bsdf, Bsdf::Dielectric { .. }));
    let b = s.materials[3].absorption;
    assert!(
        b.x.is_finite() && b.x > 40.0 && (-b.x * 0.0).exp() == 1.0,
        "{b}"
    );
    // The GPU reads it from the dielectric's k.
    let g = glint_cpu::GpuMaterial::from(&s.materials[0]);
    assert_eq!(&g.k[..3], &a.to_array()[..]);
}

#[test]
fn transmission_is_thin_walled_unless_the_volume_has_a_thickness() {
    let d = material_doc(vec![
        json!({ "pbrMetallicRoughness": { "roughnessFactor": 0, "metallicFactor": 0,
                                          "baseColorFactor": [1, 0.5, 0.25, 1] },
                "extensions": { "KHR_materials_transmission": { "transmissionFactor": 1 } } }),
        // metallic 1: the metal ignores transmission (glTF: it is the
        // dielectric part's).
        json!({ "pbrMetallicRoughness": { "roughnessFactor": 0.5, "metallicFactor": 1 },
                "extensions": { "KHR_materials_transmission": { "transmissionFactor": 0.5 },
                                "KHR_materials_ior": { "ior": 1.33 } } }),
        json!({ "pbrMetallicRoughness": { "metallicFactor": 0 },
                "extensions": { "KHR_materials_transmission": { "transmissionFactor": 0 } } }),
        // A thickness: the mesh bounds a solid dielectric.
        json!({ "pbrMetallicRoughness": { "roughnessFactor": 0.5, "metallicFactor": 0 },
                "extensions": { "KHR_materials_transmission": { "transmissionFactor": 1 },
                                "KHR_materials_volume": { "thicknessFactor": 0.1 },
                                "KHR_materials_ior": { "ior": 1.33 } } }),
        json!({ "pbrMetallicRoughness": { "metallicFactor": 0.25 },
                "extensions": { "KHR_materials_transmission": { "transmissionFactor": 0.4 },
                                "KHR_materials_volume": { "thicknessFactor": 0 } } }),
    ]);
    let s = parse_doc(&d, "transmission");
    assert_eq!(
        s.materials[0].bsdf,
        Bsdf::Coated {
            base: Vec3::new(1.0, 0.5, 0.25),
            coat: CoatParams {
                transmission: 1.0,
                ..CoatParams::GLTF_DEFAULT
            },
            roughness: rough(0.0, 0.0, Shadowing::Correlated)
        }
    );
    assert!(s.materials[0].bsdf.is_delta() && s.materials[0].bsdf.has_transmission());
    assert!(matches!(s.materials[1].bsdf, Bsdf::Conductor(_)));
    assert!(matches!(s.materials[2].bsdf, Bsdf::Coated { coat, .. } if coat.transmission == 0.0));
    assert_eq!(
        s.materials[3].bsdf,
        Bsdf::Dielectric {
            eta: 1.33,
            roughness: rough(0.25, 0.25, Shadowing::Correlated),
            tint: glint_cpu::bsdf::Tint::NONE,
        }
    );
    let Bsdf::Metallic { metallic, coat, .. } = s.materials[4].bsdf else {
        panic!("{:?}", s.materials[4].bsdf)
    };
    assert_eq!((metallic, coat.transmission), (0.25, 0.4));
    for (ext, want) in [
        (
            json!({ "KHR_materials_volume": { "thicknessFactor": -1 } }),
            "thicknessFactor",
        ),
        (
            json!({ "KHR_materials_volume": { "thicknessFactor": 1, "attenuationDistance": -2 } }),
            "attenuationDistance",
        ),
    ] {
        let d = material_doc(vec![json!({ "extensions": ext })]);
        let e = parse_doc_err(&d, "bad_volume");
        assert!(e.contains(want), "{e}");
    }
}

#[test]
fn missing_material_gets_the_gltf_default() {
    let mut d = Doc::new();
    d.material(json!({ "pbrMetallicRoughness": { "metallicFactor": 0 } }));
    let with = d.triangle_mesh(Some(0));
    let without = d.triangle_mesh(None);
    d.node(json!({ "mesh": with }));
    d.node(json!({ "mesh": without }));
    let s = parse_doc(&d, "default_material");
    assert_eq!(s.materials.len(), 2);
    assert_eq!(s.triangles[0].material, 0);
    assert_eq!(s.triangles[1].material, 1);
    assert_eq!(s.materials[1], loader::gltf_default_material());
    let Bsdf::Conductor(c) = s.materials[1].bsdf else {
        panic!()
    };
    assert_eq!(c.roughness.alpha_u, 1.0);
    // No primitive without a material: nothing appended.
    let mut d = Doc::new();
    d.material(json!({}));
    let m = d.triangle_mesh(Some(0));
    d.node(json!({ "mesh": m }));
    assert_eq!(parse_doc(&d, "default_material2").materials.len(), 1);
}

#[test]
fn emission_strength_and_double_sided() {
    let d = material_doc(vec![
        json!({ "emissiveFactor": [1, 0.5, 0.25],
                "extensions": { "KHR_materials_emissive_strength": { "emissiveStrength": 8 } } }),
        json!({ "emissiveFactor": [0.5, 0.5, 0.5], "doubleSided": true }),
        json!({ "doubleSided": true }),
    ]);
    let s = parse_doc(&d, "emission");
    assert_eq!(s.materials[0].emission, Vec3::new(8.0, 4.0, 2.0));
    assert!(!s.materials[0].double_sided);
    assert_eq!(s.materials[1].emission, Vec3::splat(0.5));
    assert!(s.materials[1].double_sided);
    // assign_emitters ran: the two emissive triangles are lights 0 and 1.
    assert_eq!(s.triangles[0].light, 0);
    assert_eq!(s.triangles[1].light, 1);
    assert_eq!(s.triangles[2].light, glint_cpu::NO_LIGHT);
    assert_eq!(s.triangles[0].flags & TRI_DOUBLE_SIDED, 0);
    assert_eq!(s.triangles[1].flags & TRI_DOUBLE_SIDED, TRI_DOUBLE_SIDED);
    assert_eq!(s.triangles[2].flags & TRI_DOUBLE_SIDED, TRI_DOUBLE_SIDED);
    assert_eq!(s.emitter_triangles(), vec![0, 1]);
}

#[test]
fn punctual_lights_of_all_kinds() {
    let mut d = Doc::new();
    d.json["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    d.json["extensions"] = json!({ "KHR_lights_punctual": { "lights": [
        { "type": "point", "color": [1, 0.5, 0.25], "intensity": 4, "range": 2 },
        { "type": "spot", "intensity": 3, "spot": { "innerConeAngle": 0.2, "outerConeAngle": 0.6 } },
        { "type": "directional", "color": [0.5, 0.5, 1], "intensity": 2 },
        { "type": "spot", "spot": {} }
    ] } });
    let ext = |i: usize| json!({ "KHR_lights_punctual": { "light": i } });
    let q = Quat::from_rotation_x(-FRAC_PI_2); // -Z turns to -Y
    let spot = d.child(json!({ "extensions": ext(1), "translation": [0, 1, 0] }));
    d.node(json!({ "extensions": ext(0), "translation": [1, 2, 3], "scale": [5, 5, 5] }));
    d.node(json!({ "rotation": q.to_array(), "translation": [0, 4, 0], "children": [spot] }));
    d.node(
        json!({ "extensions": ext(2), "rotation": Quat::from_rotation_y(FRAC_PI_2).to_array() }),
    );
    d.node(json!({ "extensions": ext(3) }));
    let s = parse_doc(&d, "lights");
    assert_eq!(s.lights.len(), 4);
    assert_eq!(
        s.lights[0],
        PunctualLight::Point {
            position: Vec3::new(1., 2., 3.),
            intensity: Vec3::new(4., 2., 1.)
        }
    );
    match s.lights[1] {
        PunctualLight::Spot {
            position,
            direction,
            intensity,
            inner_cone_angle,
            outer_cone_angle,
        } => {
            // Child at local (0, 1, 0) under a rotation x by -90 deg: (0, 0, -1) + (0, 4, 0).
            assert_close(position, Vec3::new(0., 4., -1.));
            assert_close(direction, -Vec3::Y);
            assert_eq!(intensity, Vec3::splat(3.0));
            assert_eq!((inner_cone_angle, outer_cone_angle), (0.2, 0.6));
        }
        other => panic!("{other:?}"),
    }
    match s.lights[2] {
        PunctualLight::Directional {
            direction,
            irradiance,
        } => {
            assert_close(direction, -Vec3::X);
            assert_eq!(irradiance, Vec3::new(1., 1., 2.));
        }
        other => panic!("{other:?}"),
    }
    match s.lights[3] {
        PunctualLight::Spot {
            inner_cone_angle,
            outer_cone_angle,
            direction,
            ..
        } => {
            assert_eq!(
                (inner_cone_angle, outer_cone_angle),
                (0.0, FRAC_PI_4),
                "spec defaults"
            );
            assert_close(direction, -Vec3::Z);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn background_from_scene_extras() {
    let mut d = Doc::new();
    d.json["scenes"][0]["extras"] = json!({ "background": [0.1, 0.2, 0.3], "other": "ignored" });
    assert_eq!(
        parse_doc(&d, "background").background,
        Vec3::new(0.1, 0.2, 0.3)
    );
    let d = Doc::new();
    assert_eq!(parse_doc(&d, "background_default").background, Vec3::ZERO);
}

#[test]
fn default_scene_is_the_one_marked() {
    let mut d = Doc::new();
    let m = d.triangle_mesh(None);
    let a = d.child(json!({ "mesh": m }));
    let b = d.child(json!({ "mesh": m, "translation": [0, 0, 7] }));
    d.json["scenes"] = json!([ { "nodes": [a] }, { "nodes": [b] } ]);
    d.json["scene"] = json!(1);
    let s = parse_doc(&d, "scene_marked");
    assert_eq!(s.triangles[0].vertices()[0], Vec3::new(0., 0., 7.));
    d.json.as_object_mut().unwrap().remove("scene");
    let s = parse_doc(&d, "scene_unmarked");
    assert_eq!(
        s.triangles[0].vertices()[0],
        Vec3::ZERO,
        "scene 0 when none is marked"
    );
}

#[test]
fn cameras_in_traversal_order_without_scale() {
    let mut d = Doc::new();
    d.json["cameras"] = json!([
        { "name": "wide", "type": "perspective", "perspective": { "yfov": 1.2, "znear": 0.1 } },
        { "name": "tele", "type": "perspective", "perspective": { "yfov": 0.3, "aspectRatio": 2.0, "znear": 0.1 } }
    ]);
    let q = Quat::from_rotation_y(0.7);
    let inner = d.child(json!({ "camera": 0, "translation": [0, 0, 1] }));
    d.node(json!({ "children": [inner], "rotation": q.to_array(), "scale": [3, 0.5, 2], "translation": [1, 2, 3] }));
    d.node(json!({ "camera": 1, "scale": [-1, 1, 1] }));
    d.node(json!({ "camera": 0, "name": "again" }));
    let s = parse_doc(&d, "cameras");
    assert_eq!(s.cameras.len(), 3);
    let c = &s.cameras[0];
    assert_eq!(c.name.as_deref(), Some("wide"));
    assert_eq!(c.yfov, 1.2);
    assert_eq!(c.aspect_ratio, None);
    let r = Mat3::from_mat4(c.to_world);
    assert!(
        (r.transpose() * r).abs_diff_eq(Mat3::IDENTITY, 1e-5),
        "orthonormal"
    );
    assert!((r.determinant() - 1.0).abs() < 1e-5, "right-handed");
    assert_close(r * Vec3::NEG_Z, q * Vec3::NEG_Z);
    assert_close(r * Vec3::Y, Vec3::Y);
    // Position: (0,0,1) scaled (z by 2), rotated, translated.
    assert_close(
        c.to_world.w_axis.truncate(),
        Vec3::new(1., 2., 3.) + q * Vec3::new(0., 0., 2.),
    );
    let c = &s.cameras[1];
    assert_eq!((c.yfov, c.aspect_ratio), (0.3, Some(2.0)));
    assert!(
        (Mat3::from_mat4(c.to_world).determinant() - 1.0).abs() < 1e-5,
        "mirror removed"
    );
    assert_close(c.to_world.transform_vector3(Vec3::NEG_Z), Vec3::NEG_Z);

    assert_eq!(select_camera(&s, "tele"), Ok(1));
    assert_eq!(select_camera(&s, "2"), Ok(2));
    assert_eq!(select_camera(&s, "wide"), Ok(0));
    let e = select_camera(&s, "7").unwrap_err();
    assert!(e.contains("out of range") && e.contains("'tele'"), "{e}");
    let e = select_camera(&s, "zoom").unwrap_err();
    assert!(e.contains("no camera named 'zoom'"), "{e}");
}

#[test]
fn default_camera_frames_the_bounding_sphere() {
    let mut d = Doc::new();
    let m = d.triangle_mesh(None);
    d.node(json!({ "mesh": m, "scale": [4, 2, 1], "translation": [-1, 3, -2] }));
    let s = parse_doc(&d, "default_camera");
    assert!(s.cameras.is_empty());
    let cam = default_camera(&s);
    let (lo, hi) = s.bounds();
    let center = 0.5 * (lo + hi);
    let radius = 0.5 * (hi - lo).length();
    let eye = cam.to_world.w_axis.truncate();
    assert_close(Mat3::from_mat4(cam.to_world) * Vec3::NEG_Z, Vec3::NEG_Z);
    assert!((eye.x - center.x).abs() < 1e-6 && (eye.y - center.y).abs() < 1e-6 && eye.z > hi.z);
    assert!((cam.yfov - 40f32.to_radians()).abs() < 1e-6);
    // The sphere is tangent to the view cone: distance * sin(yfov / 2) = radius.
    let dist = (eye - center).length();
    assert!((dist * (cam.yfov / 2.0).sin() - radius).abs() < 1e-4);
    // Every bounding-box corner lies inside the vertical field of view.
    for i in 0..8 {
        let p = Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        );
        let v = p - eye;
        let off_axis = (v.x * v.x + v.y * v.y).sqrt();
        assert!(
            off_axis / -v.z <= (cam.yfov / 2.0).tan() + 1e-5,
            "corner {p} outside the view"
        );
    }
    // An empty scene still gets a finite viewpoint.
    let empty = parse_doc(&Doc::new(), "default_camera_empty");
    assert!(default_camera(&empty).to_world.is_finite());
}

fn container_doc() -> Doc {
    let mut d = Doc::new();
    d.material(json!({ "emissiveFactor": [1, 1, 1] }));
    let pos = d.floats(&[0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.], "VEC3");
    let nrm = d.floats(&[0., 0., 1., 0., 0., 1., 0., 0., 1., 0., 0., 1.], "VEC3");
    let idx = d.indices_u16(&[0, 1, 2, 0, 2, 3]);
    let m = d.mesh(vec![
        json!({ "attributes": { "POSITION": pos, "NORMAL": nrm }, "indices": idx, "material": 0 }),
    ]);
    d.node(json!({ "mesh": m, "translation": [0, 0, -1] }));
    d
}

#[test]
fn glb_data_uri_and_external_buffers_agree() {
    let d = container_doc();
    let dir = temp_dir("containers");
    let paths = [
        d.write_gltf(&dir, "embedded"),
        d.write_gltf_external(&dir, "external"),
        d.write_glb(&dir, "binary"),
    ];
    let scenes: Vec<Scene> = paths
        .iter()
        .map(|p| parse(p).unwrap_or_else(|e| panic!("{e}")))
        .collect();
    for s in &scenes {
        assert_eq!(s.triangles.len(), 2);
        assert_eq!(s.triangles, scenes[0].triangles);
        assert_eq!(s.shading, scenes[0].shading);
        assert_eq!(s.materials, scenes[0].materials);
    }
    // External buffer URIs are percent-decoded relative to the .gltf.
    std::fs::copy(dir.join("external.bin"), dir.join("with space.bin")).unwrap();
    let mut j: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&paths[1]).unwrap()).unwrap();
    j["buffers"][0]["uri"] = json!("with%20space.bin");
    let p = dir.join("spaced.gltf");
    std::fs::write(&p, serde_json::to_vec(&j).unwrap()).unwrap();
    assert_eq!(parse(&p).unwrap().triangles, scenes[0].triangles);
    // A UTF-8 byte order mark before the JSON is skipped.
    let mut bom = b"\xEF\xBB\xBF".to_vec();
    bom.extend(std::fs::read(&paths[0]).unwrap());
    let p = dir.join("bom.gltf");
    std::fs::write(&p, bom).unwrap();
    assert_eq!(parse(&p).unwrap().triangles, scenes[0].triangles);
}

#[test]
fn sparse_accessors_are_applied() {
    let mut d = Doc::new();
    let pos = d.floats(&[0., 0., 0., 1., 0., 0., 0., 1., 0.], "VEC3");
    let idx_view = d.view(&2u16.to_le_bytes());
    let val_view = d.view(
        &[0f32, 5., 0.]
            .iter()
            .flat_map(|x| x.to_le_bytes())
            .collect::<Vec<u8>>(),
    );
    d.json["accessors"][pos]["sparse"] = json!({
        "count": 1,
        "indices": { "bufferView": idx_view, "componentType": 5123 },
        "values": { "bufferView": val_view }
    });
    let m = d.mesh(vec![json!({ "attributes": { "POSITION": pos } })]);
    d.node(json!({ "mesh": m }));
    let s = parse_doc(&d, "sparse");
    assert_eq!(s.triangles[0].vertices()[2], Vec3::new(0., 5., 0.));
}

fn assets_dir() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets")
}

#[test]
fn bundled_assets_load() {
    for name in [
        "cornell",
        "diffuse",
        "conductor",
        "roughconductor",
        "dielectric",
        "roughdielectric",
    ] {
        let s = parse(&assets_dir().join(format!("{name}.gltf"))).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.cameras.len(), 1, "{name}");
        assert!(s.triangles.len() > 500, "{name}");
        // NORMAL on every mesh: kept wherever the faces are curved (the
        // spheres), dropped on flat faces (their geometric normal).
        assert!(
            s.triangles
                .iter()
                .any(|t| t.flags & glint_cpu::TRI_NORMALS != 0),
            "{name}: smooth normals kept"
        );
        let has = |ty: fn(&Bsdf) -> bool| s.materials.iter().any(|m| ty(&m.bsdf));
        assert!(has(|b| matches!(b, Bsdf::Diffuse { .. })), "{name}");
        let lit = !s.emitter_triangles().is_empty() || !s.lights.is_empty();
        assert!(lit, "{name} has a light");
    }
    let s = parse(&assets_dir().join("cornell.gltf")).unwrap();
    assert_eq!(s.cameras[0].aspect_ratio, Some(1.0));
    assert_eq!(s.emitter_triangles().len(), 2, "one emissive quad");
    let kinds: Vec<&str> = s
        .materials
        .iter()
        .map(|m| match m.bsdf {
            Bsdf::Diffuse { .. } => "diffuse",
            Bsdf::Conductor(c) if c.roughness.is_smooth() => "conductor",
            Bsdf::Conductor(_) => "roughconductor",
            Bsdf::Dielectric { roughness, .. } if roughness.is_smooth() => "dielectric",
            Bsdf::Dielectric { .. } => "roughdielectric",
            Bsdf::Metallic { .. } => "metallic",
            Bsdf::Coated { .. } => "coated",
            Bsdf::Plastic(_) => "plastic",
            Bsdf::RoughPlastic(_) => "roughplastic",
            Bsdf::ThinDielectric { .. } => "thindielectric",
        })
        .collect();
    for k in [
        "diffuse",
        "conductor",
        "roughconductor",
        "dielectric",
        "roughdielectric",
    ] {
        assert!(kinds.contains(&k), "cornell lacks {k}: {kinds:?}");
    }
    // Between them the single-BSDF scenes use every light kind and a background.
    let mut seen = std::collections::BTreeSet::new();
    for name in [
        "diffuse",
        "conductor",
        "roughconductor",
        "dielectric",
        "roughdielectric",
    ] {
        let s = parse(&assets_dir().join(format!("{name}.gltf"))).unwrap();
        if !s.emitter_triangles().is_empty() {
            seen.insert("area");
        }
        if s.background != Vec3::ZERO {
            seen.insert("background");
        }
        for l in &s.lights {
            seen.insert(match l {
                PunctualLight::Point { .. } => "point",
                PunctualLight::Spot { .. } => "spot",
                PunctualLight::Directional { .. } => "directional",
            });
        }
    }
    assert_eq!(seen.len(), 5, "{seen:?}");
}

#[test]
fn bunny_parses() {
    let path = assets_dir().join("bunny.glb");
    let t = std::time::Instant::now();
    let s = parse(&path).unwrap_or_else(|e| panic!("{e}"));
    let secs = t.elapsed().as_secs_f64();
    eprintln!(
        "bunny.glb: {} triangles parsed in {secs:.3} s",
        s.triangles.len()
    );
    assert_eq!(s.triangles.len(), 69_451);
    assert!((0..s.triangles.len()).all(|i| s.shading_of(i).n.iter().all(|n| n[3] == 1.0)));
    // Normals only (no TANGENT, no texture coordinates): three vec4s each.
    assert_eq!(s.shading.len(), 3 * s.triangles.len());
    assert_eq!(s.gpu_bytes_per_triangle(), 96.0);
    assert_eq!(s.materials.len(), 1);
    assert!(s.cameras.is_empty());
}

#[test]
fn load_builds_the_bvh_and_keeps_emitters() {
    for name in ["cornell.gltf", "bunny.glb"] {
        let path = assets_dir().join(name);
        let parsed = parse(&path).unwrap();
        let (s, secs) = loader::load_timed(&path).unwrap_or_else(|e| panic!("{e}"));
        eprintln!(
            "{name}: {} triangles loaded (parse + BVH) in {secs:.3} s",
            s.triangles.len()
        );
        assert!(!s.bvh.nodes.is_empty());
        assert_eq!(s.triangles.len(), parsed.triangles.len());
        assert_eq!(s.shading.len(), parsed.shading.len());
        // Reordered into leaf order, emitters renumbered 0.. in the new order.
        let emitters = s.emitter_triangles();
        assert_eq!(emitters.len(), parsed.emitter_triangles().len());
        for (k, &t) in emitters.iter().enumerate() {
            assert_eq!(s.triangles[t as usize].light, k as u32);
        }
        // The same multiset of triangles, each still with its own shading.
        let key = |s: &Scene, i: usize| {
            let (t, sh) = (&s.triangles[i], s.shading_of(i));
            format!("{:?}{:?}{:?}{}", t.vertices(), sh.n, sh.t, t.material)
        };
        let mut a: Vec<String> = (0..parsed.triangles.len())
            .map(|i| key(&parsed, i))
            .collect();
        let mut b: Vec<String> = (0..s.triangles.len()).map(|i| key(&s, i)).collect();
        a.sort();
        b.sort();
        assert!(a == b, "{name}: load changed the triangle set");
    }
}

#[test]
fn skipped_features_are_warnings() {
    let mut d = Doc::new();
    let tri = d.triangle_mesh(None);
    let pos = d.floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0], "VEC3");
    let lines = d.mesh(vec![
        json!({ "attributes": { "POSITION": pos }, "mode": 1 }),
        json!({ "attributes": { "POSITION": pos }, "mode": 0 }),
    ]);
    let morph = d.floats(&[0.0; 9], "VEC3");
    let m = d.triangle_mesh(None);
    d.json["meshes"][m]["primitives"][0]["targets"] = json!([{ "POSITION": morph }]);
    d.node(json!({ "mesh": tri }));
    d.node(json!({ "mesh": lines }));
    d.node(json!({ "mesh": m }));
    d.json["extensionsUsed"] = json!(["EXT_unknown_optional", "KHR_materials_emissive_strength"]);
    let s = parse_doc(&d, "warnings");
    assert_eq!(s.triangles.len(), 2);
    let w = s.warnings.join("\n");
    assert!(w.contains("2 point or line primitive(s) skipped"), "{w}");
    assert!(w.contains("morph targets"), "{w}");
    assert!(
        w.contains("extension EXT_unknown_optional is not supported"),
        "{w}"
    );
    assert!(!w.contains("KHR_materials_emissive_strength"), "{w}");
    assert_eq!(s.warnings.len(), 3, "{w}");
    // A clean file has none.
    let mut d = Doc::new();
    let tri = d.triangle_mesh(None);
    d.node(json!({ "mesh": tri }));
    assert!(parse_doc(&d, "nowarnings").warnings.is_empty());
}

#[test]
fn no_light_gets_a_white_background_with_a_warning() {
    let mut d = Doc::new();
    let tri = d.triangle_mesh(None);
    d.node(json!({ "mesh": tri }));
    let mut s = parse_doc(&d, "unlit");
    assert!(!s.has_light());
    assert!(s.light_if_unlit());
    assert_eq!(s.background, Vec3::ONE);
    assert!(s.warnings.last().unwrap().contains("no light"));
    // Lit scenes keep their (black) background.
    let mut d = Doc::new();
    let mat = d.material(json!({ "emissiveFactor": [1, 1, 1] }));
    let tri = d.triangle_mesh(Some(mat));
    d.node(json!({ "mesh": tri }));
    let mut s = parse_doc(&d, "lit");
    assert!(!s.light_if_unlit());
    assert_eq!(s.background, Vec3::ZERO);
    assert!(s.warnings.is_empty());
}

#[test]
fn accessors_without_views_read_as_zeros() {
    let mut d = Doc::new();
    let pos = d.floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0], "VEC3");
    // Indices with no buffer view: three zeros, one degenerate triangle.
    let idx = d.accessor(json!({ "componentType": 5123, "count": 3, "type": "SCALAR" }));
    let m = d.mesh(vec![
        json!({ "attributes": { "POSITION": pos }, "indices": idx }),
    ]);
    d.node(json!({ "mesh": m }));
    let s = parse_doc(&d, "zeros");
    assert_eq!(s.triangles.len(), 1);
    assert_eq!(s.triangles[0].vertices(), [Vec3::ZERO; 3]);
}

#[test]
fn quantized_accessors_are_read() {
    // KHR_mesh_quantization: i16 normalized positions, i8 normalized
    // normals, u16 normalized and u8 unnormalized texcoords.
    let mut d = Doc::new();
    let p: [i16; 9] = [0, 0, 0, 32767, 0, 0, 0, -32767, 0];
    let bytes: Vec<u8> = p.iter().flat_map(|x| x.to_le_bytes()).collect();
    let v = d.view(&bytes);
    let pos = d.accessor(json!({ "bufferView": v, "componentType": 5122, "normalized": true, "count": 3, "type": "VEC3" }));
    // u8 positions, not normalized, padded to 4-byte stride.
    let q: [u8; 12] = [0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 0];
    let v = d.view(&q);
    d.json["bufferViews"][v]["byteStride"] = json!(4);
    let pos8 =
        d.accessor(json!({ "bufferView": v, "componentType": 5121, "count": 3, "type": "VEC3" }));
    // Not all the face normal (flat faces store none): +Z, +X, -Y.
    let n: [i8; 12] = [0, 0, 127, 0, 127, 0, 0, 0, 0, -127, 0, 0];
    let v = d.view(&n.map(|x| x as u8));
    d.json["bufferViews"][v]["byteStride"] = json!(4);
    let nrm = d.accessor(json!({ "bufferView": v, "componentType": 5120, "normalized": true, "count": 3, "type": "VEC3" }));
    let m = d.mesh(vec![
        json!({ "attributes": { "POSITION": pos, "NORMAL": nrm } }),
        json!({ "attributes": { "POSITION": pos8 } }),
    ]);
    d.node(json!({ "mesh": m }));
    d.json["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
    d.json["extensionsRequired"] = json!(["KHR_mesh_quantization"]);
    let s = parse_doc(&d, "quantized");
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let tris = tri_set(&s);
    assert_eq!(tris[0], [Vec3::ZERO, Vec3::X, Vec3::NEG_Y]);
    assert_eq!(
        tris[1],
        [
            Vec3::ZERO,
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 2.0, 0.0)
        ]
    );
    let sh = s.shading_of(0);
    assert_close(Vec3::from_slice(&sh.n[0][..3]), Vec3::Z);
    assert_close(Vec3::from_slice(&sh.n[1][..3]), Vec3::X);
    assert_close(Vec3::from_slice(&sh.n[2][..3]), Vec3::NEG_Y);
}
