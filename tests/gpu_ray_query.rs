//! `--traversal hardware`, by both Vulkan APIs: shaders/ray_query.glsl (ray
//! queries) and shaders/rt/ (a ray tracing pipeline, src/gpu/rt_pipeline.rs),
//! against the acceleration structures of src/gpu/accel.rs, each against
//! the software traversal, under the validation layer.
//!
//! Per ray (`tests/ray_query_test` and `tests/rt_test` with its any-hit
//! shader `tests/rt_mask_test`, against `tests/bvh_test` and, with an
//! alpha test, `tests/bvh_mask_test`): the same triangle (or an exact
//! duplicate of it), each hit point within rounding of the triangle's plane
//! (not t within a relative bound: a grazing ray's t is ill-conditioned, and
//! on such rays both traversals' t stray 1e-4 from the exact one while their
//! points stay on the plane), the same occlusion. The
//! hardware's triangle test is the driver's, not glint's watertight one, so
//! a ray within rounding of a shared edge may report the neighbour at the
//! same distance, and a grazing ray may hit in one and miss in the other: at
//! most 1 in 10^4 rays may differ so. Images: the same seed traces the same
//! paths as the software kernel (the Cornell box) and as the CPU path
//! tracer (every bundled scene), and passes the statistical comparison with
//! the CPU backend. Degenerate scenes: empty, one triangle, 2^20 triangles
//! of an instanced mesh with a coincident instance. The per-ray and image
//! tests run over one bottom-level structure and over several
//! (`--blas-parts`).
//!
//! Each API is skipped (with a line on stderr) where the device lacks it.

mod common;
#[path = "../cpu/tests/support/geometry.rs"]
mod geometry;

use std::path::Path;

use glint::cpu::compare::compare_films;
use glint::cpu::{Bvh, Bvh4, Film, Ray, RenderOptions, Scene, Triangle};
use glint::gpu::accel::Accel;
use glint::gpu::render::{GpuSetup, KernelChoice, Traversal, render_with};
use glint::gpu::rt_pipeline::{PATH_TRACER_STAGES, RtStages};
use glint::gpu::{Buffer, BufferKind, Context, ContextDesc, GpuError, Kernel, KernelOptions};
use glint::gpu::{ValidationLog, groups};

use geometry::{Pcg32, asset_triangles, bunny, random_rays};

/// A hit point's distance from its triangle's plane over the size of the
/// coordinates ([`off_plane`]): 16 float32 ulps (lavapipe measured 1.9,
/// glint's watertight test 3.5, on 4 x 10^5 rays).
const ON_PLANE: f64 = 16.0 * f32::EPSILON as f64;

/// The hardware traversal's two APIs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Api {
    Query,
    Pipeline,
}

impl Api {
    /// The traversal that renders through this API.
    fn traversal(self) -> Traversal {
        match self {
            Api::Query => Traversal::RayQuery,
            Api::Pipeline => Traversal::Pipeline,
        }
    }
}

/// The image comparisons' render: 32x24, 16 spp in variance batches of 4.
fn small_options(seed: u64) -> RenderOptions {
    RenderOptions {
        spp: 16,
        seed,
        variance_batch: 4,
        ..RenderOptions::new(32, 24)
    }
}

/// A ray tracing context under validation and the APIs it has, or `None`
/// (skip) where the device has neither.
fn rt_context() -> Option<(Context, Option<std::sync::Arc<ValidationLog>>, Vec<Api>)> {
    let desc = ContextDesc {
        device: None,
        validation: common::validation(),
        loader: None,
    };
    match Context::new_ray_tracing(&desc) {
        Ok(ctx) => {
            let log = ctx.validation_log();
            let rt = ctx.ray_tracing();
            let mut apis = Vec::new();
            if rt.query {
                apis.push(Api::Query);
            } else {
                eprintln!("ray queries skipped: the device lacks them");
            }
            if rt.pipeline.is_some() {
                apis.push(Api::Pipeline);
            } else {
                eprintln!("the ray tracing pipeline skipped: the device lacks it");
            }
            Some((ctx, log, apis))
        }
        Err(e @ GpuError::NoRayQuery { .. }) => {
            eprintln!("skipped: {e}");
            None
        }
        Err(e) => panic!("cannot create a Vulkan context: {e}"),
    }
}

