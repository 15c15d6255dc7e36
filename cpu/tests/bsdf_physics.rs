//! Physical properties of the BSDFs: Fresnel identities, reciprocity,
//! energy conservation, the white furnace, consistency of `sample` with
//! `eval`/`pdf`, the smooth dielectric's R/T choice and radiance scaling,
//! and robustness (no NaN/inf) over extreme inputs.

#![allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x > 0.0)` also catches NaN

mod common;

use common::*;
use glam::{DVec3, Vec2, Vec3};
use glint_cpu::bsdf::fresnel::*;
use glint_cpu::bsdf::microfacet::*;
use glint_cpu::bsdf::{Bsdf, ConductorParams, Roughness, Shadowing, Tint, named_ior, named_metal};
use glint_cpu::quadrature::{hemisphere_integrate, hv_two};
use rayon::prelude::*;

/// Every model over incident angles down to cos 1e-4 (both sides), alphas
/// from just above the smooth threshold to 1, isotropic and anisotropic,
/// both shadowing forms, dielectrics with eta > 1 and < 1.
fn property_cases() -> Vec<(String, Bsdf)> {
    let mut v = vec![(
        "diffuse".to_string(),
        Bsdf::Diffuse {
            reflectance: Vec3::new(0.9, 0.5, 0.1),
        },
    )];
    let alphas = [
        (0.0011, 0.0011),
        (0.01, 0.01),
        (0.3, 0.3),
        (1.0, 1.0),
        (0.02, 0.7),
    ];
    for sh in [Shadowing::Correlated, Shadowing::Separable] {
        for &(au, av) in &alphas {
            let r = rough(au, av, sh);
            v.push((
                format!("roughconductor {au},{av} {sh:?}"),
                Bsdf::Conductor(gold(r)),
            ));
            for eta in [1.5, 1.0 / 1.5] {
                v.push((
                    format!("roughdielectric eta={eta} {au},{av} {sh:?}"),
                    Bsdf::Dielectric {
                        eta,
                        roughness: r,
                        tint: glint_cpu::bsdf::Tint::NONE,
                    },
                ));
            }
            if au == av {
                v.push((
                    format!("roughplastic {au} {sh:?}"),
                    Bsdf::RoughPlastic(glint_cpu::bsdf::roughplastic::RoughPlasticParams {
                        plastic: glint_cpu::bsdf::plastic::PlasticParams {
                            diffuse: Vec3::new(0.8, 0.5, 0.2),
                            specular: Vec3::ONE,
                            eta: 1.49,
                            nonlinear: sh == Shadowing::Separable,
                        },
                        roughness: r,
                    }),
                ));
            }
            v.push((
                format!("coated {au},{av} {sh:?}"),
                Bsdf::Coated {
                    base: Vec3::new(0.8, 0.7, 0.6),
                    coat: glint_cpu::bsdf::coated::CoatParams {
                        eta: 1.5,
                        specular: Vec3::new(1.0, 0.9, 0.8),
                        transmission: if sh == Shadowing::Separable { 0.4 } else { 0.0 },
                        clearcoat: 0.0,
                        clearcoat_alpha: 0.0,
                        clearcoat_normal: glam::Vec2::ZERO,
                    },
                    roughness: r,
                },
            ));
            v.push((
                format!("metallic {au},{av} {sh:?}"),
                Bsdf::Metallic {
                    metallic: 0.3,
                    base: Vec3::new(0.8, 0.7, 0.6),
                    conductor: gold(r),
                    coat: glint_cpu::bsdf::coated::CoatParams::GLTF_DEFAULT,
                },
            ));
        }
    }
    // KHR_materials_clearcoat (rough and smooth) over the rough non-metal
    // and the blend.
    for (ca, cc) in [(0.09f32, 1.0f32), (0.0, 0.7)] {
        let coat = glint_cpu::bsdf::coated::CoatParams {
            clearcoat: cc,
            clearcoat_alpha: ca,
            ..glint_cpu::bsdf::coated::CoatParams::GLTF_DEFAULT
        };
        let r = rough(0.3, 0.3, Shadowing::Correlated);
        v.push((
            format!("clearcoat {cc} a={ca} over coated"),
            Bsdf::Coated {
                base: Vec3::new(0.8, 0.7, 0.6),
                coat,
                roughness: r,
            },
        ));
        v.push((
            format!("clearcoat {cc} a={ca} over metallic"),
            Bsdf::Metallic {
                metallic: 0.6,
                base: Vec3::new(0.8, 0.7, 0.6),
                conductor: gold(r),
                coat,
            },
        ));
    }
    v.push((
        "conductor smooth".into(),
        Bsdf::Conductor(gold(Roughness::SMOOTH)),
    ));
    for eta in [1.5, 1.0 / 1.5] {
        v.push((
            format!("dielectric smooth eta={eta}"),
            Bsdf::Dielectric {
                eta,
                roughness: Roughness::SMOOTH,
                tint: glint_cpu::bsdf::Tint::NONE,
            },
        ));
        // Mitsuba's specular_reflectance and _transmittance.
        for roughness in [Roughness::SMOOTH, rough(0.2, 0.05, Shadowing::Separable)] {
            v.push((
                format!("tinted dielectric eta={eta} alpha={}", roughness.alpha_u),
                Bsdf::Dielectric {
                    eta,
                    roughness,
                    tint: TINT,
                },
            ));
        }
    }
    for nonlinear in [false, true] {
        v.push((
            format!("plastic nonlinear={nonlinear}"),
            Bsdf::Plastic(glint_cpu::bsdf::plastic::PlasticParams {
                diffuse: Vec3::new(0.9, 0.5, 0.1),
                specular: Vec3::new(1.0, 0.9, 0.8),
                eta: 1.49,
                nonlinear,
            }),
        ));
    }
    v.push((
        "thindielectric".into(),
        Bsdf::ThinDielectric {
            eta: 1.5,
            tint: Tint::NONE,
        },
    ));
    v.push((
        "coated smooth".into(),
        Bsdf::Coated {
            base: Vec3::new(0.8, 0.7, 0.6),
            coat: glint_cpu::bsdf::coated::CoatParams::GLTF_DEFAULT,
            roughness: Roughness::SMOOTH,
        },
    ));
    v.push((
        "metallic smooth".into(),
        Bsdf::Metallic {
            metallic: 0.5,
            base: Vec3::new(0.8, 0.7, 0.6),
            conductor: gold(Roughness::SMOOTH),
            coat: glint_cpu::bsdf::coated::CoatParams::GLTF_DEFAULT,
        },
    ));
    v
}

