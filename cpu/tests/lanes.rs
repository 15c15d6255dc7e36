//! The wide lanes against the scalar path, per call: every lane-generic
//! function (`bsdf::*::lanes`) run on eight lanes at each SIMD level this
//! CPU has must give, lane by lane, what its scalar form gives on that
//! lane's inputs, bit for bit (the one polynomial sine of both lane types
//! included). Batches
//! mix ordinary inputs with the ones the branches exist for (directions on
//! the horizon or below it, the disk's centre, NaN), and lanes that a
//! caller has masked off hold garbage that must not reach the others. The
//! sampler's lanes are eight paths (pixel, sample, bounce each their own)
//! and must give the scalar sampler's streams bit for bit.

use glam::{Vec2, Vec3};
use glint_cpu::SamplerKind;
use glint_cpu::bsdf::coated::{self, Coat, CoatParams};
use glint_cpu::bsdf::conductor::{self, RoughConductor};
use glint_cpu::bsdf::dielectric::RoughDielectric;
use glint_cpu::bsdf::microfacet::{self, MIN_ALPHA};
use glint_cpu::bsdf::{BsdfSample, LaneSample, SMOOTH_ALPHA_THRESHOLD};
use glint_cpu::bsdf::{ConductorParams, Roughness, Shadowing, diffuse, fresnel, warp};
use glint_cpu::lanes::{F32x8, Lane, Mask8, SimdLevel, U32x8, ULane, V2, V3};
use glint_cpu::lights::LightSample;
use glint_cpu::simd_at;
use glint_cpu::sobol::{self, PathSampler};

/// xorshift32: the tests' own numbers.
struct Rand(u32);

impl Rand {
    fn f(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 17;
        self.0 ^= self.0 << 5;
        (self.0 >> 8) as f32 / 16_777_216.0
    }
    fn dir(&mut self) -> Vec3 {
        let z = 1.0 - 2.0 * self.f();
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = std::f32::consts::TAU * self.f();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }
    /// A GGX alpha of the rough models (above the smooth threshold: a
    /// material below it is the smooth model, decided per material).
    fn alpha(&mut self) -> f32 {
        (2.0 * SMOOTH_ALPHA_THRESHOLD).max(MIN_ALPHA) + self.f() * self.f()
    }
}

/// Lane `i`'s special case, if it has one: 0 ordinary, 1 on the horizon,
/// 2 NaN, 3 straight up, 4 the square's centre (u = 1/2).
fn special(batch: usize, i: usize) -> usize {
    if batch.is_multiple_of(4) {
        0
    } else {
        (batch + i) % 5
    }
}

fn dir_for(r: &mut Rand, kind: usize) -> Vec3 {
    match kind {
        1 => {
            let d = r.dir();
            Vec3::new(d.x, d.y, 0.0).normalize_or(Vec3::X)
        }
        2 => Vec3::new(f32::NAN, 0.3, 0.5),
        3 => Vec3::Z,
        _ => r.dir(),
    }
}

fn u_for(r: &mut Rand, kind: usize) -> Vec2 {
    if kind == 4 {
        Vec2::splat(0.5)
    } else {
        Vec2::new(r.f(), r.f())
    }
}

/// Bit-equal, or both NaN.
fn same(a: f32, b: f32) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

fn same3(a: Vec3, b: Vec3) -> bool {
    (0..3).all(|k| same(a[k], b[k]))
}

const BATCHES: usize = 400;

/// Run `wide` at every SIMD level on 8 lanes made by `inputs(batch, lane)`
/// and compare each lane with `scalar` via `check`.
fn each_level<I, W, S>(
    mut inputs: impl FnMut(usize, usize) -> I,
    wide: impl Fn(SimdLevel, [I; 8]) -> [W; 8],
    scalar: impl Fn(I) -> S,
    check: impl Fn(&W, &S) -> bool,
    name: &str,
) where
    I: Copy + std::fmt::Debug,
    W: std::fmt::Debug,
    S: std::fmt::Debug,
{
    for level in SimdLevel::available() {
        for b in 0..BATCHES {
            let lanes: [I; 8] = std::array::from_fn(|i| inputs(b, i));
            let out = wide(level, lanes);
            for i in 0..8 {
                let s = scalar(lanes[i]);
                assert!(
                    check(&out[i], &s),
                    "{name} at {level:?}, batch {b} lane {i}: inputs {:?}: wide {:?}, scalar {s:?}",
                    lanes[i],
                    out[i]
                );
            }
        }
    }
}

#[inline(always)]
fn v3x8(v: [Vec3; 8]) -> V3<F32x8> {
    v.into()
}

#[inline(always)]
fn lanes3(v: V3<F32x8>) -> [Vec3; 8] {
    std::array::from_fn(|i| v.lane(i))
}

#[inline(always)]
fn lanes1(v: F32x8) -> [f32; 8] {
    v.0
}

/// A wide sample's lanes as scalar samples.
#[inline(always)]
fn samples(s: LaneSample<F32x8>) -> [Option<BsdfSample>; 8] {
    std::array::from_fn(|i| {
        s.valid.test(i).then(|| BsdfSample {
            wi: s.wi.lane(i),
            weight: s.weight.lane(i),
            pdf: s.pdf.0[i],
            delta: s.delta,
            eta: s.eta.0[i],
        })
    })
}

/// Two samples are the same: both none, or the same bits (NaN as NaN).
fn same_sample(w: &Option<BsdfSample>, s: &Option<BsdfSample>) -> bool {
    match (w, s) {
        (None, None) => true,
        (Some(a), Some(b)) => {
            a.delta == b.delta
                && same(a.eta, b.eta)
                && same3(a.wi, b.wi)
                && same3(a.weight, b.weight)
                && same(a.pdf, b.pdf)
        }
        _ => false,
    }
}

/// A microfacet test's lanes: a direction, a second direction (wi or a
/// microfacet normal) and the two alphas.
type Mf = (Vec3, Vec3, f32, f32);

#[inline(always)]
fn split(l: [Mf; 8]) -> (V3<F32x8>, V3<F32x8>, F32x8, F32x8) {
    (
        v3x8(l.map(|x| x.0)),
        v3x8(l.map(|x| x.1)),
        F32x8(l.map(|x| x.2)),
        F32x8(l.map(|x| x.3)),
    )
}

