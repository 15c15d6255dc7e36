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

use std::path::Path;

use glam::Vec3;
use glint::cpu::{Bvh, Ray, Triangle};
use glint::gpu::groups;

/// SplitMix64.
struct Rng(u64);

impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn f(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f()
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
    fn vec_in(&mut self, lo: Vec3, hi: Vec3) -> Vec3 {
        Vec3::new(
            self.range(lo.x, hi.x),
            self.range(lo.y, hi.y),
            self.range(lo.z, hi.z),
        )
    }
    fn unit(&mut self) -> Vec3 {
        let z = self.range(-1.0, 1.0);
        let phi = self.range(0.0, std::f32::consts::TAU);
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// The bunny's triangles, read straight from the GLB (positions and indices
/// of every primitive; the file has no node transforms). The root package does
/// not depend on the gltf crate, and this test must not depend on the loader.
fn bunny() -> Vec<Triangle> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/assets/bunny.glb");
    let path = if path.exists() {
        path
    } else {
        Path::new("/work/shared/assets/bunny.glb").to_path_buf()
    };
    let glb = std::fs::read(&path).expect("bunny.glb");
    let word = |at: usize| u32::from_le_bytes(glb[at..at + 4].try_into().unwrap()) as usize;
    assert_eq!(&glb[0..4], b"glTF");
    // Header (12 bytes), then the JSON chunk, then the BIN chunk.
    let json_len = word(12);
    let json: serde_json::Value = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    let bin_at = 20 + json_len;
    let bin = &glb[bin_at + 8..bin_at + 8 + word(bin_at)];
    let accessor = |i: &serde_json::Value| -> (usize, usize, u64) {
        let a = &json["accessors"][i.as_u64().unwrap() as usize];
        let view = &json["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
        assert!(
            view.get("byteStride").is_none(),
            "strided views not handled"
        );
        let offset =
            view["byteOffset"].as_u64().unwrap_or(0) + a["byteOffset"].as_u64().unwrap_or(0);
        (
            offset as usize,
            a["count"].as_u64().unwrap() as usize,
            a["componentType"].as_u64().unwrap(),
        )
    };
    let mut out = Vec::new();
    for node in json["nodes"].as_array().unwrap() {
        assert!(node.get("matrix").is_none() && node.get("translation").is_none());
        let Some(mesh) = node.get("mesh") else {
            continue;
        };
        for prim in json["meshes"][mesh.as_u64().unwrap() as usize]["primitives"]
            .as_array()
            .unwrap()
        {
            let (off, n, ty) = accessor(&prim["attributes"]["POSITION"]);
            assert_eq!(ty, 5126);
            let pos: Vec<[f32; 3]> = (0..n)
                .map(|k| {
                    let f = |c: usize| {
                        f32::from_le_bytes(bin[off + 12 * k + 4 * c..][..4].try_into().unwrap())
                    };
                    [f(0), f(1), f(2)]
                })
                .collect();
            let (off, n, ty) = accessor(&prim["indices"]);
            let idx: Vec<usize> = (0..n)
                .map(|k| match ty {
                    5125 => {
                        u32::from_le_bytes(bin[off + 4 * k..][..4].try_into().unwrap()) as usize
                    }
                    5123 => {
                        u16::from_le_bytes(bin[off + 2 * k..][..2].try_into().unwrap()) as usize
                    }
                    _ => bin[off + k] as usize,
                })
                .collect();
            for f in idx.chunks_exact(3) {
                out.push(Triangle {
                    p0: pos[f[0]],
                    p1: pos[f[1]],
                    p2: pos[f[2]],
                    ..Default::default()
                });
            }
        }
    }
    out
}

/// As the CPU differential test: origins in and around the bounds, most
/// aimed at a random point of a random triangle, some with zero direction
/// components or unnormalised, a quarter with a short tmax.
fn random_rays(tris: &[Triangle], count: usize, rng: &mut Rng) -> Vec<Ray> {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for p in tris.iter().flat_map(|t| t.vertices()) {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let size = hi - lo;
    (0..count)
        .map(|_| {
            let o = if rng.f() < 0.5 {
                rng.vec_in(lo, hi)
            } else {
                rng.vec_in(lo - size, hi + size)
            };
            let mut d = if rng.f() < 0.7 {
                let [a, b, c] = tris[rng.below(tris.len())].vertices();
                let (mut u, mut v) = (rng.f(), rng.f());
                if u + v > 1.0 {
                    (u, v) = (1.0 - u, 1.0 - v);
                }
                (a + u * (b - a) + v * (c - a)) - o
            } else {
                rng.unit()
            };
            let zeros = rng.f();
            if zeros < 0.1 {
                d[rng.below(3)] = 0.0;
            } else if zeros < 0.15 {
                let keep = rng.below(3);
                for k in 0..3 {
                    if k != keep {
                        d[k] = 0.0;
                    }
                }
            }
            if d == Vec3::ZERO || !d.is_finite() {
                d = Vec3::X;
            }
            d = if rng.f() < 0.3 {
                d * rng.range(0.1, 10.0)
            } else {
                d.normalize()
            };
            let tmax = if rng.below(4) == 0 {
                rng.range(0.0, 1.5) * (size.length() / d.length())
            } else {
                f32::INFINITY
            };
            Ray { o, d, tmax }
        })
        .collect()
}

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
