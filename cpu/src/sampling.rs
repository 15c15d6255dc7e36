//! Random numbers and the warps the integrator draws directions with.
//!
//! The generator is counter-based: every uniform number is a pure function
//! of (seed, pixel, sample, dimension), so an image does not depend on how
//! rayon schedules tiles (or on how the GPU orders its invocations), and
//! `shaders/integrator/rng.glsl` reproduces the very same stream bit for bit
//! with 32-bit integer arithmetic only.

use glam::{Vec2, Vec3};

use crate::film::Mis;

/// `pcg4d` from Jarzynski & Olano, "Hash Functions for GPU Rendering", JCGT
/// 9(3), 2020: a 4-in/4-out bijective hash that passed their TestU01 runs,
/// and maps to a handful of GLSL integer instructions.
#[inline]
pub fn pcg4d(v: [u32; 4]) -> [u32; 4] {
    lanes::pcg4d(v)
}

/// [`pcg4d`] over any [`crate::lanes::ULane`] type (one source with the
/// scalar form).
pub mod lanes {
    use crate::film::Mis;
    use crate::lanes::{Lane, ULane, V2, V3};

    /// a / s where s (a + b, or their squares' sum) is positive and finite;
    /// 1 where `a` is infinite; else 0.
    #[inline(always)]
    fn heuristic<L: Lane>(a: L, num: L, sum: L) -> L {
        let inf = L::splat(f32::INFINITY);
        let ok = sum.gt(L::zero()) & sum.abs().lt(inf);
        L::select(
            ok,
            num / sum,
            L::select(a.abs().eq(inf), L::one(), L::zero()),
        )
    }

    /// [`super::power_heuristic`].
    #[inline(always)]
    pub fn power_heuristic<L: Lane>(a: L, b: L) -> L {
        let a2 = a * a;
        let b2 = b * b;
        heuristic(a, a2, a2 + b2)
    }

    /// [`super::balance_heuristic`].
    #[inline(always)]
    pub fn balance_heuristic<L: Lane>(a: L, b: L) -> L {
        heuristic(a, a, a + b)
    }

    /// [`super::mis_light`].
    #[inline(always)]
    pub fn mis_light<L: Lane>(mode: Mis, light_pdf: L, bsdf_pdf: L) -> L {
        match mode {
            Mis::Power => power_heuristic(light_pdf, bsdf_pdf),
            Mis::Balance => balance_heuristic(light_pdf, bsdf_pdf),
            Mis::None => L::one(),
        }
    }

    /// [`super::cosine_hemisphere_pdf`].
    #[inline(always)]
    pub fn cosine_hemisphere_pdf<L: Lane>(cos_theta: L) -> L {
        cos_theta.max(L::zero()) * L::splat(std::f32::consts::FRAC_1_PI)
    }

    /// [`super::square_to_uniform_sphere`].
    #[inline(always)]
    pub fn square_to_uniform_sphere<L: Lane>(u: V2<L>) -> V3<L> {
        let z = L::one() - L::splat(2.0) * u.x;
        let r = (L::one() - z * z).max(L::zero()).sqrt();
        let (sin, cos) = (L::splat(2.0 * std::f32::consts::PI) * u.y).sin_cos();
        V3::new(r * cos, r * sin, z)
    }

    /// [`super::square_to_uniform_triangle`].
    #[inline(always)]
    pub fn square_to_uniform_triangle<L: Lane>(u: V2<L>) -> V2<L> {
        let su0 = u.x.sqrt();
        V2 {
            x: L::one() - su0,
            y: u.y * su0,
        }
    }

    #[inline(always)]
    pub fn pcg4d<U: ULane>(v: [U; 4]) -> [U; 4] {
        let (m, c) = (U::splat(1_664_525), U::splat(1_013_904_223));
        let lcg = |x: U| x.mul(m).add(c);
        let mut v = [lcg(v[0]), lcg(v[1]), lcg(v[2]), lcg(v[3])];
        v[0] = v[0].add(v[1].mul(v[3]));
        v[1] = v[1].add(v[2].mul(v[0]));
        v[2] = v[2].add(v[0].mul(v[1]));
        v[3] = v[3].add(v[1].mul(v[2]));
        let mix = |x: U| x.xor(x.shr(16));
        v = [mix(v[0]), mix(v[1]), mix(v[2]), mix(v[3])];
        v[0] = v[0].add(v[1].mul(v[3]));
        v[1] = v[1].add(v[2].mul(v[0]));
        v[2] = v[2].add(v[0].mul(v[1]));
        v[3] = v[3].add(v[1].mul(v[2]));
        v
    }
}

/// Fold the 64-bit user seed into the 32-bit key the generator (and the GPU
/// parameters) carry: both halves go through the hash, so seeds that differ
/// only in their high bits still give different images.
pub fn seed_key(seed: u64) -> u32 {
    let lo = seed as u32;
    let hi = (seed >> 32) as u32;
    pcg4d([lo, hi, 0x9e37_79b9, 0x85eb_ca6b])[0]
}