/// tests/rt_test.rgen's other stages: the path tracer's miss and closest-hit
/// shaders, the test's alpha test; one ray per launch item.
const RT_TEST_STAGES: RtStages = RtStages {
    any_hit: "tests/rt_mask_test",
    group_size: [64, 1],
    ..PATH_TRACER_STAGES
};

/// Drop the context and assert the layer said nothing.
fn finish(ctx: Context, log: Option<std::sync::Arc<ValidationLog>>) {
    drop(ctx);
    if let Some(log) = log {
        let m = log.messages();
        assert!(m.is_empty(), "validation: {m:?}");
    }
}

/// Every third triangle is alpha-tested (shaders/tests/mask_test.glsl).
fn test_masked(tri: u32) -> bool {
    tri.is_multiple_of(3)
}

/// (t, tri, u, v) per ray and the occlusion flags.
struct Traced {
    hits: Vec<[u32; 4]>,
    occluded: Vec<u32>,
}

fn pack(rays: &[Ray]) -> Vec<[f32; 8]> {
    rays.iter()
        .map(|r| [r.o.x, r.o.y, r.o.z, r.tmax, r.d.x, r.d.y, r.d.z, 0.0])
        .collect()
}

/// The hardware traversal of `rays` against `tris` by `api`, alpha-tested
/// or not, over one bottom-level structure.
fn run_hardware(ctx: &Context, tris: &[Triangle], rays: &[Ray], masked: bool, api: Api) -> Traced {
    run_hardware_parts(ctx, tris, rays, masked, api, 1)
}

/// [`run_hardware`] over `parts` bottom-level structures.
fn run_hardware_parts(
    ctx: &Context,
    tris: &[Triangle],
    rays: &[Ray],
    masked: bool,
    api: Api,
    parts: u32,
) -> Traced {
    let storage = |name: &str, bytes: &[u8]| {
        Buffer::from_slice(ctx, name, BufferKind::Storage, bytes).expect("buffer")
    };
    let tri_buf = storage("triangles", bytemuck::cast_slice(tris));
    let rule = |i: u32| masked && test_masked(i);
    let accel =
        Accel::build_parts(ctx, &tri_buf, tris.len() as u32, &rule, parts).expect("acceleration");
    let blas = if tris.is_empty() {
        0
    } else {
        parts.min(tris.len() as u32)
    };
    assert_eq!(accel.stats.blas_count, blas);
    let ray_buf = storage("rays", bytemuck::cast_slice(&pack(rays)));
    let hits = storage("hits", &vec![0u8; rays.len() * 16]);
    let occluded = storage("occluded", &vec![7u8; rays.len() * 4]);
    let (name, ray_tracing) = match api {
        Api::Query => ("tests/ray_query_test", None),
        Api::Pipeline => ("tests/rt_test", Some(RT_TEST_STAGES)),
    };
    let options = KernelOptions {
        acceleration_structure: accel.tlas(),
        ray_tracing,
        ..Default::default()
    };
    let kinds = [BufferKind::Storage; 5];
    let mut k = Kernel::with_options(ctx, name, &kinds, 12, &options).expect("hardware kernel");
    k.bind(&[&accel.tri_map, &tri_buf, &ray_buf, &hits, &occluded])
        .expect("bind");
    let push = [rays.len() as u32, masked as u32, 3];
    k.dispatch(
        bytemuck::bytes_of(&push),
        [groups(rays.len() as u32, 64), 1, 1],
    )
    .expect("dispatch");
    Traced {
        hits: hits.read().expect("read"),
        occluded: occluded.read().expect("read"),
    }
}