#[test]
fn microfacet_terms_are_the_scalar_bits_in_every_lane() {
    use microfacet::lanes as m;
    let mut r = Rand(0x1234_5678);
    let inputs: Vec<[Mf; 8]> = (0..BATCHES)
        .map(|b| {
            std::array::from_fn(|i| {
                let k = special(b, i);
                (dir_for(&mut r, k), dir_for(&mut r, 0), r.alpha(), r.alpha())
            })
        })
        .collect();
    let at = |b: usize, i: usize| inputs[b][i];
    // One exact term: `$wide` on the lanes and `$scalar` on each lane's
    // (w, v, ax, ay), `sep` the Smith form, must give the same bits.
    macro_rules! term {
        ($name:literal, $sep:expr, |$w:ident, $v:ident, $ax:ident, $ay:ident, $s:ident| $wide:expr, $scalar:expr) => {
            each_level(
                at,
                |lv, l| {
                    simd_at!(lv, fn(l: [Mf; 8], $s: bool) -> [f32; 8] {
                        let ($w, $v, $ax, $ay) = split(l);
                        let _ = (&$w, &$v, $s);
                        lanes1($wide)
                    }(l, $sep))
                },
                |($w, $v, $ax, $ay)| {
                    let ($s, _) = ($sep, (&$w, &$v));
                    let _ = $s;
                    $scalar
                },
                |a, b| same(*a, *b),
                $name,
            )
        };
    }
    term!(
        "ggx_d",
        false,
        |w, v, ax, ay, s| m::ggx_d(v.normalize(), ax, ay),
        microfacet::ggx_d(v.normalize(), ax, ay)
    );
    term!(
        "ggx_g1",
        false,
        |w, v, ax, ay, s| m::ggx_g1(w, ax, ay),
        microfacet::ggx_g1(w, ax, ay)
    );
    term!(
        "ggx_pdf_visible",
        false,
        |w, v, ax, ay, s| m::ggx_pdf_visible(w, v, ax, ay),
        microfacet::ggx_pdf_visible(w, v, ax, ay)
    );
    for sep in [false, true] {
        term!(
            "ggx_g2",
            sep,
            |w, v, ax, ay, s| m::ggx_g2(w, v, ax, ay, s),
            microfacet::ggx_g2(w, v, ax, ay, s)
        );
        term!(
            "ggx_visibility",
            sep,
            |w, v, ax, ay, s| m::ggx_visibility(w, v, ax, ay, s),
            microfacet::ggx_visibility(w, v, ax, ay, s)
        );
    }
    // u from the alphas' fractions: the sample's own numbers per lane.
    each_level(
        at,
        |lv, l| {
            simd_at!(lv, fn(l: [Mf; 8]) -> [Vec3; 8] {
                let (w, _, ax, ay) = split(l);
                let u = V2 { x: F32x8(ax.0.map(|a| (a * 7.0).fract())), y: F32x8(ay.0.map(|a| (a * 5.0).fract())) };
                lanes3(m::ggx_sample_visible(w, ax, ay, u))
            }(l))
        },
        |(w, _, ax, ay)| {
            microfacet::ggx_sample_visible(
                w,
                ax,
                ay,
                Vec2::new((ax * 7.0).fract(), (ay * 5.0).fract()),
            )
        },
        |a, b| same3(*a, *b),
        "ggx_sample_visible",
    );
}

#[test]
fn conductor_fresnel_is_the_scalar_bits_in_every_lane() {
    type Fr = (f32, f32, f32);
    let mut r = Rand(99);
    let mut gen_in = |b: usize, i: usize| -> Fr {
        match special(b, i) {
            1 => (0.0, 1.0, 0.0),
            2 => (f32::NAN, 1.5, 2.0),
            3 => (1.0, 0.2 + 3.0 * r.f(), 5.0 * r.f()),
            _ => (r.f() * 1.2 - 0.1, 0.1 + 3.0 * r.f(), 5.0 * r.f()),
        }
    };
    let inputs: Vec<[Fr; 8]> = (0..BATCHES)
        .map(|b| std::array::from_fn(|i| gen_in(b, i)))
        .collect();
    each_level(
        |b, i| inputs[b][i],
        |lv, l| {
            simd_at!(lv, fn(l: [Fr; 8]) -> [f32; 8] {
                lanes1(fresnel::lanes::fresnel_conductor_channel(
                    F32x8(l.map(|x| x.0)),
                    F32x8(l.map(|x| x.1)),
                    F32x8(l.map(|x| x.2)),
                ))
            }(l))
        },
        |(c, eta, k)| fresnel::fresnel_conductor_channel(c, eta, k),
        |a, b| same(*a, *b),
        "fresnel_conductor_channel",
    );
}

/// A Lambertian test's lanes: rho, wo, wi, u.
type Df = (Vec3, Vec3, Vec3, Vec2);

#[test]
fn diffuse_lanes_are_the_scalar_lambertian() {
    use diffuse::lanes as d;
    let mut r = Rand(7);
    let inputs: Vec<[Df; 8]> = (0..BATCHES)
        .map(|b| {
            std::array::from_fn(|i| {
                let k = special(b, i);
                let rho = Vec3::new(r.f(), r.f(), r.f());
                (rho, dir_for(&mut r, k), r.dir(), u_for(&mut r, k))
            })
        })
        .collect();
    let at = |b: usize, i: usize| inputs[b][i];
    each_level(
        at,
        |lv, l| {
            simd_at!(lv, fn(l: [Df; 8]) -> [Vec3; 8] {
                lanes3(d::diffuse_eval(v3x8(l.map(|x| x.0)), v3x8(l.map(|x| x.1)), v3x8(l.map(|x| x.2))))
            }(l))
        },
        |(rho, wo, wi, _)| diffuse::diffuse_eval(rho, wo, wi),
        |a, b| same3(*a, *b),
        "diffuse_eval",
    );
    each_level(
        at,
        |lv, l| {
            simd_at!(lv, fn(l: [Df; 8]) -> [f32; 8] {
                lanes1(d::diffuse_pdf(v3x8(l.map(|x| x.1)), v3x8(l.map(|x| x.2))))
            }(l))
        },
        |(_, wo, wi, _)| diffuse::diffuse_pdf(wo, wi),
        |a, b| same(*a, *b),
        "diffuse_pdf",
    );
    each_level(
        at,
        |lv, l| {
            simd_at!(lv, fn(l: [Df; 8]) -> [Option<BsdfSample>; 8] {
                samples(d::diffuse_sample(v3x8(l.map(|x| x.0)), v3x8(l.map(|x| x.1)), l.map(|x| x.3).into()))
            }(l))
        },
        |(rho, wo, _, u)| diffuse::diffuse_sample(rho, wo, u),
        same_sample,
        "diffuse_sample",
    );
    each_level(
        at,
        |lv, l| {
            simd_at!(lv, fn(l: [Df; 8]) -> [Vec3; 8] {
                lanes3(warp::lanes::square_to_cosine_hemisphere(l.map(|x| x.3).into()))
            }(l))
        },
        |(_, _, _, u)| warp::square_to_cosine_hemisphere(u),
        |a, b| same3(*a, *b),
        "square_to_cosine_hemisphere",
    );
}

fn conductor_params(r: &mut Rand, separable: bool) -> ConductorParams {
    ConductorParams {
        eta: Vec3::new(0.2 + r.f(), 0.4 + r.f(), 1.0 + r.f()),
        k: Vec3::new(3.0 * r.f(), 3.0 * r.f(), 3.0 * r.f()),
        specular_reflectance: Vec3::new(r.f(), r.f(), r.f()),
        roughness: Roughness {
            alpha_u: r.alpha(),
            alpha_v: r.alpha(),
            shadowing: if separable {
                Shadowing::Separable
            } else {
                Shadowing::Correlated
            },
            multiscatter: false,
        },
    }
}

