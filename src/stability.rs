//! The stability sweep behind `glint stability`: each BSDF through its
//! failure points (grazing and below-horizon angles, alpha from 0 through
//! the smooth threshold to 1, eta from 1/2.42 to 2.42 including 1 and
//! 1 +- 1e-6, conductor k from 0 to 1e3, anisotropy to 1000, wi = wo,
//! random numbers at 0 and 1 - 2^-24), on the CPU crate and on the GLSL
//! twins through the differential kernel `shaders/tests/bsdf_test.comp`.
//!
//! At each point (a BSDF and an outgoing direction):
//! - `finite`: every eval, pdf and sample output finite, f >= 0, pdf >= 0;
//! - `recip`: the largest generalised-reciprocity error
//!   |f(wo,wi)/n_o^2 - f(wi,wo)/n_i^2|, relative to the larger side plus
//!   an absolute 1e-4 floor;
//! - `albedo`: the directional albedo from `sample` (transmission undone
//!   by eta^2, so it is the flux ratio), which must not exceed 1, and
//!   `albedo_quad`: the same integral of `eval` by the half-vector
//!   quadrature of `glint_cpu::quadrature` (independent of `sample` and
//!   `pdf`; accurate for narrow lobes; every rough single-scattering
//!   model), both for the largest channel of the mean;
//! - `pdf_mismatch`: the fraction of samples whose pdf or weight disagrees
//!   with `pdf`/`eval` at the sampled direction by more than 1e-3, and
//!   `pdf_ill` the part of such samples where f32 cannot resolve the lobe
//!   (pdf moves by more than 1e-3 under a 32-ulp jitter of wi), counted
//!   apart; `lost`: the fraction of samples `sample` refused (reported);
//! - random numbers at 0, 0.5 and 1 - 2^-24 in every combination: finite;
//! - `gpu_mismatch`: the fraction of queries where the GLSL BSDF differs
//!   from the CPU beyond 1e-4 relative (as `tests/gpu_bsdf.rs`), not
//!   counting inputs within float noise of a discontinuity
//!   (`GLINT_STABILITY_DEBUG=1` prints the first three per point). What the
//!   remaining ones are: rough glass sampled at u.y = 1 - 2^-24, where the
//!   visible normal lies on the rim of its spherical cap (grazing to wo)
//!   and the CPU and GPU roundings of the ill-conditioned refraction fall
//!   on either side of a validity check (one returns a sample, the other
//!   none); a conductor with eta 0.2 and k = 1e-3 near its Fresnel critical
//!   angle, where the complex square root of a near-zero number puts 1e-4
//!   relative between the two evaluations;
//! - `continuity`: at the first point past a threshold (alpha just above
//!   `SMOOTH_ALPHA_THRESHOLD`, eta just past `ETA_SMOOTH_THRESHOLD`), the
//!   albedo jump from the point just before it.
//!
//! Status: `fail` for non-finite or negative values, an albedo above 1
//! beyond noise, GPU mismatches on more than 5% of the queries or more
//! than 5% inconsistent samples; `degrade` for any GPU mismatch, a
//! reciprocity error above 1e-3, more than 0.5% inconsistent or
//! unresolvable samples, an albedo off its quadrature by more than noise +
//! 0.01, or a jump above 0.02 across a threshold; else `pass`.

#![allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x > 0.0)` also catches NaN

use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};
use glint_cpu::bsdf::{
    Bsdf, ConductorParams, ETA_SMOOTH_THRESHOLD, Roughness, SMOOTH_ALPHA_THRESHOLD, Shadowing,
    named_metal,
};
use glint_cpu::sampling::Pcg32;
use glint_cpu::{GpuMaterial, Material};
use rayon::prelude::*;

use crate::gpu::{Context, GpuError, groups};

/// Sweep size: `full` for the published table, `quick` for CI.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Size {
    Quick,
    Full,
}

impl Size {
    fn samples(self) -> usize {
        match self {
            Size::Quick => 2_000,
            Size::Full => 20_000,
        }
    }
    fn pairs(self) -> usize {
        match self {
            Size::Quick => 200,
            Size::Full => 2_000,
        }
    }
    fn gpu_queries(self) -> usize {
        match self {
            Size::Quick => 64,
            Size::Full => 512,
        }
    }
}

/// One point of the sweep.
#[derive(Clone, Debug)]
pub struct Point {
    /// Which sweep: `alpha`, `eta`, `k`, `aniso`.
    pub family: &'static str,
    /// The model's name in the table (`roughconductor`, ...).
    pub model: String,
    /// Index of the parameter value along the family's axis, and its label.
    pub param_index: usize,
    pub param: String,
    /// Index of cos theta_o in [`COS`].
    pub cos_index: usize,
    pub bsdf: Bsdf,
    pub wo: Vec3,
}

