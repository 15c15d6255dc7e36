//! Energy compensation of GGX conductors (`multiscatter`): Kulla & Conty
//! 2017, "Revisiting Physically Based Shading at Imageworks" (SIGGRAPH
//! course), sec. "Multiple scattering": the single-scattering lobe loses
//! 1 - E(mu_o) of the energy (E the directional albedo with F = 1), which
//! a diffuse-like lobe
//!   f_ms = (1 - E(mu_o)) (1 - E(mu_i)) / (pi (1 - E_avg)) F_ms,
//!   F_ms = F_avg^2 E_avg / (1 - F_avg (1 - E_avg)),
//! returns (E_avg = 2 int E(mu) mu dmu, F_avg = 2 int F(mu) mu dmu). With
//! F = 1 the albedo is then exactly 1 at every angle; f_ms is symmetric in
//! (wo, wi), so reciprocity holds.
//!
//! E and E_avg come from glint's own single-scattering BSDF, one table per
//! Smith form, over mu = cos theta and alpha on uniform grids: written by
//! `cargo run --release -p glint-cpu --example ms_tables` into
//! `cpu/src/bsdf/ms_tables.bin` (read by `ms_tables`); the GPU reads the same numbers from a
//! storage buffer ([`gpu_tables`], `shaders/bsdf/multiscatter.glsl`; a test
//! pins the offsets and recomputes a few entries).
//! Anisotropic surfaces look the tables up at sqrt(alpha_u alpha_v).
//!
//! Rough dielectrics (Turquin 2019, "A Practical Multiple Scattering
//! Compensation for Microfacet Models", sec. 4): the single-scattering
//! lobe (reflection + transmission) is divided by its own directional
//! albedo E(mu_o, alpha, eta'), counted as flux (transmission's
//! 1/eta_rel^2 undone), eta' the relative IOR seen from wo's side. The
//! furnace is then exactly 1 from both sides; the price is reciprocity
//! (E(mu_o) / E(mu_i) apart), as in Turquin's paper. Sampling is
//! unchanged (the pdf does not depend on the scale).

use glam::Vec3;

use super::fresnel::fresnel_conductor;
use super::microfacet::{ggx_g1, ggx_g2, ggx_sample_visible, reflect_dir};
use super::ms_tables::{MS_E, MS_E_AVG, MS_N, MS_T, MS_T_N};

/// Bilinear lookup of `table[alpha][mu]` on the uniform grids over [0, 1].
fn lerp2(table: &[f32], mu: f32, alpha: f32) -> f32 {
    let n = MS_N;
    let x = mu.clamp(0.0, 1.0) * (n - 1) as f32;
    let y = alpha.clamp(0.0, 1.0) * (n - 1) as f32;
    let (x0, y0) = ((x as usize).min(n - 2), (y as usize).min(n - 2));
    let (fx, fy) = (x - x0 as f32, y - y0 as f32);
    let at = |i: usize, j: usize| table[j * n + i];
    let a = at(x0, y0) + (at(x0 + 1, y0) - at(x0, y0)) * fx;
    let b = at(x0, y0 + 1) + (at(x0 + 1, y0 + 1) - at(x0, y0 + 1)) * fx;
    a + (b - a) * fy
}

fn lerp1(table: &[f32], alpha: f32) -> f32 {
    let n = MS_N;
    let y = alpha.clamp(0.0, 1.0) * (n - 1) as f32;
    let y0 = (y as usize).min(n - 2);
    let f = y - y0 as f32;
    table[y0] + (table[y0 + 1] - table[y0]) * f
}

/// Directional albedo E(mu) of the F = 1 single-scattering GGX lobe.
pub fn ms_albedo(mu: f32, alpha: f32, separable: bool) -> f32 {
    lerp2(&MS_E[separable as usize], mu, alpha)
}

/// Its cosine-weighted average E_avg.
pub fn ms_albedo_avg(alpha: f32, separable: bool) -> f32 {
    lerp1(&MS_E_AVG[separable as usize], alpha)
}