/// Eight conductors' parameters as lanes.
fn conductor_lanes(c: [ConductorParams; 8]) -> RoughConductor<F32x8> {
    let p = c.map(|c| RoughConductor::of(&c));
    RoughConductor {
        eta: v3x8(p.map(|p| p.eta.into())),
        k: v3x8(p.map(|p| p.k.into())),
        specular_reflectance: v3x8(p.map(|p| p.specular_reflectance.into())),
        ax: F32x8(p.map(|p| p.ax)),
        ay: F32x8(p.map(|p| p.ay)),
        separable: p[0].separable,
    }
}

/// A conductor test's lanes: the BSDF, wo, wi, u.
type Cd = (ConductorParams, Vec3, Vec3, Vec2);

#[inline(always)]
fn cd_eval(l: [Cd; 8]) -> [Vec3; 8] {
    let c = conductor_lanes(l.map(|x| x.0));
    lanes3(conductor::lanes::rough_eval(
        &c,
        v3x8(l.map(|x| x.1)),
        v3x8(l.map(|x| x.2)),
    ))
}

#[inline(always)]
fn cd_pdf(l: [Cd; 8]) -> [f32; 8] {
    let c = conductor_lanes(l.map(|x| x.0));
    lanes1(conductor::lanes::rough_pdf(
        &c,
        v3x8(l.map(|x| x.1)),
        v3x8(l.map(|x| x.2)),
    ))
}

#[inline(always)]
fn cd_sample(l: [Cd; 8]) -> [Option<BsdfSample>; 8] {
    let c = conductor_lanes(l.map(|x| x.0));
    samples(conductor::lanes::rough_sample(
        &c,
        v3x8(l.map(|x| x.1)),
        l.map(|x| x.3).into(),
    ))
}

#[test]
fn rough_conductor_lanes_are_the_scalar_bsdf() {
    for sep in [false, true] {
        let mut r = Rand(31 + sep as u32);
        let inputs: Vec<[Cd; 8]> = (0..BATCHES)
            .map(|b| {
                std::array::from_fn(|i| {
                    let k = special(b, i);
                    let c = conductor_params(&mut r, sep);
                    (c, dir_for(&mut r, k), r.dir(), u_for(&mut r, k))
                })
            })
            .collect();
        let at = |b: usize, i: usize| inputs[b][i];
        each_level(
            at,
            |lv, l| simd_at!(lv, fn(l: [Cd; 8]) -> [Vec3; 8] { cd_eval(l) }(l)),
            |(p, wo, wi, _)| conductor::conductor_eval(&p, wo, wi),
            |a, b| same3(*a, *b),
            "conductor_eval",
        );
        each_level(
            at,
            |lv, l| simd_at!(lv, fn(l: [Cd; 8]) -> [f32; 8] { cd_pdf(l) }(l)),
            |(p, wo, wi, _)| conductor::conductor_pdf(&p, wo, wi),
            |a, b| same(*a, *b),
            "conductor_pdf",
        );
        each_level(
            at,
            |lv, l| simd_at!(lv, fn(l: [Cd; 8]) -> [Option<BsdfSample>; 8] { cd_sample(l) }(l)),
            |(p, wo, _, u)| conductor::conductor_sample(&p, wo, u),
            same_sample,
            "conductor_sample",
        );
    }
}

/// A coated test's lanes: base colour, coat, roughness, wo, wi, uc, u.
type Ct = (Vec3, CoatParams, Roughness, Vec3, Vec3, f32, Vec2);

/// Eight coated non-metals' parameters as lanes.
fn coat_lanes(l: &[Ct; 8]) -> Coat<F32x8> {
    let c = l.map(|x| Coat::of(x.0, &x.1, &x.2));
    Coat {
        base: v3x8(c.map(|c| c.base.into())),
        specular: v3x8(c.map(|c| c.specular.into())),
        eta: F32x8(c.map(|c| c.eta)),
        ax: F32x8(c.map(|c| c.ax)),
        ay: F32x8(c.map(|c| c.ay)),
        smooth: Mask8(c.map(|c| if c.smooth { !0 } else { 0 })),
    }
}

/// eval, pdf and sample of eight coated non-metals' opaque part.
#[inline(always)]
fn ct_all(l: [Ct; 8]) -> ([Vec3; 8], [f32; 8], [Option<BsdfSample>; 8]) {
    let c = coat_lanes(&l);
    let (wo, wi) = (v3x8(l.map(|x| x.3)), v3x8(l.map(|x| x.4)));
    let w = coated::lanes::at_wo(&c, wo.z.abs());
    let eval = lanes3(coated::lanes::opaque_eval(&c, &w, wo, wi));
    let pdf = lanes1(coated::lanes::opaque_pdf(&c, &w, wo, wi));
    let s = coated::lanes::opaque_sample(&c, &w, wo, F32x8(l.map(|x| x.5)), l.map(|x| x.6).into());
    (eval, pdf, samples(s))
}

fn coated_case(r: &mut Rand, kind: usize, smooth: bool) -> Ct {
    let coat = CoatParams {
        eta: 1.0 + 1.5 * r.f(),
        specular: if r.f() < 0.5 {
            Vec3::ONE
        } else {
            Vec3::new(r.f(), r.f(), r.f())
        },
        ..CoatParams::GLTF_DEFAULT
    };
    let alpha = if smooth { 0.0 } else { r.alpha() };
    let rough = Roughness {
        alpha_u: alpha,
        alpha_v: if r.f() < 0.5 { alpha } else { r.alpha() },
        shadowing: Shadowing::Correlated,
        multiscatter: false,
    };
    let base = Vec3::new(r.f(), r.f(), r.f());
    (
        base,
        coat,
        rough,
        dir_for(r, kind),
        r.dir(),
        r.f(),
        u_for(r, kind),
    )
}

/// The glTF coated non-metal's opaque part (the coat's albedo tables, the
/// coat and base lobes, their mixture) in lanes: eval and pdf are the
/// scalar bits in every lane, and so are the samples; a lane whose smooth
/// coat picks its mirror (a
/// delta, the scalar code's alone) is not valid in lanes. Lanes with NaN
/// inputs and masked-off lanes of garbage leave the others' bits alone.
#[test]
fn coated_lanes_are_the_scalar_bsdf() {
    let mut r = Rand(53);
    let inputs: Vec<[Ct; 8]> = (0..BATCHES)
        .map(|b| {
            // Batches all rough, all smooth and mixed: the lookups' three ways.
            std::array::from_fn(|i| {
                let smooth = match b % 4 {
                    0 => false,
                    1 => true,
                    _ => (b + i) % 7 == 3,
                };
                coated_case(&mut r, special(b, i), smooth)
            })
        })
        .collect();
    let run = |lv: SimdLevel, l: [Ct; 8]| {
        simd_at!(lv, fn(l: [Ct; 8]) -> ([Vec3; 8], [f32; 8], [Option<BsdfSample>; 8]) {
            ct_all(l)
        }(l))
    };
    let at = |b: usize, i: usize| inputs[b][i];
    each_level(
        at,
        |lv, l| run(lv, l).0,
        |(base, coat, rough, wo, wi, _, _)| coated::coated_eval(base, &coat, &rough, wo, wi),
        |a, b| same3(*a, *b),
        "coated eval",
    );
    each_level(
        at,
        |lv, l| run(lv, l).1,
        |(base, coat, rough, wo, wi, _, _)| coated::coated_pdf(base, &coat, &rough, wo, wi),
        |a, b| same(*a, *b),
        "coated pdf",
    );
    each_level(
        at,
        |lv, l| run(lv, l).2,
        |(base, coat, rough, wo, _, uc, u)| coated::coated_sample(base, &coat, &rough, wo, uc, u),
        |a, b| match b {
            Some(s) if s.delta => a.is_none(),
            _ => same_sample(a, b),
        },
        "coated sample",
    );
    // The smooth coats' mirrors were in the batches, and most samples valid.
    let (mut delta, mut valid) = (0, 0);
    for l in &inputs {
        for x in l {
            match coated::coated_sample(x.0, &x.1, &x.2, x.3, x.5, x.6) {
                Some(s) if s.delta => delta += 1,
                Some(_) => valid += 1,
                None => {}
            }
        }
    }
    assert!(
        delta > 30 && valid > 1500,
        "{delta} mirrors, {valid} rough samples"
    );
    // Masked-off lanes of garbage: the live lanes' bits are unchanged.
    for level in SimdLevel::available() {
        for l in inputs.iter().take(100) {
            let mut junk = *l;
            for x in &mut junk[5..] {
                x.0 = Vec3::splat(f32::NAN);
                x.1.eta = f32::INFINITY;
                x.3 = Vec3::new(f32::NAN, f32::INFINITY, -0.0);
                x.6 = Vec2::new(f32::NAN, 1e30);
            }
            let (a, b) = (run(level, *l), run(level, junk));
            for i in 0..5 {
                assert!(same3(a.0[i], b.0[i]) && same(a.1[i], b.1[i]), "lane {i}");
                assert_eq!(format!("{:?}", a.2[i]), format!("{:?}", b.2[i]), "lane {i}");
            }
        }
    }
}

