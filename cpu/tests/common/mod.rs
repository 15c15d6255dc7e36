//! Shared helpers for the BSDF test suites: a small PRNG, direction
//! helpers, adaptive quadrature on the sphere and the chi-square
//! goodness-of-fit test of a sampler against its density.
#![allow(dead_code)]

use std::f64::consts::PI;

use glam::{Vec2, Vec3};
use statrs::distribution::{ChiSquared, ContinuousCDF};

pub use glint_cpu::sampling::Pcg32;

/// Unit direction from spherical angles (theta from +z, phi from +x).
pub fn sph(theta: f64, phi: f64) -> Vec3 {
    Vec3::new(
        (theta.sin() * phi.cos()) as f32,
        (theta.sin() * phi.sin()) as f32,
        theta.cos() as f32,
    )
}

/// A direction with the given cos theta (may be negative) and azimuth phi.
pub fn dir_cos(cos_theta: f32, phi: f32) -> Vec3 {
    let c = cos_theta as f64;
    let s = (1.0 - c * c).max(0.0).sqrt();
    Vec3::new(
        (s * (phi as f64).cos()) as f32,
        (s * (phi as f64).sin()) as f32,
        cos_theta,
    )
}

/// 4-point Gauss-Legendre nodes and weights on [-1, 1].
const GL_X: [f64; 4] = [
    -0.861_136_311_594_052_6,
    -0.339_981_043_584_856_3,
    0.339_981_043_584_856_3,
    0.861_136_311_594_052_6,
];
const GL_W: [f64; 4] = [
    0.347_854_845_137_453_8,
    0.652_145_154_862_546_1,
    0.652_145_154_862_546_1,
    0.347_854_845_137_453_8,
];

/// Integral of a density over the spherical rectangle
/// [t0, t1] x [p0, p1] (dw = sin theta dtheta dphi), 4x4 Gauss-Legendre.
fn gl_cell(f: &dyn Fn(Vec3) -> f64, t0: f64, t1: f64, p0: f64, p1: f64) -> f64 {
    let (tm, th) = (0.5 * (t0 + t1), 0.5 * (t1 - t0));
    let (pm, ph) = (0.5 * (p0 + p1), 0.5 * (p1 - p0));
    let mut s = 0.0;
    for i in 0..4 {
        let t = tm + th * GL_X[i];
        let st = t.sin();
        for j in 0..4 {
            let p = pm + ph * GL_X[j];
            s += GL_W[i] * GL_W[j] * f(sph(t, p)) * st;
        }
    }
    s * th * ph
}

/// Adaptive quadrature: split in 2x2 until the coarse and fine estimates
/// agree (absolute 1e-8 + relative 1e-5) or the depth limit is reached.
fn adapt(
    f: &dyn Fn(Vec3) -> f64,
    t0: f64,
    t1: f64,
    p0: f64,
    p1: f64,
    coarse: f64,
    depth: u32,
) -> f64 {
    let tm = 0.5 * (t0 + t1);
    let pm = 0.5 * (p0 + p1);
    let q = [
        (t0, tm, p0, pm),
        (t0, tm, pm, p1),
        (tm, t1, p0, pm),
        (tm, t1, pm, p1),
    ];
    let parts: Vec<f64> = q
        .iter()
        .map(|&(a, b, c, d)| gl_cell(f, a, b, c, d))
        .collect();
    let fine: f64 = parts.iter().sum();
    if depth >= 7 || (fine - coarse).abs() <= 1e-8 + 1e-5 * fine.abs() {
        return fine;
    }
    q.iter()
        .zip(&parts)
        .map(|(&(a, b, c, d), &p)| adapt(f, a, b, c, d, p, depth + 1))
        .sum()
}

