//! Owen-scrambled Sobol points for the path tracer (`--sampler sobol`),
//! after Burley, "Practical Hash-based Owen Scrambling", JCGT 9(4), 2020.
//! The crate `sobol_burley` (Burley's construction with Vegdahl's improved
//! hash) is the source of truth; `shaders/integrator/sobol.glsl` returns
//! the same bits for every (seed, pixel, sample, dimension), pinned by
//! `tests/gpu_sobol.rs`; both compute the direction numbers' XOR in closed
//! form ([`sobol_dim1`]), which a unit test checks against the crate's table.
//!
//! - Dimensions come in pairs: dimension `d` is coordinate `d % 2` of pair
//!   `d / 2`, and every pair is Sobol dimensions 0 and 1 (a (0,2)-sequence)
//!   under a seed of its own (Burley's padding, sec. 4): Burley's nested
//!   uniform shuffle of the sample index and an Owen scramble per
//!   coordinate, both keyed by that seed. So the first 2^m samples of a
//!   pixel, and any 2^m starting at a multiple of 2^m, form a (0,m,2)-net in
//!   every pair, while different pairs (and pixels, and seeds) are
//!   independently randomised.
//! - The pair's seed hashes (pixel, pair, sample / 2^16, seed key) with
//!   `pcg4d`: pixels are decorrelated by their own scrambles and shuffles.
//! - The dimensions of a path: pair 0 is the pixel position; bounce `k`
//!   (0-based) owns pairs 1 + 4k .. 1 + 4k + 3, its fixed budget of eight
//!   numbers ([`BounceSamples`]) laid out so that the 2D samples are whole
//!   pairs: (light 2D), (BSDF 2D), (light category, light index),
//!   (BSDF lobe, roulette).
//! - Where the tables end: `sobol_burley` holds 16 bits of sample index
//!   (2^16 samples per sequence). Sample `s` uses index `s mod 2^16` under
//!   seeds that also hash `s / 2^16`, so every block of 2^16 samples is a
//!   fresh, independently scrambled sequence (still stratified within the
//!   block); dimensions never run out, since padding only needs new seeds.
//!   Nothing falls back to independent numbers.
//! - Any contiguous range of sample indices is a valid set: every point
//!   is uniformly distributed (Owen scrambling), so any subset is unbiased,
//!   and a range splits into aligned power-of-two blocks, each a net.

use glam::Vec2;

use crate::lanes::{F32x8, SimdLevel, U32x8, ULane, V2};
use crate::sampling::Rng;
use crate::simd_at;

// The pair seeds' salt, the sequence length and the pairs per bounce.
pub use crate::abi::{PAIRS_PER_BOUNCE, SOBOL_BLOCK_BITS, SOBOL_SALT};

/// The seed of pair `pair` of sample `sample` in `pixel` under seed key
/// `key` (`sampling::seed_key`).
#[inline]
pub fn pair_seed(key: u32, pixel: u32, sample: u32, pair: u32) -> u32 {
    lanes::pair_seed(key, pixel, sample, pair)
}

/// Sobol dimension 1 (before scrambling) of the index bits `b`, bit k of
/// `b` taking direction k. Dimension 1's direction numbers are the rows of
/// Pascal's triangle mod 2: direction k has bit j exactly where j's bits are
/// a subset of k's (Lucas's theorem). So bit j of the XOR of the taken
/// directions is the XOR of `b`'s bits at the supersets of j: the superset
/// sum over GF(2), four shift-and-XOR steps (one per bit of j) instead of
/// sixteen masked XORs or a table. `sobol_dim1` in GLSL.
#[inline]
pub fn sobol_dim1(b: u32) -> u32 {
    lanes::sobol_dim1(b)
}

/// `(sobol_burley::sample(i, 0, seed), sobol_burley::sample(i, 1, seed))`,
/// bit for bit (a unit test checks it), at a fraction of the cost: the two
/// share the index shuffle; the shuffled index's top 16 bits, reversed, are
/// dimension 0 (van der Corput: direction k of dimension 0 is 1 << k) and,
/// through [`sobol_dim1`], dimension 1.
#[inline]
pub fn sobol_pair(i: u32, seed: u32) -> Vec2 {
    let p = lanes::sobol_pair(i, seed);
    Vec2::new(p.x, p.y)
}

