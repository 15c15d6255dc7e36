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
//!
//! `clearcoatNormalTexture` tilts the coat's normal away from the shading
//! normal ([`Clearcoat::normal`]): the coat's lobe and its albedo weights
//! are then taken about the coat's own normal, and its lobe is returned
//! with the coat's cosine in place of the shading one (f_cc |wi . n_c| /
//! |wi . n|), as Cycles weighs each closure by its own normal's cosine. The
//! albedo stays c E_cc(mu_o') + w(mu_o') x (inner albedo) <= 1 (mu_o' about
//! the coat's normal); reciprocity holds only for an untilted coat.

use glam::{Vec2, Vec3};

use super::coated::coat_albedo;
use super::fresnel::fresnel_dielectric;
use super::microfacet::{
    MIN_ALPHA, ggx_d, ggx_g1, ggx_g2, ggx_pdf_visible, ggx_sample_visible, ggx_visibility,
    reflect_dir,
};
use super::{BsdfSample, SMOOTH_ALPHA_THRESHOLD};
use crate::frame::Frame;

/// The clear coat's IOR (glTF: fixed at 1.5).
pub use crate::abi::CLEARCOAT_IOR;

/// A clear coat: weight (clearcoatFactor), GGX alpha and normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clearcoat {
    pub weight: f32,
    pub alpha: f32,
    /// The frame about the coat's normal, in front-side shading
    /// coordinates; None: the shading normal itself.
    pub frame: Option<Frame>,
}

/// `w` with z multiplied by `side` (+-1): a direction on wo's side of the
/// surface seen as on the front side.
fn front(w: Vec3, side: f32) -> Vec3 {
    Vec3::new(w.x, w.y, w.z * side)
}

/// The side of the surface `wo` is on.
fn side_of(wo: Vec3) -> f32 {
    if wo.z < 0.0 { -1.0 } else { 1.0 }
}

impl Clearcoat {
    fn smooth(&self) -> bool {
        self.alpha < SMOOTH_ALPHA_THRESHOLD
    }
    fn a(&self) -> f32 {
        self.alpha.max(MIN_ALPHA)
    }
    /// The coat of weight `weight`, alpha `alpha` and normal `normal` (its
    /// (x, y) in the shading frame, [`coat_normal`]; ZERO: the shading
    /// normal), its frame built once.
    pub fn new(weight: f32, alpha: f32, normal: Vec2) -> Self {
        Clearcoat {
            weight,
            alpha,
            frame: (normal != Vec2::ZERO).then(|| Frame::from_normal(coat_normal(normal))),
        }
    }
    /// A front-side shading direction in the coat's frame.
    fn local(&self, w: Vec3) -> Vec3 {
        self.frame.map_or(w, |f| f.to_local(w))
    }
    /// A direction in the coat's frame back in front-side shading terms.
    fn world(&self, w: Vec3) -> Vec3 {
        self.frame.map_or(w, |f| f.to_world(w))
    }
    /// The coat's lobe value `f` (about the coat's normal, at `wi_c` in its
    /// frame) as the shading-frame BSDF returns it: times the coat's
    /// cosine over the shading one (`wi_z`); `f` itself for an untilted coat.
    fn shading_value(&self, f: f32, wi_c: Vec3, wi_z: f32) -> f32 {
        if self.frame.is_none() {
            f
        } else if wi_z == 0.0 {
            0.0
        } else {
            f * (wi_c.z.abs() / wi_z.abs())
        }
    }
    /// w(mu) = 1 - c E_cc(mu), mu = |cos| about the coat's normal of the
    /// front-side direction `w_front`.
    fn through_front(&self, w_front: Vec3) -> f32 {
        let mu = self.local(w_front).z.abs();
        1.0 - self.weight * coat_albedo(mu, self.a(), CLEARCOAT_IOR, self.smooth())
    }
    /// w(mu) for `w` with `wo` on the side `side`.
    pub fn through(&self, w: Vec3, side: f32) -> f32 {
        self.through_front(front(w, side))
    }
    fn p_coat(&self, wo: Vec3) -> f32 {
        (1.0 - self.through(wo, side_of(wo))).clamp(0.0, 1.0)
    }
}

