//! shaders/bvh.glsl through shaders/tests/bvh_test.comp against the CPU
//! traversal (glint_cpu::bvh) on the bunny, under the validation layer.
//!
//! Tolerance: the GLSL mirrors the Rust step by step, and `precise` keeps the
//! edge functions free of FMA, but Vulkan only requires division to 2.5 ulp,
//! and the shear constants, reciprocals and t are quotients. A one-ulp
//! difference in the shear moves the sheared vertices by an ulp, which can
//! flip a ray passing within rounding of an edge to the neighbouring triangle
//! (same t to a few ulps), or, at the silhouette, from a grazing hit to a
//! miss. Such rays are a tiny fraction of random rays (each needs the ray to
//! pass within ~1e-7 relative of an edge): at most 1 in 10^4 may differ, and
//! every other ray must report the same triangle with t within 1e-5
//! relative and the same occlusion.

mod common;
#[path = "../cpu/tests/support/geometry.rs"]
mod geometry;

use glam::Vec3;
use glint::cpu::{Bvh, Ray, Triangle};
use glint::gpu::groups;

use geometry::{Rng, bunny, grid_cube, random_rays};

struct GpuResult {
    /// (t, tri, u, v); tri = u32::MAX for a miss.
    hits: Vec<[u32; 4]>,
    occluded: Vec<u32>,
}

fn run_gpu(ctx: &glint::gpu::Context, bvh: &Bvh, tris: &[Triangle], rays: &[Ray]) -> GpuResult {
    let packed: Vec<[f32; 8]> = rays
        .iter()
        .map(|r| [r.o.x, r.o.y, r.o.z, r.tmax, r.d.x, r.d.y, r.d.z, 0.0])
        .collect();
    let mut hits = vec![[0u32; 4]; rays.len()];
    let mut occluded = vec![7u32; rays.len()];
    let push = [rays.len() as u32, bvh.nodes.len() as u32];
    ctx.run_kernel(
        "tests/bvh_test",
        &[
            bytemuck::cast_slice(&bvh.nodes),
            bytemuck::cast_slice(tris),
            bytemuck::cast_slice(&packed),
        ],
        &mut [
            bytemuck::cast_slice_mut(&mut hits),
            bytemuck::cast_slice_mut(&mut occluded),
        ],
        bytemuck::bytes_of(&push),
        [groups(rays.len() as u32, 64), 1, 1],
    )
    .expect("bvh_test kernel");
    GpuResult { hits, occluded }
}

#[test]
fn gpu_traversal_matches_cpu_on_bunny() {
    let ctx = common::context();
    let input = bunny();
    let (bvh, order) = Bvh::build(&input);
    let tris: Vec<Triangle> = order.iter().map(|&i| input[i as usize]).collect();
    let mut rng = Rng(0x5eed);
    let rays = random_rays(&tris, 100_000, &mut rng);
    let gpu = run_gpu(&ctx, &bvh, &tris, &rays);
    // Informative only: a second, warm run (pipeline compiled and cached),
    // upload and readback included; each ray is traced twice (closest, any).
    let start = std::time::Instant::now();
    let again = run_gpu(&ctx, &bvh, &tris, &rays);
    eprintln!(
        "bvh_test kernel on {}: {:.2} M(closest + any-hit) rays/s, warm, with transfers",
        ctx.info().name,
        rays.len() as f64 / start.elapsed().as_secs_f64() / 1e6
    );
    assert!(
        again.hits == gpu.hits && again.occluded == gpu.occluded,
        "not deterministic"
    );

    let (mut hits, mut edge_swaps, mut hit_miss, mut occl_diff) = (0, 0, 0, 0);
    for (i, ray) in rays.iter().enumerate() {
        let cpu = bvh.intersect(&tris, ray);
        let [t, tri, u, v] = gpu.hits[i];
        let (t, u, v) = (f32::from_bits(t), f32::from_bits(u), f32::from_bits(v));
        match cpu {
            Some(c) if tri == c.tri => {
                hits += 1;
                assert!(
                    (t - c.t).abs() <= 1e-5 * c.t,
                    "ray {i} {ray:?}: gpu t {t}, cpu {c:?}"
                );
                assert!(
                    (u - c.u).abs() <= 1e-4 && (v - c.v).abs() <= 1e-4,
                    "ray {i} {ray:?}: gpu (u, v) ({u}, {v}), cpu {c:?}"
                );
            }
            Some(c) if tri != u32::MAX => {
                // Another triangle: only legitimate at a shared edge, where
                // both triangles are hit at the same distance.
                assert!(
                    (t - c.t).abs() <= 1e-5 * c.t,
                    "ray {i} {ray:?}: gpu tri {tri} at {t}, cpu {c:?}"
                );
                edge_swaps += 1;
            }
            None if tri == u32::MAX => {}
            _ => hit_miss += 1,
        }
        let cpu_occluded = bvh.occluded(&tris, ray);
        assert!(gpu.occluded[i] <= 1, "ray {i}: occluded flag not written");
        if (gpu.occluded[i] == 1) != cpu_occluded {
            occl_diff += 1;
        }
    }
    eprintln!(
        "gpu vs cpu, {} rays: {hits} identical hits, {edge_swaps} edge swaps, \
         {hit_miss} hit/miss differences, {occl_diff} occlusion differences",
        rays.len()
    );
    assert!(hits > rays.len() / 3, "too few hits ({hits}) to prove much");
    let allowed = rays.len() / 10_000;
    assert!(
        edge_swaps + hit_miss <= allowed && occl_diff <= allowed,
        "more than {allowed} rays differ"
    );
    eprintln!("validation layer active: {}", ctx.validated());
    let messages = ctx.finish();
    assert!(messages.is_empty(), "validation: {messages:?}");
}