/// Both coordinates of pair `pair` (dimensions 2 pair and 2 pair + 1).
#[inline]
pub fn sobol_2d(key: u32, pixel: u32, sample: u32, pair: u32) -> Vec2 {
    let p = lanes::sobol_2d(key, pixel, sample, pair);
    Vec2::new(p.x, p.y)
}

/// Dimension `dim` of sample `sample` in `pixel`: a value in [0, 1), a
/// multiple of 2^-23 (`sobol_burley`'s f32 conversion).
#[inline]
pub fn sobol_sample(key: u32, pixel: u32, sample: u32, dim: u32) -> f32 {
    sobol_2d(key, pixel, sample, dim / 2)[(dim % 2) as usize]
}

/// The numbers one bounce draws, whether it uses them or not.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BounceSamples {
    pub light_cat: f32,
    pub light_idx: f32,
    pub light: Vec2,
    pub bsdf_lobe: f32,
    pub bsdf: Vec2,
    pub rr: f32,
}

/// The first pair of bounce `bounce` (pair 0 is the pixel position).
#[inline]
pub fn bounce_pair(bounce: u32) -> u32 {
    lanes::bounce_pair(bounce)
}

/// Bounce `bounce`'s Sobol numbers for one path: [`lanes::bounce`] on one
/// lane.
#[inline]
pub fn sobol_bounce(key: u32, pixel: u32, sample: u32, bounce: u32) -> BounceSamples {
    lanes::bounce(key, pixel, sample, bounce).into()
}

impl From<lanes::BounceLanes<f32>> for BounceSamples {
    #[inline(always)]
    fn from(b: lanes::BounceLanes<f32>) -> Self {
        Self {
            light_cat: b.light_cat,
            light_idx: b.light_idx,
            light: Vec2::new(b.light.x, b.light.y),
            bsdf_lobe: b.bsdf_lobe,
            bsdf: Vec2::new(b.bsdf.x, b.bsdf.y),
            rr: b.rr,
        }
    }
}

/// The Sobol numbers of eight consecutive samples of one pixel, computed
/// eight paths per instruction ([`lanes`] on [`U32x8`] lanes, at the SIMD
/// level the render detected): the pixel positions at once, and each
/// bounce's numbers for the paths of the wave that reach it
/// ([`SampleBatch::bounces`]). The same bits as [`PathSampler::new`]'s.
///
/// Deep bounces are reached by few of the eight paths, and eight lanes
/// cost what [`SimdLevel`]'s break-even count of single paths does: a
/// bounce is drawn wide where at least that many paths need it, else path
/// by path.
#[derive(Clone, Debug)]
pub struct SampleBatch {
    level: SimdLevel,
    key: u32,
    pixel: u32,
    first: u32,
    pixel_2d: V2<F32x8>,
    /// The pixel's pair keys, pair by pair, for the block of 2^16 samples
    /// `block` (when the batch lies in one block).
    keys: Vec<lanes::PairKeys<u32>>,
    block: Option<u32>,
}

impl SampleBatch {
    pub fn new(level: SimdLevel) -> Self {
        Self {
            level,
            key: 0,
            pixel: 0,
            first: 0,
            pixel_2d: V2 {
                x: F32x8([0.0; 8]),
                y: F32x8([0.0; 8]),
            },
            keys: Vec::new(),
            block: None,
        }
    }

    /// Start the batch of samples `first .. first + 8` of `pixel`.
    pub fn reset(&mut self, key: u32, pixel: u32, first: u32) {
        let block = first >> SOBOL_BLOCK_BITS;
        let one_block = first.wrapping_add(7) >> SOBOL_BLOCK_BITS == block;
        if (self.key, self.pixel) != (key, pixel) || self.block != Some(block) || !one_block {
            self.keys.clear();
        }
        self.block = one_block.then_some(block);
        (self.key, self.pixel, self.first) = (key, pixel, first);
        let p = match self.block {
            Some(_) => {
                let k = self.pair_keys(0);
                simd_at!(self.level, fn(first: u32, k: lanes::PairKeys<u32>) -> V2<F32x8> {
                    let i = batch_samples(first).and(U32x8::splat((1 << SOBOL_BLOCK_BITS) - 1));
                    lanes::PairKeys::<U32x8>::splat(k).sample(i)
                }(first, k))
            }
            None => simd_at!(self.level, fn(key: u32, pixel: u32, first: u32) -> V2<F32x8> {
                lanes::sobol_2d(U32x8::splat(key), U32x8::splat(pixel), batch_samples(first), U32x8::splat(0))
            }(key, pixel, first)),
        };
        self.pixel_2d = p;
    }

