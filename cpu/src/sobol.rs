//! Owen-scrambled Sobol points for the path tracer (`--sampler sobol`),
//! after Burley, "Practical Hash-based Owen Scrambling", JCGT 9(4), 2020.
//! The crate `sobol_burley` (Burley's construction with Vegdahl's improved
//! hash) is the source of truth; `shaders/integrator/sobol.glsl` returns
//! the same bits for every (seed, pixel, sample, dimension), pinned by
//! `tests/gpu_sobol.rs` and, for its direction-number table, by
//! [`tests::glsl_direction_table_is_the_crates`].
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

use crate::sampling::{Rng, pcg4d};

/// Salt of the pair seeds' hash (keeps them apart from `Rng`'s stream).
pub const SOBOL_SALT: u32 = 0x5f3c_9a1d;
/// Sample indices per sequence: the direction tables' 16 bits.
pub const SOBOL_BLOCK_BITS: u32 = 16;

/// The seed of pair `pair` of sample `sample` in `pixel` under seed key
/// `key` (`sampling::seed_key`).
#[inline]
pub fn pair_seed(key: u32, pixel: u32, sample: u32, pair: u32) -> u32 {
    pcg4d([pixel, pair, sample >> SOBOL_BLOCK_BITS, key ^ SOBOL_SALT])[0]
}

/// Sobol dimensions 0 and 1's direction numbers, bit-reversed, as
/// `sobol_burley` stores them: `[dimension][bit]`. A copy, so that one pass
/// over the index bits serves both dimensions; [`direction_table`] reads
/// the crate's, and a unit test holds the two (and the GLSL's) equal.
pub const DIRECTIONS: [[u32; 16]; 2] = [
    [
        0x0000_0001,
        0x0000_0002,
        0x0000_0004,
        0x0000_0008,
        0x0000_0010,
        0x0000_0020,
        0x0000_0040,
        0x0000_0080,
        0x0000_0100,
        0x0000_0200,
        0x0000_0400,
        0x0000_0800,
        0x0000_1000,
        0x0000_2000,
        0x0000_4000,
        0x0000_8000,
    ],
    [
        0x0000_0001,
        0x0000_0003,
        0x0000_0005,
        0x0000_000f,
        0x0000_0011,
        0x0000_0033,
        0x0000_0055,
        0x0000_00ff,
        0x0000_0101,
        0x0000_0303,
        0x0000_0505,
        0x0000_0f0f,
        0x0000_1111,
        0x0000_3333,
        0x0000_5555,
        0x0000_ffff,
    ],
];

/// Dimension 1's direction numbers XORed over each byte of the (reversed)
/// index: `DIR1_BYTES[0][b]` for index bits 31..24 (b's bit 7 - k set:
/// direction k), `DIR1_BYTES[1][b]` for bits 23..16 (directions 8..15).
/// Two lookups replace sixteen masked XORs.
const DIR1_BYTES: [[u32; 256]; 2] = {
    let mut t = [[0u32; 256]; 2];
    let mut half = 0;
    while half < 2 {
        let mut b = 0;
        while b < 256 {
            let mut v = 0u32;
            let mut k = 0;
            while k < 8 {
                if (b >> (7 - k)) & 1 == 1 {
                    v ^= DIRECTIONS[1][8 * half + k];
                }
                k += 1;
            }
            t[half][b] = v;
            b += 1;
        }
        half += 1;
    }
    t
};

/// `(sobol_burley::sample(i, 0, seed), sobol_burley::sample(i, 1, seed))`,
/// bit for bit (a unit test checks it), at a fraction of the cost: the two
/// share the index shuffle; dimension 0 (van der Corput) is the shuffled
/// index's top 16 bits reversed, dimension 1 two table lookups.
#[inline]
pub fn sobol_pair(i: u32, seed: u32) -> Vec2 {
    use sobol_burley::parts::{hash, owen_scramble_rev, u32_to_f32_norm};
    let idx = owen_scramble_rev(i.reverse_bits(), hash(seed ^ 0x79c6_8e4a));
    // The top 16 bits: the crate's 2^16-sample tables. Direction k of
    // dimension 0 is 1 << k, taken where index bit 31 - k is set.
    let v0 = idx.reverse_bits() & 0xffff;
    let v1 = DIR1_BYTES[0][(idx >> 24) as usize] ^ DIR1_BYTES[1][((idx >> 16) & 0xff) as usize];
    let s = seed.wrapping_mul(0x9c8f_2d3b);
    let x = owen_scramble_rev(v0, hash(s ^ 0x912f_69ba));
    let y = owen_scramble_rev(v1, hash(s ^ 0x174f_18ab));
    Vec2::new(
        u32_to_f32_norm(x.reverse_bits()),
        u32_to_f32_norm(y.reverse_bits()),
    )
}

/// Both coordinates of pair `pair` (dimensions 2 pair and 2 pair + 1).
#[inline]
pub fn sobol_2d(key: u32, pixel: u32, sample: u32, pair: u32) -> Vec2 {
    let seed = pair_seed(key, pixel, sample, pair);
    sobol_pair(sample & ((1 << SOBOL_BLOCK_BITS) - 1), seed)
}

/// Dimension `dim` of sample `sample` in `pixel`: a value in [0, 1), a
/// multiple of 2^-23 (`sobol_burley`'s f32 conversion).
#[inline]
pub fn sobol_sample(key: u32, pixel: u32, sample: u32, dim: u32) -> f32 {
    sobol_2d(key, pixel, sample, dim / 2)[(dim % 2) as usize]
}