/// The software traversal (the 4-wide BVH, as renders use), with the test's
/// alpha test when `masked`.
fn run_software(
    ctx: &Context,
    wide: &Bvh4,
    tris: &[Triangle],
    rays: &[Ray],
    masked: bool,
) -> Traced {
    let mut hits = vec![[0u32; 4]; rays.len()];
    let mut occluded = vec![7u32; rays.len()];
    let kernel = if masked {
        "tests/bvh_mask_test"
    } else {
        "tests/bvh_test"
    };
    let push = [rays.len() as u32, wide.nodes.len() as u32, 3];
    ctx.run_kernel(
        kernel,
        &[
            bytemuck::cast_slice(&wide.nodes),
            bytemuck::cast_slice(tris),
            bytemuck::cast_slice(&pack(rays)),
        ],
        &mut [
            bytemuck::cast_slice_mut(&mut hits),
            bytemuck::cast_slice_mut(&mut occluded),
        ],
        bytemuck::bytes_of(&push),
        [groups(rays.len() as u32, 64), 1, 1],
    )
    .expect("bvh kernel");
    Traced { hits, occluded }
}

/// How far (in f64) the point at `t` along `ray` lies from the plane of
/// `tri`, over the size of the coordinates involved: a few float ulps
/// where a traversal rounds correctly. A grazing ray's t is ill-conditioned
/// (an error across the plane becomes 1 / cos larger along the ray), so the
/// test holds the point to the plane, not t to t.
fn off_plane(tri: &Triangle, ray: &Ray, t: f32) -> f64 {
    let [a, b, c] = tri.vertices().map(|v| v.as_dvec3());
    let n = (b - a).cross(c - a).normalize();
    let (o, d) = (ray.o.as_dvec3(), ray.d.as_dvec3());
    let p = o + d * t as f64;
    let size = [a, b, c, o, p]
        .iter()
        .map(|v| v.abs().max_element())
        .fold(f64::MIN_POSITIVE, f64::max);
    (p - a).dot(n).abs() / size
}

/// Hardware against software per ray, with the tolerance the module
/// comment explains; returns the rays that hit. Where both hit the same
/// triangle, each point is held to the triangle's plane ([`off_plane`]):
/// within [`ON_PLANE`]; the worst of each is printed.
fn compare(name: &str, tris: &[Triangle], rays: &[Ray], hw: &Traced, sw: &Traced) -> usize {
    let (mut hit, mut differ, mut occl) = (0, 0, 0);
    let (mut worst_hw, mut worst_sw) = (0f64, 0f64);
    for (i, ray) in rays.iter().enumerate().take(hw.hits.len()) {
        let (h, s) = (hw.hits[i], sw.hits[i]);
        let (th, ts) = (f32::from_bits(h[0]), f32::from_bits(s[0]));
        match (h[1], s[1]) {
            (u32::MAX, u32::MAX) => {}
            // One traversal hit, the other did not: a ray through a shared
            // edge, or a hit software rejects within its own t error bound.
            (u32::MAX, _) | (_, u32::MAX) => differ += 1,
            (a, b) if a == b || tris[a as usize].vertices() == tris[b as usize].vertices() => {
                let tri = &tris[b as usize];
                let (eh, es) = (off_plane(tri, ray, th), off_plane(tri, ray, ts));
                worst_hw = worst_hw.max(eh);
                worst_sw = worst_sw.max(es);
                assert!(
                    es <= ON_PLANE && eh <= ON_PLANE,
                    "{name} ray {i}: off the plane by {eh:.2e} (hardware {h:?}), {es:.2e} (software {s:?})"
                );
                hit += 1;
            }
            _ => differ += 1,
        }
        assert!(hw.occluded[i] <= 1, "{name} ray {i}: occlusion not written");
        if hw.occluded[i] != sw.occluded[i] {
            occl += 1;
        }
    }
    let n = hw.hits.len();
    eprintln!(
        "{name}: {n} rays, {hit} same hits, {differ} differ, {occl} occlusion differs; \
         worst distance from the plane over the coordinates' size: hardware {worst_hw:.2e}, \
         software {worst_sw:.2e}"
    );
    let allowed = n / 10_000;
    assert!(
        differ <= allowed && occl <= allowed,
        "{name}: more than {allowed} rays differ"
    );
    hit
}