/// Models that are not reciprocal by design, for the other properties: a
/// clear coat tilted by its own normal map (its lobe carries the coat's
/// cosine, `bsdf/clearcoat.rs`), rough and smooth, over a white non-metal
/// (the furnace's worst case) and over the blend.
/// A dielectric tint with every channel different.
const TINT: glint_cpu::bsdf::Tint = glint_cpu::bsdf::Tint {
    reflect: Vec3::new(0.9, 0.5, 0.2),
    transmit: Vec3::new(0.3, 0.8, 1.0),
};

/// Mitsuba's tints scale a dielectric's reflected part by
/// `specular_reflectance` and its transmitted part by
/// `specular_transmittance`; the sampling (directions and densities) is
/// the untinted one, and a sample's weight is scaled as its value.
#[test]
fn dielectric_tints_scale_each_part() {
    use glint_cpu::sampling::square_to_uniform_sphere;
    let mut rng = glint_cpu::sampling::Pcg32::new(7, 1);
    for roughness in [Roughness::SMOOTH, rough(0.3, 0.1, Shadowing::Correlated)] {
        for eta in [1.5, 1.0 / 1.33] {
            let plain = Bsdf::Dielectric {
                eta,
                roughness,
                tint: glint_cpu::bsdf::Tint::NONE,
            };
            let tinted = Bsdf::Dielectric {
                eta,
                roughness,
                tint: TINT,
            };
            let (mut reflected, mut transmitted) = (0, 0);
            for _ in 0..2000 {
                let wo = square_to_uniform_sphere(Vec2::new(rng.f32(), rng.f32()));
                let (uc, u) = (rng.f32(), Vec2::new(rng.f32(), rng.f32()));
                let (a, b) = (plain.sample(wo, uc, u), tinted.sample(wo, uc, u));
                assert_eq!(a.is_some(), b.is_some());
                let (Some(a), Some(b)) = (a, b) else { continue };
                assert_eq!((a.wi, a.pdf, a.eta, a.delta), (b.wi, b.pdf, b.eta, b.delta));
                let t = if wo.z * a.wi.z > 0.0 {
                    reflected += 1;
                    TINT.reflect
                } else {
                    transmitted += 1;
                    TINT.transmit
                };
                assert!(
                    (b.weight - a.weight * t).abs().max_element() <= 1e-6 * a.weight.max_element()
                );
                let wi = square_to_uniform_sphere(Vec2::new(rng.f32(), rng.f32()));
                let t = if wo.z * wi.z > 0.0 {
                    TINT.reflect
                } else {
                    TINT.transmit
                };
                let (fa, fb) = (plain.eval(wo, wi), tinted.eval(wo, wi));
                assert!((fb - fa * t).abs().max_element() <= 1e-6 * fa.max_element());
                assert_eq!(plain.pdf(wo, wi), tinted.pdf(wo, wi));
            }
            assert!(
                reflected > 100 && transmitted > 100,
                "{reflected} {transmitted}"
            );
        }
    }
}

fn nonreciprocal_cases() -> Vec<(String, Bsdf)> {
    let mut v = Vec::new();
    for (n, ca) in [
        (glam::Vec2::new(0.35, -0.2), 0.09f32),
        (glam::Vec2::new(-0.5, 0.3), 0.3),
        (glam::Vec2::new(0.2, 0.45), 0.0),
    ] {
        let coat = glint_cpu::bsdf::coated::CoatParams {
            clearcoat: 1.0,
            clearcoat_alpha: ca,
            clearcoat_normal: n,
            ..glint_cpu::bsdf::coated::CoatParams::GLTF_DEFAULT
        };
        v.push((
            format!("tilted clearcoat n={n} a={ca} over white coated"),
            Bsdf::Coated {
                base: Vec3::ONE,
                coat,
                roughness: rough(0.2, 0.2, Shadowing::Correlated),
            },
        ));
        v.push((
            format!("tilted clearcoat n={n} a={ca} over metallic"),
            Bsdf::Metallic {
                metallic: 0.5,
                base: Vec3::new(0.8, 0.7, 0.6),
                conductor: gold(rough(0.4, 0.4, Shadowing::Correlated)),
                coat,
            },
        ));
    }
    v
}

