//! Square-to-domain warps used by the BSDF samplers (GLSL twins in
//! `shaders/bsdf/warp.glsl`).

use glam::{Vec2, Vec3};

use std::f32::consts::{FRAC_PI_2, FRAC_PI_4};

/// Shirley & Chiu 1997 concentric map of [0,1)^2 onto the unit disk.
pub fn square_to_concentric_disk(u: Vec2) -> Vec2 {
    let d = lanes::square_to_concentric_disk(u.into());
    Vec2::new(d.x, d.y)
}

/// Cosine-weighted upper hemisphere (Malley's method), density cos / pi.
pub fn square_to_cosine_hemisphere(u: Vec2) -> Vec3 {
    lanes::square_to_cosine_hemisphere(u.into()).into()
}

/// The warps over any [`crate::lanes::Lane`] type (one source with the
/// scalar forms above).
pub mod lanes {
    use super::{FRAC_PI_2, FRAC_PI_4};
    use crate::lanes::{Lane, V2, V3};

    #[inline(always)]
    pub fn square_to_concentric_disk<L: Lane>(u: V2<L>) -> V2<L> {
        let two = L::splat(2.0);
        let (ox, oy) = (two * u.x - L::one(), two * u.y - L::one());
        let centre = ox.eq(L::zero()) & oy.eq(L::zero());
        let x_major = ox.abs().gt(oy.abs());
        let r = L::select(x_major, ox, oy);
        let theta = L::select(
            x_major,
            L::splat(FRAC_PI_4) * (oy / ox),
            L::splat(FRAC_PI_2) - L::splat(FRAC_PI_4) * (ox / oy),
        );
        let (sin, cos) = theta.sin_cos();
        V2 {
            x: L::select(centre, L::zero(), r * cos),
            y: L::select(centre, L::zero(), r * sin),
        }
    }

    #[inline(always)]
    pub fn square_to_cosine_hemisphere<L: Lane>(u: V2<L>) -> V3<L> {
        let d = square_to_concentric_disk(u);
        let z = (L::one() - d.x * d.x - d.y * d.y).max(L::zero()).sqrt();
        V3::new(d.x, d.y, z)
    }
}
