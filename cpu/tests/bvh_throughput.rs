//! Traversal throughput, binary vs 4-wide BVH, printed with `--nocapture`
//! (release figures: `cargo test --release -p glint-cpu --test
//! bvh_throughput -- --ignored --nocapture --test-threads 1`; a benchmark the
//! suite skips). Meshes: the bunny, the
//! bundled Cornell box, and `../shared/assets/nefertiti.glb` where that file
//! exists. Rays: coherent primary rays from a pinhole camera, and incoherent
//! diffuse bounces (cosine-distributed about the normal at each primary hit,
//! origin offset off the surface). Queries: closest hit and any hit, one
//! thread and rayon.
//!
//! Speeds are printed, never asserted (the machine is shared); what is
//! asserted: every traversal gives the binary BVH's hits, and one thread and
//! rayon give identical results.

#[path = "support/binary.rs"]
mod binary;
#[path = "support/geometry.rs"]
mod geometry;
#[path = "support/timing.rs"]
mod timing;
use binary::BinaryTraversal;
use timing::{Variant, interleaved};

use std::time::Instant;

use glint_cpu::bvh::Kernel;
use glint_cpu::{Bvh, Bvh4, Hit, Ray, Triangle};
use rayon::prelude::*;

use geometry::{Pcg32, asset_triangles, bunny, diffuse_rays, primary_rays, shared_asset_triangles};

fn measure(name: &str, input: &[Triangle]) {
    // The build on one thread and on rayon's (best of three each): the
    // large subtrees' halves are built side by side.
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let best_of_3 = |build: &dyn Fn() -> (Bvh, Vec<u32>)| {
        (0..3)
            .map(|_| {
                let start = Instant::now();
                drop(build());
                start.elapsed().as_secs_f64()
            })
            .fold(f64::INFINITY, f64::min)
    };
    let build_one_s = best_of_3(&|| one.install(|| Bvh::build(input)));
    let build_s = best_of_3(&|| Bvh::build(input));
    let (bvh, order) = Bvh::build(input);
    let tris: Vec<Triangle> = order.iter().map(|&i| input[i as usize]).collect();
    let start = Instant::now();
    let wide = Bvh4::collapse(&bvh, &tris);
    let collapse_s = start.elapsed().as_secs_f64();
    let (lo, hi) = geometry::bounds_of(&tris);
    let primary = primary_rays(lo, hi, 384, 384);
    let primary_hits: Vec<Option<Hit>> = primary.iter().map(|r| bvh.intersect(&tris, r)).collect();
    let diffuse = diffuse_rays(&tris, &primary, &primary_hits, &mut Pcg32::from_state(9));
    eprintln!(
        "{name}: {} tris; binary: build {:.1} ms on one thread, {:.1} ms on {}, {} nodes, \
         depth {}; wide: collapse {:.1} ms, {} nodes, depth {}; {} primary rays, {} diffuse",
        input.len(),
        build_one_s * 1e3,
        build_s * 1e3,
        rayon::current_num_threads(),
        bvh.nodes.len(),
        bvh.depth(),
        collapse_s * 1e3,
        wide.nodes.len(),
        wide.depth(),
        primary.len(),
        diffuse.len(),
    );
    let mrays = |n: usize, s: f64| n as f64 / s / 1e6;
    let kernels = Kernel::available();
    for (set, rays) in [("primary", &primary), ("diffuse", &diffuse)] {
        // Correctness first, untimed: every traversal gives the binary's
        // closest distance (exact ties may pick another triangle) and
        // occlusion, on one thread and on rayon.
        let want: Vec<Option<Hit>> = rays.iter().map(|r| bvh.intersect(&tris, r)).collect();
        let want_occ: Vec<bool> = rays.iter().map(|r| bvh.occluded(&tris, r)).collect();
        let par: Vec<Option<Hit>> = rays.par_iter().map(|r| wide.intersect(&tris, r)).collect();
        let par_occ: Vec<bool> = rays.par_iter().map(|r| wide.occluded(&tris, r)).collect();
        assert_eq!(par_occ, want_occ, "{name} {set}: rayon any-hit");
        assert!(
            par.iter()
                .zip(&want)
                .all(|(g, w)| g.map(|h| h.t) == w.map(|h| h.t))
        );
        for &k in &kernels {
            for (i, r) in rays.iter().enumerate() {
                let g = wide.intersect_with(k, &tris, r);
                assert_eq!(
                    g.map(|h| h.t),
                    want[i].map(|h| h.t),
                    "{name} {set} {k:?} {r:?}"
                );
                assert_eq!(
                    wide.occluded_with(k, &tris, r),
                    want_occ[i],
                    "{name} {set} {k:?}"
                );
            }
        }
        let hits = want.iter().flatten().count();

        for any in [false, true] {
            let query = if any { "any-hit" } else { "closest" };
            let bin = |c: &[Ray]| -> usize {
                if any {
                    c.iter().filter(|r| bvh.occluded(&tris, r)).count()
                } else {
                    c.iter().filter_map(|r| bvh.intersect(&tris, r)).count()
                }
            };
            let wide_k = |k: Kernel| {
                let wide = &wide;
                let tris = &tris;
                move |c: &[Ray]| -> usize {
                    if any {
                        c.iter().filter(|r| wide.occluded_with(k, tris, r)).count()
                    } else {
                        c.iter()
                            .filter_map(|r| wide.intersect_with(k, tris, r))
                            .count()
                    }
                }
            };
            let wides: Vec<_> = kernels.iter().map(|&k| wide_k(k)).collect();
            let mut variants: Vec<Variant> = vec![&bin];
            variants.extend(wides.iter().map(|f| f as Variant));
            let single = interleaved(rays, 4096, &variants);
            let bin_par = |c: &[Ray]| -> usize {
                if any {
                    c.par_iter().filter(|r| bvh.occluded(&tris, r)).count()
                } else {
                    c.par_iter().filter_map(|r| bvh.intersect(&tris, r)).count()
                }
            };
            let wide_par = |c: &[Ray]| -> usize {
                if any {
                    c.par_iter().filter(|r| wide.occluded(&tris, r)).count()
                } else {
                    c.par_iter()
                        .filter_map(|r| wide.intersect(&tris, r))
                        .count()
                }
            };
            let par = interleaved(rays, 16384, &[&bin_par, &wide_par]);
            let mut line = format!(
                "  {set:7} {query} ({hits} hit): binary {:.2} Mrays/s",
                mrays(rays.len(), single[0])
            );
            for (k, s) in kernels.iter().zip(&single[1..]) {
                line += &format!(
                    ", wide {k:?} {:.2} (x{:.2})",
                    mrays(rays.len(), *s),
                    single[0] / s
                );
            }
            line += &format!(
                "; rayon: binary {:.2}, wide {:?} {:.2} (x{:.2})",
                mrays(rays.len(), par[0]),
                Kernel::best(),
                mrays(rays.len(), par[1]),
                par[0] / par[1]
            );
            eprintln!("{line}");
        }
    }
}

#[test]
#[ignore = "benchmark: cargo test --release -p glint-cpu --test bvh_throughput -- --ignored --nocapture"]
fn traversal_throughput_binary_vs_wide() {
    eprintln!(
        "rayon threads: {}; wide kernels: {:?}",
        rayon::current_num_threads(),
        Kernel::available()
    );
    measure("bunny", &bunny());
    measure("cornell", &asset_triangles("cornell.gltf"));
    if let Some(mesh) = shared_asset_triangles("nefertiti.glb") {
        measure("nefertiti", &mesh);
    }
}
