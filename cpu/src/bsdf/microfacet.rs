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

use std::f32::consts::PI;

/// Rough alphas are clamped to at least this (pbrt-v4's
/// `TrowbridgeReitzDistribution` does the same) so that an anisotropic
/// surface with one alpha near 0 and the other large stays finite.
pub use crate::abi::MIN_ALPHA;

/// GGX normal distribution D(wm) (Walter et al. 2007 eq. 33, anisotropic
/// form of Heitz 2014 eq. 85): 1 / (pi ax ay ((x/ax)^2 + (y/ay)^2 + z^2)^2).
/// Even in wm.z; callers face-forward wm to the upper hemisphere.
pub fn ggx_d(wm: Vec3, ax: f32, ay: f32) -> f32 {
    let x = wm.x / ax;
    let y = wm.y / ay;
    let t = x * x + y * y + wm.z * wm.z;
    if t <= 0.0 {
        return 0.0;
    }
    1.0 / (PI * ax * ay * t * t)
}

/// sqrt(cos^2 + alpha(w)^2 sin^2): the projected-roughness root shared by
/// the Smith terms. Lambda(w) = (s / |cos| - 1) / 2 (Heitz 2014 eq. 86).
pub fn ggx_root(w: Vec3, ax: f32, ay: f32) -> f32 {
    let a2 = ax * ax * w.x * w.x + ay * ay * w.y * w.y;
    (w.z * w.z + a2).sqrt()
}

/// Smith Lambda (Heitz 2014 eq. 86). Infinite at cos theta = 0; only the
/// tests use it, the shading code uses the inf-free forms below.
pub fn ggx_lambda(w: Vec3, ax: f32, ay: f32) -> f32 {
    let cz = w.z.abs();
    0.5 * (ggx_root(w, ax, ay) / cz - 1.0)
}

/// Smith masking G1(w) = 1 / (1 + Lambda(w)) = 2 |cos| / (|cos| + s).
pub fn ggx_g1(w: Vec3, ax: f32, ay: f32) -> f32 {
    let cz = w.z.abs();
    let d = cz + ggx_root(w, ax, ay);
    if d <= 0.0 {
        return 0.0;
    }
    2.0 * cz / d
}

/// Masking-shadowing G2(wo, wi): height-correlated 1 / (1 + Lo + Li)
/// (Heitz 2014 eq. 99) = 2 |co ci| / (|ci| so + |co| si), or separable
/// G1(wo) G1(wi) (Mitsuba 3).
pub fn ggx_g2(wo: Vec3, wi: Vec3, ax: f32, ay: f32, separable: bool) -> f32 {
    if separable {
        return ggx_g1(wo, ax, ay) * ggx_g1(wi, ax, ay);
    }
    let co = wo.z.abs();
    let ci = wi.z.abs();
    let d = ci * ggx_root(wo, ax, ay) + co * ggx_root(wi, ax, ay);
    if d <= 0.0 {
        return 0.0;
    }
    2.0 * co * ci / d
}

/// The "visibility" V = G2 / (4 |co| |ci|), in a form finite at grazing
/// angles: correlated 1 / (2 (|ci| so + |co| si)), separable
/// 1 / ((|co| + so)(|ci| + si)).
pub fn ggx_visibility(wo: Vec3, wi: Vec3, ax: f32, ay: f32, separable: bool) -> f32 {
    let co = wo.z.abs();
    let ci = wi.z.abs();
    let so = ggx_root(wo, ax, ay);
    let si = ggx_root(wi, ax, ay);
    let d = if separable {
        (co + so) * (ci + si)
    } else {
        2.0 * (ci * so + co * si)
    };
    if d <= 0.0 {
        return 0.0;
    }
    1.0 / d
}

/// Density of visible normals D_w(wm) = G1(w) / |cos w| D(wm) |w . wm|
/// (Heitz 2014 eq. 38); G1/|cos| = 2 / (|cos| + s) keeps it finite at
/// grazing w. The density of [`ggx_sample_visible`] for w above the surface
/// (for w below it samples the visible normals of -w: same value).
pub fn ggx_pdf_visible(w: Vec3, wm: Vec3, ax: f32, ay: f32) -> f32 {
    let d = w.z.abs() + ggx_root(w, ax, ay);
    if d <= 0.0 {
        return 0.0;
    }
    2.0 * ggx_d(wm, ax, ay) * w.dot(wm).abs() / d
}

/// Sample a visible microfacet normal (upper hemisphere) for direction w,
/// using w's mirror image when w is below the surface (pbrt-v4's
/// `Sample_wm`). Dupuy & Benyoub 2023, listing 3: stretch w into the
/// alpha = 1 configuration, sample the spherical cap of directions whose
/// half vector with w lies on the hemisphere, unstretch.
pub fn ggx_sample_visible(w: Vec3, ax: f32, ay: f32, u: Vec2) -> Vec3 {
    let mut wh = Vec3::new(ax * w.x, ay * w.y, w.z);
    if wh.z < 0.0 {
        wh = -wh;
    }
    let len2 = wh.length_squared();
    if len2 <= 0.0 {
        return Vec3::Z;
    }
    wh /= len2.sqrt();
    let phi = 2.0 * PI * u.x;
    let z = (1.0 - u.y) * (1.0 + wh.z) - wh.z;
    let sin_theta = (1.0 - z * z).clamp(0.0, 1.0).sqrt();
    let c = Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), z);
    let h = c + wh;
    let wm = Vec3::new(ax * h.x, ay * h.y, h.z.max(0.0));
    let l2 = wm.length_squared();
    // h = 0 only when c = -wh, a single point of the unit square.
    if l2 <= 1e-30 {
        return Vec3::Z;
    }
    wm / l2.sqrt()
}

/// Mirror w about the (unit) normal n.
pub fn reflect_dir(w: Vec3, n: Vec3) -> Vec3 {
    -w + 2.0 * w.dot(n) * n
}
