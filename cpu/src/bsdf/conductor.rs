//! Conductors: smooth (delta) mirror or anisotropic GGX microfacet
//! reflection (Walter et al. 2007), Fresnel for a complex IOR. Two-sided
//! (a wo below the surface mirrors both directions, as Mitsuba's
//! `twosided` does).

use glam::{Vec2, Vec3};

use crate::lanes::V3;

use super::fresnel::fresnel_conductor;
use super::microfacet::{
    MIN_ALPHA, ggx_d, ggx_pdf_visible, ggx_sample_visible, ggx_visibility, reflect_dir,
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
    let (wo, wi) = lanes::two_sided(wo.into(), wi.into());
    (wo.into(), wi.into())
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
    let f_ss: Vec3 = lanes::rough_eval(&RoughConductor::of(c), wo.into(), wi.into()).into();
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
    let pdf_ss = lanes::rough_pdf(&RoughConductor::of(c), wo.into(), wi.into());
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
    if let Some((a, sep, f_avg)) = conductor_ms_params(c) {
        let ax_ay = rough_alphas(&c.roughness);
        return conductor_sample_ms(c, wo_up, flip, u, ax_ay, (a, sep, f_avg));
    }
    lanes::rough_sample(&RoughConductor::of(c), wo.into(), u.into()).single()
}

/// A rough conductor's parameters, one per lane (its single-scattering
/// lobe: the multiple-scattering one stays scalar).
#[derive(Clone, Copy, Debug)]
pub struct RoughConductor<L> {
    pub eta: V3<L>,
    pub k: V3<L>,
    pub specular_reflectance: V3<L>,
    /// The clamped alphas ([`rough_alphas`]).
    pub ax: L,
    pub ay: L,
    /// The same in every lane.
    pub separable: bool,
}

impl RoughConductor<f32> {
    pub fn of(c: &ConductorParams) -> Self {
        let (ax, ay) = rough_alphas(&c.roughness);
        Self {
            eta: c.eta.into(),
            k: c.k.into(),
            specular_reflectance: c.specular_reflectance.into(),
            ax,
            ay,
            separable: c.roughness.shadowing == Shadowing::Separable,
        }
    }
}

/// The rough conductor's single-scattering lobe over any
/// [`crate::lanes::Lane`] type: one source with the scalar forms above.
pub mod lanes {
    use super::RoughConductor;
    use crate::bsdf::LaneSample;
    use crate::bsdf::fresnel::lanes::fresnel_conductor;
    use crate::bsdf::microfacet::lanes::{
        ggx_d, ggx_g1, ggx_g2, ggx_pdf_visible, ggx_sample_visible, ggx_visibility, reflect_dir,
    };
    use crate::lanes::{Lane, V2, V3};

    /// Both directions mirrored to the upper hemisphere where wo is below
    /// it (Mitsuba's `twosided`).
    #[inline(always)]
    pub fn two_sided<L: Lane>(wo: V3<L>, wi: V3<L>) -> (V3<L>, V3<L>) {
        let flip = wo.z.lt(L::zero());
        let up = |w: V3<L>| V3::new(w.x, w.y, L::select(flip, -w.z, w.z));
        (up(wo), up(wi))
    }

    #[inline(always)]
    fn fresnel<L: Lane>(c: &RoughConductor<L>, cos: L) -> V3<L> {
        fresnel_conductor(cos, c.eta, c.k) * c.specular_reflectance
    }

    /// f(wo, wi): Walter 2007 eq. 20, D F G / (4 |co| |ci|), with
    /// V = G / (4 |co| |ci|).
    #[inline(always)]
    pub fn rough_eval<L: Lane>(c: &RoughConductor<L>, wo: V3<L>, wi: V3<L>) -> V3<L> {
        let (wo, wi) = two_sided(wo, wi);
        let below = wo.z.le(L::zero()) | wi.z.le(L::zero());
        // wo, wi both above: the half vector has z > 0 and is never zero.
        let wm = (wo + wi).normalize();
        let dv = ggx_d(wm, c.ax, c.ay) * ggx_visibility(wo, wi, c.ax, c.ay, c.separable);
        let f = fresnel(c, wo.dot(wm)).scale(dv);
        let zero = V3::new(L::zero(), L::zero(), L::zero());
        V3::select(below, zero, f)
    }

    /// The density of [`rough_sample`].
    #[inline(always)]
    pub fn rough_pdf<L: Lane>(c: &RoughConductor<L>, wo: V3<L>, wi: V3<L>) -> L {
        let (wo, wi) = two_sided(wo, wi);
        let wm = (wo + wi).normalize();
        let dot = wo.dot(wm);
        let none = wo.z.le(L::zero()) | wi.z.le(L::zero()) | dot.le(L::zero());
        // Reflection Jacobian dwm/dwi = 1 / (4 |wo . wm|) (Walter 2007 eq. 14).
        let pdf = ggx_pdf_visible(wo, wm, c.ax, c.ay) / (L::splat(4.0) * dot);
        L::select(none, L::zero(), pdf)
    }

    /// A visible-normal sample. pdf and weight come from the sampled
    /// microfacet normal (pbrt-v4 does the same): recomputing the half
    /// vector from wo + wi is ill-conditioned for near-specular lobes at
    /// grazing angles, where wo and wi are nearly opposite in the plane
    /// and their sum loses most of its bits.
    #[inline(always)]
    pub fn rough_sample<L: Lane>(c: &RoughConductor<L>, wo: V3<L>, u: V2<L>) -> LaneSample<L> {
        let flip = wo.z.lt(L::zero());
        let wo_up = V3::new(wo.x, wo.y, wo.z.abs());
        let wm = ggx_sample_visible(wo_up, c.ax, c.ay, u);
        let dot = wo_up.dot(wm);
        let wi = reflect_dir(wo_up, wm);
        let pdf = ggx_pdf_visible(wo_up, wm, c.ax, c.ay) / (L::splat(4.0) * dot);
        let g1 = ggx_g1(wo_up, c.ax, c.ay);
        let valid = !wo.z.eq(L::zero())
            & !(wi.z.le(L::zero()) | dot.le(L::zero()))
            & pdf.gt(L::zero())
            & pdf.lt(L::splat(f32::INFINITY))
            & g1.gt(L::zero());
        // f |cos_i| / pdf = F G2 / G1(wo) (Heitz 2018, eq. 19): D and the
        // reflection Jacobian cancel.
        let g2 = ggx_g2(wo_up, wi, c.ax, c.ay, c.separable);
        let weight = fresnel(c, dot).scale(g2 / g1);
        LaneSample {
            valid,
            wi: V3::new(wi.x, wi.y, L::select(flip, -wi.z, wi.z)),
            weight,
            pdf,
            eta: L::one(),
            delta: false,
        }
    }
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