    /// Lane `lane`'s position in the pixel ([`PathSampler::pixel_2d`]).
    pub fn pixel_2d(&self, lane: usize) -> Vec2 {
        Vec2::new(self.pixel_2d.x.0[lane], self.pixel_2d.y.0[lane])
    }

    /// Every lane's [`Self::pixel_2d`].
    pub fn pixels_2d(&self) -> V2<F32x8> {
        self.pixel_2d
    }

    /// Bounce `bounce`'s numbers ([`PathSampler::bounce`]) of the lanes in
    /// `live` (bit k: lane k, sample `first + k`), in lanes; the other
    /// lanes' are zero, or (drawn eight per instruction) their samples'.
    pub fn bounces(&mut self, bounce: u32, live: u8) -> lanes::BounceLanes<F32x8> {
        if live.count_ones() < u32::from(self.level.break_even()) {
            // A loop over the live lanes, not `array::from_fn`, whose
            // array was copied out (a memcpy per call).
            let mut u = [BounceSamples::default(); 8];
            for lane in crate::lanes::live_lanes(live) {
                let sample = self.first.wrapping_add(lane as u32);
                u[lane] = if self.block.is_none() {
                    sobol_bounce(self.key, self.pixel, sample, bounce)
                } else {
                    // One path, from the pixel's keys.
                    let i = sample & ((1 << SOBOL_BLOCK_BITS) - 1);
                    lanes::bounce_keyed(self.bounce_keys(bounce), i).into()
                };
            }
            return lanes::BounceLanes::pack(&u);
        }
        let (key, pixel, first) = (self.key, self.pixel, self.first);
        match self.block {
            Some(_) => {
                let k = self.bounce_keys(bounce);
                simd_at!(self.level, fn(first: u32, k: [lanes::PairKeys<u32>; 4]) -> lanes::BounceLanes<F32x8> {
                    let i = batch_samples(first).and(U32x8::splat((1 << SOBOL_BLOCK_BITS) - 1));
                    let k = [
                        lanes::PairKeys::<U32x8>::splat(k[0]),
                        lanes::PairKeys::<U32x8>::splat(k[1]),
                        lanes::PairKeys::<U32x8>::splat(k[2]),
                        lanes::PairKeys::<U32x8>::splat(k[3]),
                    ];
                    lanes::bounce_keyed(k, i)
                }(first, k))
            }
            // The batch straddles two blocks of 2^16 (their seeds differ).
            None => {
                simd_at!(self.level, fn(key: u32, pixel: u32, first: u32, b: u32) -> lanes::BounceLanes<F32x8> {
                    lanes::bounce(U32x8::splat(key), U32x8::splat(pixel), batch_samples(first), U32x8::splat(b))
                }(key, pixel, first, bounce))
            }
        }
    }

    /// The pixel's keys of bounce `bounce`'s four pairs.
    fn bounce_keys(&mut self, bounce: u32) -> [lanes::PairKeys<u32>; 4] {
        let p = bounce_pair(bounce);
        [
            self.pair_keys(p),
            self.pair_keys(p + 1),
            self.pair_keys(p + 2),
            self.pair_keys(p + 3),
        ]
    }

    /// The pixel's keys of pair `pair` in the batch's block.
    fn pair_keys(&mut self, pair: u32) -> lanes::PairKeys<u32> {
        while self.keys.len() <= pair as usize {
            let p = self.keys.len() as u32;
            let seed = pair_seed(self.key, self.pixel, self.first, p);
            self.keys.push(lanes::PairKeys::new(seed));
        }
        self.keys[pair as usize]
    }
}

