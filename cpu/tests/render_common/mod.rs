//! Scenes built in code for the render tests (no loader involved).
#![allow(dead_code)]

use glam::{Mat4, Vec3};
use glint_cpu::bsdf::Bsdf;
use glint_cpu::{Camera, Film, Material, NO_LIGHT, PunctualLight, RenderOptions, Scene, Triangle};

pub fn diffuse(name: &str, rho: f32) -> Material {
    Material {
        name: name.into(),
        bsdf: Bsdf::Diffuse {
            reflectance: Vec3::splat(rho),
        },
        emission: Vec3::ZERO,
        double_sided: false,
        absorption: glam::Vec3::ZERO,
    }
}

pub fn emitter(name: &str, le: Vec3, double_sided: bool) -> Material {
    Material {
        name: name.into(),
        bsdf: Bsdf::Diffuse {
            reflectance: Vec3::ZERO,
        },
        emission: le,
        double_sided,
        absorption: glam::Vec3::ZERO,
    }
}

pub fn tri(a: Vec3, b: Vec3, c: Vec3, material: u32) -> Triangle {
    Triangle {
        p0: a.into(),
        material,
        p1: b.into(),
        light: NO_LIGHT,
        p2: c.into(),
        flags: 0,
    }
}

/// Quad a-b-c-d (counter-clockwise seen from the front) as two triangles.
pub fn quad(a: Vec3, b: Vec3, c: Vec3, d: Vec3, material: u32) -> Vec<Triangle> {
    vec![tri(a, b, c, material), tri(a, c, d, material)]
}

/// Horizontal square at height y, half-size s, facing +Y.
pub fn floor(y: f32, s: f32, material: u32) -> Vec<Triangle> {
    quad(
        Vec3::new(-s, y, s),
        Vec3::new(s, y, s),
        Vec3::new(s, y, -s),
        Vec3::new(-s, y, -s),
        material,
    )
}

/// A UV sphere with outward (counter-clockwise) faces and flat shading
/// (no shading normals), so it is convex: n_phi segments, n_theta stacks.
pub fn uv_sphere(c: Vec3, r: f32, n_phi: u32, n_theta: u32, material: u32) -> Vec<Triangle> {
    use std::f32::consts::PI;
    let p = |i: u32, j: u32| {
        let th = PI * i as f32 / n_theta as f32;
        let ph = 2.0 * PI * j as f32 / n_phi as f32;
        c + r * Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin())
    };
    let mut out = Vec::new();
    for i in 0..n_theta {
        for j in 0..n_phi {
            let (a, b, cc, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            for (x, y, z) in [(a, b, cc), (a, cc, d)] {
                let t = tri(x, y, z, material);
                if t.area() < 1e-9 {
                    continue;
                }
                let n = t.geometric_normal();
                out.push(if n.dot((x + y + z) / 3.0 - c) < 0.0 {
                    tri(x, z, y, material)
                } else {
                    t
                });
            }
        }
    }
    out
}

/// A closed box (half-extents `h`), rotated by `rot` about its centre `c`,
/// faces counter-clockwise from outside.
pub fn box_mesh(c: Vec3, h: Vec3, rot: glam::Quat, material: u32) -> Vec<Triangle> {
    let corner = |i: u32| {
        let s = Vec3::new(
            if i & 1 == 0 { -1.0 } else { 1.0 },
            if i & 2 == 0 { -1.0 } else { 1.0 },
            if i & 4 == 0 { -1.0 } else { 1.0 },
        );
        c + rot * (s * h)
    };
    // Each face as four corner indices around it.
    let faces = [
        [0, 1, 3, 2],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 3, 7, 5],
    ];
    let mut out = Vec::new();
    for f in faces {
        let [a, b, cc, d] = f.map(corner);
        for (x, y, z) in [(a, b, cc), (a, cc, d)] {
            let t = tri(x, y, z, material);
            out.push(if t.geometric_normal().dot((x + y + z) / 3.0 - c) < 0.0 {
                tri(x, z, y, material)
            } else {
                t
            });
        }
    }
    out
}

