//! The anisotropic GGX (Trowbridge-Reitz) microfacet distribution: normal
//! distribution, Smith shadowing-masking and visible-normal sampling, in the
//! local frame (n = +z, alpha_x along s = x, alpha_y along t = y).
//!
//! Walter et al. 2007, "Microfacet Models for Refraction through Rough
//! Surfaces"; Heitz 2014, "Understanding the Masking-Shadowing Function in
//! Microfacet-Based BRDFs"; Dupuy & Benyoub 2023, "Sampling Visible GGX
//! Normals with Spherical Caps".
//!
//! The Smith terms are written without Lambda's 1/cos so that grazing
//! directions (cos theta -> 0) give finite values and no inf ever appears
//! (the GLSL twin in `shaders/bsdf/microfacet.glsl` must not meet inf
//! either). Each function has a GLSL twin of the same name.

use glam::{Vec2, Vec3};

/// Rough alphas are clamped to at least this (pbrt-v4's
/// `TrowbridgeReitzDistribution` does the same) so that an anisotropic
/// surface with one alpha near 0 and the other large stays finite.
pub use crate::abi::MIN_ALPHA;

/// GGX normal distribution D(wm) (Walter et al. 2007 eq. 33, anisotropic
/// form of Heitz 2014 eq. 85): 1 / (pi ax ay ((x/ax)^2 + (y/ay)^2 + z^2)^2).
/// Even in wm.z; callers face-forward wm to the upper hemisphere.
pub fn ggx_d(wm: Vec3, ax: f32, ay: f32) -> f32 {
    lanes::ggx_d(wm.into(), ax, ay)
}

/// sqrt(cos^2 + alpha(w)^2 sin^2): the projected-roughness root shared by
/// the Smith terms. Lambda(w) = (s / |cos| - 1) / 2 (Heitz 2014 eq. 86).
pub fn ggx_root(w: Vec3, ax: f32, ay: f32) -> f32 {
    lanes::ggx_root(w.into(), ax, ay)
}

/// Smith Lambda (Heitz 2014 eq. 86). Infinite at cos theta = 0; only the
/// tests use it, the shading code uses the inf-free forms below.
pub fn ggx_lambda(w: Vec3, ax: f32, ay: f32) -> f32 {
    let cz = w.z.abs();
    0.5 * (ggx_root(w, ax, ay) / cz - 1.0)
}

/// Smith masking G1(w) = 1 / (1 + Lambda(w)) = 2 |cos| / (|cos| + s).
pub fn ggx_g1(w: Vec3, ax: f32, ay: f32) -> f32 {
    lanes::ggx_g1(w.into(), ax, ay)
}

/// Masking-shadowing G2(wo, wi): height-correlated 1 / (1 + Lo + Li)
/// (Heitz 2014 eq. 99) = 2 |co ci| / (|ci| so + |co| si), or separable
/// G1(wo) G1(wi) (Mitsuba 3).
pub fn ggx_g2(wo: Vec3, wi: Vec3, ax: f32, ay: f32, separable: bool) -> f32 {
    lanes::ggx_g2(wo.into(), wi.into(), ax, ay, separable)
}

/// The "visibility" V = G2 / (4 |co| |ci|), in a form finite at grazing
/// angles: correlated 1 / (2 (|ci| so + |co| si)), separable
/// 1 / ((|co| + so)(|ci| + si)).
pub fn ggx_visibility(wo: Vec3, wi: Vec3, ax: f32, ay: f32, separable: bool) -> f32 {
    lanes::ggx_visibility(wo.into(), wi.into(), ax, ay, separable)
}

/// Density of visible normals D_w(wm) = G1(w) / |cos w| D(wm) |w . wm|
/// (Heitz 2014 eq. 38); G1/|cos| = 2 / (|cos| + s) keeps it finite at
/// grazing w. The density of [`ggx_sample_visible`] for w above the surface
/// (for w below it samples the visible normals of -w: same value).
pub fn ggx_pdf_visible(w: Vec3, wm: Vec3, ax: f32, ay: f32) -> f32 {
    lanes::ggx_pdf_visible(w.into(), wm.into(), ax, ay)
}

/// Sample a visible microfacet normal (upper hemisphere) for direction w,
/// using w's mirror image when w is below the surface (pbrt-v4's
/// `Sample_wm`). Dupuy & Benyoub 2023, listing 3: stretch w into the
/// alpha = 1 configuration, sample the spherical cap of directions whose
/// half vector with w lies on the hemisphere, unstretch.
pub fn ggx_sample_visible(w: Vec3, ax: f32, ay: f32, u: Vec2) -> Vec3 {
    lanes::ggx_sample_visible(w.into(), ax, ay, u.into()).into()
}