impl lanes::BounceLanes<F32x8> {
    /// Lane `i`'s numbers.
    #[inline(always)]
    pub fn lane(&self, i: usize) -> BounceSamples {
        BounceSamples {
            light_cat: self.light_cat.0[i],
            light_idx: self.light_idx.0[i],
            light: Vec2::new(self.light.x.0[i], self.light.y.0[i]),
            bsdf_lobe: self.bsdf_lobe.0[i],
            bsdf: Vec2::new(self.bsdf.x.0[i], self.bsdf.y.0[i]),
            rr: self.rr.0[i],
        }
    }

    /// Eight paths' numbers side by side.
    #[inline(always)]
    pub fn pack(u: &[BounceSamples; 8]) -> Self {
        let of = |f: fn(&BounceSamples) -> f32| F32x8(std::array::from_fn(|i| f(&u[i])));
        Self {
            light_cat: of(|b| b.light_cat),
            light_idx: of(|b| b.light_idx),
            light: V2 {
                x: of(|b| b.light.x),
                y: of(|b| b.light.y),
            },
            bsdf_lobe: of(|b| b.bsdf_lobe),
            bsdf: V2 {
                x: of(|b| b.bsdf.x),
                y: of(|b| b.bsdf.y),
            },
            rr: of(|b| b.rr),
        }
    }
}

/// The sample indices `first .. first + 8` as lanes.
#[inline(always)]
fn batch_samples(first: u32) -> U32x8 {
    U32x8(std::array::from_fn(|i| first.wrapping_add(i as u32)))
}

/// One path's random numbers, from either sampler; the GLSL twin is
/// `Sampler` in `shaders/integrator/sobol.glsl`.
#[derive(Debug)]
pub enum PathSampler {
    /// The counter-based stream, drawn in the integrator's order (pixel 2D,
    /// then per bounce: category, index, light 2D, lobe, BSDF 2D,
    /// roulette), as before samplers existed.
    Independent(Rng),
    /// Sobol pairs, the next bounce's index in `bounce`.
    Sobol {
        key: u32,
        pixel: u32,
        sample: u32,
        bounce: u32,
    },
}

impl PathSampler {
    pub fn new(kind: crate::film::SamplerKind, key: u32, pixel: u32, sample: u32) -> Self {
        match kind {
            crate::film::SamplerKind::Independent => {
                Self::Independent(Rng::new(key, pixel, sample))
            }
            crate::film::SamplerKind::Sobol => Self::Sobol {
                key,
                pixel,
                sample,
                bounce: 0,
            },
        }
    }

    /// The position in the pixel (first call only).
    #[inline]
    pub fn pixel_2d(&mut self) -> Vec2 {
        match self {
            Self::Independent(rng) => rng.next_2d(),
            Self::Sobol {
                key, pixel, sample, ..
            } => sobol_2d(*key, *pixel, *sample, 0),
        }
    }

    /// The next bounce's budget.
    #[inline]
    pub fn bounce(&mut self) -> BounceSamples {
        match self {
            Self::Independent(rng) => {
                let light_cat = rng.next_f32();
                let light_idx = rng.next_f32();
                let light = rng.next_2d();
                let bsdf_lobe = rng.next_f32();
                let bsdf = rng.next_2d();
                let rr = rng.next_f32();
                BounceSamples {
                    light_cat,
                    light_idx,
                    light,
                    bsdf_lobe,
                    bsdf,
                    rr,
                }
            }
            Self::Sobol {
                key,
                pixel,
                sample,
                bounce,
            } => {
                *bounce += 1;
                sobol_bounce(*key, *pixel, *sample, *bounce - 1)
            }
        }
    }
}

/// The sampler over any [`ULane`] type: one source for the scalar path
/// (`u32` lanes, what [`PathSampler`] and the GLSL twin give) and eight
/// paths side by side ([`crate::lanes::U32x8`], each lane its own pixel,
/// sample and bounce). `hash`, `owen_scramble_rev` and `u32_to_f32_norm`
/// are `sobol_burley::parts`' formulas (the unit test below pins
/// [`sobol_pair`] to the crate's `sample`).
pub mod lanes {
    use super::{PAIRS_PER_BOUNCE, SOBOL_BLOCK_BITS, SOBOL_SALT};
    use crate::lanes::{Lane, ULane, V2};
    use crate::sampling::lanes::pcg4d;