const COS_GRID: [f32; 9] = [1.0, 0.7, 0.3, 0.05, 1e-3, 1e-4, -1e-4, -0.4, -0.95];

// ---------------------------------------------------------------- Fresnel

#[test]
fn fresnel_normal_incidence() {
    for eta in [1.5f32, 1.333, 2.419, 1.0 / 1.5] {
        let want = ((eta - 1.0) / (eta + 1.0)).powi(2);
        let got = fresnel_dielectric(1.0, eta);
        assert!((got - want).abs() < 1e-6, "eta {eta}: {got} vs {want}");
        // From inside the same value (1/eta gives the same ratio squared).
        assert!((fresnel_dielectric(-1.0, eta) - want).abs() < 1e-6);
    }
}

#[test]
fn fresnel_brewster_angle_zeroes_p() {
    for eta in [1.5f32, 1.333, 2.419] {
        // Outside: tan theta_B = eta; inside: tan theta_B = 1 / eta.
        let (rs, rp) = fresnel_dielectric_polarized(eta.atan().cos(), eta);
        assert!(rp < 1e-9 && rs > 1e-3, "eta {eta}: rs {rs} rp {rp}");
        let (rs, rp) = fresnel_dielectric_polarized(-(1.0 / eta).atan().cos(), eta);
        assert!(rp < 1e-9 && rs > 1e-3, "inside, eta {eta}: rs {rs} rp {rp}");
    }
}

#[test]
fn fresnel_total_internal_reflection() {
    let eta = 1.5f32;
    let cos_c = (1.0 - 1.0 / (eta * eta)).sqrt();
    for i in 1..100 {
        // From inside (cos < 0), beyond the critical angle.
        let c = -cos_c * i as f32 / 100.0;
        assert_eq!(fresnel_dielectric(c, eta), 1.0, "cos {c}");
        assert!(refract_dir(dir_cos(c, 0.3), Vec3::Z, eta).is_none());
        // Outside with eta < 1 (denser medium outside): the same.
        assert_eq!(fresnel_dielectric(-c, 1.0 / eta), 1.0);
    }
    assert!(fresnel_dielectric(-cos_c * 1.01, eta) < 1.0);
}

#[test]
fn fresnel_is_reversible() {
    // F seen from side 1 at theta_i equals F seen from side 2 at theta_t.
    for eta in [1.5f32, 1.0 / 1.333, 2.419] {
        // From cos 0.01: closer to grazing F's slope turns f32 rounding of
        // the refracted cosine into errors above the tolerance.
        for i in 0..=50 {
            let c = 0.01 + 0.99 * i as f32 / 50.0;
            let wo = dir_cos(c, 0.7);
            let Some((wt, _)) = refract_dir(wo, Vec3::Z, eta) else {
                continue;
            };
            let a = fresnel_dielectric(c, eta);
            let b = fresnel_dielectric(wt.z, eta);
            // Near grazing the refracted side sits at the critical angle,
            // where F has a sqrt slope: allow for f32 rounding there.
            assert!(
                (a - b).abs() < 1e-5 + 2e-6 / c,
                "eta {eta} cos {c}: {a} vs {b}"
            );
        }
    }
}

/// pbrt-v4's `FrComplex` in f64 complex arithmetic: an independent form.
fn fr_complex(cos_i: f64, eta: f64, k: f64) -> f64 {
    #[derive(Clone, Copy)]
    struct C(f64, f64);
    let mul = |a: C, b: C| C(a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0);
    let div = |a: C, b: C| {
        let d = b.0 * b.0 + b.1 * b.1;
        C((a.0 * b.0 + a.1 * b.1) / d, (a.1 * b.0 - a.0 * b.1) / d)
    };
    let sqrt = |a: C| {
        let r = (a.0 * a.0 + a.1 * a.1).sqrt();
        let re = ((r + a.0) / 2.0).sqrt();
        let im = ((r - a.0) / 2.0).sqrt().copysign(a.1);
        C(re, im)
    };
    let n = C(eta, k);
    let sin2_i = 1.0 - cos_i * cos_i;
    let sin2_t = div(C(sin2_i, 0.0), mul(n, n));
    let cos_t = sqrt(C(1.0 - sin2_t.0, -sin2_t.1));
    let ci = C(cos_i, 0.0);
    let nci = mul(n, ci);
    let nct = mul(n, cos_t);
    let r_parl = div(
        C(nci.0 - cos_t.0, nci.1 - cos_t.1),
        C(nci.0 + cos_t.0, nci.1 + cos_t.1),
    );
    let r_perp = div(C(ci.0 - nct.0, -nct.1), C(ci.0 + nct.0, nct.1));
    let norm = |a: C| a.0 * a.0 + a.1 * a.1;
    (norm(r_parl) + norm(r_perp)) / 2.0
}

