//! BSDF calls per second, scalar against eight lanes, printed with
//! `--nocapture` (release figures: `cargo test --release -p glint-cpu --test
//! lanes_throughput -- --ignored --nocapture`; a benchmark the suite skips).
//! Each round samples, evaluates and takes the density of the rough
//! conductor (GGX, visible normals, complex Fresnel) and the Lambertian
//! for the same 2^16 random (wo, wi, u) per BSDF: the scalar functions one
//! call per lane, then the lane-generic ones on [`F32x8`] at each SIMD
//! level this CPU has, interleaved round by round so a change of load falls
//! on all alike.
//! The glTF coated non-metal: the coat at wo, eval, pdf and a sample.
//! The sampler: a bounce's eight Sobol numbers for 2^16 paths, one call
//! per path against eight paths per call. The emitter light sample on the
//! bundled Cornell box, one point per call against eight. Speeds are printed, never
//! asserted; what is asserted is that every variant gives the same
//! valid-sample count (BSDFs) or the same bits (sampler).

use std::time::Instant;

use glam::{Vec2, Vec3};
use glint_cpu::bsdf::coated::{self, Coat, CoatParams};
use glint_cpu::bsdf::conductor::{self, RoughConductor};
use glint_cpu::bsdf::{ConductorParams, Roughness, Shadowing, diffuse};
use glint_cpu::lanes::{F32x8, Lane, Mask8, SimdLevel, U32x8, ULane, V2, V3};
use glint_cpu::simd_at;

const N: usize = 1 << 16;

struct Inputs {
    c: ConductorParams,
    wo: Vec<Vec3>,
    wi: Vec<Vec3>,
    u: Vec<Vec2>,
}

fn inputs() -> Inputs {
    let mut s = 0x9e37_79b9u32;
    let mut f = move || {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        (s >> 8) as f32 / 16_777_216.0
    };
    let mut dir = || {
        let z = f();
        let r = (1.0 - z * z).sqrt();
        let phi = std::f32::consts::TAU * f();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    };
    let wo = (0..N).map(|_| dir()).collect();
    let wi = (0..N).map(|_| dir()).collect();
    let mut s2 = 17u32;
    let mut g = move || {
        s2 = s2.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (s2 >> 8) as f32 / 16_777_216.0
    };
    let u = (0..N).map(|_| Vec2::new(g(), g())).collect();
    Inputs {
        c: ConductorParams {
            eta: Vec3::new(0.2, 0.92, 1.1),
            k: Vec3::new(3.9, 2.45, 2.14),
            specular_reflectance: Vec3::ONE,
            roughness: Roughness {
                alpha_u: 0.3,
                alpha_v: 0.1,
                shadowing: Shadowing::Correlated,
                multiscatter: false,
            },
        },
        wo,
        wi,
        u,
    }
}

fn pack3(v: &[Vec3]) -> V3<F32x8> {
    let a: [Vec3; 8] = v.try_into().unwrap();
    a.into()
}

fn pack2(v: &[Vec2]) -> V2<F32x8> {
    let a: [Vec2; 8] = v.try_into().unwrap();
    a.into()
}

/// What every variant folds its results into (so nothing is optimised away):
/// the count of valid samples and a sum of f and pdf that the optimiser
/// cannot drop.
fn scalar(inp: &Inputs) -> usize {
    let mut n = 0;
    let mut acc = 0.0f32;
    for i in 0..N {
        let (wo, wi, u) = (inp.wo[i], inp.wi[i], inp.u[i]);
        if let Some(s) = conductor::conductor_sample(&inp.c, wo, u) {
            n += 1;
            acc += s.weight.x + s.pdf;
        }
        acc +=
            conductor::conductor_eval(&inp.c, wo, wi).y + conductor::conductor_pdf(&inp.c, wo, wi);
        if let Some(s) = diffuse::diffuse_sample(Vec3::splat(0.5), wo, u) {
            n += 1;
            acc += s.pdf;
        }
        acc += diffuse::diffuse_eval(Vec3::splat(0.5), wo, wi).x + diffuse::diffuse_pdf(wo, wi);
    }
    std::hint::black_box(acc);
    n
}