/// 10^5 random rays against the bunny and the Cornell box, opaque and with
/// every third triangle alpha-tested, over one bottom-level structure and
/// over 7 (`--blas-parts`: each a cluster of the triangles, as a mesh is,
/// one TLAS instance each, found again through its custom index).
#[test]
fn hardware_traversal_matches_software_per_ray() {
    let Some((ctx, log, apis)) = rt_context() else {
        return;
    };
    let mut rng = Pcg32::from_state(0x0a5e);
    for (name, mesh) in [
        ("bunny", bunny()),
        ("cornell", asset_triangles("cornell.gltf")),
    ] {
        let (bin, order) = Bvh::build(&mesh);
        let tris: Vec<Triangle> = order.iter().map(|&i| mesh[i as usize]).collect();
        let wide = Bvh4::collapse(&bin, &tris);
        let rays = random_rays(&tris, 100_000, &mut rng);
        for masked in [false, true] {
            let sw = run_software(&ctx, &wide, &tris, &rays, masked);
            for (&api, parts) in apis.iter().flat_map(|a| [(a, 1), (a, 7)]) {
                let hw = run_hardware_parts(&ctx, &tris, &rays, masked, api, parts);
                let what = format!(
                    "{name}{} ({api:?}, {parts} BLAS)",
                    if masked { " alpha-tested" } else { "" }
                );
                let hit = compare(&what, &tris, &rays, &hw, &sw);
                assert!(hit > rays.len() / 10, "{what}: too few hits ({hit})");
            }
        }
    }
    finish(ctx, log);
}

/// 2^20 triangles: the bunny instanced 16 times (the loader flattens a
/// mesh that several nodes place, so an instance is a transformed copy),
/// rotated, scaled and moved, one instance exactly on top of another (every
/// hit there a tie between two identical triangles), cut at 2^20; 2 x 10^4
/// rays, opaque and alpha-tested, against the software traversal.
#[test]
fn hardware_traversal_on_2_20_instanced_triangles() {
    let Some((ctx, log, apis)) = rt_context() else {
        return;
    };
    let mesh = bunny();
    let mut all = Vec::with_capacity(1 << 20);
    for k in 0..16 {
        // Instance 5 repeats instance 4's transform exactly.
        let j = if k == 5 { 4 } else { k };
        let m = glam::Mat4::from_scale_rotation_translation(
            glam::Vec3::splat(1.0 + 0.1 * (j % 3) as f32),
            glam::Quat::from_rotation_y(0.4 * j as f32),
            glam::Vec3::new((j % 4) as f32 * 0.15, 0.0, (j / 4) as f32 * 0.15),
        );
        for t in &mesh {
            let [a, b, c] = t.vertices().map(|v| m.transform_point3(v));
            all.push(Triangle {
                p0: a.into(),
                p1: b.into(),
                p2: c.into(),
                ..*t
            });
        }
    }
    all.truncate(1 << 20);
    let (bin, order) = Bvh::build(&all);
    let tris: Vec<Triangle> = order.iter().map(|&i| all[i as usize]).collect();
    let wide = Bvh4::collapse(&bin, &tris);
    let rays = random_rays(&tris, 20_000, &mut Pcg32::from_state(0x1_0000));
    for masked in [false, true] {
        let sw = run_software(&ctx, &wide, &tris, &rays, masked);
        for &api in &apis {
            let hw = run_hardware(&ctx, &tris, &rays, masked, api);
            let what = format!(
                "2^20 instanced{} ({api:?})",
                if masked { " alpha-tested" } else { "" }
            );
            let hit = compare(&what, &tris, &rays, &hw, &sw);
            assert!(hit > rays.len() / 10, "{what}: too few hits ({hit})");
        }
    }
    finish(ctx, log);
}

