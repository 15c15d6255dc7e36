//! Conductors: smooth (delta) mirror or anisotropic GGX microfacet
//! reflection (Walter et al. 2007), Fresnel for a complex IOR. Two-sided
//! (a wo below the surface mirrors both directions, as Mitsuba's
//! `twosided` does).

use glam::{Vec2, Vec3};

use super::fresnel::fresnel_conductor;
use super::microfacet::{
    MIN_ALPHA, ggx_d, ggx_g1, ggx_g2, ggx_pdf_visible, ggx_sample_visible, ggx_visibility,
    reflect_dir,
};
use super::multiscatter::{conductor_ms_eval, fresnel_conductor_avg, ms_albedo};
use super::warp::square_to_cosine_hemisphere;
use super::{BsdfSample, ConductorParams, Roughness, Shadowing};

/// The clamped GGX alphas of a rough model.
pub fn rough_alphas(r: &Roughness) -> (f32, f32) {
    (r.alpha_u.max(MIN_ALPHA), r.alpha_v.max(MIN_ALPHA))
}

/// Mirror both directions to the upper hemisphere when wo is below it.
pub fn two_sided(wo: Vec3, wi: Vec3) -> (Vec3, Vec3) {
    if wo.z < 0.0 {
        (Vec3::new(wo.x, wo.y, -wo.z), Vec3::new(wi.x, wi.y, -wi.z))
    } else {
        (wo, wi)
    }
}

/// With `multiscatter`: the tables' alpha (sqrt(alpha_u alpha_v)), the
/// Smith form, and the average Fresnel term F_avg (times
/// specular_reflectance) of the Kulla-Conty lobe.
pub fn conductor_ms_params(c: &ConductorParams) -> Option<(f32, bool, Vec3)> {
    if !c.roughness.multiscatter {
        return None;
    }
    let (ax, ay) = rough_alphas(&c.roughness);
    Some((
        (ax * ay).sqrt(),
        c.roughness.shadowing == Shadowing::Separable,
        fresnel_conductor_avg(c.eta, c.k) * c.specular_reflectance,
    ))
}

/// Probability of sampling the multiple-scattering lobe: its share
/// 1 - E(mu_o) of the F = 1 albedo.
pub fn conductor_ms_prob(mu_o: f32, alpha: f32, separable: bool) -> f32 {
    (1.0 - ms_albedo(mu_o, alpha, separable)).clamp(0.0, 1.0)
}

pub fn conductor_eval(c: &ConductorParams, wo: Vec3, wi: Vec3) -> Vec3 {
    if c.roughness.is_smooth() {
        return Vec3::ZERO;
    }
    let (wo, wi) = two_sided(wo, wi);
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return Vec3::ZERO;
    }
    let (ax, ay) = rough_alphas(&c.roughness);
    // wo, wi both above: the half vector has z > 0 and is never zero.
    let wm = (wo + wi).normalize();
    let f = fresnel_conductor(wo.dot(wm), c.eta, c.k) * c.specular_reflectance;
    let separable = c.roughness.shadowing == Shadowing::Separable;
    // Walter 2007 eq. 20: D F G / (4 |co| |ci|), with V = G / (4 |co| |ci|).
    let f_ss = f * (ggx_d(wm, ax, ay) * ggx_visibility(wo, wi, ax, ay, separable));
    match conductor_ms_params(c) {
        Some((a, sep, f_avg)) => f_ss + conductor_ms_eval(wo.z, wi.z, a, sep, f_avg),
        None => f_ss,
    }
}

pub fn conductor_pdf(c: &ConductorParams, wo: Vec3, wi: Vec3) -> f32 {
    if c.roughness.is_smooth() {
        return 0.0;
    }
    let (wo, wi) = two_sided(wo, wi);
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return 0.0;
    }
    let (ax, ay) = rough_alphas(&c.roughness);
    let wm = (wo + wi).normalize();
    let dot = wo.dot(wm);
    if dot <= 0.0 {
        return 0.0;
    }
    // Reflection Jacobian dwm/dwi = 1 / (4 |wo . wm|) (Walter 2007 eq. 14).
    let pdf_ss = ggx_pdf_visible(wo, wm, ax, ay) / (4.0 * dot);
    match conductor_ms_params(c) {
        Some((a, sep, _)) => {
            let p = conductor_ms_prob(wo.z, a, sep);
            (1.0 - p) * pdf_ss + p * wi.z * std::f32::consts::FRAC_1_PI
        }
        None => pdf_ss,
    }
}