#[inline(always)]
fn wide(inp: &Inputs) -> usize {
    let p = RoughConductor::of(&inp.c);
    let c = RoughConductor {
        eta: V3::splat(p.eta.into()),
        k: V3::splat(p.k.into()),
        specular_reflectance: V3::splat(p.specular_reflectance.into()),
        ax: F32x8::splat(p.ax),
        ay: F32x8::splat(p.ay),
        separable: p.separable,
    };
    let rho = V3::splat(Vec3::splat(0.5));
    let mut n = 0;
    let mut acc = F32x8::zero();
    for i in (0..N).step_by(8) {
        let wo = pack3(&inp.wo[i..i + 8]);
        let wi = pack3(&inp.wi[i..i + 8]);
        let u = pack2(&inp.u[i..i + 8]);
        let s = conductor::lanes::rough_sample(&c, wo, u);
        n += s.valid.0.iter().filter(|&&m| m != 0).count();
        acc = acc + F32x8::select(s.valid, s.weight.x + s.pdf, F32x8::zero());
        acc = acc
            + conductor::lanes::rough_eval(&c, wo, wi).y
            + conductor::lanes::rough_pdf(&c, wo, wi);
        let d = diffuse::lanes::diffuse_sample(rho, wo, u);
        n += d.valid.0.iter().filter(|&&m| m != 0).count();
        acc = acc + F32x8::select(d.valid, d.pdf, F32x8::zero());
        acc =
            acc + diffuse::lanes::diffuse_eval(rho, wo, wi).x + diffuse::lanes::diffuse_pdf(wo, wi);
    }
    std::hint::black_box(acc);
    n
}

fn wide_at(level: SimdLevel, inp: &Inputs) -> usize {
    simd_at!(level, fn(inp: &Inputs) -> usize { wide(inp) }(inp))
}

/// A bounce's eight Sobol numbers for N paths (pixel i, sample i / 7,
/// bounce i % 5), scalar: the sum of their bits.
fn sobol_scalar(key: u32) -> u32 {
    let mut acc = 0u32;
    for i in 0..N as u32 {
        let b = glint_cpu::sobol::sobol_bounce(key, i, i / 7, i % 5);
        acc = acc.wrapping_add(
            b.light.x.to_bits() ^ b.bsdf.y.to_bits() ^ b.rr.to_bits() ^ b.light_cat.to_bits(),
        );
    }
    acc
}

#[inline(always)]
fn sobol_wide(key: u32) -> u32 {
    let mut acc = 0u32;
    for i in (0..N as u32).step_by(8) {
        let pixel = U32x8(std::array::from_fn(|k| i + k as u32));
        let sample = U32x8(pixel.0.map(|p| p / 7));
        let bounce = U32x8(pixel.0.map(|p| p % 5));
        let b = glint_cpu::sobol::lanes::bounce(U32x8::splat(key), pixel, sample, bounce);
        for k in 0..8 {
            acc = acc.wrapping_add(
                b.light.x.0[k].to_bits()
                    ^ b.bsdf.y.0[k].to_bits()
                    ^ b.rr.0[k].to_bits()
                    ^ b.light_cat.0[k].to_bits(),
            );
        }
    }
    acc
}

fn sobol_at(level: SimdLevel, key: u32) -> u32 {
    simd_at!(level, fn(key: u32) -> u32 { sobol_wide(key) }(key))
}

