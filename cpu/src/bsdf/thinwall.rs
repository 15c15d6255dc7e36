//! The thin-walled transmission of glTF's `KHR_materials_transmission`
//! (without `KHR_materials_volume`, a transmissive glTF surface is a thin
//! shell: the spec's "thin-walled" default). Smooth, it is Mitsuba 3's
//! `thindielectric` (`thin.rs`): the slab's reflectance R' = 2R / (1 + R)
//! about the normal and 1 - R' straight through, tinted by baseColor.
//!
//! Rough (glint's choice, documented in README.md): the GGX reflection lobe
//! of the slab, s R'(wo.h) D(h) G2 / (4 mu_o mu_i), and its mirror image
//! through the surface plane carrying the rest,
//!
//!   f_T(wo, wi) = tint (1 - s R'(wo.h')) D(h') G2(wo, wi') / (4 mu_o |mu_i|),
//!
//! wi' = wi mirrored to wo's side, h' = normalize(wo + wi'). A rough slab
//! blurs the straight-through image the way it blurs the reflection. It
//! tends to the smooth slab as alpha -> 0, is reciprocal (D, G2 and
//! F(wo.h') = F(wi'.h') are symmetric) and conserves energy: reflection and
//! transmission together hold the F = 1 single-scattering albedo (< 1, the
//! GGX masking loss). Sampling: a visible normal, then reflection with
//! probability s R'(wo.wm), else its mirror image; the weight is G2 / G1
//! (times the tint for transmission). Two-sided; eta stays 1 (the path
//! leaves into the medium it came from).

use glam::{Vec2, Vec3};

use super::coated::CoatParams;
use super::conductor::rough_alphas;
use super::microfacet::{
    ggx_d, ggx_g1, ggx_g2, ggx_pdf_visible, ggx_sample_visible, ggx_visibility, reflect_dir,
};
use super::thin::thin_reflectance;
use super::{BsdfSample, Roughness};

/// s R' at |cos| = mu, at most 1.
fn slab_r(coat: &CoatParams, mu: f32) -> Vec3 {
    (coat.specular * thin_reflectance(mu, coat.eta)).min(Vec3::ONE)
}

fn mean(v: Vec3) -> f32 {
    (v.x + v.y + v.z) * (1.0 / 3.0)
}

/// wo and wi' (wi mirrored to wo's side, both made upper), and whether wi
/// is transmitted; None when either is grazing.
fn upper_pair(wo: Vec3, wi: Vec3) -> Option<(Vec3, Vec3, bool)> {
    if wo.z == 0.0 || wi.z == 0.0 {
        return None;
    }
    let transmitted = wo.z * wi.z < 0.0;
    let up = |w: Vec3| Vec3::new(w.x, w.y, w.z.abs());
    Some((up(wo), up(wi), transmitted))
}

pub fn thinwall_eval(tint: Vec3, coat: &CoatParams, r: &Roughness, wo: Vec3, wi: Vec3) -> Vec3 {
    if r.is_smooth() {
        return Vec3::ZERO;
    }
    let Some((wo, wi, transmitted)) = upper_pair(wo, wi) else {
        return Vec3::ZERO;
    };
    let (ax, ay) = rough_alphas(r);
    let h = (wo + wi).normalize();
    let dot = wo.dot(h);
    if dot <= 0.0 {
        return Vec3::ZERO;
    }
    let rr = slab_r(coat, dot);
    let lobe = ggx_d(h, ax, ay) * ggx_visibility(wo, wi, ax, ay, false);
    if transmitted {
        tint * (Vec3::ONE - rr) * lobe
    } else {
        rr * lobe
    }
}

pub fn thinwall_pdf(coat: &CoatParams, r: &Roughness, wo: Vec3, wi: Vec3) -> f32 {
    if r.is_smooth() {
        return 0.0;
    }
    let Some((wo, wi, transmitted)) = upper_pair(wo, wi) else {
        return 0.0;
    };
    let (ax, ay) = rough_alphas(r);
    let h = (wo + wi).normalize();
    let dot = wo.dot(h);
    if dot <= 0.0 {
        return 0.0;
    }
    let p_r = mean(slab_r(coat, dot));
    let p = if transmitted { 1.0 - p_r } else { p_r };
    p * ggx_pdf_visible(wo, h, ax, ay) / (4.0 * dot)
}

/// `uc` picks reflection or transmission, `u` the visible normal.
pub fn thinwall_sample(
    tint: Vec3,
    coat: &CoatParams,
    r: &Roughness,
    wo: Vec3,
    uc: f32,
    u: Vec2,
) -> Option<BsdfSample> {
    if wo.z == 0.0 {
        return None;
    }
    let flip = wo.z < 0.0;
    let wo_up = Vec3::new(wo.x, wo.y, wo.z.abs());
    if r.is_smooth() {
        let rr = slab_r(coat, wo_up.z);
        let p_r = mean(rr);
        return Some(if uc < p_r {
            BsdfSample {
                wi: Vec3::new(-wo.x, -wo.y, wo.z),
                weight: rr / p_r,
                pdf: p_r,
                delta: true,
                eta: 1.0,
            }
        } else {
            BsdfSample {
                wi: -wo,
                weight: tint * (Vec3::ONE - rr) / (1.0 - p_r),
                pdf: 1.0 - p_r,
                delta: true,
                eta: 1.0,
            }
        });
    }
    let (ax, ay) = rough_alphas(r);
    let wm = ggx_sample_visible(wo_up, ax, ay, u);
    let dot = wo_up.dot(wm);
    let mut wi = reflect_dir(wo_up, wm);
    let g1 = ggx_g1(wo_up, ax, ay);
    if wi.z <= 0.0 || dot <= 0.0 || !(g1 > 0.0) {
        return None;
    }
    let rr = slab_r(coat, dot);
    let p_r = mean(rr);
    let transmit = uc >= p_r;
    let p = if transmit { 1.0 - p_r } else { p_r };
    let pdf = p * ggx_pdf_visible(wo_up, wm, ax, ay) / (4.0 * dot);
    if !(pdf > 0.0) || !pdf.is_finite() {
        return None;
    }
    let g = ggx_g2(wo_up, wi, ax, ay, false) / g1;
    let weight = if transmit {
        tint * (Vec3::ONE - rr) * (g / p)
    } else {
        rr * (g / p)
    };
    if flip != transmit {
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
