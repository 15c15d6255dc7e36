//! Square-to-domain warps used by the BSDF samplers (GLSL twins in
//! `shaders/bsdf/warp.glsl`).

use glam::{Vec2, Vec3};

use std::f32::consts::{FRAC_PI_2, FRAC_PI_4};

/// Shirley & Chiu 1997 concentric map of [0,1)^2 onto the unit disk.
pub fn square_to_concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, FRAC_PI_4 * (o.y / o.x))
    } else {
        (o.y, FRAC_PI_2 - FRAC_PI_4 * (o.x / o.y))
    };
    Vec2::new(r * theta.cos(), r * theta.sin())
}

/// Cosine-weighted upper hemisphere (Malley's method), density cos / pi.
pub fn square_to_cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = square_to_concentric_disk(u);
    let z = (1.0 - d.x * d.x - d.y * d.y).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}