/// Hemispherical average of the conductor Fresnel term, 2 int F mu dmu =
/// int_0^1 F(sqrt(x)) dx, by 8-point Gauss-Legendre.
pub fn fresnel_conductor_avg(eta: Vec3, k: Vec3) -> Vec3 {
    const X: [f32; 4] = [0.183_434_64, 0.525_532_4, 0.796_666_5, 0.960_289_9];
    const W: [f32; 4] = [0.362_683_8, 0.313_706_64, 0.222_381_03, 0.101_228_54];
    let mut s = Vec3::ZERO;
    for i in 0..4 {
        for sign in [-1.0f32, 1.0] {
            let x = 0.5 + 0.5 * sign * X[i];
            s += W[i] * 0.5 * fresnel_conductor(x.sqrt(), eta, k);
        }
    }
    s
}

/// The multiple-scattering lobe f_ms for wo, wi both above the surface.
pub fn conductor_ms_eval(mu_o: f32, mu_i: f32, alpha: f32, separable: bool, f_avg: Vec3) -> Vec3 {
    let e_avg = ms_albedo_avg(alpha, separable);
    if !(e_avg < 1.0) {
        return Vec3::ZERO;
    }
    let eo = ms_albedo(mu_o, alpha, separable);
    let ei = ms_albedo(mu_i, alpha, separable);
    let f_ms = f_avg * f_avg * e_avg / (Vec3::ONE - f_avg * (1.0 - e_avg));
    f_ms * ((1.0 - eo).max(0.0) * (1.0 - ei).max(0.0) / (std::f32::consts::PI * (1.0 - e_avg)))
}

/// E(mu) of the F = 1 single-scattering lobe by visible-normal sampling on
/// an n x n stratified grid: the mean of G2 / G1 over reflected directions
/// above the surface (Heitz 2018 eq. 19 with F = 1). The generator's
/// integrand, public so that a test can recompute table entries.
pub fn ms_albedo_reference(mu: f32, alpha: f32, separable: bool, n: usize) -> f64 {
    let mu = mu.max(1e-4);
    let wo = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let a = alpha.max(super::microfacet::MIN_ALPHA);
    let g1 = ggx_g1(wo, a, a);
    let mut sum = 0.0f64;
    for i in 0..n {
        for j in 0..n {
            let u = glam::Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
            let wm = ggx_sample_visible(wo, a, a, u);
            let wi = reflect_dir(wo, wm);
            if wi.z > 0.0 && g1 > 0.0 {
                sum += (ggx_g2(wo, wi, a, a, separable) / g1) as f64;
            }
        }
    }
    sum / (n * n) as f64
}

/// Every table in one array, the GPU's storage buffer (binding 15 of the
/// path tracer; `shaders/bsdf/multiscatter.glsl` reads it at the offsets
/// [`MS_OFF_E_AVG`] and [`MS_OFF_T`], `shaders/bsdf/coated.glsl` at
/// [`MS_OFF_COAT`]): MS_E[0], MS_E[1], MS_E_AVG[0], MS_E_AVG[1], MS_T[0],
/// MS_T[1], then the glTF non-metal's coat tables (`coated::coat_tables`)
/// and `roughplastic`'s ([`MS_OFF_RP`]).
pub fn gpu_tables() -> Vec<f32> {
    let coat = super::coated::coat_tables();
    let mut v = Vec::with_capacity(MS_OFF_RP + super::roughplastic::RP_LEN);
    v.extend_from_slice(&MS_E[0]);
    v.extend_from_slice(&MS_E[1]);
    v.extend_from_slice(&MS_E_AVG[0]);
    v.extend_from_slice(&MS_E_AVG[1]);
    v.extend_from_slice(&MS_T[0]);
    v.extend_from_slice(&MS_T[1]);
    v.extend_from_slice(coat);
    v.extend_from_slice(super::roughplastic::roughplastic_tables());
    v
}

