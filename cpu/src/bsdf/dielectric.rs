//! Dielectric interfaces: smooth (delta reflection + refraction) or GGX
//! rough (Walter et al. 2007), following pbrt-v4's `DielectricBxDF`. The
//! outside is +z; `eta` = n_inside / n_outside. Transmission carries the
//! radiance scaling 1 / eta_rel^2 (eta_rel = eta_t / eta_i as the path
//! tracer crosses from wo's side to wi's side): Veach 1997, sec. 5.2.

use glam::{Vec2, Vec3};

use super::conductor::rough_alphas;
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
    let h = lanes::half_vector(eta, wo.into(), wi.into());
    h.valid.then(|| (h.wm.into(), h.etap, h.reflection))
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
    let f = lanes::rough_eval(&RoughDielectric::of(eta, r), wo.into(), wi.into());
    if f == 0.0 {
        return Vec3::ZERO;
    }
    Vec3::splat(f * dielectric_ms_scale(eta, r, wo))
}

pub fn dielectric_pdf(eta: f32, r: &Roughness, wo: Vec3, wi: Vec3) -> f32 {
    if dielectric_is_smooth(eta, r) {
        return 0.0;
    }
    lanes::rough_pdf(&RoughDielectric::of(eta, r), wo.into(), wi.into())
}

pub fn dielectric_sample(
    eta: f32,
    r: &Roughness,
    wo: Vec3,
    uc: f32,
    u: Vec2,
) -> Option<BsdfSample> {
    if dielectric_is_smooth(eta, r) {
        return lanes::smooth_sample(eta, wo.into(), uc).single();
    }
    let mut s = rough_sample(&RoughDielectric::of(eta, r), wo, uc, u)?;
    if r.multiscatter {
        s.weight *= dielectric_ms_scale(eta, r, wo);
    }
    Some(s)
}

/// [`lanes::rough_sample`] with its selects as branches: the lobe that
/// `uc` does not pick is not computed. The same operations on the picked
/// side, so the same bits as the one-lane instantiation; each early return
/// is a term of its validity mask, NaN included (`!(x > 0)`, not `x <= 0`).
#[inline]
fn rough_sample(c: &RoughDielectric<f32>, wo: Vec3, uc: f32, u: Vec2) -> Option<BsdfSample> {
    use crate::bsdf::fresnel::lanes::{fresnel_dielectric, refract_dir};
    use crate::bsdf::microfacet::lanes::{
        ggx_g1, ggx_g2, ggx_pdf_visible, ggx_sample_visible, reflect_dir,
    };
    if wo.z == 0.0 {
        return None;
    }
    let wo = crate::lanes::V3::from(wo);
    let wm = ggx_sample_visible(wo, c.ax, c.ay, u.into());
    let dot_o = wo.dot(wm);
    let pr = fresnel_dielectric(dot_o, c.eta);
    let (wi, pdf, etap) = if uc < pr {
        let wr = reflect_dir(wo, wm);
        if wr.z * wo.z <= 0.0 {
            return None;
        }
        let pdf_wm = ggx_pdf_visible(wo, wm, c.ax, c.ay);
        (wr, pdf_wm / (4.0 * dot_o.abs()) * pr, 1.0)
    } else {
        let (refracts, wt, etap) = refract_dir(wo, wm, c.eta);
        let dot_i = wt.dot(wm);
        let denom = (dot_i + dot_o / etap) * (dot_i + dot_o / etap);
        if !refracts || wt.z * wo.z >= 0.0 || !(denom > 0.0) {
            return None;
        }
        let pdf_wm = ggx_pdf_visible(wo, wm, c.ax, c.ay);
        (wt, pdf_wm * (dot_i.abs() / denom) * (1.0 - pr), etap)
    };
    if !(pdf > 0.0 && pdf < f32::INFINITY) {
        return None;
    }
    let g1 = ggx_g1(wo, c.ax, c.ay);
    if !(g1 > 0.0) || !lanes::half_vector(c.eta, wo, wi).valid {
        return None;
    }
    // etap is 1 for a reflection, and x / 1 is x exactly: the lanes'
    // g2 / g1 there.
    let w = ggx_g2(wo, wi, c.ax, c.ay, c.separable) / g1 / (etap * etap);
    Some(BsdfSample {
        wi: wi.into(),
        weight: Vec3::splat(w),
        pdf,
        delta: false,
        eta: etap,
    })
}