#[test]
fn fresnel_conductor_values() {
    // Gold at 551.04 nm as tabulated in pbrt-v4's `Au_eta`/`Au_k`
    // (src/pbrt/util/spectrum.cpp): n = 0.3455, k = 2.730625. Normal
    // incidence R = ((n-1)^2 + k^2) / ((n+1)^2 + k^2) = 0.850856.
    let r = fresnel_conductor_channel(1.0, 0.3455, 2.730625);
    assert!((r - 0.850856).abs() < 1e-5, "{r}");
    // Against the complex-arithmetic form at every angle, for each metal.
    for name in ["Au", "Ag", "Cu", "Al", "Cr"] {
        let (eta, k) = named_metal(name).unwrap();
        for c in 0..3 {
            for i in 0..=100 {
                let cos = i as f32 / 100.0;
                let a = fresnel_conductor_channel(cos, eta[c], k[c]) as f64;
                let b = fr_complex(cos as f64, eta[c] as f64, k[c] as f64);
                assert!((a - b).abs() < 1e-5, "{name} ch {c} cos {cos}: {a} vs {b}");
            }
            // The table's documented normal-incidence reflectance.
            let r0 =
                ((eta[c] - 1.0).powi(2) + k[c] * k[c]) / ((eta[c] + 1.0).powi(2) + k[c] * k[c]);
            assert!((fresnel_conductor_channel(1.0, eta[c], k[c]) - r0).abs() < 1e-6);
        }
    }
}

#[test]
fn named_tables() {
    assert_eq!(named_ior("BK7"), Some(1.5046));
    assert_eq!(named_ior("Crown Glass"), Some(1.5046));
    assert_eq!(named_ior("water ice"), Some(1.31));
    assert_eq!(named_ior("ice"), Some(1.31));
    assert_eq!(named_ior("Water"), Some(1.333));
    assert_eq!(named_ior("air"), Some(1.000277));
    assert_eq!(named_ior("vacuum"), Some(1.0));
    assert_eq!(named_ior("DIAMOND"), Some(2.419));
    assert_eq!(named_ior("unobtainium"), None);
    for m in ["Au", "ag", "CU", "Al", "cr", "gold", "aluminum"] {
        assert!(named_metal(m).is_some(), "{m}");
    }
    assert!(named_metal("Fe2").is_none());
}

// ------------------------------------------------------------ reciprocity

/// Refractive index of the medium a direction lies in.
fn medium(bsdf: &Bsdf, w: Vec3) -> f32 {
    match bsdf {
        Bsdf::Dielectric { eta, .. } if w.z < 0.0 => *eta,
        _ => 1.0,
    }
}

/// Reflection: f(wo, wi) = f(wi, wo). Transmission with the radiance
/// scaling: f(wo, wi) / n(wo)^2 = f(wi, wo) / n(wi)^2, n(w) the index of
/// the medium w lies in (Veach 1997, eq. 5.14, generalised reciprocity).
#[test]
fn reciprocity() {
    let cases = property_cases();
    let failures: Vec<String> = cases
        .par_iter()
        .enumerate()
        .flat_map_iter(|(ci, (name, bsdf))| {
            let mut rng = Pcg32::new(ci as u64, 3);
            let mut out = Vec::new();
            for &co in &COS_GRID {
                for _ in 0..400 {
                    let wo = dir_cos(co, std::f32::consts::TAU * rng.f32());
                    let ci_ = 2.0 * rng.f32() - 1.0;
                    let wi = dir_cos(ci_, std::f32::consts::TAU * rng.f32());
                    let a = bsdf.eval(wo, wi) / medium(bsdf, wo).powi(2);
                    let b = bsdf.eval(wi, wo) / medium(bsdf, wi).powi(2);
                    // The absolute term covers pairs next to the critical
                    // angle, where 1 - F ~ sqrt(cos - cos_c) turns f32
                    // rounding of the microfacet cosines into large
                    // relative errors of values that are tiny anyway.
                    let tol = 1e-3 * a.max_element().max(b.max_element()) + 2e-5;
                    if (a - b).abs().max_element() > tol {
                        out.push(format!("{name}: wo {wo} wi {wi}: {a} vs {b}"));
                    }
                }
            }
            out
        })
        .collect();
    assert!(
        failures.is_empty(),
        "{}\n...",
        failures[..failures.len().min(10)].join("\n")
    );
}

// ------------------------------------------------- sample vs eval and pdf