/// Results at one point.
#[derive(Clone, Debug, Default)]
pub struct Row {
    pub finite: bool,
    pub recip: f64,
    pub albedo: f64,
    pub albedo_se: f64,
    pub albedo_quad: Option<f64>,
    pub pdf_mismatch: f64,
    /// Fraction of samples whose pdf disagrees where f32 cannot resolve
    /// the lobe (the pdf itself moves under a 32-ulp jitter).
    pub pdf_ill: f64,
    pub lost: f64,
    pub gpu_mismatch: Option<f64>,
    pub continuity: Option<f64>,
    pub status: Status,
    pub why: String,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
pub enum Status {
    #[default]
    Pass,
    Degrade,
    Fail,
}

impl Status {
    pub fn name(self) -> &'static str {
        match self {
            Status::Pass => "pass",
            Status::Degrade => "degrade",
            Status::Fail => "fail",
        }
    }
}

/// cos theta_o, from normal incidence to grazing and below the horizon.
pub const COS: [f32; 13] = [
    1.0, 0.7, 0.3, 0.1, 1e-2, 1e-3, 1e-4, 1e-6, 1e-8, 0.0, -1e-4, -0.5, -1.0,
];

/// Alphas: 0, 1e-8, 1e-4, the smooth threshold from both sides, 0.01 .. 1.
pub fn alphas() -> Vec<f32> {
    vec![
        0.0,
        1e-8,
        1e-4,
        SMOOTH_ALPHA_THRESHOLD * 0.999,
        SMOOTH_ALPHA_THRESHOLD * 1.001,
        0.01,
        0.03,
        0.1,
        0.3,
        0.6,
        1.0,
    ]
}

/// Relative IORs from 1/2.42 to 2.42, through 1 and 1 +- 1e-6 and the eta
/// threshold from both sides.
pub fn etas() -> Vec<f32> {
    let t = ETA_SMOOTH_THRESHOLD;
    vec![
        1.0 / 2.42,
        1.0 / 1.5,
        1.0 - 1.001 * t,
        1.0 - 0.999 * t,
        1.0 - 1e-6,
        1.0,
        1.0 + 1e-6,
        1.0 + 0.999 * t,
        1.0 + 1.001 * t,
        1.05,
        1.333,
        1.5,
        2.42,
    ]
}

pub const KS: [f32; 7] = [0.0, 1e-3, 0.1, 1.0, 10.0, 100.0, 1e3];
pub const ANISO: [f32; 5] = [1.0, 10.0, 100.0, 300.0, 1000.0];

fn rough(au: f32, av: f32, sh: Shadowing) -> Roughness {
    Roughness {
        alpha_u: au,
        alpha_v: av,
        shadowing: sh,
        multiscatter: false,
    }
}

fn gold(r: Roughness) -> ConductorParams {
    let (eta, k) = named_metal("Au").expect("Au is in the table");
    ConductorParams {
        eta,
        k,
        specular_reflectance: Vec3::ONE,
        roughness: r,
    }
}

fn wo_of(c: f32) -> Vec3 {
    let s = (1.0 - c as f64 * c as f64).max(0.0).sqrt() as f32;
    // An azimuth off the axes, so anisotropy shows.
    let phi = 0.7f32;
    Vec3::new(s * phi.cos(), s * phi.sin(), c)
}

/// Every point of the sweep.
pub fn points() -> Vec<Point> {
    let mut v = Vec::new();
    let mut add = |family: &'static str, model: &str, pi: usize, param: String, b: Bsdf| {
        for (ci, &c) in COS.iter().enumerate() {
            v.push(Point {
                family,
                model: model.to_string(),
                param_index: pi,
                param: param.clone(),
                cos_index: ci,
                bsdf: b,
                wo: wo_of(c),
            });
        }
    };
    alpha_points(&mut add);
    eta_points(&mut add);
    k_points(&mut add);
    aniso_points(&mut add);
    v
}

/// Adds one model's points (over every cos theta_o): family, model, the
/// parameter's index and label, the BSDF.
type Add<'a> = dyn FnMut(&'static str, &str, usize, String, Bsdf) + 'a;

/// Family "alpha": each rough model through the smooth threshold.
fn alpha_points(add: &mut Add<'_>) {
    add(
        "alpha",
        "diffuse",
        0,
        "-".into(),
        Bsdf::Diffuse {
            reflectance: Vec3::splat(0.8),
        },
    );
    for (pi, &a) in alphas().iter().enumerate() {
        let p = format!("{a:e}");
        for (sh, tag) in [
            (Shadowing::Correlated, ""),
            (Shadowing::Separable, " separable"),
        ] {
            let r = rough(a, a, sh);
            add(
                "alpha",
                &format!("roughconductor Au{tag}"),
                pi,
                p.clone(),
                Bsdf::Conductor(gold(r)),
            );
            add(
                "alpha",
                &format!("roughdielectric 1.5{tag}"),
                pi,
                p.clone(),
                Bsdf::Dielectric {
                    eta: 1.5,
                    roughness: r,
                    tint: glint_cpu::bsdf::Tint::NONE,
                },
            );
        }
        let r = rough(a, a, Shadowing::Correlated);
        add(
            "alpha",
            "roughdielectric 1/1.5",
            pi,
            p.clone(),
            Bsdf::Dielectric {
                eta: 1.0 / 1.5,
                roughness: r,
                tint: glint_cpu::bsdf::Tint::NONE,
            },
        );
        add(
            "alpha",
            "coated 0.8 ior 1.5",
            pi,
            p.clone(),
            Bsdf::Coated {
                base: Vec3::splat(0.8),
                coat: glint_cpu::bsdf::coated::CoatParams::GLTF_DEFAULT,
                roughness: r,
            },
        );
        add(
            "alpha",
            "metallic 0.5 Au",
            pi,
            p.clone(),
            Bsdf::Metallic {
                metallic: 0.5,
                base: Vec3::splat(0.8),
                conductor: gold(r),
                coat: glint_cpu::bsdf::coated::CoatParams::GLTF_DEFAULT,
            },
        );
    }
}