/// The unit normal whose (x, y) is `xy`, on +z.
pub fn coat_normal(xy: Vec2) -> Vec3 {
    Vec3::new(xy.x, xy.y, (1.0 - xy.length_squared()).max(0.0).sqrt())
}

/// Grid steps per unit of the coat normal's x and y (GLSL
/// `COAT_NORMAL_STEPS`, pinned by `cpu/tests/bsdf_regressions.rs`).
pub use crate::abi::COAT_NORMAL_STEPS;
/// Values of q per axis, 2 STEPS + 1 (GLSL `COAT_NORMAL_STRIDE`).
pub use crate::abi::COAT_NORMAL_STRIDE;

/// `clearcoat_normal` encoding of the GPU record (`GpuMaterial::extra.w`):
/// 0 for no tilt, else 1 + qx STRIDE + qy, q = floor((x + 1) STEPS + 1/2)
/// in [0, 2 STEPS]: an integer below 2^24, exact in an f32 on every device
/// (no NaN or denormal bit patterns to lose). The step (1/2047) is finer
/// than an 8-bit normal map's (1/127.5).
pub fn encode_coat_normal(xy: Vec2) -> f32 {
    if xy == Vec2::ZERO {
        return 0.0;
    }
    let steps = COAT_NORMAL_STEPS as f32;
    let q = |x: f32| ((x.clamp(-1.0, 1.0) + 1.0) * steps + 0.5).floor() as u32;
    (1 + q(xy.x) * COAT_NORMAL_STRIDE + q(xy.y)) as f32
}

/// The inverse of [`encode_coat_normal`] (the grid's values): what the CPU
/// stores, so both backends shade with the same normal.
pub fn decode_coat_normal(e: f32) -> Vec2 {
    if e < 1.0 {
        return Vec2::ZERO;
    }
    let e = e as u32 - 1;
    let d = |q: u32| q as f32 / COAT_NORMAL_STEPS as f32 - 1.0;
    Vec2::new(d(e / COAT_NORMAL_STRIDE), d(e % COAT_NORMAL_STRIDE))
}

/// The pair (wo, wi) in the coat's frame on the front side, with their
/// half vector and its cosine; None where the coat's lobe is 0 (a smooth
/// coat, or wo and wi on different sides of the coat).
fn coat_pair(cc: &Clearcoat, wo: Vec3, wi: Vec3) -> Option<(Vec3, Vec3, Vec3, f32)> {
    if cc.smooth() || wo.z == 0.0 {
        return None;
    }
    let side = side_of(wo);
    let (wo_c, wi_c) = (cc.local(front(wo, side)), cc.local(front(wi, side)));
    if wo_c.z <= 0.0 || wi_c.z <= 0.0 {
        return None;
    }
    let h = (wo_c + wi_c).normalize();
    let dot = wo_c.dot(h);
    (dot > 0.0).then_some((wo_c, wi_c, h, dot))
}

/// c f_cc as the shading-frame BSDF returns it (0 where [`coat_pair`] is
/// None).
fn coat_eval(cc: &Clearcoat, wo: Vec3, wi: Vec3) -> f32 {
    let Some((wo_c, wi_c, h, dot)) = coat_pair(cc, wo, wi) else {
        return 0.0;
    };
    let a = cc.a();
    let f = cc.weight
        * fresnel_dielectric(dot, CLEARCOAT_IOR)
        * ggx_d(h, a, a)
        * ggx_visibility(wo_c, wi_c, a, a, false);
    cc.shading_value(f, wi_c, wi.z)
}

fn coat_pdf(cc: &Clearcoat, wo: Vec3, wi: Vec3) -> f32 {
    let Some((wo_c, _, h, dot)) = coat_pair(cc, wo, wi) else {
        return 0.0;
    };
    ggx_pdf_visible(wo_c, h, cc.a(), cc.a()) / (4.0 * dot)
}