#[test]
fn sample_weight_and_pdf_match_eval() {
    let mut cases = property_cases();
    cases.extend(nonreciprocal_cases());
    let results: Vec<(Vec<String>, usize, usize)> = cases
        .par_iter()
        .enumerate()
        .map(|(ci, (name, bsdf))| {
            let mut rng = Pcg32::new(ci as u64, 5);
            let mut out = Vec::new();
            let (mut count, mut ill) = (0usize, 0usize);
            for &co in &COS_GRID {
                let wo = dir_cos(co, PHI_O);
                for _ in 0..2000 {
                    let Some(s) = bsdf.sample(wo, rng.f32(), rng.vec2()) else {
                        continue;
                    };
                    if !(s.wi.is_finite() && s.weight.is_finite() && s.pdf.is_finite()) {
                        out.push(format!("{name}: non-finite sample {s:?}"));
                        continue;
                    }
                    if (s.wi.length() - 1.0).abs() > 1e-4 || s.pdf <= 0.0 {
                        out.push(format!("{name}: bad sample {s:?}"));
                    }
                    let transmitted = s.wi.z * wo.z < 0.0;
                    // A solid dielectric's refraction crosses eta; a thin
                    // slab's straight-through transmission does not.
                    let solid = matches!(bsdf, Bsdf::Dielectric { .. });
                    if solid && transmitted != (s.eta != 1.0) {
                        out.push(format!("{name}: eta {} for wi {}", s.eta, s.wi));
                    }
                    if s.delta {
                        continue;
                    }
                    count += 1;
                    let pdf = bsdf.pdf(wo, s.wi);
                    let f = bsdf.eval(wo, s.wi);
                    let w = f * s.wi.z.abs() / pdf;
                    if (pdf - s.pdf).abs() <= 1e-3 * pdf
                        && (w - s.weight).abs().max_element() <= 1e-3 * w.max_element() + 1e-6
                    {
                        continue;
                    }
                    // `sample` computes pdf and weight from the sampled
                    // microfacet normal; `pdf`/`eval` rebuild it from
                    // wo + wi, which near-specular lobes at grazing angles
                    // make ill-conditioned (wo and wi nearly opposite in
                    // the plane). Such points are recognised by pdf moving
                    // by more than 1e-3 under a 32-ulp jitter of wi (the
                    // rounding error of the sampled direction itself).
                    let jittered = |k: f32| {
                        let e = k * 32.0 * f32::EPSILON;
                        bsdf.pdf(
                            wo,
                            Vec3::new(s.wi.x * (1.0 + e), s.wi.y * (1.0 - e), s.wi.z),
                        )
                    };
                    let spread = (jittered(1.0) - pdf)
                        .abs()
                        .max((jittered(-1.0) - pdf).abs());
                    if spread > 1e-3 * pdf {
                        ill += 1;
                    } else {
                        out.push(format!(
                            "{name}: wo {wo}: sample {s:?} vs pdf {pdf} weight {w}"
                        ));
                    }
                }
            }
            (out, count, ill)
        })
        .collect();
    let failures: Vec<String> = results.iter().flat_map(|r| r.0.clone()).collect();
    let total: usize = results.iter().map(|r| r.1).sum();
    let ill: usize = results.iter().map(|r| r.2).sum();
    assert!(
        failures.is_empty(),
        "{}\n...",
        failures[..failures.len().min(10)].join("\n")
    );
    eprintln!("{ill} of {total} samples ill-conditioned for pdf(wo, wi)");
    // Ill-conditioning is a matter of f32 resolving the lobe: none for
    // alpha >= 0.05; rare at alpha = 0.01; common only for lobes 1e-3 wide
    // seen at grazing angles (COS_GRID holds four |cos| <= 0.05 of nine),
    // where a direction's rounding already moves the half vector by a
    // sizeable fraction of alpha.
    for ((name, bsdf), r) in cases.iter().zip(&results) {
        let a = min_alpha(bsdf);
        let allowed = if a < 0.005 {
            0.35
        } else if a < 0.05 {
            0.005
        } else {
            0.0
        };
        assert!(
            r.2 as f64 <= allowed * r.1 as f64,
            "{name}: {} of {} samples ill-conditioned",
            r.2,
            r.1
        );
    }
}

fn min_alpha(bsdf: &Bsdf) -> f32 {
    let r = match bsdf {
        Bsdf::Diffuse { .. } => return f32::INFINITY,
        Bsdf::Conductor(c) => c.roughness,
        Bsdf::Dielectric { roughness, .. } => *roughness,
        Bsdf::Metallic { conductor, .. } => conductor.roughness,
        Bsdf::Coated { roughness, .. } => *roughness,
        Bsdf::RoughPlastic(p) => p.roughness,
        Bsdf::Plastic(_) | Bsdf::ThinDielectric { .. } => return 0.0,
    };
    r.alpha_u.min(r.alpha_v)
}

// ---------------------------------------------------- energy conservation

/// MC estimate of the directional albedo integral f |cos| dwi, from the
/// sample weights (sampling verified against pdf by the chi-square suite,
/// weights against eval above). Transmitted samples count eta_rel^2 x
/// weight: the BTDF carries the radiance factor 1/eta_rel^2 (radiance is
/// compressed into the smaller solid angle of the denser side), which is
/// not a gain of energy; undoing it gives the physical flux ratio, which
/// must not exceed 1. Returns (mean, standard error) of the channel with
/// the largest mean (each channel's albedo is bounded, not the per-sample
/// maximum over channels: a mixture's lobes may favour different channels).
fn albedo(bsdf: &Bsdf, wo: Vec3, n: usize, seed: u64) -> (f64, f64) {
    let mut rng = Pcg32::new(seed, 9);
    let (mut s1, mut s2) = ([0.0f64; 3], [0.0f64; 3]);
    for _ in 0..n {
        if let Some(s) = bsdf.sample(wo, rng.f32(), rng.vec2()) {
            let w = s.weight * s.eta * s.eta;
            for c in 0..3 {
                s1[c] += w[c] as f64;
                s2[c] += (w[c] as f64).powi(2);
            }
        }
    }
    let c = (0..3).max_by(|&a, &b| s1[a].total_cmp(&s1[b])).unwrap_or(0);
    let m = s1[c] / n as f64;
    (m, ((s2[c] / n as f64 - m * m).max(0.0) / n as f64).sqrt())
}