/// Family "eta": rough glass through eta = 1.
fn eta_points(add: &mut Add<'_>) {
    for (pi, &eta) in etas().iter().enumerate() {
        for a in [0.01f32, 0.3] {
            add(
                "eta",
                &format!("roughdielectric alpha {a}"),
                pi,
                format!("{eta:.7}"),
                Bsdf::Dielectric {
                    eta,
                    roughness: rough(a, a, Shadowing::Correlated),
                    tint: glint_cpu::bsdf::Tint::NONE,
                },
            );
        }
    }
}

/// Family "k": a conductor's extinction from 0 to 1e3.
fn k_points(add: &mut Add<'_>) {
    for (pi, &k) in KS.iter().enumerate() {
        for eta in [0.2f32, 1.5] {
            add(
                "k",
                &format!("roughconductor eta {eta} alpha 0.1"),
                pi,
                format!("{k:e}"),
                Bsdf::Conductor(ConductorParams {
                    eta: Vec3::splat(eta),
                    k: Vec3::splat(k),
                    specular_reflectance: Vec3::ONE,
                    roughness: rough(0.1, 0.1, Shadowing::Correlated),
                }),
            );
        }
    }
}

/// Family "aniso": anisotropy ratios to 1000.
fn aniso_points(add: &mut Add<'_>) {
    for (pi, &ratio) in ANISO.iter().enumerate() {
        let r = rough(0.3, 0.3 / ratio, Shadowing::Correlated);
        add(
            "aniso",
            "roughconductor Au 0.3/ratio",
            pi,
            format!("{ratio}"),
            Bsdf::Conductor(gold(r)),
        );
        add(
            "aniso",
            "roughdielectric 1.5 0.3/ratio",
            pi,
            format!("{ratio}"),
            Bsdf::Dielectric {
                eta: 1.5,
                roughness: r,
                tint: glint_cpu::bsdf::Tint::NONE,
            },
        );
    }
}

/// The largest random number a 24-bit sampler produces, 1 - 2^-24.
pub const U_MAX: f32 = 1.0 - f32::EPSILON / 2.0;

/// Random numbers with the corners 0 and 1 - 2^-24 mixed in (1 in 8 of
/// each coordinate).
fn u_corner(rng: &mut Pcg32) -> f32 {
    match rng.next_u32() % 16 {
        0 => 0.0,
        1 => U_MAX,
        _ => rng.f32(),
    }
}

fn medium(b: &Bsdf, w: Vec3) -> f32 {
    match b {
        Bsdf::Dielectric { eta, .. } if w.z < 0.0 => *eta,
        _ => 1.0,
    }
}

