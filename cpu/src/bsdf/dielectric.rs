//! Dielectric interfaces: smooth (delta reflection + refraction) or GGX
//! rough (Walter et al. 2007), following pbrt-v4's `DielectricBxDF`. The
//! outside is +z; `eta` = n_inside / n_outside. Transmission carries the
//! radiance scaling 1 / eta_rel^2 (eta_rel = eta_t / eta_i as the path
//! tracer crosses from wo's side to wi's side): Veach 1997, sec. 5.2.

use glam::{Vec2, Vec3};

use super::conductor::rough_alphas;
use super::fresnel::{fresnel_dielectric, refract_dir};
use super::microfacet::{
    ggx_d, ggx_g1, ggx_g2, ggx_pdf_visible, ggx_sample_visible, ggx_visibility, reflect_dir,
};
use super::multiscatter::dielectric_ms_albedo;
use super::{BsdfSample, ETA_SMOOTH_THRESHOLD, Roughness, Shadowing};

/// Whether the interface is rendered as the smooth (delta) model: a small
/// alpha, or eta within [`ETA_SMOOTH_THRESHOLD`] of 1, where the rough
/// transmission lobe collapses to the straight-through direction (pbrt-v4
/// does the same for eta = 1 exactly).
pub fn dielectric_is_smooth(eta: f32, r: &Roughness) -> bool {
    r.is_smooth() || (eta - 1.0).abs() < ETA_SMOOTH_THRESHOLD
}

/// The generalised half vector of Walter 2007 eq. 16, face-forwarded to
/// +z, with eta_rel (1 for reflection); None when degenerate or when a
/// direction sees the back of the microfacet (Walter's condition
/// chi+(v . m / v . n)).
pub fn dielectric_half_vector(eta: f32, wo: Vec3, wi: Vec3) -> Option<(Vec3, f32, bool)> {
    let co = wo.z;
    let ci = wi.z;
    if co == 0.0 || ci == 0.0 {
        return None;
    }
    let is_reflection = co * ci > 0.0;
    let etap = if is_reflection {
        1.0
    } else if co > 0.0 {
        eta
    } else {
        1.0 / eta
    };
    let h = wi * etap + wo;
    let len2 = h.length_squared();
    if !(len2 > 1e-12) {
        return None;
    }
    let mut wm = h / len2.sqrt();
    if wm.z < 0.0 {
        wm = -wm;
    }
    if wm.dot(wi) * ci <= 0.0 || wm.dot(wo) * co <= 0.0 {
        return None;
    }
    Some((wm, etap, is_reflection))
}

/// `multiscatter`: 1 / E(mu_o) of the single-scattering lobe seen from wo's
/// side (Turquin 2019; see multiscatter.rs); 1 otherwise.
pub fn dielectric_ms_scale(eta: f32, r: &Roughness, wo: Vec3) -> f32 {
    if !r.multiscatter {
        return 1.0;
    }
    let (ax, ay) = rough_alphas(r);
    let side_eta = if wo.z >= 0.0 { eta } else { 1.0 / eta };
    let separable = r.shadowing == Shadowing::Separable;
    let e = dielectric_ms_albedo(wo.z.abs(), (ax * ay).sqrt(), side_eta, separable);
    if e > 0.0 { 1.0 / e } else { 1.0 }
}

pub fn dielectric_eval(eta: f32, r: &Roughness, wo: Vec3, wi: Vec3) -> Vec3 {
    if dielectric_is_smooth(eta, r) {
        return Vec3::ZERO;
    }
    let Some((wm, etap, is_reflection)) = dielectric_half_vector(eta, wo, wi) else {
        return Vec3::ZERO;
    };
    let (ax, ay) = rough_alphas(r);
    let separable = r.shadowing == Shadowing::Separable;
    let d = ggx_d(wm, ax, ay);
    let v = ggx_visibility(wo, wi, ax, ay, separable);
    let f = fresnel_dielectric(wo.dot(wm), eta);
    let scale = dielectric_ms_scale(eta, r, wo);
    if is_reflection {
        // Walter 2007 eq. 20 with V = G / (4 |co| |ci|).
        return Vec3::splat(d * f * v * scale);
    }
    // Walter 2007 eq. 21 (G / (|ci| |co|) = 4 V), in pbrt-v4's form with
    // the denominator (wi.wm + wo.wm / etap)^2, then the radiance scaling.
    let dot_i = wi.dot(wm);
    let dot_o = wo.dot(wm);
    let denom = (dot_i + dot_o / etap) * (dot_i + dot_o / etap);
    if !(denom > 0.0) {
        return Vec3::ZERO;
    }
    let ft = d * (1.0 - f) * 4.0 * v * (dot_i * dot_o).abs() / denom;
    Vec3::splat(ft / (etap * etap) * scale)
}