/// A rough dielectric's parameters, one per lane (without the
/// multiple-scattering scale, which stays scalar).
#[derive(Clone, Copy, Debug)]
pub struct RoughDielectric<L> {
    /// n_inside / n_outside.
    pub eta: L,
    /// The clamped alphas ([`rough_alphas`]).
    pub ax: L,
    pub ay: L,
    /// The same in every lane.
    pub separable: bool,
}

impl RoughDielectric<f32> {
    pub fn of(eta: f32, r: &Roughness) -> Self {
        let (ax, ay) = rough_alphas(r);
        Self {
            eta,
            ax,
            ay,
            separable: r.shadowing == Shadowing::Separable,
        }
    }
}

/// The dielectric over any [`crate::lanes::Lane`] type: one source with
/// the scalar forms above (each early return a select).
pub mod lanes {
    use super::RoughDielectric;
    use crate::bsdf::LaneSample;
    use crate::bsdf::fresnel::lanes::{fresnel_dielectric, refract_dir};
    use crate::bsdf::microfacet::lanes::{
        ggx_d, ggx_g1, ggx_g2, ggx_pdf_visible, ggx_sample_visible, ggx_visibility, reflect_dir,
    };
    use crate::lanes::{Lane, V2, V3};

    /// Walter 2007 eq. 16's generalised half vector ([`super::dielectric_half_vector`]).
    #[derive(Clone, Copy, Debug)]
    pub struct HalfVector<L: Lane> {
        pub valid: L::Mask,
        pub wm: V3<L>,
        pub etap: L,
        pub reflection: L::Mask,
    }

    #[inline(always)]
    pub fn half_vector<L: Lane>(eta: L, wo: V3<L>, wi: V3<L>) -> HalfVector<L> {
        let (co, ci) = (wo.z, wi.z);
        let reflection = (co * ci).gt(L::zero());
        let etap = L::select(
            reflection,
            L::one(),
            L::select(co.gt(L::zero()), eta, L::one() / eta),
        );
        let h = wi.scale(etap) + wo;
        let len2 = h.length_squared();
        let wm = h / len2.sqrt();
        let wm = V3::select(wm.z.lt(L::zero()), -wm, wm);
        let valid = !(co.eq(L::zero()) | ci.eq(L::zero()))
            & len2.gt(L::splat(1e-12))
            & !((wm.dot(wi) * ci).le(L::zero()) | (wm.dot(wo) * co).le(L::zero()));
        HalfVector {
            valid,
            wm,
            etap,
            reflection,
        }
    }

    /// f(wo, wi) (one value for the three channels), without the
    /// multiple-scattering scale.
    #[inline(always)]
    pub fn rough_eval<L: Lane>(c: &RoughDielectric<L>, wo: V3<L>, wi: V3<L>) -> L {
        let h = half_vector(c.eta, wo, wi);
        let d = ggx_d(h.wm, c.ax, c.ay);
        let v = ggx_visibility(wo, wi, c.ax, c.ay, c.separable);
        let f = fresnel_dielectric(wo.dot(h.wm), c.eta);
        // Walter 2007 eq. 20 with V = G / (4 |co| |ci|).
        let fr = d * f * v;
        // Walter 2007 eq. 21 (G / (|ci| |co|) = 4 V), in pbrt-v4's form with
        // the denominator (wi.wm + wo.wm / etap)^2, then the radiance scaling.
        let (dot_i, dot_o) = (wi.dot(h.wm), wo.dot(h.wm));
        let denom = (dot_i + dot_o / h.etap) * (dot_i + dot_o / h.etap);
        let ft = d * (L::one() - f) * L::splat(4.0) * v * (dot_i * dot_o).abs() / denom;
        let ft = L::select(denom.gt(L::zero()), ft / (h.etap * h.etap), L::zero());
        L::select(h.valid, L::select(h.reflection, fr, ft), L::zero())
    }

    /// The density of [`rough_sample`].
    #[inline(always)]
    pub fn rough_pdf<L: Lane>(c: &RoughDielectric<L>, wo: V3<L>, wi: V3<L>) -> L {
        let h = half_vector(c.eta, wo, wi);
        let (dot_o, dot_i) = (wo.dot(h.wm), wi.dot(h.wm));
        let pr = fresnel_dielectric(dot_o, c.eta);
        let pt = L::one() - pr;
        let pdf_wm = ggx_pdf_visible(wo, h.wm, c.ax, c.ay);
        // Walter 2007 eq. 14.
        let reflect = pdf_wm / (L::splat(4.0) * dot_o.abs()) * pr;
        // Walter 2007 eq. 17: dwm/dwi = |wi.wm| / (wi.wm + wo.wm / etap)^2.
        let denom = (dot_i + dot_o / h.etap) * (dot_i + dot_o / h.etap);
        let transmit = L::select(
            denom.gt(L::zero()),
            pdf_wm * (dot_i.abs() / denom) * pt,
            L::zero(),
        );
        L::select(
            h.valid,
            L::select(h.reflection, reflect, transmit),
            L::zero(),
        )
    }