/// Directional albedo (flux, per channel) of a rough, single-scattering
/// `b` seen from `wo`, with its error estimate, by deterministic
/// quadrature of its `eval`
/// (`glint_cpu::quadrature::hv_two`); the metallic blend adds its diffuse
/// part exactly (its albedo is its base colour). None for smooth lobes,
/// diffuse alone, grazing-exact wo, and `multiscatter` (whose diffuse-like
/// lobe the half-vector rule does not resolve).
fn albedo_by_quadrature(b: &Bsdf, wo: Vec3) -> Option<(glam::DVec3, glam::DVec3)> {
    use glint_cpu::quadrature::hv_two;
    let r = match b {
        Bsdf::Diffuse { .. }
        | Bsdf::Plastic(_)
        | Bsdf::RoughPlastic(_)
        | Bsdf::ThinDielectric { .. } => return None,
        Bsdf::Conductor(c) => c.roughness,
        Bsdf::Dielectric { roughness, .. } => *roughness,
        Bsdf::Metallic { conductor, .. } => conductor.roughness,
        Bsdf::Coated { roughness, .. } => *roughness,
    };
    if r.is_smooth() || r.multiscatter || b.is_delta() || wo.z == 0.0 {
        return None;
    }
    let (ax, ay) = (
        r.alpha_u.max(glint_cpu::bsdf::microfacet::MIN_ALPHA) as f64,
        r.alpha_v.max(glint_cpu::bsdf::microfacet::MIN_ALPHA) as f64,
    );
    // The coated non-metal: its coat by quadrature (a black base leaves
    // the coat alone), its base term exactly: base (1 - s E(mu_o)), E the
    // tables' (coated.rs: the base term integrates to that by construction).
    let coated = |base: Vec3, coat: &glint_cpu::bsdf::coated::CoatParams| {
        let black = Bsdf::Coated {
            base: Vec3::ZERO,
            coat: *coat,
            roughness: r,
        };
        let (q, e) = hv_two(&black, wo, ax, ay);
        let e_tab = glint_cpu::bsdf::coated::coated_albedo(Vec3::ZERO, coat, &r, wo.z.abs());
        (q.r + (base * (Vec3::ONE - e_tab)).as_dvec3(), e.r)
    };
    match b {
        Bsdf::Metallic {
            metallic,
            base,
            conductor,
            coat,
        } => {
            let (q, e) = hv_two(&Bsdf::Conductor(*conductor), wo, ax, ay);
            let (qn, en) = coated(*base, coat);
            let w = *metallic as f64;
            Some((q.r * w + qn * (1.0 - w), e.r * w + en * (1.0 - w)))
        }
        Bsdf::Coated { base, coat, .. } => Some(coated(*base, coat)),
        _ => {
            let (q, e) = hv_two(b, wo, ax, ay);
            Some((q.r + glam::DVec3::splat(q.t), e.r + glam::DVec3::splat(e.t)))
        }
    }
}

fn finite_ok(f: Vec3, p: f32) -> bool {
    f.is_finite() && f.min_element() >= 0.0 && p.is_finite() && p >= 0.0
}

/// The CPU measurements at one point (all but the GPU and continuity).
pub fn measure_cpu(pt: &Point, size: Size, seed: u64) -> Row {
    let b = &pt.bsdf;
    let wo = pt.wo;
    let mut rng = Pcg32::from_state(seed.wrapping_mul(0x9e3779b97f4a7c15) | 1);
    let mut row = Row {
        finite: true,
        ..Row::default()
    };
    reciprocity(b, wo, size, &mut rng, &mut row);
    // Samples: albedo, consistency with pdf/eval, lost samples.
    let n = size.samples();
    // Per channel: the albedo is the largest channel's mean.
    let (mut s1, mut s2) = (glam::DVec3::ZERO, glam::DVec3::ZERO);
    let (mut lost, mut checked, mut bad) = (0usize, 0usize, 0usize);
    if !corners_finite(b, wo) {
        row.finite = false;
    }
    let mut ill = 0usize;
    for _ in 0..n {
        let uc = rng.f32();
        let u = Vec2::new(rng.f32(), rng.f32());
        let Some(s) = b.sample(wo, uc, u) else {
            lost += 1;
            continue;
        };
        if !(s.wi.is_finite() && s.weight.is_finite() && s.pdf.is_finite())
            || s.weight.min_element() < 0.0
            || !(s.pdf > 0.0)
        {
            row.finite = false;
            continue;
        }
        let v = (s.weight * s.eta * s.eta).as_dvec3();
        s1 += v;
        s2 += v * v;
        if s.delta {
            continue;
        }
        checked += 1;
        match sample_check(b, wo, &s) {
            SampleCheck::Ok => {}
            SampleCheck::Ill => ill += 1,
            SampleCheck::Bad => bad += 1,
        }
    }
    row.pdf_ill = if checked > 0 {
        ill as f64 / checked as f64
    } else {
        0.0
    };
    let mean = s1 / n as f64;
    let c = (0..3).fold(0, |c, k| if mean[k] > mean[c] { k } else { c });
    let m = mean[c];
    row.albedo = m;
    row.albedo_se = ((s2[c] / n as f64 - m * m).max(0.0) / n as f64).sqrt();
    row.lost = if wo.z == 0.0 {
        0.0
    } else {
        lost as f64 / n as f64
    };
    row.pdf_mismatch = if checked > 0 {
        bad as f64 / checked as f64
    } else {
        0.0
    };
    // The same albedo by quadrature of eval alone (glint_cpu::quadrature:
    // half-vector space, accurate for narrow lobes too), channel c.
    // Left out where the quadrature's own error estimate (two orders) says
    // it has not converged.
    row.albedo_quad = albedo_by_quadrature(b, wo)
        .filter(|(_, err)| err[c] <= 2e-3)
        .map(|(q, _)| q[c]);
    row
}

