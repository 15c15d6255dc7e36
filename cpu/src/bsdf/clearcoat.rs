//! `KHR_materials_clearcoat`: a GGX dielectric coat (IOR 1.5, alpha =
//! clearcoatRoughness^2, height-correlated Smith) of weight c over the whole
//! glTF material (metal, non-metal or their blend). glint's layering
//! (README.md, "Materials"):
//!
//!   f = c f_cc(wo, wi) + w(mu_o) w(mu_i) f_inner(wo, wi),  w(mu) = 1 - c E_cc(mu),
//!
//! E_cc the coat's directional albedo (the non-metal's tables, `coated.rs`).
//! Reciprocal (both weights symmetric) and energy conserving: the albedo is
//! at most c E_cc(mu_o) + w(mu_o) x (the inner albedo, <= 1) <= 1. The
//! inner material loses what the coat reflects on the way in and on the way
//! out; light reflected back down by the coat's underside is not returned
//! (a small loss, the price of a closed form). Sampling: the coat with
//! probability c E_cc(mu_o), else the inner material.

use glam::{Vec2, Vec3};

use super::coated::coat_albedo;
use super::fresnel::fresnel_dielectric;
use super::microfacet::{
    MIN_ALPHA, ggx_d, ggx_g1, ggx_g2, ggx_pdf_visible, ggx_sample_visible, ggx_visibility,
    reflect_dir,
};
use super::{BsdfSample, SMOOTH_ALPHA_THRESHOLD};

/// The clear coat's IOR (glTF: fixed at 1.5).
pub const CLEARCOAT_IOR: f32 = 1.5;

/// A clear coat: weight (clearcoatFactor) and GGX alpha.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clearcoat {
    pub weight: f32,
    pub alpha: f32,
}

impl Clearcoat {
    fn smooth(&self) -> bool {
        self.alpha < SMOOTH_ALPHA_THRESHOLD
    }
    fn a(&self) -> f32 {
        self.alpha.max(MIN_ALPHA)
    }
    /// w(mu) = 1 - c E_cc(mu).
    pub fn through(&self, mu: f32) -> f32 {
        1.0 - self.weight * coat_albedo(mu.abs(), self.a(), CLEARCOAT_IOR, self.smooth())
    }
    fn p_coat(&self, mu_o: f32) -> f32 {
        (1.0 - self.through(mu_o)).clamp(0.0, 1.0)
    }
}

/// c f_cc for wo, wi on the same side (0 otherwise, and for a smooth coat).
fn coat_eval(cc: &Clearcoat, wo: Vec3, wi: Vec3) -> f32 {
    if cc.smooth() || wo.z * wi.z <= 0.0 {
        return 0.0;
    }
    let (wo, wi) = (
        Vec3::new(wo.x, wo.y, wo.z.abs()),
        Vec3::new(wi.x, wi.y, wi.z.abs()),
    );
    let a = cc.a();
    let h = (wo + wi).normalize();
    let dot = wo.dot(h);
    if dot <= 0.0 {
        return 0.0;
    }
    cc.weight
        * fresnel_dielectric(dot, CLEARCOAT_IOR)
        * ggx_d(h, a, a)
        * ggx_visibility(wo, wi, a, a, false)
}

fn coat_pdf(cc: &Clearcoat, wo: Vec3, wi: Vec3) -> f32 {
    if cc.smooth() || wo.z * wi.z <= 0.0 {
        return 0.0;
    }
    let (wo, wi) = (
        Vec3::new(wo.x, wo.y, wo.z.abs()),
        Vec3::new(wi.x, wi.y, wi.z.abs()),
    );
    let h = (wo + wi).normalize();
    let dot = wo.dot(h);
    if dot <= 0.0 {
        return 0.0;
    }
    ggx_pdf_visible(wo, h, cc.a(), cc.a()) / (4.0 * dot)
}