/// Lanes a caller has masked off may hold anything (NaN, infinities, the
/// previous path's leftovers): the live lanes' results are the same bits.
#[test]
fn masked_off_lanes_do_not_reach_the_live_ones() {
    let mut r = Rand(5);
    let live = Mask8::first(5);
    let run = |lv: SimdLevel, l: [Cd; 8]| {
        simd_at!(lv, fn(l: [Cd; 8]) -> ([Option<BsdfSample>; 8], [Option<BsdfSample>; 8]) {
            let wo = v3x8(l.map(|x| x.1));
            (cd_sample(l), samples(diffuse::lanes::diffuse_sample(wo, wo, l.map(|x| x.3).into())))
        }(l))
    };
    for level in SimdLevel::available() {
        for _ in 0..BATCHES {
            let l: [Cd; 8] = std::array::from_fn(|_| {
                (
                    conductor_params(&mut r, false),
                    r.dir(),
                    r.dir(),
                    Vec2::new(r.f(), r.f()),
                )
            });
            let mut junk = l;
            for x in &mut junk[5..] {
                x.0.eta = Vec3::splat(f32::NAN);
                x.0.k = Vec3::splat(f32::INFINITY);
                x.1 = Vec3::new(f32::NAN, f32::INFINITY, -0.0);
                x.3 = Vec2::new(f32::NAN, 1e30);
            }
            let (a, da) = run(level, l);
            let (b, db) = run(level, junk);
            for i in (0..8).filter(|&i| live.test(i)) {
                assert_eq!(a[i], b[i], "conductor lane {i} at {level:?}");
                assert_eq!(da[i], db[i], "diffuse lane {i} at {level:?}");
            }
        }
    }
}

/// Every SIMD level gives the same bits (the lanes are IEEE arithmetic,
/// whatever the instruction width).
#[test]
fn simd_levels_agree_bit_for_bit() {
    let mut r = Rand(77);
    for _ in 0..BATCHES {
        let l: [Cd; 8] = std::array::from_fn(|_| {
            (
                conductor_params(&mut r, false),
                r.dir(),
                r.dir(),
                Vec2::new(r.f(), r.f()),
            )
        });
        let outs: Vec<_> = SimdLevel::available()
            .into_iter()
            .map(|lv| simd_at!(lv, fn(l: [Cd; 8]) -> [Option<BsdfSample>; 8] { cd_sample(l) }(l)))
            .collect();
        for o in &outs[1..] {
            assert_eq!(o, &outs[0]);
        }
    }
}

/// The lanes' sine and cosine (one polynomial for both lane types) are
/// within 2e-7 of libm over the angles the samplers draw, and eight lanes
/// at every SIMD level are the one-lane type's bits.
#[test]
fn lane_sine_is_libm_within_its_bound_and_one_formula() {
    for level in SimdLevel::available() {
        let worst = simd_at!(level, fn() -> f32 {
            let mut worst = 0.0f32;
            for j in 0..5_000 {
                let x = F32x8(std::array::from_fn(|i| {
                    (j * 8 + i) as f32 * (2.0 * std::f32::consts::TAU / 40_000.0) - std::f32::consts::TAU
                }));
                let (s, c) = x.sin_cos();
                for i in 0..8 {
                    let (ls, lc) = Lane::sin_cos(x.0[i]);
                    assert!(same(s.0[i], ls) && same(c.0[i], lc), "{}", x.0[i]);
                    let (rs, rc) = x.0[i].sin_cos();
                    worst = worst.max((s.0[i] - rs).abs()).max((c.0[i] - rc).abs());
                }
            }
            worst
        }());
        assert!(worst <= 2e-7, "{level:?}: {worst:e}");
    }
}

/// One sampler tuple per lane: (seed key, pixel, sample, bounce).
type St = (u32, u32, u32, u32);

#[inline(always)]
fn u32x8(l: [St; 8], f: impl Fn(St) -> u32) -> U32x8 {
    U32x8(l.map(f))
}