/// Finiteness and reciprocity at wi = wo, wi = -wo and `size.pairs()`
/// random pairs: `row.finite` cleared on a non-finite value, `row.recip`
/// the largest relative reciprocity error.
fn reciprocity(b: &Bsdf, wo: Vec3, size: Size, rng: &mut Pcg32, row: &mut Row) {
    // wi = wo and wi = -wo, then random pairs: finiteness and reciprocity.
    let mut recip = 0.0f64;
    for k in 0..size.pairs() + 2 {
        let wi = match k {
            0 => wo,
            1 => -wo,
            _ => rng.dir(),
        };
        let f = b.eval(wo, wi);
        let p = b.pdf(wo, wi);
        let fr = b.eval(wi, wo);
        let pr = b.pdf(wi, wo);
        if !finite_ok(f, p) || !finite_ok(fr, pr) {
            row.finite = false;
            continue;
        }
        let a = f / medium(b, wo).powi(2);
        let r = fr / medium(b, wi).powi(2);
        // Relative, with the absolute floor of bsdf_physics.rs (2e-5 at
        // the 1e-3 level) for tiny values next to the critical angle.
        let scale = a.max_element().max(r.max_element()) as f64 + 2e-2;
        recip = recip.max((a - r).abs().max_element() as f64 / scale);
    }
    row.recip = recip;
}

/// Whether `sample` stays finite at the corners 0 and 1 - 2^-24 of every
/// random number (a sampler meets them once in 2^24 draws).
fn corners_finite(b: &Bsdf, wo: Vec3) -> bool {
    let corners = [0.0, 0.5, U_MAX];
    for &uc in &corners {
        for &ux in &corners {
            for &uy in &corners {
                if let Some(s) = b.sample(wo, uc, Vec2::new(ux, uy))
                    && (!(s.wi.is_finite() && s.weight.is_finite() && s.pdf.is_finite())
                        || s.weight.min_element() < 0.0
                        || !(s.pdf > 0.0))
                {
                    return false;
                }
            }
        }
    }
    true
}

enum SampleCheck {
    Ok,
    /// f32 cannot resolve the lobe at this direction.
    Ill,
    Bad,
}

/// A non-delta sample against `pdf` and `eval` (1e-3). Ill-conditioned (as
/// bsdf_physics.rs tells them): pdf moves by more than 1e-3 under a 32-ulp
/// jitter of wi.
fn sample_check(b: &Bsdf, wo: Vec3, s: &glint_cpu::BsdfSample) -> SampleCheck {
    let pdf = b.pdf(wo, s.wi);
    let w = b.eval(wo, s.wi) * s.wi.z.abs() / pdf;
    let ok = (pdf - s.pdf).abs() <= 1e-3 * pdf
        && (w - s.weight).abs().max_element() <= 1e-3 * w.max_element() + 1e-6;
    if ok {
        return SampleCheck::Ok;
    }
    let jit = |k: f32| {
        let e = k * 32.0 * f32::EPSILON;
        b.pdf(
            wo,
            Vec3::new(s.wi.x * (1.0 + e), s.wi.y * (1.0 - e), s.wi.z),
        )
    };
    let spread = (jit(1.0) - pdf).abs().max((jit(-1.0) - pdf).abs());
    if spread > 1e-3 * pdf {
        SampleCheck::Ill
    } else {
        SampleCheck::Bad
    }
}

// ------------------------------------------------------------------ GPU

/// One query of `shaders/tests/bsdf_test.comp` (std430 mirror): wo, wi,
/// and the sample's random numbers (uc, u.x, u.y).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Query {
    pub wo: [f32; 4],
    pub wi: [f32; 4],
    pub u: [f32; 4],
}

/// One answer of `shaders/tests/bsdf_test.comp` (std430 mirror): f and
/// pdf of (wo, wi), then the sample's wi, pdf, weight, eta and flags.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuResult {
    pub f_pdf: [f32; 4],
    pub s_wi_pdf: [f32; 4],
    pub s_weight_eta: [f32; 4],
    pub flags: [u32; 4],
}

type CpuOut = (Vec3, f32, Option<(Vec3, f32, Vec3, f32, bool)>, bool);

fn cpu_out(b: &Bsdf, q: &Query) -> CpuOut {
    let wo = Vec3::new(q.wo[0], q.wo[1], q.wo[2]);
    let wi = Vec3::new(q.wi[0], q.wi[1], q.wi[2]);
    (
        b.eval(wo, wi),
        b.pdf(wo, wi),
        b.sample(wo, q.wo[3], Vec2::new(q.wi[3], q.u[0]))
            .map(|s| (s.wi, s.pdf, s.weight, s.eta, s.delta)),
        b.is_delta(),
    )
}

fn close(a: f32, b: f32) -> bool {
    (a - b).abs() <= 1e-4 * a.abs().max(b.abs()) + 1e-6 || (a.is_nan() && b.is_nan())
}
fn close3(a: Vec3, b: Vec3) -> bool {
    close(a.x, b.x) && close(a.y, b.y) && close(a.z, b.z)
}