/// Integral of `f` over one cell, pre-split `pre` x `pre` so narrow lobes
/// (alpha = 0.01 spreads reflected directions over ~0.02 rad) are seen by
/// the first-level nodes, then adaptive.
pub fn integrate_cell(
    f: &dyn Fn(Vec3) -> f64,
    t0: f64,
    t1: f64,
    p0: f64,
    p1: f64,
    pre: usize,
) -> f64 {
    let mut s = 0.0;
    for i in 0..pre {
        let a = t0 + (t1 - t0) * i as f64 / pre as f64;
        let b = t0 + (t1 - t0) * (i + 1) as f64 / pre as f64;
        for j in 0..pre {
            let c = p0 + (p1 - p0) * j as f64 / pre as f64;
            let d = p0 + (p1 - p0) * (j + 1) as f64 / pre as f64;
            let coarse = gl_cell(f, a, b, c, d);
            s += adapt(f, a, b, c, d, coarse, 0);
        }
    }
    s
}

/// The grid of the chi-square test: `theta_res` x `phi_res` cells over the
/// whole sphere (theta_res even, so the horizon is a cell edge).
#[derive(Clone, Debug)]
pub struct Grid {
    pub theta_res: usize,
    pub phi_res: usize,
    /// Pre-split of the two rows beside the horizon (4 elsewhere).
    pub horizon_pre: usize,
    /// Polar angles where the density jumps: cells are integrated
    /// separately on each side, so a thin strip the quadrature nodes would
    /// straddle is not smeared over.
    pub breaks: Vec<f64>,
}

impl Grid {
    pub fn new(theta_res: usize, phi_res: usize) -> Self {
        Self {
            theta_res,
            phi_res,
            horizon_pre: 16,
            breaks: Vec::new(),
        }
    }
    /// The chi-square grid for outgoing direction `wo`: 20 x 40 cells. At
    /// grazing incidence lobes crowd against the horizon and the rows next
    /// to it get a finer start; a rough dielectric's transmission density
    /// drops to 0 where the generalised half vector etap wi + wo turns
    /// horizontal (wi.z = -wo.z / etap, just across the horizon from wo),
    /// a break the quadrature must respect.
    pub fn for_case(bsdf: &glint_cpu::Bsdf, wo: Vec3) -> Self {
        let mut g = Self::new(20, 40);
        if wo.z.abs() < 0.01 {
            g.horizon_pre = 64;
        }
        if let glint_cpu::Bsdf::Dielectric { eta, .. } = bsdf {
            let etap = if wo.z > 0.0 { *eta } else { 1.0 / *eta };
            let z = (-wo.z / etap).clamp(-1.0, 1.0) as f64;
            g.breaks.push(z.acos());
        }
        g
    }
    pub fn cells(&self) -> usize {
        self.theta_res * self.phi_res
    }
    pub fn index(&self, w: Vec3) -> usize {
        let w = w.as_dvec3().normalize();
        let theta = w.z.clamp(-1.0, 1.0).acos();
        let mut phi = w.y.atan2(w.x);
        if phi < 0.0 {
            phi += 2.0 * PI;
        }
        let i = ((theta / PI * self.theta_res as f64) as usize).min(self.theta_res - 1);
        let j = ((phi / (2.0 * PI) * self.phi_res as f64) as usize).min(self.phi_res - 1);
        i * self.phi_res + j
    }
    /// Integral of the density over each cell (rows beside the horizon
    /// pre-split `horizon_pre` x `horizon_pre`, the others 4 x 4; rows
    /// split at the `breaks`).
    pub fn integrate(&self, f: &(dyn Fn(Vec3) -> f64 + Sync)) -> Vec<f64> {
        use rayon::prelude::*;
        let dt = PI / self.theta_res as f64;
        let dp = 2.0 * PI / self.phi_res as f64;
        (0..self.cells())
            .into_par_iter()
            .map(|c| {
                let (i, j) = (c / self.phi_res, c % self.phi_res);
                let (t0, t1) = (i as f64 * dt, (i + 1) as f64 * dt);
                let pre = if i + 1 == self.theta_res / 2 || i == self.theta_res / 2 {
                    self.horizon_pre
                } else {
                    4
                };
                let mut edges = vec![t0];
                edges.extend(self.breaks.iter().copied().filter(|&b| b > t0 && b < t1));
                edges.push(t1);
                edges
                    .windows(2)
                    .map(|e| integrate_cell(f, e[0], e[1], j as f64 * dp, (j + 1) as f64 * dp, pre))
                    .sum()
            })
            .collect()
    }
}