/// The per-sample generator: one `pcg4d` call yields four numbers for the
/// input (pixel, sample, block, key); `block` counts up as they are used.
#[derive(Clone, Debug)]
pub struct Rng {
    pixel: u32,
    sample: u32,
    key: u32,
    block: u32,
    buf: [u32; 4],
    used: u32,
}

impl Rng {
    pub fn new(key: u32, pixel: u32, sample: u32) -> Self {
        Self {
            pixel,
            sample,
            key,
            block: 0,
            buf: [0; 4],
            used: 4,
        }
    }

    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        if self.used == 4 {
            self.buf = pcg4d([self.pixel, self.sample, self.block, self.key]);
            self.block = self.block.wrapping_add(1);
            self.used = 0;
        }
        let x = self.buf[self.used as usize];
        self.used += 1;
        x
    }

    /// Uniform in [0, 1): the top 24 bits, exactly representable in f32.
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        let x = self.next_f32();
        let y = self.next_f32();
        Vec2::new(x, y)
    }
}

/// PCG32 (O'Neill 2014, XSH-RR output): the one deterministic generator
/// of glint's tests and tools (the stability sweeps, fuzzers, per-call
/// agreement queries, random rays). The renderer's own numbers are Sobol
/// points and the counter-based [`Rng`]; nothing here reaches an image.
#[derive(Clone, Debug)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Pcg32 {
    /// The increment of PCG's default stream.
    pub const DEFAULT_INC: u64 = 1_442_695_040_888_963_407;

    /// O'Neill's `pcg32_srandom`: `seed` on stream `stream`.
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut r = Self {
            state: 0,
            inc: (stream << 1) | 1,
        };
        r.next_u32();
        r.state = r.state.wrapping_add(seed);
        r.next_u32();
        r
    }

    /// The default stream from the raw state `state`.
    pub fn from_state(state: u64) -> Self {
        Self {
            state,
            inc: Self::DEFAULT_INC,
        }
    }

    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        xorshifted.rotate_right((old >> 59) as u32)
    }

    pub fn next_u64(&mut self) -> u64 {
        let hi = self.next_u32() as u64;
        (hi << 32) | self.next_u32() as u64
    }

    /// Uniform in [0, 1) with 24 bits (every value exactly representable).
    pub fn f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    pub fn vec2(&mut self) -> Vec2 {
        Vec2::new(self.f32(), self.f32())
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }

    /// Uniform in 0..n (0 for n = 0; the modulo bias is below 2^-32 n).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }

    /// Uniform in the box lo..hi.
    pub fn vec_in(&mut self, lo: Vec3, hi: Vec3) -> Vec3 {
        Vec3::new(
            self.range(lo.x, hi.x),
            self.range(lo.y, hi.y),
            self.range(lo.z, hi.z),
        )
    }

    /// Uniform on the unit sphere.
    pub fn dir(&mut self) -> Vec3 {
        let z = 2.0 * self.f32() - 1.0;
        let phi = std::f32::consts::TAU * self.f32();
        let s = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(s * phi.cos(), s * phi.sin(), z)
    }
}

pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    lanes::cosine_hemisphere_pdf(cos_theta)
}

/// Uniform direction on the unit sphere; pdf 1 / (4 pi). (The cosine
/// hemisphere is [`crate::bsdf::warp::square_to_cosine_hemisphere`].)
pub fn square_to_uniform_sphere(u: Vec2) -> Vec3 {
    lanes::square_to_uniform_sphere(u.into()).into()
}

pub const UNIFORM_SPHERE_PDF: f32 = 1.0 / (4.0 * std::f32::consts::PI);

/// Barycentrics (b1, b2) uniform over a triangle by area (the square-root
/// map, Turk 1990 / pbrt-v4 `SampleUniformTriangle`'s classic form):
/// p = (1 - b1 - b2) p0 + b1 p1 + b2 p2.
pub fn square_to_uniform_triangle(u: Vec2) -> Vec2 {
    let b = lanes::square_to_uniform_triangle(u.into());
    Vec2::new(b.x, b.y)
}

/// Index i with cdf[i-1] <= u < cdf[i] in an inclusive, non-decreasing CDF
/// whose last entry is 1; entries with zero probability are never chosen
/// (the search finds the first entry strictly above u). Binary search,
/// written the same way in GLSL.
pub fn sample_cdf(cdf: impl Fn(u32) -> f32, n: u32, u: f32) -> u32 {
    // Smallest i in [0, n) with u < cdf(i); n - 1 if none (u rounding at 1).
    let mut lo = 0u32;
    let mut hi = n.saturating_sub(1);
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        if u < cdf(mid) {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    lo
}

/// Power heuristic with beta = 2 (Veach 1997, eq. 9.13): the weight of a
/// sample drawn from the strategy with density `a` against one with `b`.
/// Mitsuba 3's path tracer uses the same.
#[inline]
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    lanes::power_heuristic(a, b)
}

/// Balance heuristic (Veach 1997, eq. 9.10): a / (a + b).
#[inline]
pub fn balance_heuristic(a: f32, b: f32) -> f32 {
    lanes::balance_heuristic(a, b)
}

