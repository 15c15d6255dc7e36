//! The glTF metallic-roughness blend (Mitsuba 3's `blendbsdf` with weight
//! `metallic`): the conductor lobe with probability `metallic`, the coated
//! non-metal (`coated.rs`) with 1 - metallic, both with the conductor's
//! roughness. A one-sample mixture (pbrt-v4 style): eval and pdf are the
//! mixtures, so MIS sees the combined density. Two-sided.
//!
//! A lobe whose weight is exactly zero (metallic 0 or 1: every textured
//! glTF material is this blend, and most sit at one of its ends) is not
//! evaluated: its term, zero times a finite number, added nothing, so the
//! blend gives the same bits without it ([`lobes`]).

use glam::{Vec2, Vec3};

use super::coated::{
    CoatAtWo, CoatParams, coat_at_wo, coated_eval_at, coated_pdf_at, coated_sample_at,
};
use super::conductor::{conductor_eval, conductor_pdf, conductor_sample};
use super::{BsdfSample, ConductorParams};

/// The non-delta part of the blend: smooth lobes contribute nothing here
/// (they are Dirac deltas, reached only through sampling).
pub fn metallic_eval(
    m: f32,
    base: Vec3,
    c: &ConductorParams,
    coat: &CoatParams,
    wo: Vec3,
    wi: Vec3,
) -> Vec3 {
    let w = metallic_coat_at_wo(m, base, c, coat, wo);
    metallic_eval_at(m, base, c, coat, &w, wo, wi)
}

pub fn metallic_pdf(
    m: f32,
    base: Vec3,
    c: &ConductorParams,
    coat: &CoatParams,
    wo: Vec3,
    wi: Vec3,
) -> f32 {
    let w = metallic_coat_at_wo(m, base, c, coat, wo);
    metallic_pdf_at(m, c, coat, &w, wo, wi)
}

/// [`metallic_eval`] with the non-metal's coat at wo already looked up.
pub fn metallic_eval_at(
    m: f32,
    base: Vec3,
    c: &ConductorParams,
    coat: &CoatParams,
    w: &CoatAtWo,
    wo: Vec3,
    wi: Vec3,
) -> Vec3 {
    let (f_c, f_n) = lobes(
        m,
        || conductor_eval(c, wo, wi),
        || coated_eval_at(base, coat, &c.roughness, w, wo, wi),
    );
    m * f_c + (1.0 - m) * f_n
}

/// [`metallic_pdf`] with the non-metal's coat at wo already looked up.
pub fn metallic_pdf_at(
    m: f32,
    c: &ConductorParams,
    coat: &CoatParams,
    w: &CoatAtWo,
    wo: Vec3,
    wi: Vec3,
) -> f32 {
    let (pdf_c, pdf_n) = lobes(
        m,
        || conductor_pdf(c, wo, wi),
        || coated_pdf_at(coat, &c.roughness, w, wo, wi),
    );
    m * pdf_c + (1.0 - m) * pdf_n
}

/// The metal's and the non-metal's values, each only where its weight
/// (`m`, `1 - m`) is not zero, else zero: the blend `m a + (1 - m) b` of
/// them is the blend of both computed, bit for bit, wherever the skipped
/// one is finite (0 x finite is +-0, and x + 0 is x).
#[inline(always)]
fn lobes<T: Default>(m: f32, metal: impl FnOnce() -> T, nonmetal: impl FnOnce() -> T) -> (T, T) {
    let a = if m != 0.0 { metal() } else { T::default() };
    let b = if 1.0 - m != 0.0 {
        nonmetal()
    } else {
        T::default()
    };
    (a, b)
}

/// The non-metal's coat at wo, for a blend that reads it: a pure metal
/// (metallic 1) reads none of it, and skips the table lookups.
pub fn metallic_coat_at_wo(
    m: f32,
    base: Vec3,
    c: &ConductorParams,
    coat: &CoatParams,
    wo: Vec3,
) -> CoatAtWo {
    if 1.0 - m != 0.0 {
        coat_at_wo(base, coat, &c.roughness, wo)
    } else {
        CoatAtWo::UNREAD
    }
}

/// `uc` first picks the metal (uc < m), then, rescaled to [0, 1), the
/// non-metal's own lobe.
pub fn metallic_sample(
    m: f32,
    base: Vec3,
    c: &ConductorParams,
    coat: &CoatParams,
    wo: Vec3,
    uc: f32,
    u: Vec2,
) -> Option<BsdfSample> {
    let w = metallic_coat_at_wo(m, base, c, coat, wo);
    metallic_sample_at(m, base, c, coat, &w, wo, uc, u)
}

/// [`metallic_sample`] with the non-metal's coat at wo already looked up.
#[allow(clippy::too_many_arguments)]
pub fn metallic_sample_at(
    m: f32,
    base: Vec3,
    c: &ConductorParams,
    coat: &CoatParams,
    w: &CoatAtWo,
    wo: Vec3,
    uc: f32,
    u: Vec2,
) -> Option<BsdfSample> {
    // The lobe that was sampled contributes its own (well-conditioned)
    // pdf and f; the other is evaluated at the sampled direction.
    let (wi, pdf_c, f_c, pdf_n, f_n);
    if uc < m {
        let s = conductor_sample(c, wo, u)?;
        if s.delta {
            // The delta lobe of the mixture: f = m F delta / |cos| picked
            // with probability m, so the throughput stays F (the lobe's own
            // weight) and the discrete probability is m.
            return Some(BsdfSample { pdf: m, ..s });
        }
        wi = s.wi;
        pdf_c = s.pdf;
        f_c = s.weight * (s.pdf / wi.z.abs());
        // The other lobe where its weight is not zero (as in `lobes`).
        (pdf_n, f_n) = if 1.0 - m != 0.0 {
            (
                coated_pdf_at(coat, &c.roughness, w, wo, wi),
                coated_eval_at(base, coat, &c.roughness, w, wo, wi),
            )
        } else {
            (0.0, Vec3::ZERO)
        };
    } else {
        let uc = ((uc - m) / (1.0 - m)).clamp(0.0, ONE_MINUS_EPS);
        let s = coated_sample_at(base, coat, &c.roughness, w, wo, uc, u)?;
        if s.delta {
            // The smooth coat's mirror, (1 - m) s F delta / |cos|, picked
            // with probability (1 - m) P: the coat's own throughput.
            return Some(BsdfSample {
                pdf: (1.0 - m) * s.pdf,
                ..s
            });
        }
        wi = s.wi;
        pdf_n = s.pdf;
        f_n = s.weight * (s.pdf / wi.z.abs());
        (pdf_c, f_c) = if m != 0.0 {
            (conductor_pdf(c, wo, wi), conductor_eval(c, wo, wi))
        } else {
            (0.0, Vec3::ZERO)
        };
    }
    let pdf = m * pdf_c + (1.0 - m) * pdf_n;
    if !(pdf > 0.0) || !pdf.is_finite() {
        return None;
    }
    let f = m * f_c + (1.0 - m) * f_n;
    Some(BsdfSample {
        wi,
        weight: f * (wi.z.abs() / pdf),
        pdf,
        delta: false,
        eta: 1.0,
    })
}

/// The largest f32 below 1: a rescaled random number stays in [0, 1).
const ONE_MINUS_EPS: f32 = 1.0 - f32::EPSILON / 2.0;
