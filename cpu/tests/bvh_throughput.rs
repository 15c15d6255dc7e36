//! Traversal throughput on the bunny, one thread and rayon, printed with
//! `--nocapture` (release figures: `cargo test --release -p glint-cpu --test
//! bvh_throughput -- --nocapture`). The check: both runs give identical hits,
//! so closest-hit results do not depend on threading.

#[path = "support/geometry.rs"]
mod geometry;

use std::time::Instant;

use glam::Vec3;
use glint_cpu::{Bvh, Hit, Ray, Triangle};
use rayon::prelude::*;

use geometry::bunny;

/// A pinhole camera framing the bounds from +z: the rays a render's first
/// bounce traces.
fn primary_rays(lo: Vec3, hi: Vec3, w: usize, h: usize) -> Vec<Ray> {
    let c = 0.5 * (lo + hi);
    let r = 0.5 * (hi - lo).length();
    let eye = c + Vec3::new(0.3, 0.2, 1.0).normalize() * 2.5 * r;
    let fwd = (c - eye).normalize();
    let right = fwd.cross(Vec3::Y).normalize();
    let up = right.cross(fwd);
    let tan = (0.5f32 * 40f32.to_radians()).tan();
    (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
            let sx = (2.0 * x / w as f32 - 1.0) * tan;
            let sy = (1.0 - 2.0 * y / h as f32) * tan;
            Ray {
                o: eye,
                d: (fwd + sx * right + sy * up).normalize(),
                tmax: f32::INFINITY,
            }
        })
        .collect()
}

#[test]
fn bunny_closest_hit_throughput() {
    let input = bunny();
    let start = Instant::now();
    let (bvh, order) = Bvh::build(&input);
    let build_s = start.elapsed().as_secs_f64();
    let tris: Vec<Triangle> = order.iter().map(|&i| input[i as usize]).collect();
    let (lo, hi) = tris.iter().flat_map(|t| t.vertices()).fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    );
    let rays = primary_rays(lo, hi, 384, 384);

    // Best of three runs: the shortest time is the least disturbed by other
    // processes on a shared machine.
    fn best_of_3<T>(mut f: impl FnMut() -> T) -> (T, f64) {
        let mut best = f64::INFINITY;
        let mut out = None;
        for _ in 0..3 {
            let start = Instant::now();
            out = Some(f());
            best = best.min(start.elapsed().as_secs_f64());
        }
        (out.unwrap(), best)
    }
    let (single, single_s) = best_of_3(|| {
        rays.iter()
            .map(|r| bvh.intersect(&tris, r))
            .collect::<Vec<Option<Hit>>>()
    });
    let (parallel, parallel_s) = best_of_3(|| {
        rays.par_iter()
            .map(|r| bvh.intersect(&tris, r))
            .collect::<Vec<Option<Hit>>>()
    });
    let (shadow_single, any_single_s) =
        best_of_3(|| rays.iter().filter(|r| bvh.occluded(&tris, r)).count());
    let (shadow, any_parallel_s) =
        best_of_3(|| rays.par_iter().filter(|r| bvh.occluded(&tris, r)).count());

    let hits = single.iter().flatten().count();
    let mrays = |s: f64| rays.len() as f64 / s / 1e6;
    eprintln!(
        "bunny: {} tris, build {:.1} ms, {} nodes, depth {}; {} primary rays, {} hit; \
         closest {:.2} Mrays/s (1 thread), {:.2} ({} rayon threads); \
         any-hit {:.2} Mrays/s (1 thread), {:.2} (rayon)",
        input.len(),
        build_s * 1e3,
        bvh.nodes.len(),
        bvh.depth(),
        rays.len(),
        hits,
        mrays(single_s),
        mrays(parallel_s),
        rayon::current_num_threads(),
        mrays(any_single_s),
        mrays(any_parallel_s),
    );
    assert_eq!(shadow_single, shadow);
    assert_eq!(single, parallel);
    assert_eq!(shadow, hits);
    // The camera frames the bunny: a good share of the image is bunny.
    assert!(hits > rays.len() / 10, "{hits} hits");
}