/// A Dirac lobe of the sampler: samples flagged `delta` must land within
/// 1e-4 of `dir`; `mass` is its discrete probability.
#[derive(Clone, Copy, Debug)]
pub struct DeltaLobe {
    pub dir: Vec3,
    pub mass: f64,
}

/// One sampled outcome: a direction and whether it came from a delta lobe;
/// `None` is a sample the sampler rejected (lost energy).
pub type Outcome = Option<(Vec3, bool)>;

#[derive(Clone, Debug)]
pub struct Chi2Report {
    pub statistic: f64,
    pub dof: usize,
    pub p_value: f64,
    /// Integral of the continuous density over the sphere.
    pub pdf_integral: f64,
    /// Fraction of samples the sampler rejected.
    pub lost_fraction: f64,
}

/// Chi-square goodness of fit of `sample` against the continuous density
/// `pdf` plus the Dirac lobes `deltas`, in the manner of pbrt's
/// `bsdfs_test.cpp` and Mitsuba 3's `chi2` module: `n` samples binned on
/// the theta/phi grid plus one bin per delta lobe; expected counts from
/// integrating `pdf` over each cell (normalised to the samples the sampler
/// did not reject, whose fraction is checked separately); cells with expected
/// count < 5 pooled; the statistic compared with the chi-square law of
/// (bins - 1) degrees of freedom. Errors describe a structural failure
/// (a delta sample off its lobe, samples where the density is zero).
pub fn chi2_test(
    sample: &(dyn Fn(f32, Vec2) -> Outcome + Sync),
    pdf: &(dyn Fn(Vec3) -> f64 + Sync),
    deltas: &[DeltaLobe],
    n: usize,
    seed: u64,
    grid: &Grid,
) -> Result<Chi2Report, String> {
    let cells = grid.cells();
    let mut observed = vec![0u64; cells + deltas.len() + 1];
    let lost = cells + deltas.len();
    let mut rng = Pcg32::new(seed, 0x5eed);
    for _ in 0..n {
        let uc = rng.f32();
        let u = rng.vec2();
        match sample(uc, u) {
            None => observed[lost] += 1,
            Some((w, true)) => {
                let k = deltas
                    .iter()
                    .position(|d| d.dir.dot(w) > 1.0 - 1e-4)
                    .ok_or_else(|| format!("delta sample {w} matches no expected lobe"))?;
                observed[cells + k] += 1;
            }
            Some((w, false)) => {
                if !w.is_finite() || (w.length() - 1.0).abs() > 1e-3 {
                    return Err(format!("sampled direction {w} is not a unit vector"));
                }
                observed[grid.index(w)] += 1;
            }
        }
    }
    let mut expected = grid.integrate(pdf);
    let pdf_integral: f64 = expected.iter().sum();
    let delta_mass: f64 = deltas.iter().map(|d| d.mass).sum();
    // Normalisation: density + delta masses + the rejected fraction account
    // for every sample, within 5 sigma of the binomial rejected fraction
    // plus 1e-4 for the quadrature (lobes squeezed against the horizon at
    // cos theta_o = 1e-4 are integrated to about that accuracy).
    let lost_fraction = observed[lost] as f64 / n as f64;
    let total = pdf_integral + delta_mass + lost_fraction;
    let sigma = (lost_fraction * (1.0 - lost_fraction) / n as f64).sqrt();
    if (total - 1.0).abs() > 5.0 * sigma + 1e-4 {
        return Err(format!(
            "density {pdf_integral} + delta masses {delta_mass} + rejected fraction {lost_fraction} = {total}, not 1"
        ));
    }
    // The shape: the kept samples against the normalised density (the
    // rejected fraction was checked above; leaving it out of the statistic
    // keeps the quadrature's 1e-4 out of a bin that may hold only tens of
    // samples).
    let kept = (n as u64 - observed[lost]) as f64;
    let norm = kept / (pdf_integral + delta_mass);
    expected.extend(deltas.iter().map(|d| d.mass));
    for e in &mut expected {
        *e *= norm;
    }
    observed.truncate(lost);

    // Pool low-expectation bins (pbrt's scheme), sorted by expectation.
    let mut order: Vec<usize> = (0..expected.len()).collect();
    order.sort_by(|&a, &b| expected[a].partial_cmp(&expected[b]).unwrap());
    let (mut pooled_obs, mut pooled_exp) = (0.0f64, 0.0f64);
    let mut stat = 0.0;
    let mut bins = 0usize;
    for &i in &order {
        let (o, e) = (observed[i] as f64, expected[i]);
        if e <= 0.0 {
            if o > n as f64 * 1e-5 {
                return Err(format!("{o} samples in bin {i} whose expected count is 0"));
            }
            pooled_obs += o;
        } else if e < 5.0 || (pooled_exp > 0.0 && pooled_exp < 5.0) {
            pooled_obs += o;
            pooled_exp += e;
        } else {
            stat += (o - e) * (o - e) / e;
            bins += 1;
        }
    }
    if pooled_exp > 0.0 || pooled_obs > 0.0 {
        let e = pooled_exp.max(1e-12);
        stat += (pooled_obs - e) * (pooled_obs - e) / e;
        bins += 1;
    }
    let dof = bins.saturating_sub(1).max(1);
    let p_value = ChiSquared::new(dof as f64).unwrap().sf(stat);
    Ok(Chi2Report {
        statistic: stat,
        dof,
        p_value,
        pdf_integral,
        lost_fraction,
    })
}