pub fn clearcoat_eval(cc: &Clearcoat, inner: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
    let side = side_of(wo);
    Vec3::splat(coat_eval(cc, wo, wi)) + inner * (cc.through(wo, side) * cc.through(wi, side))
}

pub fn clearcoat_pdf(cc: &Clearcoat, inner_pdf: f32, wo: Vec3, wi: Vec3) -> f32 {
    let p = cc.p_coat(wo);
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
    let side = side_of(wo);
    let p = cc.p_coat(wo);
    let w_o = cc.through(wo, side);
    if uc < p {
        // In the coat's frame, on the front side.
        let up = cc.local(front(wo, side));
        if up.z <= 0.0 {
            return None;
        }
        if cc.smooth() {
            // The coat's mirror, c F delta / |cos|, picked with probability
            // c F (= p for the smooth coat).
            let f = cc.weight * fresnel_dielectric(up.z, CLEARCOAT_IOR);
            return Some(BsdfSample {
                wi: front(cc.world(Vec3::new(-up.x, -up.y, up.z)), side),
                weight: Vec3::splat(f / p),
                pdf: p,
                delta: true,
                eta: 1.0,
            });
        }
        let a = cc.a();
        let wm = ggx_sample_visible(up, a, a, u);
        let dot = up.dot(wm);
        let wi_c = reflect_dir(up, wm);
        if wi_c.z <= 0.0 || dot <= 0.0 || !(ggx_g1(up, a, a) > 0.0) {
            return None;
        }
        let pdf_c = ggx_pdf_visible(up, wm, a, a) / (4.0 * dot);
        let wi = front(cc.world(wi_c), side);
        let f_c = cc.shading_value(
            cc.weight
                * fresnel_dielectric(dot, CLEARCOAT_IOR)
                * ggx_d(wm, a, a)
                * ggx_g2(up, wi_c, a, a, false)
                / (4.0 * up.z * wi_c.z),
            wi_c,
            wi.z,
        );
        let pdf = p * pdf_c + (1.0 - p) * inner_pdf(wi);
        if !(pdf > 0.0) || !pdf.is_finite() {
            return None;
        }
        let f = Vec3::splat(f_c) + inner_eval(wi) * (w_o * cc.through(wi, side));
        return Some(BsdfSample {
            wi,
            weight: f * (wi.z.abs() / pdf),
            pdf,
            delta: false,
            eta: 1.0,
        });
    }
    let s = inner_sample(((uc - p) / (1.0 - p)).clamp(0.0, ONE_MINUS_EPS))?;
    let w_i = cc.through(s.wi, side);
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coat_normal_codes_round_trip_exactly() {
        assert_eq!(encode_coat_normal(Vec2::ZERO), 0.0);
        assert_eq!(decode_coat_normal(0.0), Vec2::ZERO);
        // The largest code is an integer an f32 holds exactly.
        let top = encode_coat_normal(Vec2::ONE);
        assert!(top < (1u32 << 24) as f32 && top.fract() == 0.0, "{top}");
        assert_eq!(decode_coat_normal(top), Vec2::ONE);
        assert_eq!(
            decode_coat_normal(encode_coat_normal(-Vec2::ONE)),
            -Vec2::ONE
        );
        for k in 0..2000 {
            let xy = Vec2::new(
                (k as f32 * 0.618_034).fract() * 1.6 - 0.8,
                (k as f32 * 0.414_214).fract() * 1.6 - 0.8,
            );
            let e = encode_coat_normal(xy);
            let d = decode_coat_normal(e);
            assert!(
                (d - xy).abs().max_element() <= 0.5 / 2047.0 + 1e-6,
                "{xy} {d}"
            );
            // What the CPU stores encodes to the same code.
            assert_eq!(encode_coat_normal(d), e, "{xy}");
        }
    }
}
