//! Fresnel reflectance for unpolarised light: dielectric interfaces (real
//! relative IOR, valid from both sides, total internal reflection) and
//! conductors (complex IOR eta + i k).
//!
//! Every function here has a GLSL twin of the same name in
//! `shaders/bsdf/fresnel.glsl`, written line for line.

use glam::Vec3;

/// Reflectances (R_s, R_p) of the perpendicular (s) and parallel (p)
/// polarisations at a dielectric interface, for `cos_i` measured against the
/// normal on the outside (+z) and `eta` = n_inside / n_outside.
///
/// A negative `cos_i` means the light arrives from inside: the relative IOR
/// is then 1 / eta (pbrt-v4's `FrDielectric`, Pharr et al. 4th ed. eq. 9.5).
/// Beyond the critical angle both are 1 (total internal reflection).
pub fn fresnel_dielectric_polarized(cos_i: f32, eta: f32) -> (f32, f32) {
    lanes::fresnel_dielectric_polarized(cos_i, eta)
}

/// Unpolarised dielectric Fresnel reflectance: the mean of R_s and R_p.
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    lanes::fresnel_dielectric(cos_i, eta)
}

/// Unpolarised Fresnel reflectance of a conductor with complex relative IOR
/// eta + i k, one channel, for `cos_i` in [0, 1].
///
/// The exact closed form in real arithmetic (Born & Wolf 14.2; as written in
/// S. Lagarde, "Memo on Fresnel equations", 2013, and Mitsuba's
/// `fresnel_conductor`): with a^2 + b^2 = |eta^2 - k^2 - sin^2 + 2 i eta k|,
/// R_s = (a^2+b^2 + cos^2 - 2 a cos) / (a^2+b^2 + cos^2 + 2 a cos) and
/// R_p = R_s (cos^2 (a^2+b^2) + sin^4 - 2 a cos sin^2) /
///           (cos^2 (a^2+b^2) + sin^4 + 2 a cos sin^2).
/// Equal to pbrt-v4's complex `FrComplex`; with k = 0 and eta > 1 it reduces
/// to [`fresnel_dielectric`].
pub fn fresnel_conductor_channel(cos_i: f32, eta: f32, k: f32) -> f32 {
    lanes::fresnel_conductor_channel(cos_i, eta, k)
}

/// The Fresnel terms and refraction over any [`crate::lanes::Lane`] type
/// (one source with the scalar forms above; each early return is a
/// select).
pub mod lanes {
    use crate::lanes::{Lane, V3};

    #[inline(always)]
    pub fn fresnel_dielectric_polarized<L: Lane>(cos_i: L, eta: L) -> (L, L) {
        let cos_i = cos_i.clamp(-1.0, 1.0);
        let inside = cos_i.lt(L::zero());
        let eta = L::select(inside, L::one() / eta, eta);
        let cos_i = L::select(inside, -cos_i, cos_i);
        // Snell: sin_t = sin_i / eta.
        let sin2_i = (L::one() - cos_i * cos_i).max(L::zero());
        let sin2_t = sin2_i / (eta * eta);
        let tir = sin2_t.ge(L::one());
        let cos_t = (L::one() - sin2_t).max(L::zero()).sqrt();
        // Amplitude coefficients (Born & Wolf 1.5.2, eqs. 21a/21b). The
        // denominators vanish only when cos_i = cos_t = 0, which needs
        // sin2_t = 1, total internal reflection.
        let r_s = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
        let r_p = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
        (
            L::select(tir, L::one(), r_s * r_s),
            L::select(tir, L::one(), r_p * r_p),
        )
    }

    #[inline(always)]
    pub fn fresnel_dielectric<L: Lane>(cos_i: L, eta: L) -> L {
        let (rs, rp) = fresnel_dielectric_polarized(cos_i, eta);
        L::splat(0.5) * (rs + rp)
    }

