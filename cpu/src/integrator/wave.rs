//! The wave: the eight samples of a pixel's [`SampleBatch`] traced side
//! by side, bounce by bounce, so that each step of a bounce runs for
//! every live path before the next step starts. Each path takes the
//! steps [`PathTracer::trace`] takes with the same numbers, so a wave
//! gives every path's radiance bit for bit as one path at a time does
//! (`cpu/tests/lanes.rs`).

use glam::Vec3;

use super::{Arrival, PathState, PathTracer};
use crate::sobol::SampleBatch;

/// The lanes of `live` (bit k: lane k), lowest first.
fn lanes_of(live: u8) -> impl Iterator<Item = usize> {
    (0..8).filter(move |k| live & (1 << k) != 0)
}

impl PathTracer<'_> {
    /// The radiance of the batch's first `n` samples (n <= 8) of pixel
    /// (x, y), the batch [`SampleBatch::reset`] to them; `rays` counts
    /// every ray, as [`PathTracer::trace`] does.
    pub fn trace_wave(
        &self,
        x: u32,
        y: u32,
        batch: &mut SampleBatch,
        n: usize,
        rays: &mut u64,
    ) -> [Vec3; 8] {
        debug_assert!(n <= 8);
        let mut paths: [PathState; 8] =
            std::array::from_fn(|k| PathState::new(self.camera.ray(x, y, batch.pixel_2d(k))));
        let mut live = ((1u16 << n) - 1) as u8;
        let mut arrivals = [None::<Arrival>; 8];
        let mut depth = 0u32;
        while live != 0 {
            for k in lanes_of(live) {
                arrivals[k] = self.arrive(&mut paths[k], rays);
                if arrivals[k].is_none() {
                    live &= !(1 << k);
                }
            }
            if live == 0 || depth.saturating_add(1) >= self.max_depth {
                break;
            }
            for k in lanes_of(live) {
                let Some(at) = &arrivals[k] else { continue };
                let u = batch.bounce(k, depth);
                let (sf, bsdf) = self.shade(at.material, at.hit.tri, at.hit.u, at.hit.v, at.wo);
                let mut v = self.begin(at, &sf, &bsdf, &u, rays);
                if let Some(ne) = &mut v.nee {
                    self.test_shadow(ne);
                }
                if !self.scatter(&mut paths[k], at, &sf, &v, &u, depth) {
                    live &= !(1 << k);
                }
            }
            depth += 1;
        }
        std::array::from_fn(|k| paths[k].radiance)
    }
}