    #[inline(always)]
    fn hash<U: ULane>(n: U) -> U {
        let n = n.xor(U::splat(0xe6fe_3beb));
        let n = n.xor(n.shr(16)).mul(U::splat(0x7feb_352d));
        let n = n.xor(n.shr(15)).mul(U::splat(0x846c_a68b));
        n.xor(n.shr(16))
    }

    #[inline(always)]
    fn owen_scramble_rev<U: ULane>(n: U, scramble: U) -> U {
        let n = n.xor(n.mul(U::splat(0x3d20_adea)));
        let n = n.add(scramble);
        let n = n.mul(scramble.shr(16).or(U::splat(1)));
        let n = n.xor(n.mul(U::splat(0x0552_6c56)));
        n.xor(n.mul(U::splat(0x53a2_2864)))
    }

    #[inline(always)]
    fn u32_to_f32_norm<U: ULane>(n: U) -> U::F {
        n.shr(9).or(U::splat(0x3f80_0000)).bits_to_f32() - U::F::one()
    }

    #[inline(always)]
    pub fn sobol_dim1<U: ULane>(b: U) -> U {
        let v = b.and(U::splat(0xffff));
        let v = v.xor(v.shr(1).and(U::splat(0x5555)));
        let v = v.xor(v.shr(2).and(U::splat(0x3333)));
        let v = v.xor(v.shr(4).and(U::splat(0x0f0f)));
        v.xor(v.shr(8).and(U::splat(0x00ff)))
    }

    #[inline(always)]
    pub fn sobol_pair<U: ULane>(i: U, seed: U) -> V2<U::F> {
        PairKeys::new(seed).sample(i)
    }

    /// The part of a pair's scrambling that its seed alone fixes: the
    /// index shuffle's and the two coordinates' scramble keys. A pixel's
    /// samples within one block of 2^16 share every pair's seed, so a
    /// batch of its samples computes these once.
    #[derive(Clone, Copy, Debug)]
    pub struct PairKeys<U> {
        shuffle: U,
        x: U,
        y: U,
    }

    impl<U: ULane> PairKeys<U> {
        #[inline(always)]
        pub fn new(seed: U) -> Self {
            let s = seed.mul(U::splat(0x9c8f_2d3b));
            Self {
                shuffle: hash(seed.xor(U::splat(0x79c6_8e4a))),
                x: hash(s.xor(U::splat(0x912f_69ba))),
                y: hash(s.xor(U::splat(0x174f_18ab))),
            }
        }

        /// Keys of one lane type splat across another's lanes.
        #[inline(always)]
        pub fn splat<V: ULane>(k: PairKeys<u32>) -> PairKeys<V> {
            PairKeys {
                shuffle: V::splat(k.shuffle),
                x: V::splat(k.x),
                y: V::splat(k.y),
            }
        }

        /// Point `i` of the pair's sequence.
        #[inline(always)]
        pub fn sample(&self, i: U) -> V2<U::F> {
            let idx = owen_scramble_rev(i.reverse_bits(), self.shuffle);
            // The top 16 bits: the crate's 2^16-sample tables.
            let bits = idx.reverse_bits().and(U::splat(0xffff));
            let x = owen_scramble_rev(bits, self.x);
            let y = owen_scramble_rev(sobol_dim1(bits), self.y);
            V2 {
                x: u32_to_f32_norm(x.reverse_bits()),
                y: u32_to_f32_norm(y.reverse_bits()),
            }
        }
    }

    #[inline(always)]
    pub fn pair_seed<U: ULane>(key: U, pixel: U, sample: U, pair: U) -> U {
        let block = sample.shr(SOBOL_BLOCK_BITS);
        pcg4d([pixel, pair, block, key.xor(U::splat(SOBOL_SALT))])[0]
    }

    #[inline(always)]
    pub fn sobol_2d<U: ULane>(key: U, pixel: U, sample: U, pair: U) -> V2<U::F> {
        let i = sample.and(U::splat((1 << SOBOL_BLOCK_BITS) - 1));
        sobol_pair(i, pair_seed(key, pixel, sample, pair))
    }

    /// [`super::BounceSamples`] per lane.
    #[derive(Clone, Copy, Debug)]
    pub struct BounceLanes<F> {
        pub light_cat: F,
        pub light_idx: F,
        pub light: V2<F>,
        pub bsdf_lobe: F,
        pub bsdf: V2<F>,
        pub rr: F,
    }