/// The sampler's numbers for eight paths at once (each lane its own pixel,
/// sample index, with blocks past 2^16, and bounce) are the scalar
/// sampler's bits: the pixel pair, a bounce's eight numbers, and `pcg4d`.
#[test]
fn sampler_lanes_are_the_scalar_streams_bit_for_bit() {
    let mut r = Rand(2024);
    let mut next = move || {
        r.f();
        r.0
    };
    let inputs: Vec<[St; 8]> = (0..BATCHES)
        .map(|_| {
            std::array::from_fn(|_| {
                let sample = if next() % 4 == 0 {
                    next()
                } else {
                    next() % 4096
                };
                (next(), next() % (1 << 20), sample, next() % 12)
            })
        })
        .collect();
    let at = |b: usize, i: usize| inputs[b][i];
    each_level(
        at,
        |lv, l| {
            simd_at!(lv, fn(l: [St; 8]) -> [[f32; 8]; 8] {
                let (k, p, s, b) = (u32x8(l, |x| x.0), u32x8(l, |x| x.1), u32x8(l, |x| x.2), u32x8(l, |x| x.3));
                let n = sobol::lanes::bounce(k, p, s, b);
                let v = [n.light_cat, n.light_idx, n.light.x, n.light.y, n.bsdf_lobe, n.bsdf.x, n.bsdf.y, n.rr];
                std::array::from_fn(|i| v.map(|x| x.0[i]))
            }(l))
        },
        |(k, p, s, b)| {
            let mut ps = PathSampler::new(SamplerKind::Sobol, k, p, s);
            for _ in 0..b {
                ps.bounce();
            }
            let n = ps.bounce();
            [
                n.light_cat,
                n.light_idx,
                n.light.x,
                n.light.y,
                n.bsdf_lobe,
                n.bsdf.x,
                n.bsdf.y,
                n.rr,
            ]
        },
        |a, b| a.iter().zip(b).all(|(x, y)| same(*x, *y)),
        "sobol bounce",
    );
    each_level(
        at,
        |lv, l| {
            simd_at!(lv, fn(l: [St; 8]) -> [Vec2; 8] {
                let (k, p, s) = (u32x8(l, |x| x.0), u32x8(l, |x| x.1), u32x8(l, |x| x.2));
                let px = sobol::lanes::sobol_2d(k, p, s, U32x8::splat(0));
                std::array::from_fn(|i| Vec2::new(px.x.0[i], px.y.0[i]))
            }(l))
        },
        |(k, p, s, _)| PathSampler::new(SamplerKind::Sobol, k, p, s).pixel_2d(),
        |a, b| same(a.x, b.x) && same(a.y, b.y),
        "sobol pixel pair",
    );
    each_level(
        at,
        |lv, l| {
            simd_at!(lv, fn(l: [St; 8]) -> [[u32; 4]; 8] {
                let h = glint_cpu::sampling::lanes::pcg4d([u32x8(l, |x| x.0), u32x8(l, |x| x.1), u32x8(l, |x| x.2), u32x8(l, |x| x.3)]);
                std::array::from_fn(|i| h.map(|v| v.0[i]))
            }(l))
        },
        |(k, p, s, b)| glint_cpu::sampling::pcg4d([k, p, s, b]),
        |a, b| a == b,
        "pcg4d",
    );
}

/// A pixel's samples drawn in batches of eight ([`sobol::SampleBatch`]:
/// each bounce wide where enough of the wave's paths reach it, one path at
/// a time past that, generic lanes where a batch straddles two blocks of
/// 2^16 samples) are `PathSampler::new`'s numbers bit for bit, at every
/// SIMD level, however deep each path goes.
#[test]
fn batched_samples_are_the_scalar_sampler_s() {
    let mut r = Rand(11);
    let starts = [0u32, 8, 65_528, 65_532, 131_070, 4_000_000_000];
    for level in SimdLevel::available() {
        let mut batch = sobol::SampleBatch::new(level);
        for (pi, pixel) in [0u32, 1, 977, 1 << 20].into_iter().enumerate() {
            let key = 0x5eed + pi as u32;
            for &start in &starts {
                // Three batches in a row, the count of live paths varying.
                for k in 0..3u32 {
                    let first = start.wrapping_add(8 * k);
                    batch.reset(key, pixel, first);
                    let live = if k == 1 { 3 } else { 8 };
                    let depth: [u32; 8] = std::array::from_fn(|_| (r.f() * r.f() * 12.0) as u32);
                    let mut paths: Vec<_> = (0..live)
                        .map(|lane| {
                            let s = first.wrapping_add(lane);
                            PathSampler::new(SamplerKind::Sobol, key, pixel, s)
                        })
                        .collect();
                    for (lane, b) in paths.iter_mut().enumerate() {
                        assert_eq!(
                            batch.pixel_2d(lane),
                            b.pixel_2d(),
                            "{level:?} pixel {pixel} lane {lane}"
                        );
                    }
                    // Bounce by bounce, for the paths that reach it.
                    for d in 0..12 {
                        let mask = (0..live as usize)
                            .filter(|&lane| depth[lane] > d)
                            .fold(0u8, |m, lane| m | 1 << lane);
                        let got = batch.bounces(d, mask);
                        for (lane, b) in paths.iter_mut().enumerate() {
                            if mask & (1 << lane) != 0 {
                                assert_eq!(
                                    got.lane(lane),
                                    b.bounce(),
                                    "{level:?} pixel {pixel} lane {lane} bounce {d}"
                                );
                            }
                        }
                    }
                }
            }
        }
    }
}

/// A render through the waves (a pixel's eight samples traced side by
/// side, `PathTracer::trace_wave`) and the batched sampler is the
/// one-path-at-a-time render (`PathTracer::sample`, each sample's own
/// sampler) bit for bit, with the same rays, at every SIMD level, on every
/// bundled scene, waves cut short included (21 spp: 8 + 8 + 5), with depth
/// limits, a first sample off the batches' grid, no light sampling and the
/// independent sampler, and under a background, with the vertices shaded
/// one at a time and, where the lanes know the model, in lanes
/// (`PathTracer::wide_shading`): the wave, the wide sampler and the wide
/// vertices change the speed, not the image.
#[test]
fn batched_render_is_the_unbatched_render_bit_for_bit() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets");
    let mut names: Vec<_> = std::fs::read_dir(&root)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.ends_with(".gltf") || n.ends_with(".glb"))
        .collect();
    names.sort();
    assert!(names.len() >= 9, "the bundled scenes: {names:?}");
    let base = glint_cpu::RenderOptions {
        spp: 21,
        ..glint_cpu::RenderOptions::new(24, 16)
    };
    // The default, and waves that stop early (depth limits), start off the
    // batch grid (sample_start) and draw no light samples.
    let variants = [
        base.clone(),
        glint_cpu::RenderOptions {
            spp: 11,
            max_depth: 1,
            sample_start: 5,
            ..base.clone()
        },
        glint_cpu::RenderOptions {
            spp: 9,
            max_depth: 3,
            seed: 7,
            nee: false,
            ..base.clone()
        },
        glint_cpu::RenderOptions {
            spp: 10,
            sampler: glint_cpu::film::SamplerKind::Independent,
            ..base.clone()
        },
    ];
    for name in &names {
        let scene = glint_cpu::loader::load(&root.join(name)).unwrap();
        // And the scene under a background (a light sampled lane by lane
        // in the wide vertices, its frame the BSDF's side or none for a
        // transmitting one), in the default variant.
        let mut lit = scene.clone();
        lit.background += Vec3::new(0.3, 0.4, 0.5);
        let lit_variant = [(&lit, &variants[0])];
        for (((scene, opts), level), wide) in variants
            .iter()
            .map(|o| (&scene, o))
            .chain(lit_variant)
            .flat_map(|o| SimdLevel::available().into_iter().map(move |l| (o, l)))
            .flat_map(|c| [(c, false), (c, true)])
        {
            let mut pt = glint_cpu::PathTracer::new(scene, opts).unwrap();
            pt.simd = level;
            pt.wide_shading = wide;
            let (film, stats) = pt.render(opts.spp, &|_, _| {});
            let mut rays = 0;
            for y in 0..16 {
                for x in 0..24 {
                    let first = opts.sample_start;
                    let sum = (first..first + opts.spp).fold(Vec3::ZERO, |acc, s| {
                        let l = pt.sample(x, y, s, &mut rays);
                        acc + if l.is_finite() { l } else { Vec3::ZERO }
                    });
                    let got = film.sum[film.index(x, y)];
                    assert_eq!(
                        got, sum,
                        "{name} {opts:?} at {level:?}, wide shading {wide}, pixel ({x}, {y})"
                    );
                }
            }
            assert_eq!(
                stats.rays, rays,
                "{name} {opts:?} at {level:?}, wide {wide}"
            );
        }
    }
}