/// Significance level of one of `tests` chi-square tests so that the whole
/// family has level `alpha` (Sidak correction).
pub fn sidak(alpha: f64, tests: usize) -> f64 {
    1.0 - (1.0 - alpha).powf(1.0 / tests as f64)
}

use glint_cpu::bsdf::coated::{CoatParams, coated_coat_probability};
use glint_cpu::bsdf::{Bsdf, ConductorParams, Roughness, Shadowing, Tint, fresnel};

pub fn rough(alpha_u: f32, alpha_v: f32, shadowing: Shadowing) -> Roughness {
    Roughness {
        alpha_u,
        alpha_v,
        shadowing,
        multiscatter: false,
    }
}

/// Gold (the crate's named metal) with the given roughness.
pub fn gold(roughness: Roughness) -> ConductorParams {
    let (eta, k) = glint_cpu::bsdf::named_metal("Au").unwrap();
    ConductorParams {
        eta,
        k,
        specular_reflectance: Vec3::ONE,
        roughness,
    }
}

/// The Dirac lobes a BSDF's sampler produces for `wo`, with their masses.
pub fn delta_lobes(bsdf: &Bsdf, wo: Vec3) -> Vec<DeltaLobe> {
    let mirror = Vec3::new(-wo.x, -wo.y, wo.z);
    match bsdf {
        Bsdf::Diffuse { .. } => vec![],
        Bsdf::Conductor(c) if c.roughness.is_smooth() => vec![DeltaLobe {
            dir: mirror,
            mass: 1.0,
        }],
        // The metal's mirror and the smooth coat's share one direction.
        Bsdf::Metallic {
            metallic,
            conductor,
            base,
            coat,
        } if conductor.roughness.is_smooth() => {
            let p = coated_coat_probability(*base, coat, &conductor.roughness, wo.z) as f64;
            vec![DeltaLobe {
                dir: mirror,
                mass: *metallic as f64 + (1.0 - *metallic as f64) * p,
            }]
        }
        Bsdf::Plastic(p) => {
            let f = fresnel::fresnel_dielectric(wo.z.abs(), p.eta) as f64;
            let w = p.specular_sampling_weight() as f64;
            vec![DeltaLobe {
                dir: mirror,
                mass: f * w / (f * w + (1.0 - f) * (1.0 - w)),
            }]
        }
        Bsdf::ThinDielectric { eta, .. } => {
            let r = glint_cpu::bsdf::thin::thin_reflectance(wo.z, *eta) as f64;
            vec![
                DeltaLobe {
                    dir: mirror,
                    mass: r,
                },
                DeltaLobe {
                    dir: -wo,
                    mass: 1.0 - r,
                },
            ]
        }
        // The opaque part's mirror (1 - t) P and the thin wall's mirror and
        // straight-through lobes t p_r, t (1 - p_r).
        Bsdf::Coated {
            base,
            coat,
            roughness,
        } if roughness.is_smooth() => {
            let t = coat.transmission as f64;
            let p = coated_coat_probability(*base, coat, roughness, wo.z) as f64;
            let r = glint_cpu::bsdf::thin::thin_reflectance(wo.z, coat.eta);
            let p_r = ((coat.specular * r).min(Vec3::ONE).element_sum() / 3.0) as f64;
            let mut v = vec![DeltaLobe {
                dir: mirror,
                mass: (1.0 - t) * p + t * p_r,
            }];
            if t > 0.0 {
                v.push(DeltaLobe {
                    dir: -wo,
                    mass: t * (1.0 - p_r),
                });
            }
            v
        }
        Bsdf::Dielectric { eta, .. } if bsdf.is_delta() => {
            let f = fresnel::fresnel_dielectric(wo.z, *eta) as f64;
            let mut v = vec![DeltaLobe {
                dir: mirror,
                mass: f,
            }];
            if let Some((wt, _)) = fresnel::refract_dir(wo, Vec3::Z, *eta) {
                v.push(DeltaLobe {
                    dir: wt,
                    mass: 1.0 - f,
                });
            }
            v
        }
        _ => vec![],
    }
}

