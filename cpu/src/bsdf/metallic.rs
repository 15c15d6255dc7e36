//! The glTF metallic-roughness blend: `metallic` x conductor lobe +
//! (1 - metallic) x Lambertian lobe, the lobe picked with probability
//! `metallic` (pbrt-v4 style one-sample mixture; eval and pdf are the
//! mixtures, so MIS sees the combined density). Two-sided.

use glam::{Vec2, Vec3};

use super::conductor::{conductor_eval, conductor_pdf, conductor_sample};
use super::diffuse::{diffuse_eval, diffuse_pdf, diffuse_sample};
use super::{BsdfSample, ConductorParams};

/// The non-delta part of the blend: a smooth conductor lobe contributes
/// nothing here (it is a Dirac delta, reached only through sampling).
pub fn metallic_eval(m: f32, base: Vec3, c: &ConductorParams, wo: Vec3, wi: Vec3) -> Vec3 {
    m * conductor_eval(c, wo, wi) + (1.0 - m) * diffuse_eval(base, wo, wi)
}

pub fn metallic_pdf(m: f32, c: &ConductorParams, wo: Vec3, wi: Vec3) -> f32 {
    m * conductor_pdf(c, wo, wi) + (1.0 - m) * diffuse_pdf(wo, wi)
}

pub fn metallic_sample(
    m: f32,
    base: Vec3,
    c: &ConductorParams,
    wo: Vec3,
    uc: f32,
    u: Vec2,
) -> Option<BsdfSample> {
    // The lobe that was sampled contributes its own (well-conditioned)
    // pdf and f; the other lobe is evaluated at the sampled direction.
    let (wi, pdf_c, f_c, pdf_d, f_d);
    if uc < m {
        let s = conductor_sample(c, wo, u)?;
        if s.delta {
            // The delta lobe of the mixture: f = m F delta / |cos| picked
            // with probability m, so the throughput stays F (the lobe's own
            // weight) and the discrete probability is m.
            return Some(BsdfSample { pdf: m, ..s });
        }
        wi = s.wi;
        pdf_c = s.pdf;
        f_c = s.weight * (s.pdf / wi.z.abs());
        pdf_d = diffuse_pdf(wo, wi);
        f_d = diffuse_eval(base, wo, wi);
    } else {
        let s = diffuse_sample(base, wo, u)?;
        wi = s.wi;
        pdf_d = s.pdf;
        f_d = diffuse_eval(base, wo, wi);
        pdf_c = conductor_pdf(c, wo, wi);
        f_c = conductor_eval(c, wo, wi);
    }
    let pdf = m * pdf_c + (1.0 - m) * pdf_d;
    if !(pdf > 0.0) || !pdf.is_finite() {
        return None;
    }
    let f = m * f_c + (1.0 - m) * f_d;
    Some(BsdfSample {
        wi,
        weight: f * (wi.z.abs() / pdf),
        pdf,
        delta: false,
        eta: 1.0,
    })
}