/// An empty scene misses everything; one triangle is hit where it is.
#[test]
fn hardware_traversal_degenerate_scenes() {
    let Some((ctx, log, apis)) = rt_context() else {
        return;
    };
    for &api in &apis {
        degenerate_scenes(&ctx, api);
    }
    finish(ctx, log);
}

fn degenerate_scenes(ctx: &Context, api: Api) {
    let ray = |o: [f32; 3], d: [f32; 3]| Ray {
        o: o.into(),
        d: d.into(),
        tmax: f32::INFINITY,
    };
    let rays = vec![ray([0.2, 0.2, 0.0], [0.0, 0.0, 1.0]); 70];
    let empty = run_hardware(ctx, &[], &rays, false, api);
    assert!(empty.hits.iter().all(|h| h[1] == u32::MAX));
    assert!(empty.occluded.iter().all(|&o| o == 0));
    let one = [Triangle {
        p0: [0.0, 0.0, 1.0],
        p1: [1.0, 0.0, 1.0],
        p2: [0.0, 1.0, 1.0],
        ..Default::default()
    }];
    let rays = [
        ray([0.2, 0.3, 0.0], [0.0, 0.0, 1.0]),
        ray([0.2, 0.3, 3.0], [0.0, 0.0, -1.0]),
        ray([0.8, 0.8, 0.0], [0.0, 0.0, 1.0]),
        Ray {
            tmax: 0.5,
            ..ray([0.2, 0.3, 0.0], [0.0, 0.0, 1.0])
        },
    ];
    let r = run_hardware(ctx, &one, &rays, false, api);
    let t: Vec<f32> = r.hits.iter().map(|h| f32::from_bits(h[0])).collect();
    assert_eq!([r.hits[0][1], r.hits[1][1]], [0, 0]);
    assert!(
        (t[0] - 1.0).abs() < 1e-6 && (t[1] - 2.0).abs() < 1e-6,
        "{t:?}"
    );
    let (u, v) = (f32::from_bits(r.hits[0][2]), f32::from_bits(r.hits[0][3]));
    assert!(
        (u - 0.2).abs() < 1e-5 && (v - 0.3).abs() < 1e-5,
        "({u}, {v})"
    );
    assert_eq!(
        [r.hits[2][1], r.hits[3][1]],
        [u32::MAX, u32::MAX],
        "{api:?}"
    );
    assert_eq!(r.occluded, [1, 1, 0, 0], "{api:?}");
}

fn load(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(name);
    glint::cpu::prepare::prepare_default(&path).unwrap()
}

/// The kernel specialised to the scene, as renders use by default: the
/// software one is compiled (and cached on disk by Mesa) by other tests
/// too, where the generic kernels cost minutes of cold LLVM compilation.
fn gpu_film(ctx: &Context, scene: &Scene, opts: &RenderOptions, t: Traversal) -> Film {
    gpu_film_parts(ctx, scene, opts, t, 1)
}

/// [`gpu_film`] with the scene split into `blas_parts` bottom-level
/// structures (hardware traversal).
fn gpu_film_parts(
    ctx: &Context,
    scene: &Scene,
    opts: &RenderOptions,
    traversal: Traversal,
    blas_parts: u32,
) -> Film {
    let setup = GpuSetup {
        kernel: KernelChoice::Specialized,
        traversal,
        blas_parts,
    };
    let cache = ash::vk::PipelineCache::null();
    render_with(ctx, scene, opts, setup, cache, &|_, _| {})
        .unwrap()
        .film
}