#[test]
#[ignore = "benchmark: cargo test --release -p glint-cpu --test lanes_throughput -- --ignored --nocapture --test-threads 1"]
fn sampler_lanes_throughput() {
    let levels = SimdLevel::available();
    let reference = sobol_scalar(7);
    for l in &levels {
        assert_eq!(sobol_at(*l, 7), reference, "{l:?}");
    }
    let rounds = 20;
    let mut secs = vec![0.0f64; 1 + levels.len()];
    for _ in 0..rounds {
        let t = Instant::now();
        std::hint::black_box(sobol_scalar(std::hint::black_box(7)));
        secs[0] += t.elapsed().as_secs_f64();
        for (k, l) in levels.iter().enumerate() {
            let t = Instant::now();
            std::hint::black_box(sobol_at(*l, std::hint::black_box(7)));
            secs[k + 1] += t.elapsed().as_secs_f64();
        }
    }
    let bounces = (rounds * N) as f64;
    println!("| variant | M Sobol bounces/s (8 numbers each) | over scalar |\n|---|---:|---:|");
    println!("| scalar | {:.1} | 1.00 |", bounces / secs[0] / 1e6);
    for (k, l) in levels.iter().enumerate() {
        println!(
            "| 8 lanes, {l:?} | {:.1} | {:.2} |",
            bounces / secs[k + 1] / 1e6,
            secs[0] / secs[k + 1]
        );
    }
}

#[test]
#[ignore = "benchmark: cargo test --release -p glint-cpu --test lanes_throughput -- --ignored --nocapture --test-threads 1"]
fn bsdf_lanes_throughput() {
    let inp = inputs();
    compare("M BSDF calls/s", 6, || scalar(&inp), |l| wide_at(l, &inp));
}

/// The glTF coated non-metal's opaque part (rough coat, IOR 1.5): the coat
/// at wo, eval, pdf and a sample per (wo, wi, u), scalar against lanes.
#[test]
#[ignore = "benchmark: cargo test --release -p glint-cpu --test lanes_throughput -- --ignored --nocapture --test-threads 1"]
fn coated_lanes_throughput() {
    let inp = inputs();
    compare(
        "M coated (at wo, eval, pdf, sample)/s",
        1,
        || coated_scalar(&inp),
        |l| simd_at!(l, fn(inp: &Inputs) -> usize { coated_wide(inp) }(&inp)),
    );
}

const BASE: Vec3 = Vec3::new(0.8, 0.5, 0.3);

fn coated_scalar(inp: &Inputs) -> usize {
    let (coat, r) = (CoatParams::GLTF_DEFAULT, inp.c.roughness);
    let (mut n, mut acc) = (0, 0.0f32);
    for i in 0..N {
        let (wo, wi, u) = (inp.wo[i], inp.wi[i], inp.u[i]);
        let w = coated::coat_at_wo(BASE, &coat, &r, wo);
        acc += coated::coated_eval_at(BASE, &coat, &r, &w, wo, wi).y
            + coated::coated_pdf_at(&coat, &r, &w, wo, wi);
        if let Some(s) = coated::coated_sample_at(BASE, &coat, &r, &w, wo, inp.u[(i + 1) % N].x, u)
        {
            n += 1;
            acc += s.weight.x + s.pdf;
        }
    }
    std::hint::black_box(acc);
    n
}

#[inline(always)]
fn coated_wide(inp: &Inputs) -> usize {
    let one = Coat::of(BASE, &CoatParams::GLTF_DEFAULT, &inp.c.roughness);
    let c = Coat {
        base: V3::splat(one.base.into()),
        specular: V3::splat(one.specular.into()),
        eta: F32x8::splat(one.eta),
        ax: F32x8::splat(one.ax),
        ay: F32x8::splat(one.ay),
        smooth: Mask8::first(0),
    };
    let (mut n, mut acc) = (0, F32x8::splat(0.0));
    for i in (0..N).step_by(8) {
        let (wo, wi) = (pack3(&inp.wo[i..i + 8]), pack3(&inp.wi[i..i + 8]));
        let uc = F32x8(std::array::from_fn(|k| inp.u[(i + k + 1) % N].x));
        let w = coated::lanes::at_wo(&c, wo.z.abs());
        acc = acc + coated::lanes::opaque_eval(&c, &w, wo, wi).y;
        acc = acc + coated::lanes::opaque_pdf(&c, &w, wo, wi);
        let s = coated::lanes::opaque_sample(&c, &w, wo, uc, pack2(&inp.u[i..i + 8]));
        acc = acc + s.weight.x + s.pdf;
        n += (0..8).filter(|&k| s.valid.test(k)).count();
    }
    std::hint::black_box(acc);
    n
}