/// A named test configuration: a BSDF and an outgoing direction.
#[derive(Clone, Debug)]
pub struct Case {
    pub name: String,
    pub bsdf: Bsdf,
    pub wo: Vec3,
}

/// Azimuth of wo in the test grids: away from the anisotropy axes.
pub const PHI_O: f32 = 1.1;

/// The BSDF configurations the statistical tests run over: every model,
/// incident angles down to cos theta = 1e-4 on both sides, alphas
/// 0.01 .. 1, isotropic and anisotropic, both shadowing forms,
/// dielectrics from inside (below and beyond the critical angle) and with
/// the denser medium outside (eta < 1).
pub fn chi2_cases() -> Vec<Case> {
    let mut v = Vec::new();
    let alphas = [(0.01, 0.01), (0.2, 0.2), (1.0, 1.0), (0.05, 0.6)];
    for (ai, &(au, av)) in alphas.iter().enumerate() {
        let sh = if ai % 2 == 0 {
            Shadowing::Correlated
        } else {
            Shadowing::Separable
        };
        for &c in &[1.0, 0.5, 0.05, 1e-4, -0.6] {
            v.push(Case {
                name: format!("roughconductor a=({au},{av}) cos={c}"),
                bsdf: Bsdf::Conductor(gold(rough(au, av, sh))),
                wo: dir_cos(c, PHI_O),
            });
        }
        for &c in &[1.0, 0.5, 1e-4, -0.9, -0.3, -1e-4] {
            v.push(Case {
                name: format!("roughdielectric eta=1.5 a=({au},{av}) cos={c}"),
                bsdf: Bsdf::Dielectric {
                    eta: 1.5,
                    roughness: rough(au, av, sh),
                    tint: glint_cpu::bsdf::Tint::NONE,
                },
                wo: dir_cos(c, PHI_O),
            });
        }
    }
    for &c in &[0.9, 0.5, -0.5] {
        v.push(Case {
            name: format!("roughdielectric eta=1/1.333 a=0.2 cos={c}"),
            bsdf: Bsdf::Dielectric {
                eta: 1.0 / 1.333,
                roughness: rough(0.2, 0.2, Shadowing::Correlated),
                tint: glint_cpu::bsdf::Tint::NONE,
            },
            wo: dir_cos(c, PHI_O),
        });
    }
    for &c in &[0.7, 1e-4, -0.3] {
        v.push(Case {
            name: format!("diffuse cos={c}"),
            bsdf: Bsdf::Diffuse {
                reflectance: Vec3::new(0.8, 0.5, 0.2),
            },
            wo: dir_cos(c, PHI_O),
        });
    }
    for &c in &[0.8, -0.2] {
        v.push(Case {
            name: format!("metallic m=0.4 a=0.3 cos={c}"),
            bsdf: Bsdf::Metallic {
                metallic: 0.4,
                base: Vec3::new(0.9, 0.6, 0.3),
                conductor: gold(rough(0.3, 0.3, Shadowing::Correlated)),
                coat: glint_cpu::bsdf::coated::CoatParams::GLTF_DEFAULT,
            },
            wo: dir_cos(c, PHI_O),
        });
    }
    v.push(Case {
        name: "metallic m=0.6 smooth cos=0.5".into(),
        bsdf: Bsdf::Metallic {
            metallic: 0.6,
            base: Vec3::new(0.9, 0.6, 0.3),
            conductor: gold(Roughness::SMOOTH),
            coat: glint_cpu::bsdf::coated::CoatParams::GLTF_DEFAULT,
        },
        wo: dir_cos(0.5, PHI_O),
    });
    // The glTF non-metal: smooth and rough coats, black and coloured bases
    // (a black base samples only the coat), eta near 1 (a faint coat),
    // grazing and from below.
    let coated = |base: Vec3, eta: f32, specular: Vec3, r: Roughness| Bsdf::Coated {
        base,
        coat: CoatParams {
            eta,
            specular,
            transmission: 0.0,
            clearcoat: 0.0,
            clearcoat_alpha: 0.0,
            clearcoat_normal: glam::Vec2::ZERO,
        },
        roughness: r,
    };
    for &(a, c) in &[
        (0.3, 0.8),
        (0.3, -0.4),
        (0.05, 0.2),
        (1.0, 0.6),
        (0.002, 0.7),
        (0.6, 1e-3),
    ] {
        v.push(Case {
            name: format!("coated a={a} cos={c}"),
            bsdf: coated(
                Vec3::new(0.8, 0.5, 0.2),
                1.5,
                Vec3::ONE,
                rough(a, a, Shadowing::Correlated),
            ),
            wo: dir_cos(c, PHI_O),
        });
    }
    v.push(Case {
        name: "coated black a=0.2 cos=0.5".into(),
        bsdf: coated(
            Vec3::ZERO,
            1.5,
            Vec3::ONE,
            rough(0.2, 0.2, Shadowing::Correlated),
        ),
        wo: dir_cos(0.5, PHI_O),
    });
    v.push(Case {
        name: "coated eta=1.01 specular a=0.4 cos=0.3".into(),
        bsdf: coated(
            Vec3::splat(0.5),
            1.01,
            Vec3::new(1.0, 0.5, 0.2),
            rough(0.4, 0.4, Shadowing::Correlated),
        ),
        wo: dir_cos(0.3, PHI_O),
    });
    // Thin-walled glTF transmission (KHR_materials_transmission), rough
    // and smooth, partial and full.
    for &(a, t, c) in &[
        (0.3, 0.5, 0.7),
        (0.05, 1.0, -0.3),
        (0.0, 0.6, 0.4),
        (0.0, 1.0, 0.8),
    ] {
        v.push(Case {
            name: format!("coated thin-walled a={a} t={t} cos={c}"),
            bsdf: Bsdf::Coated {
                base: Vec3::new(0.8, 0.5, 0.2),
                coat: CoatParams {
                    eta: 1.5,
                    specular: Vec3::ONE,
                    transmission: t,
                    clearcoat: 0.0,
                    clearcoat_alpha: 0.0,
                    clearcoat_normal: glam::Vec2::ZERO,
                },
                roughness: rough(a, a, Shadowing::Correlated),
            },
            wo: dir_cos(c, PHI_O),
        });
    }
    // KHR_materials_clearcoat over the non-metal and over the blend, its
    // normal the shading normal or tilted (clearcoatNormalTexture).
    let tilt_a = glam::Vec2::new(0.3, -0.25);
    let tilt_b = glam::Vec2::new(-0.2, 0.35);
    for &(a, cc, ca, c, n) in &[
        (0.3, 1.0, 0.05, 0.7, glam::Vec2::ZERO),
        (0.5, 0.6, 0.3, -0.4, glam::Vec2::ZERO),
        (0.3, 0.8, 0.1, 0.5, tilt_a),
        (0.4, 1.0, 0.2, -0.6, tilt_b),
    ] {
        let coat = CoatParams {
            clearcoat: cc,
            clearcoat_alpha: ca,
            clearcoat_normal: n,
            ..CoatParams::GLTF_DEFAULT
        };
        v.push(Case {
            name: format!("clearcoat {cc} a={ca} n={n} over coated a={a} cos={c}"),
            bsdf: Bsdf::Coated {
                base: Vec3::new(0.8, 0.5, 0.2),
                coat,
                roughness: rough(a, a, Shadowing::Correlated),
            },
            wo: dir_cos(c, PHI_O),
        });
        v.push(Case {
            name: format!("clearcoat {cc} a={ca} n={n} over metallic a={a} cos={c}"),
            bsdf: Bsdf::Metallic {
                metallic: 0.7,
                base: Vec3::new(0.9, 0.6, 0.3),
                conductor: gold(rough(a, a, Shadowing::Correlated)),
                coat,
            },
            wo: dir_cos(c, PHI_O),
        });
    }
    for &c in &[0.5, -0.7] {
        v.push(Case {
            name: format!("coated smooth cos={c}"),
            bsdf: coated(Vec3::new(0.8, 0.5, 0.2), 1.5, Vec3::ONE, Roughness::SMOOTH),
            wo: dir_cos(c, PHI_O),
        });
    }
    // Mitsuba's plastic and thindielectric.
    for &c in &[0.9, 0.2, -0.5] {
        v.push(Case {
            name: format!("plastic cos={c}"),
            bsdf: Bsdf::Plastic(glint_cpu::bsdf::plastic::PlasticParams {
                diffuse: Vec3::new(0.8, 0.4, 0.1),
                specular: Vec3::ONE,
                eta: 1.49,
                nonlinear: c < 0.0,
            }),
            wo: dir_cos(c, PHI_O),
        });
        v.push(Case {
            name: format!("thindielectric cos={c}"),
            bsdf: Bsdf::ThinDielectric {
                eta: 1.5,
                tint: Tint::NONE,
            },
            wo: dir_cos(c, PHI_O),
        });
    }
    for &(a, c, sh) in &[
        (0.1, 0.8, Shadowing::Separable),
        (0.4, 0.3, Shadowing::Correlated),
        (0.02, -0.6, Shadowing::Separable),
    ] {
        v.push(Case {
            name: format!("roughplastic a={a} cos={c} {sh:?}"),
            bsdf: Bsdf::RoughPlastic(glint_cpu::bsdf::roughplastic::RoughPlasticParams {
                plastic: glint_cpu::bsdf::plastic::PlasticParams {
                    diffuse: Vec3::new(0.8, 0.4, 0.1),
                    specular: Vec3::ONE,
                    eta: 1.49,
                    nonlinear: false,
                },
                roughness: rough(a, a, sh),
            }),
            wo: dir_cos(c, PHI_O),
        });
    }
    v.push(Case {
        name: "conductor smooth cos=0.5".into(),
        bsdf: Bsdf::Conductor(gold(Roughness::SMOOTH)),
        wo: dir_cos(0.5, PHI_O),
    });
    for &c in &[0.8, 1e-4, -0.9, -0.3] {
        v.push(Case {
            name: format!("dielectric eta=1.5 cos={c}"),
            bsdf: Bsdf::Dielectric {
                eta: 1.5,
                roughness: Roughness::SMOOTH,
                tint: glint_cpu::bsdf::Tint::NONE,
            },
            wo: dir_cos(c, PHI_O),
        });
    }
    v
}
