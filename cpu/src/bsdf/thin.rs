//! Mitsuba 3's `thindielectric`: a thin slab of dielectric (a window pane,
//! a soap bubble) whose two parallel interfaces are collapsed onto one
//! surface. Light is reflected about the normal or passes straight through
//! (wi = -wo: the two refractions cancel), with the slab's infinite series
//! of internal reflections summed in closed form (Mitsuba 3,
//! `src/bsdfs/thindielectric.cpp`):
//!
//!   R' = R + T^2 R / (1 - R^2) = 2 R / (1 + R),   T' = 1 - R',
//!
//! R the interface's Fresnel reflectance at |cos theta|. Both lobes are
//! Dirac deltas; the reflection is picked with probability R'. No radiance
//! scaling (the path leaves into the medium it came from); two-sided.

use glam::{Vec2, Vec3};

use super::BsdfSample;
use super::fresnel::fresnel_dielectric;

/// The slab's reflectance R' = 2R / (1 + R) at |cos theta| = mu.
pub fn thin_reflectance(mu: f32, eta: f32) -> f32 {
    let r = fresnel_dielectric(mu.abs().min(1.0), eta);
    2.0 * r / (1.0 + r)
}

/// `reflectance` and `transmittance` are Mitsuba's specular_reflectance
/// and specular_transmittance.
pub fn thin_sample(
    eta: f32,
    reflectance: Vec3,
    transmittance: Vec3,
    wo: Vec3,
    uc: f32,
    _u: Vec2,
) -> Option<BsdfSample> {
    if wo.z == 0.0 {
        return None;
    }
    let r = thin_reflectance(wo.z, eta);
    let (wi, weight, pdf) = if uc < r {
        (Vec3::new(-wo.x, -wo.y, wo.z), reflectance, r)
    } else {
        (-wo, transmittance, 1.0 - r)
    };
    Some(BsdfSample {
        wi,
        weight,
        pdf,
        delta: true,
        eta: 1.0,
    })
}