/// A dielectric test's lanes: eta, alphas, wo, wi, uc, u.
type Dl = (f32, f32, f32, Vec3, Vec3, f32, Vec2);

#[inline(always)]
fn dl_lanes(l: [Dl; 8], separable: bool) -> RoughDielectric<F32x8> {
    RoughDielectric {
        eta: F32x8(l.map(|x| x.0)),
        ax: F32x8(l.map(|x| x.1)),
        ay: F32x8(l.map(|x| x.2)),
        separable,
    }
}

fn dl_roughness(x: &Dl, separable: bool) -> Roughness {
    Roughness {
        alpha_u: x.1,
        alpha_v: x.2,
        shadowing: if separable {
            Shadowing::Separable
        } else {
            Shadowing::Correlated
        },
        multiscatter: false,
    }
}

/// The dielectric (rough: eval, pdf, sample; smooth: sample) and its
/// Fresnel term and refraction, lane by lane against the scalar forms,
/// from both sides of the interface, with eta below and above 1 (total
/// internal reflection included).
#[test]
fn dielectric_lanes_are_the_scalar_bsdf() {
    use glint_cpu::bsdf::dielectric::{self, lanes as dl};
    for sep in [false, true] {
        let mut r = Rand(404 + sep as u32);
        let inputs: Vec<[Dl; 8]> = (0..BATCHES)
            .map(|b| {
                std::array::from_fn(|i| {
                    let k = special(b, i);
                    let eta = if r.f() < 0.3 {
                        0.5 + 0.45 * r.f()
                    } else {
                        1.05 + 1.5 * r.f()
                    };
                    let wo = dir_for(&mut r, k);
                    // wi near the refraction of wo half the time (a
                    // transmission lobe to evaluate), anywhere otherwise.
                    let jitter = r.dir();
                    let wi = match fresnel::refract_dir(wo, Vec3::Z, eta) {
                        Some((t, _)) if r.f() < 0.5 => (t + 0.2 * jitter).normalize(),
                        _ => r.dir(),
                    };
                    (eta, r.alpha(), r.alpha(), wo, wi, r.f(), u_for(&mut r, k))
                })
            })
            .collect();
        let at = |b: usize, i: usize| inputs[b][i];
        each_level(
            at,
            |lv, l| {
                simd_at!(lv, fn(l: [Dl; 8], sep: bool) -> [f32; 8] {
                    lanes1(dl::rough_eval(&dl_lanes(l, sep), v3x8(l.map(|x| x.3)), v3x8(l.map(|x| x.4))))
                }(l, sep))
            },
            |x| dielectric::dielectric_eval(x.0, &dl_roughness(&x, sep), x.3, x.4).x,
            |a, b| same(*a, *b),
            "dielectric_eval",
        );
        each_level(
            at,
            |lv, l| {
                simd_at!(lv, fn(l: [Dl; 8], sep: bool) -> [f32; 8] {
                    lanes1(dl::rough_pdf(&dl_lanes(l, sep), v3x8(l.map(|x| x.3)), v3x8(l.map(|x| x.4))))
                }(l, sep))
            },
            |x| dielectric::dielectric_pdf(x.0, &dl_roughness(&x, sep), x.3, x.4),
            |a, b| same(*a, *b),
            "dielectric_pdf",
        );
        each_level(
            at,
            |lv, l| {
                simd_at!(lv, fn(l: [Dl; 8], sep: bool) -> [Option<BsdfSample>; 8] {
                    let s = dl::rough_sample(&dl_lanes(l, sep), v3x8(l.map(|x| x.3)), F32x8(l.map(|x| x.5)), l.map(|x| x.6).into());
                    samples(s)
                }(l, sep))
            },
            |x| dielectric::dielectric_sample(x.0, &dl_roughness(&x, sep), x.3, x.5, x.6),
            same_sample,
            "dielectric_sample",
        );
        each_level(
            at,
            |lv, l| {
                simd_at!(lv, fn(l: [Dl; 8]) -> [Option<BsdfSample>; 8] {
                    samples(dl::smooth_sample(F32x8(l.map(|x| x.0)), v3x8(l.map(|x| x.3)), F32x8(l.map(|x| x.5))))
                }(l))
            },
            |x| dielectric::dielectric_sample(x.0, &Roughness::SMOOTH, x.3, x.5, x.6),
            |a, b| match (a, b) {
                (Some(a), Some(b)) => {
                    same3(a.wi, b.wi)
                        && same3(a.weight, b.weight)
                        && same(a.pdf, b.pdf)
                        && same(a.eta, b.eta)
                        && a.delta
                        && b.delta
                }
                (a, b) => a.is_none() && b.is_none(),
            },
            "dielectric smooth sample",
        );
        each_level(
            at,
            |lv, l| {
                simd_at!(lv, fn(l: [Dl; 8]) -> [(f32, Option<(Vec3, f32)>); 8] {
                    let (eta, wo, wi) = (F32x8(l.map(|x| x.0)), v3x8(l.map(|x| x.3)), v3x8(l.map(|x| x.4)));
                    let f = fresnel::lanes::fresnel_dielectric(wo.z, eta);
                    let (ok, wt, e) = fresnel::lanes::refract_dir(wo, wi.normalize(), eta);
                    std::array::from_fn(|i| (f.0[i], ok.test(i).then(|| (wt.lane(i), e.0[i]))))
                }(l))
            },
            |x| {
                (
                    fresnel::fresnel_dielectric(x.3.z, x.0),
                    fresnel::refract_dir(x.3, x.4.normalize(), x.0),
                )
            },
            |a, b| {
                same(a.0, b.0)
                    && match (a.1, b.1) {
                        (Some((w, e)), Some((v, f))) => same3(w, v) && same(e, f),
                        (x, y) => x.is_none() && y.is_none(),
                    }
            },
            "fresnel_dielectric and refract_dir",
        );
    }
}

/// One emitter light sample's inputs: the shading point, the index number
/// and the point's pair.
type Em = (Vec3, f32, Vec2);

/// Two light samples are the same: both none, or the same bits.
fn same_light(w: &Option<LightSample>, s: &Option<LightSample>) -> bool {
    match (w, s) {
        (None, None) => true,
        (Some(a), Some(b)) => {
            a.delta == b.delta
                && same3(a.wi, b.wi)
                && same(a.dist, b.dist)
                && same3(a.weight, b.weight)
                && same(a.pdf, b.pdf)
        }
        _ => false,
    }
}

