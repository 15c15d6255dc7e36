//! Lambertian reflection, two-sided.

use glam::{Vec2, Vec3};

use super::BsdfSample;

/// f = rho / pi when wo and wi are on the same side, else 0.
#[inline]
pub fn diffuse_eval(rho: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
    lanes::diffuse_eval(rho.into(), wo.into(), wi.into()).into()
}

/// Cosine-weighted density on wo's side.
#[inline]
pub fn diffuse_pdf(wo: Vec3, wi: Vec3) -> f32 {
    lanes::diffuse_pdf(wo.into(), wi.into())
}

#[inline]
pub fn diffuse_sample(rho: Vec3, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
    lanes::diffuse_sample(rho.into(), wo.into(), u.into()).single()
}

/// The Lambertian BSDF over any [`crate::lanes::Lane`] type (one source
/// with the scalar forms above).
pub mod lanes {
    use std::f32::consts::FRAC_1_PI;

    use crate::bsdf::LaneSample;
    use crate::bsdf::warp::lanes::square_to_cosine_hemisphere;
    use crate::lanes::{Lane, V2, V3};

    #[inline(always)]
    pub fn diffuse_eval<L: Lane>(rho: V3<L>, wo: V3<L>, wi: V3<L>) -> V3<L> {
        let below = (wo.z * wi.z).le(L::zero());
        let zero = V3::new(L::zero(), L::zero(), L::zero());
        V3::select(below, zero, rho.scale(L::splat(FRAC_1_PI)))
    }

    #[inline(always)]
    pub fn diffuse_pdf<L: Lane>(wo: V3<L>, wi: V3<L>) -> L {
        let below = (wo.z * wi.z).le(L::zero());
        L::select(below, L::zero(), wi.z.abs() * L::splat(FRAC_1_PI))
    }

    #[inline(always)]
    pub fn diffuse_sample<L: Lane>(rho: V3<L>, wo: V3<L>, u: V2<L>) -> LaneSample<L> {
        let mut wi = square_to_cosine_hemisphere(u);
        let valid = !wo.z.eq(L::zero()) & !wi.z.le(L::zero());
        wi.z = L::select(wo.z.lt(L::zero()), -wi.z, wi.z);
        LaneSample {
            valid,
            wi,
            // f |cos| / pdf = (rho / pi) |cos| / (|cos| / pi).
            weight: rho,
            pdf: wi.z.abs() * L::splat(FRAC_1_PI),
            eta: L::one(),
            delta: false,
        }
    }
}