fn agrees(c: &CpuOut, g: &GpuResult) -> bool {
    let v3 = |a: &[f32]| Vec3::new(a[0], a[1], a[2]);
    if !(close3(c.0, v3(&g.f_pdf)) && close(c.1, g.f_pdf[3])) || (g.flags[2] == 1) != c.3 {
        return false;
    }
    match c.2 {
        None => g.flags[0] == 0,
        Some((wi, pdf, w, eta, delta)) => {
            g.flags[0] == 1
                && (g.flags[1] == 1) == delta
                && (wi - v3(&g.s_wi_pdf)).abs().max_element() <= 1e-4
                && close(pdf, g.s_wi_pdf[3])
                && close3(w, v3(&g.s_weight_eta))
                && close(eta, g.s_weight_eta[3])
        }
    }
}

fn as_gpu(c: &CpuOut) -> GpuResult {
    GpuResult {
        f_pdf: [c.0.x, c.0.y, c.0.z, c.1],
        s_wi_pdf: c.2.map_or([0.0; 4], |s| [s.0.x, s.0.y, s.0.z, s.1]),
        s_weight_eta: c.2.map_or([0.0; 4], |s| [s.2.x, s.2.y, s.2.z, s.3]),
        flags: [
            c.2.is_some() as u32,
            c.2.is_some_and(|s| s.4) as u32,
            c.3 as u32,
            0,
        ],
    }
}

/// Whether the CPU result itself moves beyond the tolerance under a
/// few-ulp jitter of the directions and 1e-6 of the random numbers (the
/// size of the two implementations' rounding differences).
fn sensitive(b: &Bsdf, q: &Query, rng: &mut Pcg32) -> bool {
    let base = cpu_out(b, q);
    for _ in 0..8 {
        let mut j = *q;
        for k in 0..3 {
            for a in [&mut j.wo[k], &mut j.wi[k]] {
                *a += a.abs().max(1e-30) * (rng.f32() - 0.5) * 8.0 * f32::EPSILON;
            }
        }
        for a in [&mut j.wo[3], &mut j.wi[3], &mut j.u[0]] {
            *a = (*a + (rng.f32() - 0.5) * 2e-6).clamp(0.0, U_MAX);
        }
        if !agrees(&base, &as_gpu(&cpu_out(b, &j))) {
            return true;
        }
    }
    false
}

/// The GLSL BSDFs' answers to `queries` (`shaders/tests/bsdf_test.comp`:
/// eval, pdf, sample and is_delta of material `u[1]`'s bits), in one
/// dispatch (the kernel reads a few thousand materials comfortably).
pub fn bsdf_kernel(
    ctx: &Context,
    mats: &[GpuMaterial],
    queries: &[Query],
) -> Result<Vec<GpuResult>, GpuError> {
    let mut results = vec![GpuResult::default(); queries.len()];
    let n = queries.len() as u32;
    ctx.run_kernel(
        "tests/bsdf_test",
        &[
            bytemuck::cast_slice(mats),
            bytemuck::cast_slice(queries),
            bytemuck::cast_slice(&glint_cpu::bsdf::multiscatter::gpu_tables()),
        ],
        &mut [bytemuck::cast_slice_mut(&mut results)],
        bytemuck::bytes_of(&n),
        [groups(n, 64), 1, 1],
    )?;
    Ok(results)
}

/// Fraction of queries per point where the GLSL BSDFs disagree with the
/// CPU crate (not counting inputs within float noise of a discontinuity).
pub fn measure_gpu(ctx: &Context, pts: &[Point], size: Size) -> Result<Vec<f64>, GpuError> {
    let mats: Vec<GpuMaterial> = pts
        .iter()
        .map(|p| {
            GpuMaterial::from(&Material {
                name: String::new(),
                bsdf: p.bsdf,
                emission: Vec3::ZERO,
                double_sided: false,
                absorption: glam::Vec3::ZERO,
            })
        })
        .collect();
    let per = size.gpu_queries();
    let mut rng = Pcg32::from_state(0x5eed);
    let mut queries = Vec::with_capacity(pts.len() * per);
    for (i, p) in pts.iter().enumerate() {
        for k in 0..per {
            let wo = p.wo;
            let (uc, u0, u1) = (u_corner(&mut rng), u_corner(&mut rng), u_corner(&mut rng));
            // wi = wo, wi = -wo, on the sampled lobe, and uniform.
            let wi = match k {
                0 => wo,
                1 => -wo,
                _ => match p
                    .bsdf
                    .sample(wo, rng.f32(), Vec2::new(rng.f32(), rng.f32()))
                {
                    Some(s) if k % 2 == 0 => s.wi,
                    _ => rng.dir(),
                },
            };
            queries.push(Query {
                wo: [wo.x, wo.y, wo.z, uc],
                wi: [wi.x, wi.y, wi.z, u0],
                u: [u1, f32::from_bits(i as u32), 0.0, 0.0],
            });
        }
    }
    let results = bsdf_kernel(ctx, &mats, &queries)?;
    Ok(pts
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            let mut rng = Pcg32::from_state(i as u64 * 7 + 1);
            let mut bad = 0usize;
            for k in 0..per {
                let q = &queries[i * per + k];
                let g = &results[i * per + k];
                let c = cpu_out(&p.bsdf, q);
                if !agrees(&c, g) && !sensitive(&p.bsdf, q, &mut rng) {
                    bad += 1;
                    if std::env::var_os("GLINT_STABILITY_DEBUG").is_some() && bad <= 3 {
                        eprintln!(
                            "GPU differs: {:?}\n  wo {:?} wi {:?} u {:?}\n  cpu {c:?}\n  gpu {g:?}",
                            p.bsdf, q.wo, q.wi, q.u
                        );
                    }
                }
            }
            bad as f64 / per as f64
        })
        .collect())
}

