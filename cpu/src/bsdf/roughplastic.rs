//! Mitsuba 3's `roughplastic`: a GGX dielectric interface over a Lambertian
//! base (Mitsuba 3, `src/bsdfs/roughplastic.cpp`), for scenes ported from
//! Mitsuba. The glTF non-metal is `coated.rs` (this model's single-scattering
//! coat darkens a rough surface: a 0.8 base reflects 0.27 at alpha 1).
//!
//!   specular: s F(wo.h) D(h) G(wo, wi) / (4 mu_o mu_i);
//!   diffuse:  rho' T(mu_o) T(mu_i) / (eta^2 pi), rho' = rho / (1 - R_int)
//!             (rho / (1 - rho R_int) with `nonlinear`).
//!
//! T(mu) is the rough interface's external transmittance (the mean over
//! visible normals of (1 - F) G1 of the refracted direction, Mitsuba's
//! `eval_transmittance`) and R_int its internal diffuse reflectance
//! (2 x the mean over 64 uniform mu nodes of mu R(mu) seen from inside,
//! Mitsuba's `eval_reflectance` and its own rule, kept so that ported
//! scenes match). Mitsuba computes both per material on 64 uniform mu
//! nodes and interpolates linearly in mu; glint tabulates them once over
//! sqrt(alpha) and sqrt((eta - 1)/(eta + 1)) as well
//! (`cargo run --release -p glint-cpu --example roughplastic_tables`,
//! `roughplastic_tables.bin`), on the same 64 mu nodes, one table per Smith
//! form: Mitsuba's separable G1 G1, or the height-correlated G2 (glint's
//! default `shadowing`, where G1 of the refracted direction becomes
//! G2 / G1(wo)).
//!
//! Sampling as Mitsuba's: the specular lobe with probability proportional
//! to (1 - T(mu_o)) w_s against T(mu_o) (1 - w_s), w_s = mean(specular) /
//! (mean(diffuse) + mean(specular)). Isotropic only (as Mitsuba); two-sided
//! (Mitsuba's is one-sided). Below the smooth threshold it is `plastic`.

use std::f32::consts::FRAC_1_PI;
use std::sync::LazyLock;

use glam::{Vec2, Vec3};

use super::coated::{bilinear, cell, coat_eta_coord, trilinear};
use super::conductor::two_sided;
use super::fresnel::{fresnel_dielectric, refract_dir};
use super::microfacet::{
    MIN_ALPHA, ggx_d, ggx_g1, ggx_g2, ggx_pdf_visible, ggx_sample_visible, reflect_dir,
};
use super::plastic::PlasticParams;
use super::warp::square_to_cosine_hemisphere;
use super::{BsdfSample, Roughness, Shadowing};

// Grids: mu uniform (Mitsuba's 64 nodes), sqrt(alpha), sqrt(x) with
// x = (eta - 1) / (eta + 1) (as the coat tables, `coated.rs`); floats of
// one Smith form's T table (`[eta][alpha][mu]`) and of R_int.
pub use crate::abi::{RP_N_ALPHA, RP_N_ETA, RP_N_MU, RP_R_LEN, RP_T_LEN};
/// The tables hold T for both forms, then R_int (`[form][eta][alpha]`).
pub const RP_LEN: usize = 2 * (RP_T_LEN + RP_R_LEN);

const RP_TABLE_BYTES: &[u8] = include_bytes!("roughplastic_tables.bin");

/// The tables (header "GLRP" and the three grid sizes, then little-endian
/// floats: T correlated, T separable, R_int correlated, R_int separable).
pub fn roughplastic_tables() -> &'static [f32] {
    static TABLES: LazyLock<Vec<f32>> = LazyLock::new(|| {
        super::coated::decode_table(
            RP_TABLE_BYTES,
            b"GLRP",
            [RP_N_MU, RP_N_ALPHA, RP_N_ETA],
            RP_LEN,
        )
        .expect("cpu/src/bsdf/roughplastic_tables.bin is corrupt")
    });
    &TABLES
}

/// The `roughplastic` model: `plastic`'s parameters and a roughness.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughPlasticParams {
    pub plastic: PlasticParams,
    /// Isotropic (`alpha_u` = `alpha_v`).
    pub roughness: Roughness,
}

fn form(r: &Roughness) -> usize {
    (r.shadowing == Shadowing::Separable) as usize
}

fn alpha_of(r: &Roughness) -> f32 {
    r.alpha_u.max(MIN_ALPHA)
}

/// T(mu) of the rough interface (trilinear: mu on Mitsuba's nodes).
pub fn rp_transmittance(mu: f32, alpha: f32, eta: f32, separable: bool) -> f32 {
    trilinear(
        &roughplastic_tables()[separable as usize * RP_T_LEN..],
        (RP_N_MU, RP_N_ALPHA),
        cell(mu, RP_N_MU),
        cell(alpha.sqrt(), RP_N_ALPHA),
        cell(coat_eta_coord(eta), RP_N_ETA),
    )
}

/// R_int of the rough interface (bilinear).
pub fn rp_internal_reflectance(alpha: f32, eta: f32, separable: bool) -> f32 {
    bilinear(
        &roughplastic_tables()[2 * RP_T_LEN + separable as usize * RP_R_LEN..],
        RP_N_ALPHA,
        cell(alpha.sqrt(), RP_N_ALPHA),
        cell(coat_eta_coord(eta), RP_N_ETA),
    )
}