pub fn conductor_sample(c: &ConductorParams, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
    if wo.z == 0.0 {
        return None;
    }
    let flip = wo.z < 0.0;
    let wo_up = Vec3::new(wo.x, wo.y, wo.z.abs());
    if c.roughness.is_smooth() {
        let f = fresnel_conductor(wo_up.z, c.eta, c.k) * c.specular_reflectance;
        return Some(BsdfSample {
            wi: Vec3::new(-wo.x, -wo.y, wo.z),
            weight: f,
            pdf: 1.0,
            delta: true,
            eta: 1.0,
        });
    }
    let (ax, ay) = rough_alphas(&c.roughness);
    if let Some((a, sep, f_avg)) = conductor_ms_params(c) {
        return conductor_sample_ms(c, wo_up, flip, u, (ax, ay), (a, sep, f_avg));
    }
    let wm = ggx_sample_visible(wo_up, ax, ay, u);
    let dot = wo_up.dot(wm);
    let mut wi = reflect_dir(wo_up, wm);
    if wi.z <= 0.0 || dot <= 0.0 {
        return None;
    }
    // pdf and weight from the sampled microfacet normal (pbrt-v4 does the
    // same): recomputing the half vector from wo + wi is ill-conditioned
    // for near-specular lobes at grazing angles, where wo and wi are
    // nearly opposite in the plane and their sum loses most of its bits.
    let pdf = ggx_pdf_visible(wo_up, wm, ax, ay) / (4.0 * dot);
    let g1 = ggx_g1(wo_up, ax, ay);
    if !(pdf > 0.0) || !pdf.is_finite() || !(g1 > 0.0) {
        return None;
    }
    let separable = c.roughness.shadowing == Shadowing::Separable;
    // f |cos_i| / pdf = F G2 / G1(wo) (Heitz 2018, eq. 19): D and the
    // reflection Jacobian cancel.
    let f = fresnel_conductor(dot, c.eta, c.k) * c.specular_reflectance;
    let weight = f * (ggx_g2(wo_up, wi, ax, ay, separable) / g1);
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

/// [`conductor_sample`] with the Kulla-Conty lobe: u.x first picks the
/// lobe (multiple scattering with probability 1 - E(mu_o)) and is then
/// rescaled to [0, 1) for the lobe's own warp; pdf and f are the
/// mixture's, so MIS and eval see one density.
fn conductor_sample_ms(
    c: &ConductorParams,
    wo: Vec3,
    flip: bool,
    u: Vec2,
    (ax, ay): (f32, f32),
    (a, sep, f_avg): (f32, bool, Vec3),
) -> Option<BsdfSample> {
    let p_ms = conductor_ms_prob(wo.z, a, sep);
    let separable = c.roughness.shadowing == Shadowing::Separable;
    let (mut wi, pdf_ss, f_ss);
    if u.x < p_ms {
        let u = Vec2::new((u.x / p_ms).min(ONE_MINUS_EPS), u.y);
        wi = square_to_cosine_hemisphere(u);
        if wi.z <= 0.0 {
            return None;
        }
        let wm = (wo + wi).normalize();
        let dot = wo.dot(wm);
        if dot <= 0.0 {
            return None;
        }
        pdf_ss = ggx_pdf_visible(wo, wm, ax, ay) / (4.0 * dot);
        f_ss = fresnel_conductor(dot, c.eta, c.k)
            * c.specular_reflectance
            * (ggx_d(wm, ax, ay) * ggx_visibility(wo, wi, ax, ay, separable));
    } else {
        let u = Vec2::new(((u.x - p_ms) / (1.0 - p_ms)).min(ONE_MINUS_EPS), u.y);
        let wm = ggx_sample_visible(wo, ax, ay, u);
        let dot = wo.dot(wm);
        wi = reflect_dir(wo, wm);
        if wi.z <= 0.0 || dot <= 0.0 {
            return None;
        }
        pdf_ss = ggx_pdf_visible(wo, wm, ax, ay) / (4.0 * dot);
        f_ss = fresnel_conductor(dot, c.eta, c.k)
            * c.specular_reflectance
            * (ggx_d(wm, ax, ay) * ggx_visibility(wo, wi, ax, ay, separable));
    }
    let pdf = (1.0 - p_ms) * pdf_ss + p_ms * wi.z * std::f32::consts::FRAC_1_PI;
    if !(pdf > 0.0) || !pdf.is_finite() {
        return None;
    }
    let f = f_ss + conductor_ms_eval(wo.z, wi.z, a, sep, f_avg);
    let weight = f * (wi.z / pdf);
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

/// The largest f32 below 1: a rescaled random number stays in [0, 1).
const ONE_MINUS_EPS: f32 = 1.0 - f32::EPSILON / 2.0;