/// Per channel (mean, standard error) of the flux albedo, as [`albedo`].
fn albedo_rgb(bsdf: &Bsdf, wo: Vec3, n: usize, seed: u64) -> (DVec3, DVec3) {
    let mut rng = Pcg32::new(seed, 9);
    let (mut s1, mut s2) = (DVec3::ZERO, DVec3::ZERO);
    for _ in 0..n {
        if let Some(s) = bsdf.sample(wo, rng.f32(), rng.vec2()) {
            let w = (s.weight * s.eta * s.eta).as_dvec3();
            s1 += w;
            s2 += w * w;
        }
    }
    let m = s1 / n as f64;
    (
        m,
        ((s2 / n as f64 - m * m).max(DVec3::ZERO) / n as f64).powf(0.5),
    )
}

/// The albedo by a method that never calls the sampler, where one applies:
/// (value, error) per channel. Smooth conductor: its Fresnel term; smooth
/// and thin dielectrics: flux R + T = 1 (their white thin walls too);
/// rough conductors and dielectrics: the half-vector quadrature of eval
/// ([`hv_two`]; transmission counts as flux); diffuse and the layered
/// models whose lobes are at least 0.3 wide: a fine (cos theta, phi)
/// quadrature of eval over both hemispheres (their transmission is
/// thin-walled, eta 1, so it counts as it is). The narrow layered lobes
/// and the delta-plus-diffuse mixtures have none here (their furnaces are
/// in bsdf_coated.rs and bsdf_albedo.rs).
fn reference_albedo(bsdf: &Bsdf, wo: Vec3) -> Option<(DVec3, DVec3)> {
    let layered_wide = |r: &Roughness| r.alpha_u.min(r.alpha_v) >= 0.3;
    match bsdf {
        Bsdf::Conductor(c) if c.roughness.is_smooth() => {
            let f = fresnel_conductor(wo.z.abs(), c.eta, c.k) * c.specular_reflectance;
            Some((f.as_dvec3(), DVec3::splat(1e-6)))
        }
        Bsdf::Dielectric {
            eta,
            roughness,
            tint,
        } if roughness.is_smooth() => {
            // F reflected, 1 - F transmitted (1 untinted).
            let f = fresnel_dielectric(wo.z, *eta) as f64;
            let a = tint.reflect.as_dvec3() * f + tint.transmit.as_dvec3() * (1.0 - f);
            Some((a, DVec3::splat(1e-6)))
        }
        Bsdf::ThinDielectric { tint, .. } if *tint == Tint::NONE => {
            Some((DVec3::ONE, DVec3::splat(1e-6)))
        }
        Bsdf::Conductor(c) if !c.roughness.multiscatter => {
            let (q, e) = hv_two(
                bsdf,
                wo,
                c.roughness.alpha_u as f64,
                c.roughness.alpha_v as f64,
            );
            Some((q.r, e.r))
        }
        Bsdf::Dielectric {
            eta,
            roughness: r,
            tint,
        } if !r.multiscatter => {
            // The untinted quadrature's two parts, each times its tint.
            let plain = Bsdf::Dielectric {
                eta: *eta,
                roughness: *r,
                tint: glint_cpu::bsdf::Tint::NONE,
            };
            let (q, e) = hv_two(&plain, wo, r.alpha_u as f64, r.alpha_v as f64);
            let (rt, tt) = (tint.reflect.as_dvec3(), tint.transmit.as_dvec3());
            Some((rt * q.r.x + tt * q.t, rt * e.r.x + tt * e.t))
        }
        Bsdf::Diffuse { .. } => Some(sphere_quadrature(bsdf, wo)),
        Bsdf::RoughPlastic(p) if layered_wide(&p.roughness) => Some(sphere_quadrature(bsdf, wo)),
        Bsdf::Coated {
            roughness, coat, ..
        }
        | Bsdf::Metallic {
            conductor: ConductorParams { roughness, .. },
            coat,
            ..
        } if layered_wide(roughness) && (coat.clearcoat <= 0.0 || coat.clearcoat_alpha >= 0.3) => {
            Some(sphere_quadrature(bsdf, wo))
        }
        _ => None,
    }
}

/// eval |cos| over both hemispheres at two orders: (fine, |fine - coarse|).
fn sphere_quadrature(bsdf: &Bsdf, wo: Vec3) -> (DVec3, DVec3) {
    let g = |wi: Vec3| bsdf.eval(wo, wi).as_dvec3();
    let at = |nm, nphi| {
        hemisphere_integrate(&g, 1.0, nm, nphi) + hemisphere_integrate(&g, -1.0, nm, nphi)
    };
    let (fine, coarse) = (at(48, 48), at(24, 24));
    (fine, (fine - coarse).abs())
}