/// The numbers one bounce draws, whether it uses them or not.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BounceSamples {
    pub light_cat: f32,
    pub light_idx: f32,
    pub light: Vec2,
    pub bsdf_lobe: f32,
    pub bsdf: Vec2,
    pub rr: f32,
}

/// Pairs per bounce.
pub const PAIRS_PER_BOUNCE: u32 = 4;

/// The first pair of bounce `bounce` (pair 0 is the pixel position).
#[inline]
pub fn bounce_pair(bounce: u32) -> u32 {
    1 + PAIRS_PER_BOUNCE * bounce
}

/// One path's random numbers, from either sampler; the GLSL twin is
/// `Sampler` in `shaders/integrator/sobol.glsl`.
#[derive(Clone, Debug)]
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
                let p = bounce_pair(*bounce);
                *bounce += 1;
                let light = sobol_2d(*key, *pixel, *sample, p);
                let bsdf = sobol_2d(*key, *pixel, *sample, p + 1);
                let cat_idx = sobol_2d(*key, *pixel, *sample, p + 2);
                let lobe_rr = sobol_2d(*key, *pixel, *sample, p + 3);
                BounceSamples {
                    light_cat: cat_idx.x,
                    light_idx: cat_idx.y,
                    light,
                    bsdf_lobe: lobe_rr.x,
                    bsdf,
                    rr: lobe_rr.y,
                }
            }
        }
    }
}

/// Sobol dimensions 0 and 1's direction numbers, bit-reversed, as
/// `sobol_burley` stores them (`parts::sobol_rev` of a one-bit index):
/// `[dimension][bit]`. `shaders/integrator/sobol.glsl` holds them as
/// constants; [`glsl_table`] prints them in its syntax.
pub fn direction_table() -> [[u32; 16]; 2] {
    let mut t = [[0u32; 16]; 2];
    for (d, row) in t.iter_mut().enumerate() {
        for (k, v) in row.iter_mut().enumerate() {
            *v = sobol_burley::parts::sobol_rev((1u32 << k).reverse_bits(), d as u32);
        }
    }
    t
}

/// [`direction_table`] as the GLSL constants of `sobol.glsl`.
pub fn glsl_table() -> String {
    let t = direction_table();
    let mut s = String::new();
    for (d, row) in t.iter().enumerate() {
        s.push_str(&format!("const uint SOBOL_REV_DIM{d}[16] = uint[16](\n"));
        for (k, chunk) in row.chunks(4).enumerate() {
            let items: Vec<String> = chunk.iter().map(|v| format!("0x{v:08x}u")).collect();
            s.push_str("    ");
            s.push_str(&items.join(", "));
            s.push_str(if k == 3 { "\n" } else { ",\n" });
        }
        s.push_str(");\n");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The GLSL's table is the crate's. To regenerate it after a crate
    /// update: `cargo test -p glint-cpu --lib sobol -- --nocapture` prints
    /// the block to paste between the markers.
    #[test]
    fn glsl_direction_table_is_the_crates() {
        let glsl = include_str!("../../shaders/integrator/sobol.glsl");
        let begin = "// BEGIN TABLE (cpu/src/sobol.rs glsl_table)\n";
        let end = "// END TABLE\n";
        let a = glsl.find(begin).expect("table start marker") + begin.len();
        let b = glsl.find(end).expect("table end marker");
        let want = glsl_table();
        if glsl[a..b] != want {
            println!("{want}");
        }
        assert_eq!(
            glsl[a..b],
            want,
            "shaders/integrator/sobol.glsl's table is stale"
        );
    }

    /// The copy is the crate's table, and `sobol_pair` the crate's
    /// `sample` for dimensions 0 and 1, bit for bit.
    #[test]
    fn sobol_pair_is_the_crates_sample() {
        assert_eq!(DIRECTIONS, direction_table());
        let mut seed = 1u32;
        for _ in 0..64 {
            seed = crate::sampling::pcg4d([seed, 1, 2, 3])[0];
            for i in (0..4096u32).chain([65535, 40_000, 12_345]) {
                let p = sobol_pair(i, seed);
                assert_eq!(p.x.to_bits(), sobol_burley::sample(i, 0, seed).to_bits());
                assert_eq!(p.y.to_bits(), sobol_burley::sample(i, 1, seed).to_bits());
            }
        }
    }

    /// A reimplementation from the table alone (what the GLSL does) gives
    /// the crate's bits.
    #[test]
    fn table_reimplementation_matches_the_crate() {
        use sobol_burley::parts::{hash, owen_scramble_rev, u32_to_f32_norm};
        let t = direction_table();
        for seed in [0u32, 1, 0xdead_beef, 12345] {
            for i in 0..4096u32 {
                let idx = owen_scramble_rev(i.reverse_bits(), hash(seed ^ 0x79c6_8e4a));
                for d in 0..2u32 {
                    let mut v = 0u32;
                    for (k, dn) in t[d as usize].iter().enumerate() {
                        if idx & (0x8000_0000 >> k) != 0 {
                            v ^= dn;
                        }
                    }
                    let sc =
                        seed.wrapping_mul(0x9c8f_2d3b) ^ [0x912f_69ba, 0x174f_18ab][d as usize];
                    let x = u32_to_f32_norm(owen_scramble_rev(v, hash(sc)).reverse_bits());
                    assert_eq!(x.to_bits(), sobol_burley::sample(i, d, seed).to_bits());
                }
            }
        }
    }
}