    /// The smooth interface: reflection with probability F (weight 1),
    /// else refraction (weight 1 / eta_rel^2).
    #[inline(always)]
    pub fn smooth_sample<L: Lane>(eta: L, wo: V3<L>, uc: L) -> LaneSample<L> {
        let pr = fresnel_dielectric(wo.z, eta);
        let reflect = uc.lt(pr);
        let (refracts, wt, etap) = refract_dir(wo, V3::new(L::zero(), L::zero(), L::one()), eta);
        let mirror = V3::new(-wo.x, -wo.y, wo.z);
        let t_weight = L::one() / (etap * etap);
        let valid = !wo.z.eq(L::zero()) & (reflect | (refracts & !wt.z.eq(L::zero())));
        LaneSample {
            valid,
            wi: V3::select(reflect, mirror, wt),
            weight: V3::select(
                reflect,
                V3::new(L::one(), L::one(), L::one()),
                V3::new(t_weight, t_weight, t_weight),
            ),
            pdf: L::select(reflect, pr, L::one() - pr),
            eta: L::select(reflect, L::one(), etap),
            delta: true,
        }
    }

    /// A visible-normal sample, reflection or refraction by the sampled
    /// microfacet's Fresnel term. As for conductors, pdf and weight come
    /// from the sampled normal (well conditioned); the weights are
    /// f |cos_i| / pdf simplified: reflection F G2 / (G1 pr) = G2 / G1,
    /// transmission (1 - F) G2 / (G1 pt eta_rel^2) = G2 / (G1 eta_rel^2).
    /// Without the multiple-scattering scale.
    #[inline(always)]
    pub fn rough_sample<L: Lane>(
        c: &RoughDielectric<L>,
        wo: V3<L>,
        uc: L,
        u: V2<L>,
    ) -> LaneSample<L> {
        let wm = ggx_sample_visible(wo, c.ax, c.ay, u);
        let dot_o = wo.dot(wm);
        // Choose R or T by the Fresnel term of the sampled microfacet.
        let pr = fresnel_dielectric(dot_o, c.eta);
        let pdf_wm = ggx_pdf_visible(wo, wm, c.ax, c.ay);
        let g1 = ggx_g1(wo, c.ax, c.ay);
        let reflect = uc.lt(pr);
        // Reflection.
        let wr = reflect_dir(wo, wm);
        let r_ok = !(wr.z * wo.z).le(L::zero());
        let r_pdf = pdf_wm / (L::splat(4.0) * dot_o.abs()) * pr;
        // Transmission.
        let (refracts, wt, etap) = refract_dir(wo, wm, c.eta);
        let dot_i = wt.dot(wm);
        let denom = (dot_i + dot_o / etap) * (dot_i + dot_o / etap);
        let t_ok = refracts & !(wt.z * wo.z).ge(L::zero()) & denom.gt(L::zero());
        let t_pdf = pdf_wm * (dot_i.abs() / denom) * (L::one() - pr);
        let wi = V3::select(reflect, wr, wt);
        let pdf = L::select(reflect, r_pdf, t_pdf);
        let g2 = ggx_g2(wo, wi, c.ax, c.ay, c.separable);
        let w = L::select(reflect, g2 / g1, g2 / g1 / (etap * etap));
        // Keep the support consistent with eval/pdf: where rounding makes
        // the half vector rebuilt from (wo, wi) fail its back-facing test
        // (grazing, near-specular), eval would return 0 for this direction.
        let rebuilt = half_vector(c.eta, wo, wi).valid;
        let valid = !wo.z.eq(L::zero())
            & g1.gt(L::zero())
            & L::select_mask(reflect, r_ok, t_ok)
            & pdf.gt(L::zero())
            & pdf.lt(L::splat(f32::INFINITY))
            & rebuilt;
        LaneSample {
            valid,
            wi,
            weight: V3::new(w, w, w),
            pdf,
            eta: L::select(reflect, L::one(), etap),
            delta: false,
        }
    }
}