/// The Cornell box: the hardware traversal, by each API, over one
/// bottom-level structure and over 5, traces the software kernel's paths
/// with the same seed (768 of 768 pixels, 2026-12-02 and, for the pipeline
/// and the split, 2026-12-05), and agrees statistically with the CPU
/// backend.
///
/// Then `glint bench --compare-traversals` on it (after the images, so the
/// kernels it needs are in Mesa's disk cache, not compiled twice at once).
#[test]
fn hardware_traversal_images() {
    images(&["cornell.gltf"]);
    if let Some((_, _, apis)) = rt_context() {
        bench_compares_traversals(&apis);
        render_reports_the_api(&apis);
    }
}

/// `glint render --traversal hardware` with each `--ray-tracing` the device
/// has (and `auto`) names the API it traced with in `--stats`.
fn render_reports_the_api(apis: &[Api]) {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell.gltf");
    let dir = std::env::temp_dir().join(format!("glint-rt-stats-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let auto = if apis.contains(&Api::Query) {
        "query"
    } else {
        "pipeline"
    };
    let mut runs = vec![("auto", auto)];
    runs.extend(apis.iter().map(|a| match a {
        Api::Query => ("query", "query"),
        Api::Pipeline => ("pipeline", "pipeline"),
    }));
    for (arg, want) in runs {
        let stats = dir.join(format!("{arg}.json"));
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_glint"))
            .args(["render", "--backend", "gpu", "--traversal", "hardware"])
            .args(["--ray-tracing", arg, "--blas-parts", "3", "--width", "32"])
            .args(["--spp", "2", "--quiet", "-o"])
            .arg(dir.join(format!("{arg}.png")))
            .arg("--stats")
            .arg(&stats)
            .arg(&scene)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let doc: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
        assert_eq!(doc["traversal"], "hardware", "{doc}");
        assert_eq!(doc["ray_tracing"], want, "--ray-tracing {arg}: {doc}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `glint bench --compare-traversals`: the GPU with the software traversal
/// and the hardware one by each API the device has, and the CPU, one row
/// each, and the hardware/software ratios, in the table and the JSON.
fn bench_compares_traversals(apis: &[Api]) {
    let json = std::env::temp_dir().join(format!("glint-bench-rq-{}.json", std::process::id()));
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell.gltf");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_glint"))
        .args([
            "bench",
            "--width",
            "32",
            "--spp",
            "2",
            "--compare-traversals",
            "--json",
        ])
        .arg(&json)
        .arg(&scene)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let _ = std::fs::remove_file(&json);
    let rows = doc["backends"].as_array().unwrap();
    let names: Vec<(&str, Option<&str>, Option<&str>)> = rows
        .iter()
        .map(|r| {
            (
                r["backend"].as_str().unwrap(),
                r["traversal"].as_str(),
                r["ray_tracing"].as_str(),
            )
        })
        .collect();
    let mut want = vec![("gpu", Some("software"), None)];
    for api in apis {
        let a = match api {
            Api::Query => "query",
            Api::Pipeline => "pipeline",
        };
        want.push(("gpu", Some("hardware"), Some(a)));
        let x = doc["hardware_over_software_samples_per_second"][a]
            .as_f64()
            .unwrap();
        assert!(x > 0.0 && x.is_finite(), "{doc}");
        assert!(
            stdout.contains(&format!(
                "gpu hardware ({a})/software traversal samples/s ratio: "
            )),
            "{stdout}"
        );
    }
    want.push(("cpu", None, None));
    assert_eq!(names, want, "{doc}");
}

/// Every bundled scene through the hardware traversal by each API, with
/// the generic kernels (one cold compile each serves all nine scenes: 96 s
/// for the pipeline, 224 s for the ray-query kernel here, where the
/// specialised ones would compile per feature set, 7.8 min for the
/// textured scene's ray-query kernel alone): it traces the CPU path
/// tracer's paths with the same seed (as tests/pathtrace_kernel.rs holds
/// the compute kernel to: sums and batch sums within 1e-3 relative in 98%
/// of the pixels, ray counts within 1%) and agrees with the CPU
/// statistically. The textured scene runs the alpha test (the pipeline's
/// any-hit shader, the ray-query loop) and texture reads.
#[test]
fn hardware_traversal_traces_the_cpu_paths_in_every_bundled_scene() {
    let Some((ctx, log, apis)) = rt_context() else {
        return;
    };
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets");
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".gltf") || n.ends_with(".glb"))
        .collect();
    names.sort();
    assert!(names.len() >= 9, "{names:?}");
    let runs = apis.iter().flat_map(|&a| names.iter().map(move |n| (a, n)));
    for (api, name) in runs {
        let scene = load(name);
        let opts = small_options(11);
        let traversal = api.traversal();
        let kernel = (KernelChoice::Generic, traversal);
        let cache = ash::vk::PipelineCache::null();
        let r = render_with(&ctx, &scene, &opts, kernel, cache, &|_, _| {}).unwrap();
        assert_eq!(r.traversal, traversal);
        let name = format!("{name} ({api:?})");
        let (gpu, gpu_rays) = (r.film, r.stats.rays);
        let (cpu, cpu_stats) = glint::cpu::render(&scene, &opts, &|_, _| {}).unwrap();
        let near = |a: glam::Vec3, b: glam::Vec3| {
            (a - b).abs().max_element() <= 1e-3 * a.abs().max(b.abs()).max_element().max(1e-3)
        };
        let close = (0..cpu.sum.len())
            .filter(|&i| near(gpu.sum[i], cpu.sum[i]) && near(gpu.batch_sq[i], cpu.batch_sq[i]))
            .count();
        let rel = (gpu_rays as f64 - cpu_stats.rays as f64).abs() / cpu_stats.rays as f64;
        let c = compare_films(&gpu, &cpu).unwrap();
        eprintln!(
            "{name}: {close} of {} pixels as the CPU's, rays {gpu_rays} vs {}; {c}",
            cpu.sum.len(),
            cpu_stats.rays
        );
        assert!(
            close as f64 >= 0.98 * cpu.sum.len() as f64,
            "{name}: only {close} of {} pixels trace the CPU's paths",
            cpu.sum.len()
        );
        assert!(rel < 0.01, "{name}: rays {gpu_rays} vs {}", cpu_stats.rays);
        assert!(c.pass, "{name} against the CPU: {c}");
    }
    finish(ctx, log);
}