/// The emitter light sample (the power CDF, the far test, the solid angle
/// and Arvo's spherical triangle where near, the uniform triangle where
/// far, the emission and the density) in lanes on the bundled Cornell box
/// (two emitter triangles) is the scalar sample's bits in every lane, by
/// solid angle and by area alike: points spread through the box, in the
/// light's own plane (the height test), on the light, beside it (the solid
/// angle's upper bound), and lanes of NaN; lanes masked off are not valid
/// and leave the others alone (the same lanes with garbage in the masked
/// ones give the same bits).
#[test]
fn emitter_samples_in_lanes_are_the_scalar_ones() {
    use glint_cpu::film::LightSampling;
    use glint_cpu::lights::Lights;
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/cornell.gltf");
    let scene = glint_cpu::loader::load(&path).unwrap();
    let ceiling = scene
        .triangles
        .iter()
        .find(|t| t.light != glint_cpu::scene::NO_LIGHT)
        .unwrap()
        .p0[1];
    let mut r = Rand(77);
    let point = |r: &mut Rand, kind: usize| match kind {
        1 => Vec3::new(r.f() - 0.5, ceiling, r.f() - 0.5),
        2 => Vec3::new(f32::NAN, 1.0, 0.0),
        3 => Vec3::new(0.2 * r.f() - 0.1, ceiling - 1e-3 * r.f(), 0.2 * r.f() - 0.1),
        4 => Vec3::new(0.0, ceiling - 0.02 - 0.2 * r.f(), 0.0),
        _ => Vec3::new(2.0 * r.f() - 1.0, 2.0 * r.f(), 2.0 * r.f() - 1.0),
    };
    let inputs: Vec<[Em; 8]> = (0..BATCHES)
        .map(|b| {
            std::array::from_fn(|i| {
                let p = point(&mut r, special(b, i));
                (p, r.f(), Vec2::new(r.f(), r.f()))
            })
        })
        .collect();
    let (mut by_angle, mut valid) = (0, 0);
    for sampling in [LightSampling::SolidAngle, LightSampling::Area] {
        let lights = Lights {
            sampling,
            ..Lights::new(&scene)
        };
        let run = |lv: SimdLevel, l: [Em; 8], mask: Mask8| {
            simd_at!(lv, fn(lights: &Lights, scene: &glint_cpu::scene::Scene, l: [Em; 8], mask: Mask8) -> [Option<LightSample>; 8] {
                let s = lights.sample_emitter_lanes(
                    scene,
                    v3x8(l.map(|x| x.0)),
                    F32x8(l.map(|x| x.1)),
                    l.map(|x| x.2).into(),
                    mask,
                );
                std::array::from_fn(|k| s.lane(k))
            }(&lights, &scene, l, mask))
        };
        let scalar = |(p, ui, u): Em| lights.sample(&scene, p, Vec3::Z, 0.0, ui, u);
        each_level(
            |b, i| inputs[b][i],
            |lv, l| run(lv, l, Mask8::first(8)),
            scalar,
            same_light,
            "sample_emitter_lanes",
        );
        // Lanes 5..8 masked off, holding garbage: not valid, and the live
        // lanes keep their bits.
        for level in SimdLevel::available() {
            for l in &inputs {
                let mut g = *l;
                for x in &mut g[5..] {
                    *x = (Vec3::splat(f32::NAN), f32::NAN, Vec2::splat(1e30));
                }
                let (a, b) = (
                    run(level, *l, Mask8::first(5)),
                    run(level, g, Mask8::first(5)),
                );
                for k in 0..8 {
                    assert!(same_light(&a[k], &b[k]));
                    if k >= 5 {
                        assert!(a[k].is_none());
                    }
                }
            }
        }
        // Both ways of picking the point were exercised.
        for l in &inputs {
            for &(p, ui, u) in l {
                valid += usize::from(lights.sample(&scene, p, Vec3::Z, 0.0, ui, u).is_some());
                by_angle += usize::from(
                    sampling == LightSampling::SolidAngle && {
                        let e = &lights.emitters[0];
                        let v = scene.triangles[e.tri as usize].vertices();
                        glint_cpu::lights::spherical_sampling_angle(v, e, p).is_some()
                    },
                );
            }
        }
    }
    assert!(
        valid > 3000 && by_angle > 300,
        "{valid} valid, {by_angle} by solid angle"
    );
}

/// A punctual or background light test's lanes: the point, the light
/// index number, the background's axis and the direction pair.
type Pb = (Vec3, f32, Vec3, Vec2);

/// The punctual light samples (one light of each kind, or one light alone:
/// the splat form) and the constant background's (about an axis, or over
/// the sphere where the axis is zero) in lanes are the scalar
/// `Lights::sample`'s bits in every lane, at every SIMD level: points
/// spread about the lights, on a point light itself (no sample), behind
/// and inside the spot's cone and on its ramp, lanes of NaN, and lanes
/// masked off holding garbage that are not valid and leave the others
/// alone.
#[test]
fn punctual_and_background_samples_in_lanes_are_the_scalar_ones() {
    use glint_cpu::lights::{CategoryProbs, GpuLight, Lights};
    use glint_cpu::scene::PunctualLight;
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/cornell.gltf");
    let scene = glint_cpu::loader::load(&path).unwrap();
    let spot_at = Vec3::new(0.0, 1.5, 0.0);
    let all: Vec<GpuLight> = [
        PunctualLight::Point {
            position: Vec3::new(0.3, 1.0, -0.2),
            intensity: Vec3::new(2.0, 1.5, 1.0),
        },
        PunctualLight::Spot {
            position: spot_at,
            direction: Vec3::NEG_Y,
            intensity: Vec3::new(3.0, 3.0, 2.0),
            inner_cone_angle: 0.3,
            outer_cone_angle: 0.6,
        },
        PunctualLight::Directional {
            direction: Vec3::new(0.2, -1.0, 0.1).normalize(),
            irradiance: Vec3::new(1.0, 0.9, 0.8),
        },
    ]
    .iter()
    .map(GpuLight::from)
    .collect();
    let mut r = Rand(91);
    let point = |r: &mut Rand, kind: usize| match kind {
        1 => Vec3::new(0.3, 1.0, -0.2),
        2 => Vec3::new(f32::NAN, 1.0, 0.0),
        3 => spot_at + Vec3::new(0.5 * r.f() - 0.25, -1.0, 0.5 * r.f() - 0.25),
        4 => spot_at + Vec3::new(r.f() - 0.5, 0.2, r.f() - 0.5),
        _ => Vec3::new(2.0 * r.f() - 1.0, 2.0 * r.f(), 2.0 * r.f() - 1.0),
    };
    let axis = |r: &mut Rand, kind: usize| match kind {
        1 | 4 => Vec3::ZERO,
        2 => Vec3::new(f32::NAN, 0.0, 1.0),
        3 => Vec3::NEG_Z,
        _ => r.dir(),
    };
    let inputs: Vec<[Pb; 8]> = (0..BATCHES)
        .map(|b| {
            std::array::from_fn(|i| {
                let k = special(b, i);
                (point(&mut r, k), r.f(), axis(&mut r, k), u_for(&mut r, k))
            })
        })
        .collect();
    let garbage: Pb = (
        Vec3::splat(f32::NAN),
        f32::NAN,
        Vec3::splat(f32::NAN),
        Vec2::splat(1e30),
    );
    let (mut delta, mut sky) = (0, 0);
    for punctual in [all.clone(), vec![all[1]]] {
        let lights = Lights {
            punctual,
            background: Vec3::new(0.3, 0.4, 0.5),
            probs: CategoryProbs {
                area: 0.0,
                punctual: 0.5,
                background: 0.5,
            },
            ..Lights::new(&scene)
        };
        let run = |lv: SimdLevel, l: [Pb; 8], mask: Mask8, bg: bool| {
            simd_at!(lv, fn(lights: &Lights, l: [Pb; 8], mask: Mask8, bg: bool) -> [Option<LightSample>; 8] {
                let s = if bg {
                    lights.sample_constant_background_lanes(v3x8(l.map(|x| x.2)), l.map(|x| x.3).into(), mask)
                } else {
                    lights.sample_punctual_lanes(v3x8(l.map(|x| x.0)), F32x8(l.map(|x| x.1)), mask)
                };
                std::array::from_fn(|k| s.lane(k).map(|x| LightSample { delta: !bg, ..x }))
            }(&lights, l, mask, bg))
        };
        for bg in [false, true] {
            let u_cat = if bg { 0.75 } else { 0.25 };
            let scalar = |(p, ui, n, u): Pb| lights.sample(&scene, p, n, u_cat, ui, u);
            each_level(
                |b, i| inputs[b][i],
                |lv, l| run(lv, l, Mask8::first(8), bg),
                scalar,
                same_light,
                if bg {
                    "sample_constant_background_lanes"
                } else {
                    "sample_punctual_lanes"
                },
            );
            for level in SimdLevel::available() {
                for l in &inputs {
                    let mut g = *l;
                    g[5..].fill(garbage);
                    let (a, b) = (
                        run(level, *l, Mask8::first(5), bg),
                        run(level, g, Mask8::first(5), bg),
                    );
                    for k in 0..8 {
                        assert!(same_light(&a[k], &b[k]));
                        assert!(k < 5 || a[k].is_none());
                    }
                }
            }
            for l in &inputs {
                for &(p, ui, n, u) in l {
                    let s = lights.sample(&scene, p, n, u_cat, ui, u);
                    delta += usize::from(s.is_some_and(|s| s.delta));
                    sky += usize::from(s.is_some_and(|s| !s.delta));
                }
            }
        }
    }
    assert!(
        delta > 2000 && sky > 6000,
        "{delta} punctual, {sky} background samples"
    );
}