/// The functions above over any [`Lane`] type, one source for the scalar
/// path (`f32`) and the wide one ([`crate::lanes::F32x8`]): each early
/// return of the scalar form is a select of both sides.
pub mod lanes {
    use std::f32::consts::PI;

    use crate::lanes::{Lane, V2, V3};

    #[inline(always)]
    pub fn reflect_dir<L: Lane>(w: V3<L>, n: V3<L>) -> V3<L> {
        -w + n.scale(L::splat(2.0) * w.dot(n))
    }

    #[inline(always)]
    pub fn ggx_d<L: Lane>(wm: V3<L>, ax: L, ay: L) -> L {
        let x = wm.x / ax;
        let y = wm.y / ay;
        let t = x * x + y * y + wm.z * wm.z;
        let d = L::one() / (L::splat(PI) * ax * ay * t * t);
        L::select(t.le(L::zero()), L::zero(), d)
    }

    #[inline(always)]
    pub fn ggx_root<L: Lane>(w: V3<L>, ax: L, ay: L) -> L {
        let a2 = ax * ax * w.x * w.x + ay * ay * w.y * w.y;
        (w.z * w.z + a2).sqrt()
    }

    #[inline(always)]
    pub fn ggx_g1<L: Lane>(w: V3<L>, ax: L, ay: L) -> L {
        let cz = w.z.abs();
        let d = cz + ggx_root(w, ax, ay);
        L::select(d.le(L::zero()), L::zero(), L::splat(2.0) * cz / d)
    }

    #[inline(always)]
    pub fn ggx_g2<L: Lane>(wo: V3<L>, wi: V3<L>, ax: L, ay: L, separable: bool) -> L {
        if separable {
            return ggx_g1(wo, ax, ay) * ggx_g1(wi, ax, ay);
        }
        let co = wo.z.abs();
        let ci = wi.z.abs();
        let d = ci * ggx_root(wo, ax, ay) + co * ggx_root(wi, ax, ay);
        L::select(d.le(L::zero()), L::zero(), L::splat(2.0) * co * ci / d)
    }

    #[inline(always)]
    pub fn ggx_visibility<L: Lane>(wo: V3<L>, wi: V3<L>, ax: L, ay: L, separable: bool) -> L {
        let co = wo.z.abs();
        let ci = wi.z.abs();
        let so = ggx_root(wo, ax, ay);
        let si = ggx_root(wi, ax, ay);
        let d = if separable {
            (co + so) * (ci + si)
        } else {
            L::splat(2.0) * (ci * so + co * si)
        };
        L::select(d.le(L::zero()), L::zero(), L::one() / d)
    }

    #[inline(always)]
    pub fn ggx_pdf_visible<L: Lane>(w: V3<L>, wm: V3<L>, ax: L, ay: L) -> L {
        let d = w.z.abs() + ggx_root(w, ax, ay);
        let pdf = L::splat(2.0) * ggx_d(wm, ax, ay) * w.dot(wm).abs() / d;
        L::select(d.le(L::zero()), L::zero(), pdf)
    }

    #[inline(always)]
    pub fn ggx_sample_visible<L: Lane>(w: V3<L>, ax: L, ay: L, u: V2<L>) -> V3<L> {
        let wh = V3::new(ax * w.x, ay * w.y, w.z);
        let wh = V3::select(wh.z.lt(L::zero()), -wh, wh);
        let len2 = wh.length_squared();
        let wh = wh / len2.sqrt();
        let phi = L::splat(2.0 * PI) * u.x;
        let z = (L::one() - u.y) * (L::one() + wh.z) - wh.z;
        let sin_theta = (L::one() - z * z).clamp(0.0, 1.0).sqrt();
        let (sin_phi, cos_phi) = phi.sin_cos();
        let c = V3::new(sin_theta * cos_phi, sin_theta * sin_phi, z);
        let h = c + wh;
        let wm = V3::new(ax * h.x, ay * h.y, h.z.max(L::zero()));
        let l2 = wm.length_squared();
        // h = 0 only when c = -wh, a single point of the unit square.
        let up = V3::new(L::zero(), L::zero(), L::one());
        let bad = len2.le(L::zero()) | l2.le(L::splat(1e-30));
        V3::select(bad, up, wm / l2.sqrt())
    }
}

/// Mirror w about the (unit) normal n.
pub fn reflect_dir(w: Vec3, n: Vec3) -> Vec3 {
    lanes::reflect_dir(w.into(), n.into()).into()
}