/// The radius of the largest ball inside `uv_sphere` (a bound: each face
/// lies within a spherical cap of half-angle pi/n_phi by pi/n_theta).
pub fn uv_sphere_inner_radius(r: f32, n_phi: u32, n_theta: u32) -> f32 {
    use std::f32::consts::PI;
    r * (PI / n_phi as f32).cos() * (PI / n_theta as f32).cos()
}

pub fn look_at(eye: Vec3, target: Vec3, up: Vec3, yfov_deg: f32) -> Camera {
    Camera {
        name: None,
        node_name: None,
        to_world: Mat4::look_at_rh(eye, target, up).inverse(),
        yfov: yfov_deg.to_radians(),
        aspect_ratio: None,
    }
}

pub fn scene(
    triangles: Vec<Triangle>,
    materials: Vec<Material>,
    lights: Vec<PunctualLight>,
    camera: Camera,
    background: Vec3,
) -> Scene {
    let mut s = Scene {
        triangles,
        shading: Vec::new(),
        materials,
        lights,
        cameras: vec![camera],
        background,
        ..Scene::default()
    };
    s.build_bvh();
    s
}

pub fn opts(size: u32, spp: u32, max_depth: i32, seed: u64) -> RenderOptions {
    RenderOptions {
        spp,
        max_depth,
        seed,
        ..RenderOptions::new(size, size)
    }
}

pub fn render(scene: &Scene, o: &RenderOptions) -> Film {
    glint_cpu::render(scene, o, &|_, _| {})
        .expect("valid options")
        .0
}

pub fn render_no_nee(scene: &Scene, o: &RenderOptions) -> Film {
    let o = RenderOptions {
        nee: false,
        ..o.clone()
    };
    glint_cpu::render(scene, &o, &|_, _| {})
        .expect("valid options")
        .0
}

/// A closed-ish diffuse room lit by a ceiling quad (front face down) and a
/// dim background through the open front; a diffuse sphere inside. Every
/// light path type appears: NEE on area and background, MIS on both.
pub fn lit_room(extra_materials: Vec<Material>) -> Scene {
    let mut mats = vec![
        diffuse("white", 0.7),
        diffuse("grey", 0.4),
        emitter("light", Vec3::new(4.0, 3.5, 3.0), false),
    ];
    let sphere_mat = if extra_materials.is_empty() {
        0
    } else {
        mats.len() as u32
    };
    mats.extend(extra_materials);
    let mut t = floor(-1.0, 1.0, 0);
    // Back wall (facing +Z) and left wall (facing +X).
    t.extend(quad(
        Vec3::new(-1.0, -1.0, -1.0),
        Vec3::new(1.0, -1.0, -1.0),
        Vec3::new(1.0, 1.0, -1.0),
        Vec3::new(-1.0, 1.0, -1.0),
        1,
    ));
    t.extend(quad(
        Vec3::new(-1.0, -1.0, 1.0),
        Vec3::new(-1.0, -1.0, -1.0),
        Vec3::new(-1.0, 1.0, -1.0),
        Vec3::new(-1.0, 1.0, 1.0),
        0,
    ));
    // Ceiling light facing down, a broad one so BSDF sampling finds it.
    t.extend(quad(
        Vec3::new(-0.5, 0.99, -0.5),
        Vec3::new(0.5, 0.99, -0.5),
        Vec3::new(0.5, 0.99, 0.5),
        Vec3::new(-0.5, 0.99, 0.5),
        2,
    ));
    t.extend(uv_sphere(
        Vec3::new(0.2, -0.55, -0.1),
        0.45,
        16,
        8,
        sphere_mat,
    ));
    scene(
        t,
        mats,
        vec![],
        look_at(
            Vec3::new(0.0, 0.0, 3.2),
            Vec3::new(0.0, -0.1, 0.0),
            Vec3::Y,
            45.0,
        ),
        Vec3::splat(0.3),
    )
}