pub fn dielectric_pdf(eta: f32, r: &Roughness, wo: Vec3, wi: Vec3) -> f32 {
    if dielectric_is_smooth(eta, r) {
        return 0.0;
    }
    let Some((wm, etap, is_reflection)) = dielectric_half_vector(eta, wo, wi) else {
        return 0.0;
    };
    let (ax, ay) = rough_alphas(r);
    let dot_o = wo.dot(wm);
    let dot_i = wi.dot(wm);
    let pr = fresnel_dielectric(dot_o, eta);
    let pt = 1.0 - pr;
    let pdf_wm = ggx_pdf_visible(wo, wm, ax, ay);
    if is_reflection {
        // Walter 2007 eq. 14.
        pdf_wm / (4.0 * dot_o.abs()) * pr
    } else {
        // Walter 2007 eq. 17: dwm/dwi = |wi.wm| / (wi.wm + wo.wm / etap)^2.
        let denom = (dot_i + dot_o / etap) * (dot_i + dot_o / etap);
        if !(denom > 0.0) {
            return 0.0;
        }
        pdf_wm * (dot_i.abs() / denom) * pt
    }
}

pub fn dielectric_sample(
    eta: f32,
    r: &Roughness,
    wo: Vec3,
    uc: f32,
    u: Vec2,
) -> Option<BsdfSample> {
    if wo.z == 0.0 {
        return None;
    }
    if dielectric_is_smooth(eta, r) {
        // Choose reflection with probability F: the weights F / pr = 1 and
        // (1 - F) / pt / etap^2 = 1 / etap^2.
        let pr = fresnel_dielectric(wo.z, eta);
        if uc < pr {
            return Some(BsdfSample {
                wi: Vec3::new(-wo.x, -wo.y, wo.z),
                weight: Vec3::ONE,
                pdf: pr,
                delta: true,
                eta: 1.0,
            });
        }
        let (wi, etap) = refract_dir(wo, Vec3::Z, eta)?;
        if wi.z == 0.0 {
            return None;
        }
        return Some(BsdfSample {
            wi,
            weight: Vec3::splat(1.0 / (etap * etap)),
            pdf: 1.0 - pr,
            delta: true,
            eta: etap,
        });
    }
    let (ax, ay) = rough_alphas(r);
    let wm = ggx_sample_visible(wo, ax, ay, u);
    let dot_o = wo.dot(wm);
    // Choose R or T by the Fresnel term of the sampled microfacet.
    let pr = fresnel_dielectric(dot_o, eta);
    let pdf_wm = ggx_pdf_visible(wo, wm, ax, ay);
    let g1 = ggx_g1(wo, ax, ay);
    if !(g1 > 0.0) {
        return None;
    }
    let separable = r.shadowing == Shadowing::Separable;
    // As for conductors, pdf and weight come from the sampled normal
    // (well conditioned); the weights are f |cos_i| / pdf simplified:
    // reflection F G2 / (G1 pr) = G2 / G1, transmission
    // (1 - F) G2 / (G1 pt eta_rel^2) = G2 / (G1 eta_rel^2).
    let (wi, pdf, weight, eta_rel) = if uc < pr {
        let wi = reflect_dir(wo, wm);
        if wi.z * wo.z <= 0.0 {
            return None;
        }
        let pdf = pdf_wm / (4.0 * dot_o.abs()) * pr;
        (wi, pdf, ggx_g2(wo, wi, ax, ay, separable) / g1, 1.0)
    } else {
        let (wi, etap) = refract_dir(wo, wm, eta)?;
        if wi.z * wo.z >= 0.0 {
            return None;
        }
        let dot_i = wi.dot(wm);
        let denom = (dot_i + dot_o / etap) * (dot_i + dot_o / etap);
        if !(denom > 0.0) {
            return None;
        }
        let pdf = pdf_wm * (dot_i.abs() / denom) * (1.0 - pr);
        let w = ggx_g2(wo, wi, ax, ay, separable) / g1 / (etap * etap);
        (wi, pdf, w, etap)
    };
    if !(pdf > 0.0) || !pdf.is_finite() {
        return None;
    }
    // Keep the support consistent with eval/pdf: where rounding makes the
    // half vector rebuilt from (wo, wi) fail its back-facing test (grazing,
    // near-specular), eval would return 0 for this direction.
    dielectric_half_vector(eta, wo, wi)?;
    Some(BsdfSample {
        wi,
        weight: Vec3::splat(weight * dielectric_ms_scale(eta, r, wo)),
        pdf,
        delta: false,
        eta: eta_rel,
    })
}