/// A ray-offset test's lanes: p, err, ng, w, the light's distance.
type Ro = (Vec3, Vec3, Vec3, Vec3, f32);

/// The floats the offsets' bit steps branch on: zeros of both signs,
/// denormals, the largest floats, infinities and NaN.
const EDGES: [f32; 12] = [
    0.0,
    -0.0,
    1e-45,
    -1e-45,
    f32::MIN_POSITIVE,
    f32::MAX,
    -f32::MAX,
    f32::INFINITY,
    f32::NEG_INFINITY,
    f32::NAN,
    1.0,
    -3.5,
];

/// The ray offsets (`offset_origin_lanes`) and the shadow rays
/// (`shadow_ray_lanes`) that the wave's Lambertian vertices compute in
/// lanes are `offset_origin`'s and `PathTracer::shadow_ray`'s bits in every
/// lane, on ordinary points and on the floats the bit steps branch on
/// (signed zeros, denormals, the largest floats, infinities, NaN), with
/// normals along the axes (zero offsets), directions on the surface and
/// lights at infinity; and the lanes' next float up and down are the
/// scalar steps on the edge cases themselves.
#[test]
fn ray_offsets_in_lanes_are_the_scalar_ones() {
    use glint_cpu::integrator::{
        next_float_down, next_float_up, offset_origin, offset_origin_lanes, shadow_ray_lanes,
    };
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets");
    let scene = glint_cpu::loader::load(&root.join("cornell.gltf")).unwrap();
    let pt = glint_cpu::PathTracer::new(&scene, &glint_cpu::RenderOptions::new(8, 8)).unwrap();
    let mut r = Rand(0x0ff5_e7a1);
    let mut inputs = |b: usize, i: usize| -> Ro {
        let mut p = Vec3::new(r.f() - 0.5, r.f() * 4.0, -r.f()) * 10f32.powi((b % 7) as i32 - 3);
        if b % 3 == 1 {
            p[(b + i) % 3] = EDGES[(b * 8 + i) % EDGES.len()];
        }
        let err = Vec3::new(r.f(), r.f(), r.f()) * 1e-5 * (b % 2) as f32;
        let mut ng = r.dir();
        if b % 5 == 2 {
            ng = [Vec3::X, -Vec3::Y, Vec3::Z][i % 3];
        }
        let mut w = r.dir();
        if b % 5 == 3 {
            w = ng.cross(r.dir()).normalize_or(Vec3::X);
        }
        let dist = if (b + i).is_multiple_of(4) {
            f32::INFINITY
        } else {
            r.f() * 8.0
        };
        (p, err, ng, w, dist)
    };
    let split = |l: &[Ro; 8]| {
        (
            v3x8(std::array::from_fn(|i| l[i].0)),
            v3x8(std::array::from_fn(|i| l[i].1)),
            v3x8(std::array::from_fn(|i| l[i].2)),
            v3x8(std::array::from_fn(|i| l[i].3)),
            F32x8(std::array::from_fn(|i| l[i].4)),
        )
    };
    each_level(
        &mut inputs,
        |lv, l| {
            let (p, err, ng, w, _) = split(&l);
            simd_at!(lv, fn(p: V3<F32x8>, err: V3<F32x8>, ng: V3<F32x8>, w: V3<F32x8>) -> [Vec3; 8] {
                lanes3(offset_origin_lanes(p, err, ng, w))
            }(p, err, ng, w))
        },
        |(p, err, ng, w, _)| offset_origin(p, err, ng, w),
        |a, b| same3(*a, *b),
        "offset_origin",
    );
    each_level(
        &mut inputs,
        |lv, l| {
            let (p, err, ng, w, dist) = split(&l);
            let (o, d, t) = simd_at!(lv, fn(p: V3<F32x8>, err: V3<F32x8>, ng: V3<F32x8>, w: V3<F32x8>, dist: F32x8) -> ([Vec3; 8], [Vec3; 8], [f32; 8]) {
                let (o, d, t) = shadow_ray_lanes(p, err, ng, w, dist);
                (lanes3(o), lanes3(d), lanes1(t))
            }(p, err, ng, w, dist));
            std::array::from_fn(|i| (o[i], d[i], t[i]))
        },
        |(p, err, ng, w, dist)| {
            let ls = LightSample {
                wi: w,
                dist,
                weight: Vec3::ONE,
                pdf: 1.0,
                delta: false,
            };
            let ray = pt.shadow_ray(p, err, ng, &ls);
            (ray.o, ray.d, ray.tmax)
        },
        |a, b| same3(a.0, b.0) && same3(a.1, b.1) && same(a.2, b.2),
        "shadow_ray",
    );
    for level in SimdLevel::available() {
        for chunk in EDGES.chunks(4) {
            let v: [f32; 8] = std::array::from_fn(|i| {
                let e = chunk[i % chunk.len()];
                if i < 4 { e } else { -e }
            });
            let (up, down) = simd_at!(level, fn(v: F32x8) -> ([f32; 8], [f32; 8]) {
                (v.next_up().0, v.next_down().0)
            }(F32x8(v)));
            for i in 0..8 {
                assert!(
                    same(up[i], next_float_up(v[i])),
                    "up {:e} at {level:?}",
                    v[i]
                );
                assert!(
                    same(down[i], next_float_down(v[i])),
                    "down {:e} at {level:?}",
                    v[i]
                );
            }
        }
    }
}