    #[inline(always)]
    pub fn bounce_pair<U: ULane>(bounce: U) -> U {
        U::splat(1).add(U::splat(PAIRS_PER_BOUNCE).mul(bounce))
    }

    /// Bounce `bounce`'s numbers (see the module notes).
    #[inline(always)]
    pub fn bounce<U: ULane>(key: U, pixel: U, sample: U, bounce: U) -> BounceLanes<U::F> {
        let p = bounce_pair(bounce);
        // No closures here: one would be compiled out of line, without
        // the AVX2 copy's instructions (measured: 5x slower).
        let k0 = PairKeys::new(pair_seed(key, pixel, sample, p));
        let k1 = PairKeys::new(pair_seed(key, pixel, sample, p.add(U::splat(1))));
        let k2 = PairKeys::new(pair_seed(key, pixel, sample, p.add(U::splat(2))));
        let k3 = PairKeys::new(pair_seed(key, pixel, sample, p.add(U::splat(3))));
        let i = sample.and(U::splat((1 << SOBOL_BLOCK_BITS) - 1));
        bounce_keyed([k0, k1, k2, k3], i)
    }

    /// A bounce's numbers from its four pairs' keys, at sequence index `i`:
    /// the pairs (light 2D), (BSDF 2D), (light category, light index),
    /// (BSDF lobe, roulette).
    #[inline(always)]
    pub fn bounce_keyed<U: ULane>(k: [PairKeys<U>; 4], i: U) -> BounceLanes<U::F> {
        let (light, bsdf) = (k[0].sample(i), k[1].sample(i));
        let (cat_idx, lobe_rr) = (k[2].sample(i), k[3].sample(i));
        BounceLanes {
            light_cat: cat_idx.x,
            light_idx: cat_idx.y,
            light,
            bsdf_lobe: lobe_rr.x,
            bsdf,
            rr: lobe_rr.y,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sobol dimensions 0 and 1's direction numbers, bit-reversed, as
    /// `sobol_burley` stores them (`parts::sobol_rev` of a one-bit index):
    /// `[dimension][bit]`. What [`sobol_pair`] computes in closed form.
    fn direction_table() -> [[u32; 16]; 2] {
        let mut t = [[0u32; 16]; 2];
        for (d, row) in t.iter_mut().enumerate() {
            for (k, v) in row.iter_mut().enumerate() {
                *v = sobol_burley::parts::sobol_rev((1u32 << k).reverse_bits(), d as u32);
            }
        }
        t
    }

    /// The closed forms are the crate's direction numbers: dimension 0's
    /// direction k is 1 << k, dimension 1's is `sobol_dim1` of bit k, and
    /// `sobol_dim1` is linear (XOR of the directions of the bits set).
    #[test]
    fn closed_forms_are_the_crates_directions() {
        let t = direction_table();
        for (k, (&d0, &d1)) in t[0].iter().zip(&t[1]).enumerate() {
            assert_eq!(d0, 1 << k, "dimension 0, direction {k}");
            assert_eq!(d1, sobol_dim1(1 << k), "dimension 1, direction {k}");
        }
        let mut seed = 7u32;
        for _ in 0..10_000 {
            seed = crate::sampling::pcg4d([seed, 4, 5, 6])[0];
            let b = seed & 0xffff;
            let xor = (0..16)
                .filter(|k| b & (1 << k) != 0)
                .fold(0, |v, k| v ^ t[1][k]);
            assert_eq!(sobol_dim1(b), xor, "bits {b:#06x}");
        }
    }

    /// `sobol_pair` is the crate's `sample` for dimensions 0 and 1, bit for
    /// bit.
    #[test]
    fn sobol_pair_is_the_crates_sample() {
        let mut seed = 1u32;
        for _ in 0..64 {
            seed = crate::sampling::pcg4d([seed, 1, 2, 3])[0];
            for i in (0..4096u32).chain((4096..65536).step_by(61)).chain([65535]) {
                let p = sobol_pair(i, seed);
                assert_eq!(p.x.to_bits(), sobol_burley::sample(i, 0, seed).to_bits());
                assert_eq!(p.y.to_bits(), sobol_burley::sample(i, 1, seed).to_bits());
            }
        }
    }
}
