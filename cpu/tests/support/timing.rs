//! Interleaved timing for the traversal benchmarks
//! (`cpu/tests/bvh_throughput.rs`, `bench/embree`, through `#[path]`).
#![allow(dead_code)]

use std::time::Instant;

use glint_cpu::Ray;

/// A traversal under test: rays in, a checksum out.
pub type Variant<'a> = &'a dyn Fn(&[Ray]) -> usize;

/// Seconds each variant takes on all of `rays`, measured interleaved: the
/// rays are cut into chunks and every variant runs on a chunk before the next
/// chunk starts, so a change of load on the shared machine falls on all
/// variants alike; per chunk the best of three rounds counts. A variant maps
/// a chunk of rays to a checksum (kept, so nothing is optimised away).
pub fn interleaved(rays: &[Ray], chunk: usize, variants: &[Variant]) -> Vec<f64> {
    let mut total = vec![0.0; variants.len()];
    let mut sink = 0;
    for c in rays.chunks(chunk) {
        let mut best = vec![f64::INFINITY; variants.len()];
        for _ in 0..3 {
            for (v, f) in variants.iter().enumerate() {
                let start = Instant::now();
                sink += f(c);
                best[v] = best[v].min(start.elapsed().as_secs_f64());
            }
        }
        for (t, b) in total.iter_mut().zip(best) {
            *t += b;
        }
    }
    std::hint::black_box(sink);
    total
}