// The offsets of MS_E_AVG, MS_T, the coat tables (E, then E_avg) and
// `roughplastic`'s tables in [`gpu_tables`]; the dielectric table's eta'
// grid, log-uniform over [MS_T_ETA_MIN, MS_T_ETA_MAX] = [1/3, 3].
pub use crate::abi::{MS_OFF_COAT, MS_OFF_E_AVG, MS_OFF_RP, MS_OFF_T, MS_T_ETA_MAX, MS_T_ETA_MIN};

/// eta' of grid index j of an `n`-point grid (the table's: `MS_T_N`; the
/// generator passes the size it writes, which may not be the one compiled
/// in yet).
pub fn ms_t_eta(j: usize, n: usize) -> f32 {
    let t = j as f32 / (n - 1) as f32;
    (MS_T_ETA_MIN.ln() + t * (MS_T_ETA_MAX.ln() - MS_T_ETA_MIN.ln())).exp()
}

/// Flux albedo E(mu, alpha, eta') of the single-scattering rough
/// dielectric with the given Smith form (trilinear in mu, alpha, ln eta').
pub fn dielectric_ms_albedo(mu: f32, alpha: f32, eta: f32, separable: bool) -> f32 {
    let table = &MS_T[separable as usize];
    let n = MS_T_N;
    let x = mu.clamp(0.0, 1.0) * (n - 1) as f32;
    let y = alpha.clamp(0.0, 1.0) * (n - 1) as f32;
    let lo = MS_T_ETA_MIN.ln();
    let hi = MS_T_ETA_MAX.ln();
    let z = ((eta.max(1e-6).ln() - lo) / (hi - lo)).clamp(0.0, 1.0) * (n - 1) as f32;
    let (x0, y0, z0) = (
        (x as usize).min(n - 2),
        (y as usize).min(n - 2),
        (z as usize).min(n - 2),
    );
    let (fx, fy, fz) = (x - x0 as f32, y - y0 as f32, z - z0 as f32);
    let at = |i: usize, j: usize, k: usize| table[(k * n + j) * n + i];
    let plane = |k: usize| {
        let a = at(x0, y0, k) + (at(x0 + 1, y0, k) - at(x0, y0, k)) * fx;
        let b = at(x0, y0 + 1, k) + (at(x0 + 1, y0 + 1, k) - at(x0, y0 + 1, k)) * fx;
        a + (b - a) * fy
    };
    let p0 = plane(z0);
    let p1 = plane(z0 + 1);
    p0 + (p1 - p0) * fz
}

/// E of the rough dielectric by stratified sampling (`n` x `n` normals,
/// 4 passes, the R/T choice by a Kronecker sequence over the cells so that
/// it is uniform and independent of the normal): the generator's
/// integrand.
pub fn dielectric_albedo_reference(
    mu: f32,
    alpha: f32,
    eta: f32,
    separable: bool,
    n: usize,
) -> f64 {
    let mu = mu.max(1e-4);
    let wo = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let a = alpha.max(super::SMOOTH_ALPHA_THRESHOLD * 1.001);
    let b = super::Bsdf::Dielectric {
        eta,
        tint: super::Tint::NONE,
        roughness: super::Roughness {
            alpha_u: a,
            alpha_v: a,
            shadowing: if separable {
                super::Shadowing::Separable
            } else {
                super::Shadowing::Correlated
            },
            multiscatter: false,
        },
    };
    let mut sum = 0.0f64;
    let strata = 4;
    for s in 0..strata {
        for i in 0..n {
            for j in 0..n {
                let k = ((s * n + i) * n + j) as f64;
                let uc = (0.5 + k * 0.618_033_988_749_895).fract() as f32;
                let u = glam::Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                if let Some(smp) = b.sample(wo, uc, u) {
                    sum += (smp.weight.x * smp.eta * smp.eta) as f64;
                }
            }
        }
    }
    sum / (strata * n * n) as f64
}
