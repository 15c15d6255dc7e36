//! The Sobol sampler's promises (cpu/src/sobol.rs): stratification of every
//! pair of one path vertex's dimensions, for the first 2^m samples and for
//! any aligned range (shards, passes), and decorrelation between
//! neighbouring pixels, between pairs, and between seeds.

use glam::Vec2;
use glint_cpu::SamplerKind;
use glint_cpu::compare::normal_quantile;
use glint_cpu::sampling::{Rng, seed_key};
use glint_cpu::sobol::{PathSampler, bounce_pair, sobol_2d, sobol_sample};

/// Whether `pts` (2^m of them) put exactly one point in every elementary
/// interval [i/2^a, (i+1)/2^a) x [j/2^(m-a), (j+1)/2^(m-a)), a = 0..=m:
/// a (0,m,2)-net in base 2.
fn is_net(pts: &[Vec2], m: u32) -> bool {
    assert_eq!(pts.len(), 1 << m);
    let mut seen = vec![false; 1 << m];
    for a in 0..=m {
        seen.iter_mut().for_each(|s| *s = false);
        for p in pts {
            // Exact: the coordinates are multiples of 2^-23.
            let i = (p.x * (1u32 << a) as f32) as usize;
            let j = (p.y * (1u32 << (m - a)) as f32) as usize;
            let cell = (i << (m - a)) | j;
            if std::mem::replace(&mut seen[cell], true) {
                return false;
            }
        }
    }
    true
}

/// The pairs of the pixel vertex and of bounces 0, 1 and 20.
fn pairs() -> Vec<u32> {
    let mut v = vec![0];
    for bounce in [0, 1, 20] {
        v.extend((0..4).map(|k| bounce_pair(bounce) + k));
    }
    v
}

#[test]
fn every_pair_of_a_vertex_is_a_0m2_net_for_the_first_2m_samples() {
    for key in [seed_key(0), seed_key(3)] {
        for pixel in [0u32, 1, 777, 65535 * 3] {
            for pair in pairs() {
                for m in 0..=10u32 {
                    let pts: Vec<Vec2> = (0..1u32 << m)
                        .map(|s| sobol_2d(key, pixel, s, pair))
                        .collect();
                    assert!(is_net(&pts, m), "key {key} pixel {pixel} pair {pair} m {m}");
                    // The dimensions' own numbering says the same.
                    let s = (1u32 << m) - 1;
                    let p = sobol_2d(key, pixel, s, pair);
                    assert_eq!(p.x, sobol_sample(key, pixel, s, 2 * pair));
                    assert_eq!(p.y, sobol_sample(key, pixel, s, 2 * pair + 1));
                }
            }
        }
    }
}

#[test]
fn any_aligned_range_of_2m_samples_is_a_0m2_net() {
    // A shard or a pass that starts at a multiple of 2^m, including ranges
    // in later 2^16-sample blocks (fresh scrambles, same structure).
    let key = seed_key(11);
    for pixel in [5u32, 40_000] {
        for pair in pairs() {
            for m in 1..=10u32 {
                for k in [
                    1u32,
                    3,
                    7,
                    64,
                    (1 << 16) >> m,
                    5 << (16 - m),
                    1000 << (16 - m),
                ] {
                    let start = k << m;
                    let pts: Vec<Vec2> = (start..start + (1 << m))
                        .map(|s| sobol_2d(key, pixel, s, pair))
                        .collect();
                    assert!(
                        is_net(&pts, m),
                        "pixel {pixel} pair {pair} m {m} start {start}"
                    );
                }
            }
        }
    }
}

#[test]
fn the_net_test_fails_independent_numbers_and_unaligned_sobol_ranges() {
    // The test of the test: independent numbers are almost never a net.
    let mut fails = 0;
    for pixel in 0..20u32 {
        let pts: Vec<Vec2> = (0..64u32)
            .map(|s| Rng::new(seed_key(0), pixel, s).next_2d())
            .collect();
        fails += !is_net(&pts, 6) as u32;
    }
    assert_eq!(fails, 20);
    // And an unaligned Sobol range is a valid set (see the next test) but
    // not a net in general.
    let pts: Vec<Vec2> = (3..3 + 64)
        .map(|s| sobol_2d(seed_key(0), 0, s, 1))
        .collect();
    assert!(!is_net(&pts, 6));
}

#[test]
fn any_range_is_a_union_of_nets_and_stays_uniform() {
    // [start, start + n) splits into aligned power-of-two blocks, each a
    // net: every 1D projection of any range has at most one point per
    // cell of width 1/2^k for the largest aligned block 2^k inside.
    let key = seed_key(2);
    for (start, n) in [(3u32, 100u32), (1000, 37), (65530, 20), (123_456, 300)] {
        let mut s = start;
        while s < start + n {
            let k = s.trailing_zeros().min(31 - (start + n - s).leading_zeros());
            let pts: Vec<Vec2> = (s..s + (1 << k)).map(|i| sobol_2d(key, 9, i, 3)).collect();
            assert!(
                is_net(&pts, k),
                "block [{s}, {}) of [{start}, {})",
                s + (1 << k),
                start + n
            );
            s += 1 << k;
        }
    }
}

/// Pearson's correlation coefficient and the means.
fn correlation(a: &[f64], b: &[f64]) -> (f64, f64, f64) {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma) * (x - ma);
        sbb += (y - mb) * (y - mb);
    }
    (sab / (saa * sbb).sqrt(), ma, mb)
}