pub fn clearcoat_eval(cc: &Clearcoat, inner: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
    Vec3::splat(coat_eval(cc, wo, wi)) + inner * (cc.through(wo.z) * cc.through(wi.z))
}

pub fn clearcoat_pdf(cc: &Clearcoat, inner_pdf: f32, wo: Vec3, wi: Vec3) -> f32 {
    let p = cc.p_coat(wo.z);
    p * coat_pdf(cc, wo, wi) + (1.0 - p) * inner_pdf
}

/// `inner_sample(uc)` samples the inner material, `inner_eval(wi)` and
/// `inner_pdf(wi)` evaluate it (non-delta parts).
pub fn clearcoat_sample(
    cc: &Clearcoat,
    wo: Vec3,
    uc: f32,
    u: Vec2,
    inner_sample: &dyn Fn(f32) -> Option<BsdfSample>,
    inner_eval: &dyn Fn(Vec3) -> Vec3,
    inner_pdf: &dyn Fn(Vec3) -> f32,
) -> Option<BsdfSample> {
    if wo.z == 0.0 {
        return None;
    }
    let p = cc.p_coat(wo.z);
    let w_o = cc.through(wo.z);
    if uc < p {
        if cc.smooth() {
            // The coat's mirror, c F delta / |cos|, picked with probability
            // c F (= p for the smooth coat).
            let f = cc.weight * fresnel_dielectric(wo.z.abs(), CLEARCOAT_IOR);
            return Some(BsdfSample {
                wi: Vec3::new(-wo.x, -wo.y, wo.z),
                weight: Vec3::splat(f / p),
                pdf: p,
                delta: true,
                eta: 1.0,
            });
        }
        let up = Vec3::new(wo.x, wo.y, wo.z.abs());
        let a = cc.a();
        let wm = ggx_sample_visible(up, a, a, u);
        let dot = up.dot(wm);
        let mut wi = reflect_dir(up, wm);
        if wi.z <= 0.0 || dot <= 0.0 || !(ggx_g1(up, a, a) > 0.0) {
            return None;
        }
        let pdf_c = ggx_pdf_visible(up, wm, a, a) / (4.0 * dot);
        let f_c = cc.weight
            * fresnel_dielectric(dot, CLEARCOAT_IOR)
            * ggx_d(wm, a, a)
            * ggx_g2(up, wi, a, a, false)
            / (4.0 * up.z * wi.z);
        if wo.z < 0.0 {
            wi.z = -wi.z;
        }
        let pdf = p * pdf_c + (1.0 - p) * inner_pdf(wi);
        if !(pdf > 0.0) || !pdf.is_finite() {
            return None;
        }
        let f = Vec3::splat(f_c) + inner_eval(wi) * (w_o * cc.through(wi.z));
        return Some(BsdfSample {
            wi,
            weight: f * (wi.z.abs() / pdf),
            pdf,
            delta: false,
            eta: 1.0,
        });
    }
    let s = inner_sample(((uc - p) / (1.0 - p)).clamp(0.0, ONE_MINUS_EPS))?;
    let w_i = cc.through(s.wi.z);
    if s.delta {
        return Some(BsdfSample {
            weight: s.weight * (w_o * w_i / (1.0 - p)),
            pdf: (1.0 - p) * s.pdf,
            ..s
        });
    }
    let f_in = s.weight * (s.pdf / s.wi.z.abs());
    let pdf = p * coat_pdf(cc, wo, s.wi) + (1.0 - p) * s.pdf;
    if !(pdf > 0.0) || !pdf.is_finite() {
        return None;
    }
    let f = Vec3::splat(coat_eval(cc, wo, s.wi)) + f_in * (w_o * w_i);
    Some(BsdfSample {
        weight: f * (s.wi.z.abs() / pdf),
        pdf,
        ..s
    })
}

/// The largest f32 below 1: a rescaled random number stays in [0, 1).
const ONE_MINUS_EPS: f32 = 1.0 - f32::EPSILON / 2.0;