    /// `w` refracted through the interface of normal `n` (either side):
    /// where the refraction exists (not total internal reflection), the
    /// transmitted direction and the relative IOR crossed.
    #[inline(always)]
    pub fn refract_dir<L: Lane>(w: V3<L>, n: V3<L>, eta: L) -> (L::Mask, V3<L>, L) {
        let cos_i = n.dot(w);
        let inside = cos_i.lt(L::zero());
        let eta = L::select(inside, L::one() / eta, eta);
        let cos_i = L::select(inside, -cos_i, cos_i);
        let n = V3::select(inside, -n, n);
        let sin2_i = (L::one() - cos_i * cos_i).max(L::zero());
        let sin2_t = sin2_i / (eta * eta);
        let cos_t = (L::one() - sin2_t).max(L::zero()).sqrt();
        let wt = (-w) / eta + n.scale(cos_i / eta - cos_t);
        (!sin2_t.ge(L::one()), wt, eta)
    }

    #[inline(always)]
    pub fn fresnel_conductor_channel<L: Lane>(cos_i: L, eta: L, k: L) -> L {
        let cos_i = cos_i.clamp(0.0, 1.0);
        let cos2 = cos_i * cos_i;
        let sin2 = (L::one() - cos2).max(L::zero());
        let eta2 = eta * eta;
        let k2 = k * k;
        let t0 = eta2 - k2 - sin2;
        let a2b2 = (t0 * t0 + L::splat(4.0) * eta2 * k2).max(L::zero()).sqrt();
        let a = (L::splat(0.5) * (a2b2 + t0)).max(L::zero()).sqrt();
        let t1 = a2b2 + cos2;
        let t2 = L::splat(2.0) * a * cos_i;
        // t1 + t2 = 0 only for a2b2 = 0 and cos_i = 0 (eta = 1, k = 0 at
        // grazing): a vacuum "interface", whose grazing reflectance is 1.
        let denom_s = t1 + t2;
        let rs = (t1 - t2) / denom_s;
        let t3 = cos2 * a2b2 + sin2 * sin2;
        let t4 = t2 * sin2;
        let denom_p = t3 + t4;
        let rp = L::select(denom_p.gt(L::zero()), rs * (t3 - t4) / denom_p, rs);
        L::select(denom_s.le(L::zero()), L::one(), L::splat(0.5) * (rs + rp))
    }

    /// Per RGB channel.
    #[inline(always)]
    pub fn fresnel_conductor<L: Lane>(cos_i: L, eta: V3<L>, k: V3<L>) -> V3<L> {
        V3::new(
            fresnel_conductor_channel(cos_i, eta.x, k.x),
            fresnel_conductor_channel(cos_i, eta.y, k.y),
            fresnel_conductor_channel(cos_i, eta.z, k.z),
        )
    }
}

/// [`fresnel_conductor_channel`] for each RGB channel.
pub fn fresnel_conductor(cos_i: f32, eta: Vec3, k: Vec3) -> Vec3 {
    Vec3::new(
        fresnel_conductor_channel(cos_i, eta.x, k.x),
        fresnel_conductor_channel(cos_i, eta.y, k.y),
        fresnel_conductor_channel(cos_i, eta.z, k.z),
    )
}

/// Refract `w` (pointing away from the surface, on either side) through the
/// interface with normal +z and relative IOR `eta` = n_inside / n_outside.
/// Returns the transmitted direction (pointing away, on the other side) and
/// the relative IOR eta_t / eta_i actually crossed, or `None` under total
/// internal reflection. pbrt-v4's `Refract` with n = (0, 0, 1) or -n.
pub fn refract_dir(w: Vec3, n: Vec3, eta: f32) -> Option<(Vec3, f32)> {
    let (ok, wt, eta) = lanes::refract_dir(w.into(), n.into(), eta);
    ok.then(|| (wt.into(), eta))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conductor_with_zero_k_is_a_dielectric() {
        for i in 0..=20 {
            let c = i as f32 / 20.0;
            let a = fresnel_conductor_channel(c, 1.5, 0.0);
            let b = fresnel_dielectric(c, 1.5);
            assert!((a - b).abs() < 1e-5, "cos {c}: {a} vs {b}");
        }
    }
}
