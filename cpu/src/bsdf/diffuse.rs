//! Lambertian reflection, two-sided.

use glam::{Vec2, Vec3};

use std::f32::consts::FRAC_1_PI;

use super::BsdfSample;
use super::warp::square_to_cosine_hemisphere;

/// f = rho / pi when wo and wi are on the same side, else 0.
pub fn diffuse_eval(rho: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
    if wo.z * wi.z <= 0.0 {
        return Vec3::ZERO;
    }
    rho * FRAC_1_PI
}

/// Cosine-weighted density on wo's side.
pub fn diffuse_pdf(wo: Vec3, wi: Vec3) -> f32 {
    if wo.z * wi.z <= 0.0 {
        return 0.0;
    }
    wi.z.abs() * FRAC_1_PI
}

pub fn diffuse_sample(rho: Vec3, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
    if wo.z == 0.0 {
        return None;
    }
    let mut wi = square_to_cosine_hemisphere(u);
    if wi.z <= 0.0 {
        return None;
    }
    if wo.z < 0.0 {
        wi.z = -wi.z;
    }
    Some(BsdfSample {
        wi,
        // f |cos| / pdf = (rho / pi) |cos| / (|cos| / pi).
        weight: rho,
        pdf: wi.z.abs() * FRAC_1_PI,
        delta: false,
        eta: 1.0,
    })
}