// ------------------------------------------------------------ the sweep

/// Run the sweep: the CPU measurements, the GPU's when a context is given,
/// continuity across the thresholds, and each point's status.
pub fn run(size: Size, ctx: Option<&Context>) -> Result<Vec<(Point, Row)>, GpuError> {
    let pts = points();
    let mut rows: Vec<Row> = pts
        .par_iter()
        .enumerate()
        .map(|(i, p)| measure_cpu(p, size, i as u64))
        .collect();
    if let Some(ctx) = ctx {
        let g = measure_gpu(ctx, &pts, size)?;
        for (r, m) in rows.iter_mut().zip(g) {
            r.gpu_mismatch = Some(m);
        }
    }
    // Continuity: the point just past a threshold against the one before.
    let a = alphas();
    let e = etas();
    let after_alpha = a
        .iter()
        .position(|&x| x > SMOOTH_ALPHA_THRESHOLD)
        .expect("an alpha past the threshold");
    let after_eta = [
        e.iter().position(|&x| x > 1.0 + ETA_SMOOTH_THRESHOLD),
        e.iter().rposition(|&x| x < 1.0 - ETA_SMOOTH_THRESHOLD),
    ];
    for i in 0..pts.len() {
        let p = &pts[i];
        let before = match p.family {
            "alpha" if p.param_index == after_alpha => Some(after_alpha - 1),
            "eta" if after_eta[0] == Some(p.param_index) => Some(p.param_index - 1),
            "eta" if after_eta[1] == Some(p.param_index) => Some(p.param_index + 1),
            _ => None,
        };
        if let Some(bi) = before
            && let Some(j) = pts.iter().position(|q| {
                q.family == p.family
                    && q.model == p.model
                    && q.cos_index == p.cos_index
                    && q.param_index == bi
            })
        {
            rows[i].continuity = Some((rows[i].albedo - rows[j].albedo).abs());
        }
    }
    for r in rows.iter_mut() {
        classify(r);
    }
    Ok(pts.into_iter().zip(rows).collect())
}

/// Set a row's status and its reasons from its measurements.
pub fn classify(r: &mut Row) {
    let mut why = Vec::new();
    let mut st = Status::Pass;
    let mut mark = |s: Status, w: String| {
        st = st.max(s);
        why.push(w);
    };
    if !r.finite {
        mark(Status::Fail, "non-finite or negative".into());
    }
    if r.albedo > 1.0 + 4.0 * r.albedo_se + 1e-3 {
        mark(Status::Fail, format!("albedo {:.4} > 1", r.albedo));
    }
    if let Some(g) = r.gpu_mismatch
        && g > 0.0
    {
        let s = if g > 0.05 {
            Status::Fail
        } else {
            Status::Degrade
        };
        mark(s, format!("GPU differs on {:.1}%", 100.0 * g));
    }
    if r.pdf_ill > 0.005 {
        mark(
            Status::Degrade,
            format!(
                "f32 cannot resolve the lobe for {:.1}% of samples",
                100.0 * r.pdf_ill
            ),
        );
    }
    if r.pdf_mismatch > 0.05 {
        mark(
            Status::Fail,
            format!("sample/pdf disagree on {:.1}%", 100.0 * r.pdf_mismatch),
        );
    } else if r.pdf_mismatch > 0.005 {
        mark(
            Status::Degrade,
            format!("sample/pdf disagree on {:.1}%", 100.0 * r.pdf_mismatch),
        );
    }
    if r.recip > 1e-3 {
        mark(Status::Degrade, format!("reciprocity {:.1e}", r.recip));
    }
    // Lost samples alone are not a defect (single scattering loses energy
    // at high alpha); the albedo checks judge them.
    if let Some(q) = r.albedo_quad
        && (q - r.albedo).abs() > 4.0 * r.albedo_se + 0.01
    {
        mark(
            Status::Degrade,
            format!("albedo {:.4} vs quadrature {q:.4}", r.albedo),
        );
    }
    if let Some(c) = r.continuity
        && c > 0.02
    {
        mark(Status::Degrade, format!("jump {c:.3} at threshold"));
    }
    r.status = st;
    r.why = why.join("; ");
}