/// Every model's albedo is at most 1 (its flux, transmission undone of the
/// 1/eta^2 radiance factor), and, where [`reference_albedo`] has a value,
/// no less than it either: the sampled albedo equals the reference within
/// 4 standard errors plus the reference's error, so a lobe that loses
/// energy (a weight too small, a sample dropped) fails as a gain does.
#[test]
fn energy_conservation() {
    let mut cases = property_cases();
    cases.extend(nonreciprocal_cases());
    let referenced = std::sync::atomic::AtomicUsize::new(0);
    let failures: Vec<String> = cases
        .par_iter()
        .enumerate()
        .flat_map_iter(|(ci, (name, bsdf))| {
            let referenced = &referenced;
            COS_GRID
                .iter()
                .flat_map(move |&co| {
                    let wo = dir_cos(co, PHI_O);
                    let (m, se) = albedo_rgb(bsdf, wo, 20_000, ci as u64);
                    let mut out = Vec::new();
                    for c in 0..3 {
                        if m[c] > 1.0 + 3.0 * se[c] + 1e-6 {
                            out.push(format!("{name} cos {co}: channel {c} {} +- {} > 1", m[c], se[c]));
                        }
                    }
                    if let Some((q, qe)) = reference_albedo(bsdf, wo) {
                        referenced.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        for c in 0..3 {
                            if (m[c] - q[c]).abs() > 4.0 * se[c] + qe[c] + 1e-4 {
                                out.push(format!(
                                    "{name} cos {co}: channel {c} sampled {} +- {} vs reference {} +- {}",
                                    m[c], se[c], q[c], qe[c]
                                ));
                            }
                        }
                    }
                    out
                })
                .collect::<Vec<_>>()
        })
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    // Most cases are bounded from both sides.
    let n = referenced.into_inner();
    assert!(
        n * 2 > cases.len() * COS_GRID.len(),
        "{n} of {} bounded below",
        cases.len() * COS_GRID.len()
    );
}

/// White furnace (Heitz 2014 sec. 6): with F = 1 and alpha = 1 the
/// single-scattering albedo at normal incidence is
/// integral D G2 / (4 cos_o) dwi = integral_0^1 c / (1 + c) dc... = 1 - ln 2
/// for height-correlated Smith (D = 1/pi, Lambda(wi) = (1/cos_i - 1)/2).
#[test]
fn white_furnace_rough_conductor() {
    let white = Bsdf::Conductor(ConductorParams {
        // eta = 1, k = 1e4: F = 1 - O(1e-8) at every angle.
        eta: Vec3::ONE,
        k: Vec3::splat(1e4),
        specular_reflectance: Vec3::ONE,
        roughness: rough(1.0, 1.0, Shadowing::Correlated),
    });
    let want = 1.0 - std::f64::consts::LN_2;
    // Importance-sampled estimate, 1e6 samples.
    let (m, se) = albedo(&white, Vec3::Z, 1_000_000, 1);
    assert!((m - want).abs() < 4.0 * se, "MC {m} +- {se} vs {want}");
    // Deterministic quadrature of eval, independent of the sampler.
    let q: f64 = Grid::new(20, 40)
        .integrate(&|wi| (white.eval(Vec3::Z, wi).x * wi.z.abs()) as f64)
        .iter()
        .sum();
    assert!((q - want).abs() < 1e-4, "quadrature {q} vs {want}");
}

#[test]
fn smith_terms() {
    // G1 = 1 / (1 + Lambda), G2 correlated = 1 / (1 + Lo + Li).
    let mut rng = Pcg32::new(4, 4);
    for _ in 0..1000 {
        let (ax, ay) = (0.01 + rng.f32(), 0.01 + rng.f32());
        let wo = dir_cos(0.01 + 0.99 * rng.f32(), std::f32::consts::TAU * rng.f32());
        let wi = dir_cos(0.01 + 0.99 * rng.f32(), std::f32::consts::TAU * rng.f32());
        let (lo, li) = (ggx_lambda(wo, ax, ay), ggx_lambda(wi, ax, ay));
        assert!((ggx_g1(wo, ax, ay) - 1.0 / (1.0 + lo)).abs() < 1e-5);
        assert!((ggx_g2(wo, wi, ax, ay, false) - 1.0 / (1.0 + lo + li)).abs() < 1e-5);
        let v = ggx_visibility(wo, wi, ax, ay, true);
        let g = ggx_g1(wo, ax, ay) * ggx_g1(wi, ax, ay) / (4.0 * wo.z * wi.z);
        assert!((v - g).abs() < 1e-4 * g.max(1.0));
    }
    // Normalisation: integral D(wm) cos(wm) dwm = 1, anisotropic.
    let q: f64 = Grid::new(20, 40)
        .integrate(&|wm| {
            if wm.z > 0.0 {
                (ggx_d(wm, 0.3, 0.7) * wm.z) as f64
            } else {
                0.0
            }
        })
        .iter()
        .sum();
    assert!((q - 1.0).abs() < 1e-4, "{q}");
}

// ------------------------------------------------------- smooth dielectric

