//! Mitsuba 3's smooth `plastic`: a smooth dielectric interface over a
//! Lambertian base, with the light reflected back and forth inside the
//! coating accounted for in closed form (Mitsuba 3, `src/bsdfs/plastic.cpp`;
//! Weidlich and Wilkie 2007). For scenes ported from Mitsuba; the glTF
//! non-metal is `coated.rs`.
//!
//!   specular: the mirror, weighted by specular_reflectance x F(mu_o);
//!   diffuse:  f = rho' (1 - F(mu_o)) (1 - F(mu_i)) / (eta^2 pi), with
//!             rho' = rho / (1 - F_dr,int) (or rho / (1 - rho F_dr,int)
//!             with `nonlinear`), F_dr,int the diffuse Fresnel reflectance
//!             of the interface seen from inside (Mitsuba's polynomial fits).
//!
//! Sampling as Mitsuba's: the mirror with probability
//! P = F w_s / (F w_s + (1 - F)(1 - w_s)), w_s = mean(specular) /
//! (mean(diffuse) + mean(specular)); the cosine lobe otherwise. Mitsuba's
//! plugin is one-sided; glint's opaque BSDFs are two-sided (a wo below the
//! surface mirrors both directions).

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};

use super::BsdfSample;
use super::conductor::two_sided;
use super::fresnel::fresnel_dielectric;
use super::warp::square_to_cosine_hemisphere;

/// Mitsuba 3's `plastic` parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlasticParams {
    /// `diffuse_reflectance` (default 0.5).
    pub diffuse: Vec3,
    /// `specular_reflectance` (default 1).
    pub specular: Vec3,
    /// int_ior / ext_ior (defaults 1.49 polypropylene over air).
    pub eta: f32,
    /// `nonlinear`: the internal scattering shifts the colour (default false).
    pub nonlinear: bool,
}

/// Mitsuba 3's diffuse Fresnel reflectance F_dr(eta) (`fresnel.h`): the
/// Egan and Hilgeman (1973) fit for eta < 1, d'Eon and Irving's (2011)
/// otherwise.
pub fn fresnel_diffuse_reflectance(eta: f32) -> f32 {
    let inv = 1.0 / eta;
    if eta < 1.0 {
        0.0636 * inv + (eta * (eta * -1.4399 + 0.7099) + 0.6681)
    } else {
        let c = [0.919317f32, -3.4793, 6.75335, -7.80989, 4.98554, -1.36881];
        let mut acc = c[5];
        for k in (0..5).rev() {
            acc = acc * inv + c[k];
        }
        acc
    }
}

fn mean(v: Vec3) -> f32 {
    (v.x + v.y + v.z) * (1.0 / 3.0)
}

impl PlasticParams {
    /// w_s: the share of the specular lobe in the sampling weights.
    pub fn specular_sampling_weight(&self) -> f32 {
        let (s, d) = (mean(self.specular), mean(self.diffuse));
        if s + d > 0.0 { s / (s + d) } else { 0.5 }
    }

    /// rho': the base reflectance with the internal reflections summed.
    pub fn diffuse_scaled(&self) -> Vec3 {
        let fdr = fresnel_diffuse_reflectance(1.0 / self.eta);
        if self.nonlinear {
            self.diffuse / (Vec3::ONE - self.diffuse * fdr)
        } else {
            self.diffuse / (1.0 - fdr)
        }
    }

    /// The mirror's sampling probability P at mu_o, and 1 - P computed
    /// without the cancellation.
    fn probabilities(&self, mu_o: f32) -> (f32, f32) {
        let f = fresnel_dielectric(mu_o, self.eta);
        let w = self.specular_sampling_weight();
        let (s, d) = (f * w, (1.0 - f) * (1.0 - w));
        if s + d > 0.0 {
            (s / (s + d), d / (s + d))
        } else {
            (0.0, 1.0)
        }
    }

    fn diffuse_term(&self, mu_o: f32, mu_i: f32) -> Vec3 {
        let (fo, fi) = (
            fresnel_dielectric(mu_o, self.eta),
            fresnel_dielectric(mu_i, self.eta),
        );
        self.diffuse_scaled() * ((1.0 - fo) * (1.0 - fi) * FRAC_1_PI / (self.eta * self.eta))
    }
}

pub fn plastic_eval(p: &PlasticParams, wo: Vec3, wi: Vec3) -> Vec3 {
    let (wo, wi) = two_sided(wo, wi);
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return Vec3::ZERO;
    }
    p.diffuse_term(wo.z, wi.z)
}

pub fn plastic_pdf(p: &PlasticParams, wo: Vec3, wi: Vec3) -> f32 {
    let (wo, wi) = two_sided(wo, wi);
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return 0.0;
    }
    p.probabilities(wo.z).1 * wi.z * FRAC_1_PI
}

pub fn plastic_sample(p: &PlasticParams, wo: Vec3, uc: f32, u: Vec2) -> Option<BsdfSample> {
    if wo.z == 0.0 {
        return None;
    }
    let flip = wo.z < 0.0;
    let mu_o = wo.z.abs();
    let (p_spec, p_diff) = p.probabilities(mu_o);
    if uc < p_spec {
        let f = p.specular * fresnel_dielectric(mu_o, p.eta);
        return Some(BsdfSample {
            wi: Vec3::new(-wo.x, -wo.y, wo.z),
            weight: f / p_spec,
            pdf: p_spec,
            delta: true,
            eta: 1.0,
        });
    }
    let mut wi = square_to_cosine_hemisphere(u);
    if wi.z <= 0.0 || !(p_diff > 0.0) {
        return None;
    }
    let pdf = p_diff * wi.z * FRAC_1_PI;
    let weight = p.diffuse_term(mu_o, wi.z) * (wi.z / pdf);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Mitsuba's fits against the integral they fit, F_dr = 2 int F mu dmu.
    #[test]
    fn diffuse_fresnel_fits_the_integral() {
        for eta in [1.0 / 1.49, 1.0 / 1.33, 1.33, 1.49, 2.0] {
            let n = 20000;
            let q: f64 = (0..n)
                .map(|i| {
                    let mu = (i as f64 + 0.5) / n as f64;
                    2.0 * mu * fresnel_dielectric(mu as f32, eta) as f64
                })
                .sum::<f64>()
                / n as f64;
            let fit = fresnel_diffuse_reflectance(eta) as f64;
            assert!(
                (fit - q).abs() < 0.01 * q.max(0.05),
                "eta {eta}: {fit} vs {q}"
            );
        }
    }
}