fn images(names: &[&str]) {
    let Some((ctx, log, apis)) = rt_context() else {
        return;
    };
    let runs = names
        .iter()
        .flat_map(|n| apis.iter().flat_map(move |a| [(n, a, 1), (n, a, 5)]));
    for (&name, &api, parts) in runs {
        let scene = load(name);
        let opts = small_options(3);
        let traversal = api.traversal();
        let hw = gpu_film_parts(&ctx, &scene, &opts, traversal, parts);
        let sw = gpu_film(&ctx, &scene, &opts, Traversal::Software);
        let near = |a: glam::Vec3, b: glam::Vec3| {
            (a - b).abs().max_element() <= 1e-3 * a.abs().max(b.abs()).max_element().max(1e-3)
        };
        let same = (0..hw.sum.len())
            .filter(|&i| near(hw.sum[i], sw.sum[i]))
            .count();
        assert!(
            same as f64 >= 0.98 * hw.sum.len() as f64,
            "{name} ({api:?}, {parts} BLAS): only {same} of {} pixels trace the software kernel's paths",
            hw.sum.len()
        );
        let (cpu, _) = glint::cpu::render(&scene, &opts, &|_, _| {}).unwrap();
        let r = compare_films(&hw, &cpu).unwrap();
        assert!(
            r.pass,
            "{name} ({api:?}, {parts} BLAS) against the CPU: {r}"
        );
        eprintln!(
            "{name} ({api:?}, {parts} BLAS): {same} of {} pixels as software; {r}",
            hw.sum.len()
        );
    }
    finish(ctx, log);
}