#[test]
fn smooth_dielectric_choice_scaling_and_tir() {
    let eta = 1.5f32;
    let glass = Bsdf::Dielectric {
        eta,
        roughness: Roughness::SMOOTH,
        tint: glint_cpu::bsdf::Tint::NONE,
    };
    let mut rng = Pcg32::new(2, 2);
    for &c in &[0.9f32, 0.4, 0.05, -0.95, -0.8] {
        let wo = dir_cos(c, 0.4);
        let f = fresnel_dielectric(c, eta) as f64;
        let n = 200_000;
        let mut refl = 0usize;
        for _ in 0..n {
            let s = glass.sample(wo, rng.f32(), rng.vec2()).unwrap();
            assert!(s.delta);
            if s.wi.z * wo.z > 0.0 {
                refl += 1;
                assert_eq!(s.weight, Vec3::ONE);
                assert!((s.pdf as f64 - f).abs() < 1e-6);
                assert!((s.wi - Vec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-6);
            } else {
                // Radiance scaling 1/eta_rel^2, eta_rel = eta_t / eta_i.
                let eta_rel = if c > 0.0 { eta } else { 1.0 / eta };
                assert!((s.eta - eta_rel).abs() < 1e-6);
                assert!((s.weight.x - 1.0 / (eta_rel * eta_rel)).abs() < 1e-6);
                // Snell: n_i sin_i = n_t sin_t.
                let sin_i = (1.0 - c * c).sqrt();
                let sin_t = (1.0 - s.wi.z * s.wi.z).sqrt();
                assert!((sin_i - eta_rel * sin_t).abs() < 1e-5);
                // Entering then leaving: the product of the weights is 1,
                // so a smooth glass sphere under a white sky renders 1.
                let back = glass
                    .sample(s.wi, 0.999_999, Vec2::ZERO)
                    .filter(|b| b.wi.z * s.wi.z < 0.0)
                    .unwrap();
                assert!((back.weight.x * s.weight.x - 1.0).abs() < 1e-5);
            }
        }
        let p = refl as f64 / n as f64;
        let se = (f * (1.0 - f) / n as f64).sqrt();
        assert!(
            (p - f).abs() <= 5.0 * se + 1e-9,
            "cos {c}: R freq {p} vs F {f}"
        );
    }
    // TIR from inside beyond the critical angle: always reflected, weight 1.
    let wo = dir_cos(-0.3, 0.4);
    for _ in 0..1000 {
        let s = glass.sample(wo, rng.f32(), rng.vec2()).unwrap();
        assert_eq!((s.wi.z, s.weight, s.pdf), (wo.z, Vec3::ONE, 1.0));
    }
    assert_eq!(glass.eval(wo, Vec3::Z), Vec3::ZERO);
    assert_eq!(glass.pdf(wo, Vec3::Z), 0.0);
    assert!(glass.is_delta());
}

// -------------------------------------------------------------- robustness

#[test]
fn no_nan_or_inf_on_extreme_inputs() {
    let mut rng = Pcg32::new(99, 1);
    let mut bad = Vec::new();
    for i in 0..200_000 {
        let alpha = |r: &mut Pcg32| {
            let x = r.f32();
            if x < 0.1 {
                0.0
            } else {
                10f32.powf(-4.0 + 4.0 * r.f32())
            }
        };
        let r = rough(
            alpha(&mut rng),
            alpha(&mut rng),
            if i % 2 == 0 {
                Shadowing::Correlated
            } else {
                Shadowing::Separable
            },
        );
        let bsdf = match i % 4 {
            0 => Bsdf::Diffuse {
                reflectance: Vec3::splat(rng.f32()),
            },
            1 => Bsdf::Conductor(gold(r)),
            2 => Bsdf::Dielectric {
                eta: 0.4 + 2.5 * rng.f32(),
                roughness: r,
                tint: glint_cpu::bsdf::Tint::NONE,
            },
            _ => Bsdf::Metallic {
                metallic: rng.f32(),
                base: Vec3::ONE,
                conductor: gold(r),
                coat: glint_cpu::bsdf::coated::CoatParams::GLTF_DEFAULT,
            },
        };
        // cos theta from 1 down to 1e-8 and exactly 0, on both sides.
        let e = -8.0 * rng.f32();
        let mut c = if rng.f32() < 0.05 { 0.0 } else { 10f32.powf(e) };
        if rng.f32() < 0.5 {
            c = -c;
        }
        let wo = dir_cos(c, std::f32::consts::TAU * rng.f32());
        let wi = dir_cos(2.0 * rng.f32() - 1.0, std::f32::consts::TAU * rng.f32());
        let f = bsdf.eval(wo, wi);
        let p = bsdf.pdf(wo, wi);
        if !f.is_finite() || f.min_element() < 0.0 || !p.is_finite() || p < 0.0 {
            bad.push(format!("{bsdf:?} wo {wo} wi {wi}: f {f} pdf {p}"));
        }
        if let Some(s) = bsdf.sample(wo, rng.f32(), rng.vec2())
            && (!(s.wi.is_finite() && s.weight.is_finite() && s.pdf.is_finite())
                || s.weight.min_element() < 0.0
                || !(s.pdf > 0.0))
        {
            bad.push(format!("{bsdf:?} wo {wo}: {s:?}"));
        }
    }
    assert!(bad.is_empty(), "{}", bad[..bad.len().min(10)].join("\n"));
}
