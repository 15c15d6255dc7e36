//! Conductors: smooth (delta) mirror or anisotropic GGX microfacet
//! reflection (Walter et al. 2007), Fresnel for a complex IOR. Two-sided
//! (a wo below the surface mirrors both directions, as Mitsuba's
//! `twosided` does).

use glam::{Vec2, Vec3};

use super::fresnel::fresnel_conductor;
use super::microfacet::{
    MIN_ALPHA, ggx_d, ggx_pdf_visible, ggx_sample_visible, ggx_visibility, reflect,
};
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
    f * (ggx_d(wm, ax, ay) * ggx_visibility(wo, wi, ax, ay, separable))
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
    ggx_pdf_visible(wo, wm, ax, ay) / (4.0 * dot)
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
    let wm = ggx_sample_visible(wo_up, ax, ay, u);
    let mut wi = reflect(wo_up, wm);
    if wi.z <= 0.0 {
        return None;
    }
    if flip {
        wi.z = -wi.z;
    }
    // Re-evaluate f and pdf at the sampled direction: the weight is then
    // exactly f |cos| / pdf as eval and pdf compute them (the MIS weights
    // of the integrator rely on that consistency).
    let pdf = conductor_pdf(c, wo, wi);
    if !(pdf > 0.0) || !pdf.is_finite() {
        return None;
    }
    let f = conductor_eval(c, wo, wi);
    Some(BsdfSample {
        wi,
        weight: f * (wi.z.abs() / pdf),
        pdf,
        delta: false,
        eta: 1.0,
    })
}