/// Time `scalar` against `wide_at` at every SIMD level (each must give the
/// same count), interleaved over 20 rounds, and print calls per second
/// (`per_item` calls for each of the N inputs).
fn compare(
    unit: &str,
    per_item: usize,
    scalar: impl Fn() -> usize,
    wide_at: impl Fn(SimdLevel) -> usize,
) {
    let levels = SimdLevel::available();
    let reference = scalar();
    for l in &levels {
        assert_eq!(wide_at(*l), reference, "{l:?}");
    }
    let rounds = 20;
    let mut secs = vec![0.0f64; 1 + levels.len()];
    for _ in 0..rounds {
        let t = Instant::now();
        std::hint::black_box(scalar());
        secs[0] += t.elapsed().as_secs_f64();
        for (k, l) in levels.iter().enumerate() {
            let t = Instant::now();
            std::hint::black_box(wide_at(*l));
            secs[k + 1] += t.elapsed().as_secs_f64();
        }
    }
    let calls = (rounds * N * per_item) as f64;
    println!("| variant | {unit} | over scalar |\n|---|---:|---:|");
    println!("| scalar | {:.1} | 1.00 |", calls / secs[0] / 1e6);
    for (k, l) in levels.iter().enumerate() {
        println!(
            "| 8 lanes, {l:?} | {:.1} | {:.2} |",
            calls / secs[k + 1] / 1e6,
            secs[0] / secs[k + 1]
        );
    }
}

/// Emitter light samples (the power CDF, the far test, the solid angle
/// and Arvo's sample where near, the emission and density) on the bundled
/// Cornell box from 2^16 random points inside it: one call per point
/// against eight points per call.
#[test]
#[ignore = "benchmark: cargo test --release -p glint-cpu --test lanes_throughput -- --ignored --nocapture --test-threads 1"]
fn emitter_lanes_throughput() {
    use glint_cpu::lights::Lights;
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/cornell.gltf");
    let scene = glint_cpu::loader::load(&path).unwrap();
    let lights = Lights::new(&scene);
    let inp = inputs();
    let p: Vec<Vec3> = (0..N)
        .map(|i| {
            let (a, b) = (inp.u[i], inp.u[(i + 7) % N]);
            Vec3::new(2.0 * a.x - 1.0, 2.0 * a.y, 2.0 * b.x - 1.0)
        })
        .collect();
    let scalar = || {
        let mut n = 0;
        for (i, &p) in p.iter().enumerate() {
            let u = inp.u[(i + 3) % N];
            if let Some(s) = lights.sample(&scene, p, Vec3::Z, 0.0, inp.u[i].y, u) {
                n += 1;
                std::hint::black_box(s);
            }
        }
        n
    };
    compare("M emitter samples/s", 1, scalar, |l| {
        simd_at!(l, fn(lights: &Lights, scene: &glint_cpu::scene::Scene, p: &[Vec3], inp: &Inputs) -> usize {
                let mut n = 0;
                for i in (0..N).step_by(8) {
                    let u = V2 {
                        x: F32x8(std::array::from_fn(|k| inp.u[(i + k + 3) % N].x)),
                        y: F32x8(std::array::from_fn(|k| inp.u[(i + k + 3) % N].y)),
                    };
                    let ui = F32x8(std::array::from_fn(|k| inp.u[i + k].y));
                    let s = lights.sample_emitter_lanes(scene, pack3(&p[i..i + 8]), ui, u, Mask8::first(8));
                    n += (0..8).filter(|&k| s.valid.test(k)).count();
                    std::hint::black_box(s);
                }
                n
            }(&lights, &scene, &p, &inp))
    });
}
