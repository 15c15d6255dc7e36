//! The wave: eight samples of a pixel (a Sobol [`SampleBatch`]'s, or
//! eight independent ones) traced side by side, bounce by bounce: the
//! live paths' rays are traced one after another (alike rays, whose
//! traversals take the same branches), then each path's hit is shaded,
//! its light sample's shadow ray traced and its next ray drawn. Each path
//! takes the steps [`PathTracer::trace`] takes with the same numbers, so a
//! wave gives every path's radiance and rays bit for bit as one path at a
//! time does (`cpu/tests/lanes.rs`). Keeping each path's shading in one
//! go was measured faster than a loop per step (docs/benchmarks.md).

use glam::Vec3;

use super::wide::Shaded;
use super::{Arrival, PathState, PathTracer};
use crate::bvh::{PACKET, Ray};
use crate::lanes::{F32x8, V2, live_lanes};
use crate::sobol::lanes::BounceLanes;
use crate::sobol::{BounceSamples, PathSampler, SampleBatch};

/// Where a wave's random numbers come from. (Made once per wave and moved
/// into it: boxing the larger variant would allocate per wave.)
#[allow(clippy::large_enum_variant)]
pub enum WaveSampler<'a> {
    /// The Sobol batch of the wave's samples ([`SampleBatch::reset`] to
    /// them): eight samples' numbers per instruction.
    Batch(&'a mut SampleBatch),
    /// Each path its own sampler (the independent sampler).
    Paths([PathSampler; 8]),
}

impl WaveSampler<'_> {
    /// Each lane's position in the pixel.
    fn pixels_2d(&mut self) -> V2<F32x8> {
        match self {
            Self::Batch(batch) => batch.pixels_2d(),
            Self::Paths(paths) => crate::lanes::build8(|k| paths[k].pixel_2d()).into(),
        }
    }

    /// Bounce `bounce`'s numbers of the lanes in `live` (bit k: lane k).
    fn bounces(&mut self, bounce: u32, live: u8) -> BounceLanes<F32x8> {
        match self {
            Self::Batch(batch) => batch.bounces(bounce, live),
            Self::Paths(paths) => {
                // A loop, not `array::from_fn`, whose array was copied out.
                let mut u = [BounceSamples::default(); 8];
                for k in live_lanes(live) {
                    u[k] = paths[k].bounce();
                }
                BounceLanes::pack(&u)
            }
        }
    }
}

impl PathTracer<'_> {
    /// The radiance of the first `n` (n <= 8) of the wave's samples of
    /// pixel (x, y), their numbers from `rng`; `rays` counts every ray, as
    /// [`PathTracer::trace`] does.
    pub fn trace_wave(
        &self,
        x: u32,
        y: u32,
        mut rng: WaveSampler,
        n: usize,
        rays: &mut u64,
    ) -> [Vec3; 8] {
        debug_assert!(n <= 8);
        let mut paths = [PathState::START; 8];
        // The paths' rays side by side: the camera packet reads them as
        // they are.
        let none = Ray {
            o: Vec3::ZERO,
            d: Vec3::ZERO,
            tmax: 0.0,
        };
        let mut ray_of = [none; PACKET];
        // The camera rays' directions in lanes (`PinholeCamera::ray`'s).
        let d = self.camera.directions(x, y, rng.pixels_2d());
        for (k, ray) in ray_of.iter_mut().enumerate() {
            *ray = Ray {
                o: self.camera.origin,
                d: d.lane(k),
                tmax: f32::MAX,
            };
        }
        let mut live = ((1u16 << n) - 1) as u8;
        let mut arrivals = [None::<Arrival>; 8];
        let mut packet_hits = [None; PACKET];
        // The camera rays, and rays that every live path drew from a
        // delta lobe (mirrors, smooth glass: still alike), in one packet;
        // other bounces' rays one at a time (measured: docs/benchmarks.md).
        let mut alike = true;
        let mut depth = 0u32;
        while live != 0 {
            if alike {
                for k in live_lanes(live) {
                    packet_hits[k] = None;
                }
                self.scene
                    .intersect_packet(&ray_of, live, self.masks, &mut packet_hits);
            }
            for k in live_lanes(live) {
                arrivals[k] = if alike {
                    self.arrive_at(&mut paths[k], &ray_of[k], packet_hits[k], rays)
                } else {
                    self.arrive(&mut paths[k], &ray_of[k], rays)
                };
                if arrivals[k].is_none() {
                    live &= !(1 << k);
                }
            }
            if live == 0 || depth.saturating_add(1) >= self.max_depth {
                break;
            }
            let bounce = rng.bounces(depth, live);
            // The vertices of the models the lanes know eight per
            // instruction where enough paths stand on one, the rest one
            // at a time.
            let mut one_by_one = live;
            let mut shaded = Shaded::default();
            if self.wide_shading {
                live &= !self.wide_vertices(
                    &mut paths,
                    &mut ray_of,
                    &arrivals,
                    &bounce,
                    &mut shaded,
                    &mut one_by_one,
                    depth,
                    rays,
                );
            }
            for k in live_lanes(one_by_one) {
                let Some(at) = &arrivals[k] else { continue };
                let (path, ray, u) = (&mut paths[k], &mut ray_of[k], &bounce.lane(k));
                // A hit the lanes shaded but left (`Shaded`) is not shaded
                // again.
                let pre = shaded.sf[k].as_ref().zip(shaded.textured[k].as_ref());
                if !self.vertex(path, ray, at, pre, u, depth, rays) {
                    live &= !(1 << k);
                }
            }
            // Two rays or more, all from delta lobes.
            alike =
                live & live.wrapping_sub(1) != 0 && live_lanes(live).all(|k| paths[k].prev_delta);
            depth += 1;
        }
        std::array::from_fn(|k| paths[k].radiance)
    }
}