/// Mitsuba's `eval_transmittance` (`transmit`) or `eval_reflectance` of the
/// rough interface of relative IOR `eta` seen from wi = (sqrt(1-mu^2), 0,
/// mu), by an n x n midpoint rule over the visible-normal warp: the mean of
/// (1 - F) G1(wt) (or F G1(wr)), G1 of the outgoing direction replaced by
/// G2 / G1(wi) for the correlated form. The generator's integrand.
pub fn rp_interface_reference(
    mu: f32,
    alpha: f32,
    eta: f32,
    separable: bool,
    transmit: bool,
    n: usize,
) -> f64 {
    let mu = mu.max(1e-6);
    let wi = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let a = alpha.max(MIN_ALPHA);
    let g1i = ggx_g1(wi, a, a);
    let mut sum = 0.0f64;
    for i in 0..n {
        for j in 0..n {
            let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
            let m = ggx_sample_visible(wi, a, a, u);
            let f = fresnel_dielectric(wi.dot(m), eta);
            let (wo, weight) = if transmit {
                match refract_dir(wi, m, eta) {
                    Some((wt, _)) => (wt, 1.0 - f),
                    None => continue,
                }
            } else {
                (reflect_dir(wi, m), f)
            };
            if transmit == (wo.z * wi.z >= 0.0) || wo.dot(m) * wo.z <= 0.0 {
                continue;
            }
            let g = if separable {
                ggx_g1(wo, a, a)
            } else if g1i > 0.0 {
                ggx_g2(wi, wo, a, a, false) / g1i
            } else {
                0.0
            };
            sum += (weight * g) as f64;
        }
    }
    sum / (n * n) as f64
}

struct AtWo {
    alpha: f32,
    separable: bool,
    to: f32,
    p_spec: f32,
    p_diff: f32,
}

fn at_wo(p: &RoughPlasticParams, mu_o: f32) -> AtWo {
    let alpha = alpha_of(&p.roughness);
    let separable = form(&p.roughness) == 1;
    let to = rp_transmittance(mu_o, alpha, p.plastic.eta, separable);
    let w = p.plastic.specular_sampling_weight();
    let (s, d) = ((1.0 - to) * w, to * (1.0 - w));
    let (p_spec, p_diff) = if s + d > 0.0 {
        (s / (s + d), d / (s + d))
    } else {
        (0.0, 1.0)
    };
    AtWo {
        alpha,
        separable,
        to,
        p_spec,
        p_diff,
    }
}

fn diffuse_scaled(p: &RoughPlasticParams, w: &AtWo) -> Vec3 {
    let r_int = rp_internal_reflectance(w.alpha, p.plastic.eta, w.separable);
    let rho = p.plastic.diffuse;
    if p.plastic.nonlinear {
        rho / (Vec3::ONE - rho * r_int)
    } else {
        rho / (1.0 - r_int)
    }
}

/// f for wo, wi above the surface, `wm` their half vector.
fn rp_f(p: &RoughPlasticParams, w: &AtWo, wo: Vec3, wi: Vec3, wm: Vec3) -> Vec3 {
    let a = w.alpha;
    let f = fresnel_dielectric(wo.dot(wm), p.plastic.eta);
    let spec = p.plastic.specular
        * (f * ggx_d(wm, a, a) * ggx_g2(wo, wi, a, a, w.separable) / (4.0 * wo.z * wi.z));
    let ti = rp_transmittance(wi.z, a, p.plastic.eta, w.separable);
    let eta2 = p.plastic.eta * p.plastic.eta;
    spec + diffuse_scaled(p, w) * (FRAC_1_PI * w.to * ti / eta2)
}

fn rp_pdf_at(w: &AtWo, wo: Vec3, wi: Vec3, wm: Vec3) -> f32 {
    let dot = wo.dot(wm);
    let spec = if dot > 0.0 {
        ggx_pdf_visible(wo, wm, w.alpha, w.alpha) / (4.0 * dot)
    } else {
        0.0
    };
    w.p_spec * spec + w.p_diff * wi.z * FRAC_1_PI
}

pub fn roughplastic_eval(p: &RoughPlasticParams, wo: Vec3, wi: Vec3) -> Vec3 {
    let (wo, wi) = two_sided(wo, wi);
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return Vec3::ZERO;
    }
    let w = at_wo(p, wo.z);
    rp_f(p, &w, wo, wi, (wo + wi).normalize())
}

pub fn roughplastic_pdf(p: &RoughPlasticParams, wo: Vec3, wi: Vec3) -> f32 {
    let (wo, wi) = two_sided(wo, wi);
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return 0.0;
    }
    let w = at_wo(p, wo.z);
    rp_pdf_at(&w, wo, wi, (wo + wi).normalize())
}

pub fn roughplastic_sample(
    p: &RoughPlasticParams,
    wo: Vec3,
    uc: f32,
    u: Vec2,
) -> Option<BsdfSample> {
    if wo.z == 0.0 {
        return None;
    }
    let flip = wo.z < 0.0;
    let wo = Vec3::new(wo.x, wo.y, wo.z.abs());
    let w = at_wo(p, wo.z);
    let (mut wi, wm) = if uc < w.p_spec {
        let wm = ggx_sample_visible(wo, w.alpha, w.alpha, u);
        (reflect_dir(wo, wm), wm)
    } else {
        let wi = square_to_cosine_hemisphere(u);
        (wi, (wo + wi).normalize())
    };
    if wi.z <= 0.0 {
        return None;
    }
    let pdf = rp_pdf_at(&w, wo, wi, wm);
    if !(pdf > 0.0) || !pdf.is_finite() {
        return None;
    }
    let weight = rp_f(p, &w, wo, wi, wm) * (wi.z / pdf);
    if flip {
        wi.z = -wi.z;
    }
    Some(BsdfSample {
        wi,
        weight,
        pdf,
        delta: false,
        eta: 1.0,
    })
}
