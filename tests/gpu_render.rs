//! The renderer's host side with a stand-in kernel that follows the path
//! tracer's binding table (shaders/tests/render_plumbing.comp), so the film
//! is known exactly: bindings, uploads, batching, accumulation, readback.

mod common;

use glint::gpu::render::{SceneBytes, render_film};

fn f32s(v: &[f32]) -> &[u8] {
    bytemuck::cast_slice(v)
}

#[test]
fn film_accumulates_every_sample_once_across_batches() {
    plumbing(common::context());
}

#[test]
fn film_through_staging_buffers() {
    plumbing(common::staging_context());
}

fn plumbing(ctx: common::ValidatedContext) {
    // Not multiples of the 8x8 workgroup: exercises the bounds check.
    let (w, h, spp) = (13u32, 7u32, 37u32);
    let mut params = vec![0u32; 36];
    params[20] = w;
    params[21] = h;
    params[22] = spp;
    let tri = [0.5f32, 0.0, 0.0, 0.0];
    let node = [0.0f32, 0.25, 0.0, 0.0];
    let shading = [0.0f32, 0.0, 0.125, 0.0];
    let material = [0.0f32, 0.0, 0.0, 1.0];
    let emitter = [2.0f32, 0.0, 0.0, 0.0];
    let light = [0.0f32, 3.0, 0.0, 0.0];
    let scene = SceneBytes {
        params: bytemuck::cast_slice(&params),
        triangles: f32s(&tri),
        bvh_nodes: f32s(&node),
        shading: f32s(&shading),
        materials: f32s(&material),
        emitters: f32s(&emitter),
        lights: f32s(&light),
        texels: &[],
        textures: &[],
        material_textures: &[],
        uvs: &[],
        env_texels: &[],
        env_dist: &[],
        variance_batch: 1,
    };
    let calls = std::cell::RefCell::new(Vec::new());
    let r = render_film(&ctx, "tests/render_plumbing", &scene, w, h, spp, &|d, t| {
        calls.borrow_mut().push((d, t))
    })
    .unwrap();
    assert_eq!(r.batches.iter().sum::<u32>(), spp);
    let calls = calls.into_inner();
    assert_eq!(calls.len(), r.batches.len());
    assert_eq!(calls.last(), Some(&(spp, spp)));
    assert!(calls.windows(2).all(|p| p[0].0 < p[1].0));

    assert_eq!((r.film.width, r.film.height, r.film.spp), (w, h, spp));
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            let base = [x as f64 + 0.75, y as f64 + 1.125, 5.0];
            let mut sum = [0.0f64; 3];
            let mut sq = [0.0f64; 3];
            // The stand-in's variance batches of 4: 9 whole, 1 sample left.
            let mut run = [0.0f64; 3];
            let mut bsq = [0.0f64; 3];
            for s in 0..spp {
                for c in 0..3 {
                    let v = base[c] + if c == 2 { s as f64 } else { 0.0 };
                    sum[c] += v;
                    sq[c] += v * v;
                    run[c] += v;
                    if (s + 1) % 4 == 0 {
                        bsq[c] += run[c] * run[c];
                        run[c] = 0.0;
                    }
                }
            }
            let got = r.film.sum[i].to_array();
            let got_sq = r.film.sum_sq[i].to_array();
            let (got_run, got_bsq) = (
                r.film.batch_run[i].to_array(),
                r.film.batch_sq[i].to_array(),
            );
            for c in 0..3 {
                assert!(
                    (got_run[c] as f64 - run[c]).abs() <= 1e-5 * run[c].abs().max(1.0)
                        && (got_bsq[c] as f64 - bsq[c]).abs() <= 1e-5 * bsq[c].abs().max(1.0),
                    "pixel {x},{y} batch sums {got_run:?} {got_bsq:?} vs {run:?} {bsq:?}"
                );
                assert!(
                    (got[c] as f64 - sum[c]).abs() <= 1e-5 * sum[c].abs().max(1.0),
                    "pixel {x},{y} sum {got:?} vs {sum:?}"
                );
                assert!(
                    (got_sq[c] as f64 - sq[c]).abs() <= 1e-5 * sq[c].abs().max(1.0),
                    "pixel {x},{y} sum_sq {got_sq:?} vs {sq:?}"
                );
            }
        }
    }
    assert_eq!(r.stats.rays, 3 * spp as u64 * (w * h) as u64);
    assert!(r.stats.render_seconds > 0.0 && r.stats.render_seconds.is_finite());
}

#[test]
fn empty_scene_arrays_and_tiny_images_render() {
    let ctx = common::context();
    let mut params = vec![0u32; 36];
    params[20] = 1;
    params[21] = 1;
    let scene = SceneBytes {
        params: bytemuck::cast_slice(&params),
        triangles: &[],
        bvh_nodes: &[],
        shading: &[],
        materials: &[],
        emitters: &[],
        lights: &[],
        texels: &[],
        textures: &[],
        material_textures: &[],
        uvs: &[],
        env_texels: &[],
        env_dist: &[],
        variance_batch: 1,
    };
    let r = render_film(&ctx, "tests/render_plumbing", &scene, 1, 1, 1, &|_, _| {}).unwrap();
    assert_eq!(r.film.sum.len(), 1);
    // Empty arrays read as zeros: the pixel saw only its coordinates (0, 0).
    assert_eq!(r.film.sum[0].to_array(), [0.0, 0.0, 0.0]);
    assert_eq!(r.stats.rays, 3);
    assert!(render_film(&ctx, "tests/render_plumbing", &scene, 0, 4, 1, &|_, _| {}).is_err());
}