/// The CSV table, one line per point.
pub fn csv(rows: &[(Point, Row)]) -> String {
    let mut s = String::from(
        "family,model,param,cos_o,status,finite,recip_err,albedo,albedo_se,albedo_quad,pdf_mismatch,pdf_ill,lost,gpu_mismatch,continuity,why\n",
    );
    let opt = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x:.6e}"));
    for (p, r) in rows {
        s += &format!(
            "{},{},{},{:e},{},{},{:.3e},{:.6},{:.2e},{},{:.4},{:.4},{:.4},{},{},\"{}\"\n",
            p.family,
            p.model,
            p.param,
            COS[p.cos_index],
            r.status.name(),
            r.finite,
            r.recip,
            r.albedo,
            r.albedo_se,
            opt(r.albedo_quad),
            r.pdf_mismatch,
            r.pdf_ill,
            r.lost,
            opt(r.gpu_mismatch),
            opt(r.continuity),
            r.why
        );
    }
    s
}

/// The Markdown report: the headline (counts, every failing or degraded
/// point grouped by model), then a pass/degrade/fail map per model over
/// (parameter, cos theta_o).
pub fn markdown(rows: &[(Point, Row)], size: Size, gpu: Option<&str>) -> String {
    let count = |s: Status| rows.iter().filter(|(_, r)| r.status == s).count();
    let mut md = String::from("# glint stability sweep\n\n");
    md += &format!(
        "Generated by `glint stability -o DIR{}` ({} points; GPU: {}). Each point is a BSDF and \
         an outgoing direction; the measurements and the status rules are in \
         `src/stability.rs`. The CSV beside this file holds every value. Where the sampling \
         methods (BSDF sampling, light sampling, MIS) fail is the other sweep: \
         [methods.md](methods.md) (`glint stability --methods`).\n\n",
        if size == Size::Quick { " --quick" } else { "" },
        rows.len(),
        gpu.unwrap_or("not run")
    );
    md += &format!(
        "**{} pass, {} degrade, {} fail.**\n\n",
        count(Status::Pass),
        count(Status::Degrade),
        count(Status::Fail)
    );
    md += "## Points that fail or degrade\n\n| family | model | param | cos theta_o | status | why |\n|---|---|---|---|---|---|\n";
    for (p, r) in rows.iter().filter(|(_, r)| r.status != Status::Pass) {
        md += &format!(
            "| {} | {} | {} | {:e} | {} | {} |\n",
            p.family,
            p.model,
            p.param,
            COS[p.cos_index],
            r.status.name(),
            r.why
        );
    }
    md += "\n## Maps\n\nRows: the family's parameter; columns: cos theta_o (";
    md += &COS.map(|c| format!("{c:e}")).join(", ");
    md += "). `.` pass, `d` degrade, `F` fail.\n\n";
    let mut keys: Vec<(&str, String)> = Vec::new();
    for (p, _) in rows {
        let k = (p.family, p.model.clone());
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    for (family, model) in keys {
        md += &format!("### {family}: {model}\n\n```\n");
        let sub: Vec<&(Point, Row)> = rows
            .iter()
            .filter(|(p, _)| p.family == family && p.model == model)
            .collect();
        let n_param = sub.iter().map(|(p, _)| p.param_index).max().unwrap_or(0) + 1;
        for pi in 0..n_param {
            let label = sub
                .iter()
                .find(|(p, _)| p.param_index == pi)
                .map(|(p, _)| p.param.clone())
                .unwrap_or_default();
            let cells: String = (0..COS.len())
                .map(|ci| {
                    sub.iter()
                        .find(|(p, _)| p.param_index == pi && p.cos_index == ci)
                        .map_or(' ', |(_, r)| match r.status {
                            Status::Pass => '.',
                            Status::Degrade => 'd',
                            Status::Fail => 'F',
                        })
                })
                .collect();
            md += &format!("{label:>14} {cells}\n");
        }
        md += "```\n\n";
    }
    md
}

/// The heat maps for the chart: per (family, model), a grid of statuses.
pub fn heatmaps(rows: &[(Point, Row)]) -> Vec<crate::chart::Heatmap> {
    let mut out: Vec<crate::chart::Heatmap> = Vec::new();
    for (p, r) in rows {
        let title = format!("{}: {}", p.family, p.model);
        let h = match out.iter_mut().find(|h| h.title == title) {
            Some(h) => h,
            None => {
                out.push(crate::chart::Heatmap {
                    title,
                    rows: Vec::new(),
                    cols: COS.len(),
                    cells: Vec::new(),
                });
                out.last_mut().expect("just pushed")
            }
        };
        if h.rows.len() <= p.param_index {
            h.rows.resize(p.param_index + 1, String::new());
        }
        h.rows[p.param_index] = p.param.clone();
        // Value: 0 pass, 1 degrade, 2 fail; the error shade within each
        // status is the log10 of the largest relative error.
        let err = r
            .pdf_mismatch
            .max(r.recip)
            .max(r.albedo_quad.map_or(0.0, |q| (q - r.albedo).abs()));
        h.cells
            .push((p.param_index, p.cos_index, r.status as u8, err));
    }
    out
}

/// An angle's cosine as the table shows it (for tests and messages).
pub fn cos_label(i: usize) -> String {
    format!("{:e}", COS[i])
}