/// Independent uniform pairs give a correlation coefficient approximately
/// normal with variance 1/n (n = 10^5: standard deviation 0.0032), and a
/// mean with standard deviation sqrt(1/12/n). Over `tests` such checks the
/// Sidak-style bound z(1 - alpha / (2 tests)) keeps the chance that a
/// correct sampler fails any of them at alpha = 1e-6.
fn tolerance(n: usize, tests: usize) -> f64 {
    normal_quantile(1.0 - 1e-6 / (2.0 * tests as f64)) / (n as f64).sqrt()
}

const W: u32 = 500;
const PAIRS: usize = 100_000;

#[test]
fn neighbouring_pixels_pairs_and_seeds_are_uncorrelated() {
    let key = seed_key(0);
    // (dimension, sample): the pixel pair, bounce 0 and a deep bounce, at
    // the first sample, odd ones, and in a later 2^16 block.
    let cases: Vec<(u32, u32)> = [0u32, 1, 2, 5, 9, 17, 2 + 8 * 12]
        .iter()
        .flat_map(|&d| [0u32, 1, 3, 64, 65_536 + 2].map(|s| (d, s)))
        .collect();
    let tests = cases.len() * 4 + 1;
    let tol = tolerance(PAIRS, tests);
    let mean_tol = tol * (1.0f64 / 12.0).sqrt();
    for &(d, s) in &cases {
        // Horizontal neighbours (2i, y), (2i + 1, y); vertical (x, 2j),
        // (x, 2j + 1): 10^5 disjoint pairs each.
        let horizontal = |i: u32| {
            let (x, y) = (2 * (i % (W / 2)), i / (W / 2));
            (y * W + x, y * W + x + 1)
        };
        let vertical = |i: u32| {
            let (x, y) = (i % W, 2 * (i / W));
            (y * W + x, (y + 1) * W + x)
        };
        for (name, nb) in [
            ("horizontal", &horizontal as &dyn Fn(u32) -> (u32, u32)),
            ("vertical", &vertical),
        ] {
            let (a, b): (Vec<f64>, Vec<f64>) = (0..PAIRS as u32)
                .map(|i| {
                    let (p, q) = nb(i);
                    (
                        sobol_sample(key, p, s, d) as f64,
                        sobol_sample(key, q, s, d) as f64,
                    )
                })
                .unzip();
            let (r, ma, _) = correlation(&a, &b);
            assert!(
                r.abs() < tol,
                "{name} dim {d} sample {s}: r = {r} (tolerance {tol})"
            );
            assert!((ma - 0.5).abs() < mean_tol, "dim {d} sample {s}: mean {ma}");
        }
        // Two pairs of one sample in one pixel: the next pair's first
        // coordinate, over pixels.
        let (a, b): (Vec<f64>, Vec<f64>) = (0..PAIRS as u32)
            .map(|p| {
                (
                    sobol_sample(key, p, s, d) as f64,
                    sobol_sample(key, p, s, (d | 1) + 1) as f64,
                )
            })
            .unzip();
        let (r, _, _) = correlation(&a, &b);
        assert!(r.abs() < tol, "dims {d}, {}: r = {r}", (d | 1) + 1);
        // Another seed, same pixel, sample and dimension.
        let (a, b): (Vec<f64>, Vec<f64>) = (0..PAIRS as u32)
            .map(|p| {
                (
                    sobol_sample(key, p, s, d) as f64,
                    sobol_sample(seed_key(1), p, s, d) as f64,
                )
            })
            .unzip();
        let (r, _, _) = correlation(&a, &b);
        assert!(r.abs() < tol, "seeds 0 and 1, dim {d} sample {s}: r = {r}");
        let same = a.iter().zip(&b).filter(|(x, y)| x == y).count();
        assert!(same < 10, "seeds 0 and 1 agree on {same} points");
    }
    // The test of the test: pixels sharing one scramble (the same seed for
    // every pixel) are perfectly correlated and fail it.
    let (a, b): (Vec<f64>, Vec<f64>) = (0..PAIRS as u32)
        .map(|i| {
            let s = i % 1024;
            let f = |_pixel: u32| sobol_burley::sample(s, 1, 42) as f64;
            (f(2 * i), f(2 * i + 1))
        })
        .unzip();
    assert!(correlation(&a, &b).0.abs() >= tol);
}

#[test]
fn the_path_sampler_lays_bounces_out_as_documented() {
    let (key, pixel, s) = (seed_key(4), 12, 345);
    let mut ps = PathSampler::new(SamplerKind::Sobol, key, pixel, s);
    assert_eq!(ps.pixel_2d(), sobol_2d(key, pixel, s, 0));
    for bounce in 0..5 {
        let b = ps.bounce();
        let p = bounce_pair(bounce);
        assert_eq!(b.light, sobol_2d(key, pixel, s, p));
        assert_eq!(b.bsdf, sobol_2d(key, pixel, s, p + 1));
        assert_eq!(
            Vec2::new(b.light_cat, b.light_idx),
            sobol_2d(key, pixel, s, p + 2)
        );
        assert_eq!(Vec2::new(b.bsdf_lobe, b.rr), sobol_2d(key, pixel, s, p + 3));
    }
    // The independent sampler keeps the stream order it always had.
    let mut ps = PathSampler::new(SamplerKind::Independent, key, pixel, s);
    let mut rng = Rng::new(key, pixel, s);
    assert_eq!(ps.pixel_2d(), rng.next_2d());
    let b = ps.bounce();
    let want = [
        rng.next_f32(),
        rng.next_f32(),
        rng.next_f32(),
        rng.next_f32(),
        rng.next_f32(),
        rng.next_f32(),
        rng.next_f32(),
        rng.next_f32(),
    ];
    assert_eq!(
        [
            b.light_cat,
            b.light_idx,
            b.light.x,
            b.light.y,
            b.bsdf_lobe,
            b.bsdf.x,
            b.bsdf.y,
            b.rr
        ],
        want
    );
}