/// Watertightness on the GPU: from inside a closed grid cube, rays at every
/// grid vertex and edge midpoint, and axis-aligned rays along the grid lines
/// (zero direction components, origins on box faces), must all hit, at the
/// distance the CPU finds.
#[test]
fn gpu_closed_cube_does_not_leak() {
    let ctx = common::context();
    let n = 8;
    let (bvh, order) = Bvh::build(&grid_cube(n));
    let cube = grid_cube(n);
    let tris: Vec<Triangle> = order.iter().map(|&i| cube[i as usize]).collect();
    let coord = |i: usize| -1.0 + 2.0 * i as f32 / n as f32;
    let mut rays = Vec::new();
    let mut targets = Vec::new();
    for t in &tris {
        let v = t.vertices();
        for k in 0..3 {
            targets.push(v[k]);
            targets.push(0.5 * (v[k] + v[(k + 1) % 3]));
        }
    }
    for o in [
        Vec3::ZERO,
        Vec3::new(0.25, -0.5, 0.125),
        Vec3::new(-0.7, 0.3, 0.6),
    ] {
        for &p in &targets {
            rays.push(Ray {
                o,
                d: p - o,
                tmax: f32::INFINITY,
            });
        }
    }
    for axis in 0..3 {
        for i in 1..n {
            for j in 1..n {
                for sign in [-1.0f32, 1.0] {
                    let mut o = Vec3::ZERO;
                    o[axis] = 0.3;
                    o[(axis + 1) % 3] = coord(i);
                    o[(axis + 2) % 3] = coord(j);
                    let mut d = Vec3::ZERO;
                    d[axis] = sign;
                    rays.push(Ray {
                        o,
                        d,
                        tmax: f32::INFINITY,
                    });
                }
            }
        }
    }
    let gpu = run_gpu(&ctx, &bvh, &tris, &rays);
    let mut leaks = 0;
    for (i, ray) in rays.iter().enumerate() {
        let [t, tri, _, _] = gpu.hits[i];
        if tri == u32::MAX || gpu.occluded[i] != 1 {
            leaks += 1;
            continue;
        }
        let cpu = bvh
            .intersect(&tris, ray)
            .expect("the CPU tests prove it hits");
        let t = f32::from_bits(t);
        assert!(
            (t - cpu.t).abs() <= 1e-5 * cpu.t,
            "ray {ray:?}: gpu {t}, cpu {cpu:?}"
        );
    }
    assert_eq!(leaks, 0, "{leaks} of {} rays leaked", rays.len());
}

/// Axis-aligned rays whose origins lie exactly on the box's faces (zero
/// direction components), through a triangle's edges and vertices: the
/// slab test's zero-direction case, which random rays never reach.
#[test]
fn gpu_zero_direction_rays_on_box_faces() {
    let ctx = common::context();
    let tris = [Triangle {
        p0: [0.0, 0.0, 1.0],
        p1: [1.0, 0.0, 1.0],
        p2: [0.0, 1.0, 1.0],
        ..Default::default()
    }];
    let (bvh, _) = Bvh::build(&tris);
    let cases = [
        (Vec3::new(0.0, 0.25, 0.0), Vec3::Z, 1.0),
        (Vec3::new(0.25, 0.0, 0.0), Vec3::Z, 1.0),
        (Vec3::new(0.0, 0.0, 0.0), Vec3::Z, 1.0),
        (Vec3::new(0.0, 1.0, 2.0), -Vec3::Z, 1.0),
        (Vec3::new(1.0, 0.0, 3.0), -Vec3::Z, 2.0),
        (Vec3::new(0.5, 0.5, 0.0), Vec3::Z, 1.0),
    ];
    let rays: Vec<Ray> = cases
        .iter()
        .map(|&(o, d, _)| Ray {
            o,
            d,
            tmax: f32::INFINITY,
        })
        .collect();
    let gpu = run_gpu(&ctx, &bvh, &tris, &rays);
    for (i, &(_, _, t)) in cases.iter().enumerate() {
        assert_eq!(gpu.hits[i][1], 0, "ray {:?} missed", rays[i]);
        assert_eq!(f32::from_bits(gpu.hits[i][0]), t, "ray {:?}", rays[i]);
        assert_eq!(gpu.occluded[i], 1, "ray {:?}", rays[i]);
    }
}

#[test]
fn gpu_empty_scene_misses() {
    let ctx = common::context();
    let bvh = Bvh::default();
    let rays = [Ray {
        o: Vec3::ZERO,
        d: Vec3::X,
        tmax: f32::INFINITY,
    }; 70];
    let gpu = run_gpu(&ctx, &bvh, &[], &rays);
    assert!(gpu.hits.iter().all(|h| h[1] == u32::MAX));
    assert!(gpu.occluded.iter().all(|&o| o == 0));
}