/// MIS weight of a light sample with density `light_pdf`, against BSDF
/// sampling with density `bsdf_pdf` of the same direction.
#[inline]
pub fn mis_light(mode: Mis, light_pdf: f32, bsdf_pdf: f32) -> f32 {
    lanes::mis_light(mode, light_pdf, bsdf_pdf)
}

/// MIS weight of a BSDF sample that found an emitter the same vertex also
/// sampled lights for (`Mis::None`: light sampling alone counts, so 0).
#[inline]
pub fn mis_bsdf(mode: Mis, bsdf_pdf: f32, light_pdf: f32) -> f32 {
    match mode {
        Mis::Power => power_heuristic(bsdf_pdf, light_pdf),
        Mis::Balance => balance_heuristic(bsdf_pdf, light_pdf),
        Mis::None => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rng_is_deterministic_and_keyed() {
        let a: Vec<u32> = {
            let mut r = Rng::new(seed_key(7), 3, 11);
            (0..9).map(|_| r.next_u32()).collect()
        };
        let b: Vec<u32> = {
            let mut r = Rng::new(seed_key(7), 3, 11);
            (0..9).map(|_| r.next_u32()).collect()
        };
        assert_eq!(a, b);
        for (key, pix, s) in [
            (seed_key(8), 3, 11),
            (seed_key(7), 4, 11),
            (seed_key(7), 3, 12),
        ] {
            let mut r = Rng::new(key, pix, s);
            let c: Vec<u32> = (0..9).map(|_| r.next_u32()).collect();
            assert_ne!(a, c);
        }
        // Seeds differing only in the high half differ too.
        assert_ne!(seed_key(1), seed_key(1 | (1 << 40)));
    }

    #[test]
    fn rng_uniform_moments() {
        // Mean and variance of 2^16 draws against 1/2 and 1/12; a z-bound of
        // 5 sigma on the mean (sigma = sqrt(1/12 / n)).
        let n = 1 << 16;
        let mut sum = 0.0f64;
        let mut sum_sq = 0.0f64;
        for p in 0..(n / 16) {
            let mut r = Rng::new(seed_key(0), p, 0);
            for _ in 0..16 {
                let x = r.next_f32() as f64;
                assert!((0.0..1.0).contains(&x));
                sum += x;
                sum_sq += x * x;
            }
        }
        let mean = sum / n as f64;
        let var = sum_sq / n as f64 - mean * mean;
        let sigma = (1.0 / 12.0 / n as f64).sqrt();
        assert!((mean - 0.5).abs() < 5.0 * sigma, "mean {mean}");
        assert!((var - 1.0 / 12.0).abs() < 0.005, "var {var}");
    }

    #[test]
    fn warps_land_where_they_should() {
        let mut r = Rng::new(1, 2, 3);
        for _ in 0..1000 {
            let u = r.next_2d();
            let w = crate::bsdf::warp::square_to_cosine_hemisphere(u);
            assert!(w.z >= 0.0 && (w.length() - 1.0).abs() < 1e-4);
            let s = square_to_uniform_sphere(u);
            assert!((s.length() - 1.0).abs() < 1e-4);
            let b = square_to_uniform_triangle(u);
            assert!(b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0 + 1e-6);
        }
    }

    #[test]
    fn cdf_sampling_skips_empty_entries() {
        let cdf = [0.25f32, 0.25, 0.75, 1.0];
        let f = |i: u32| cdf[i as usize];
        assert_eq!(sample_cdf(f, 4, 0.0), 0);
        assert_eq!(sample_cdf(f, 4, 0.2499), 0);
        assert_eq!(sample_cdf(f, 4, 0.25), 2);
        assert_eq!(sample_cdf(f, 4, 0.74), 2);
        assert_eq!(sample_cdf(f, 4, 0.75), 3);
        assert_eq!(sample_cdf(f, 4, 0.99999), 3);
        assert_eq!(sample_cdf(|_| 1.0, 1, 0.5), 0);
    }

    #[test]
    fn power_heuristic_weights_sum_to_one() {
        for (a, b) in [(1.0f32, 2.0f32), (0.3, 0.0), (5.0, 1e-3)] {
            let s = power_heuristic(a, b) + power_heuristic(b, a);
            assert!((s - 1.0).abs() < 1e-6);
        }
        assert_eq!(power_heuristic(1.0, 0.0), 1.0);
        assert_eq!(power_heuristic(0.0, 1.0), 0.0);
    }

    #[test]
    fn mis_modes_weights_sum_to_one() {
        for mode in [Mis::Power, Mis::Balance, Mis::None] {
            for (l, b) in [(1.0f32, 2.0f32), (0.3, 0.0), (5.0, 1e-3), (0.0, 4.0)] {
                let s = mis_light(mode, l, b) + mis_bsdf(mode, b, l);
                assert!((s - 1.0).abs() < 1e-6, "{mode:?} {l} {b}: {s}");
            }
        }
        assert!((balance_heuristic(1.0, 3.0) - 0.25).abs() < 1e-7);
        assert_eq!(balance_heuristic(f32::INFINITY, 1.0), 1.0);
    }
}
