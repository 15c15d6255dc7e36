//! BSDFs in a local shading frame (normal = +z, `cos theta = w.z`).
//!
//! Conventions (pbrt-v4): `wo` points toward the viewer, `wi` toward the
//! light, both unit vectors in the local frame, both pointing away from the
//! surface. Radiance transport: transmission carries the (eta_i/eta_t)^2
//! factor, so the BTDF obeys generalised reciprocity f(wo,wi)/eta_i^2 =
//! f(wi,wo)/eta_o^2 rather than plain symmetry.

// `!(x > 0.0)` is deliberate throughout: it is also true for NaN, and it
// reads the same as the GLSL twin in shaders/bsdf.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::lanes::{Lane, V3};
use glam::{Vec2, Vec3};

pub mod clearcoat;
pub mod coated;
pub mod conductor;
pub mod dielectric;
pub mod diffuse;
pub mod fold;
pub mod fresnel;
pub mod metallic;
pub mod microfacet;
// Generated numbers, printed with every digit the generator computed.
#[allow(clippy::excessive_precision)]
pub mod ms_tables;
pub mod multiscatter;
pub mod plastic;
pub mod roughplastic;
mod tables;
pub mod thin;
pub mod thinwall;
pub mod warp;

use coated::{
    CoatAtWo, CoatParams, coat_at_wo, coated_eval, coated_eval_at, coated_pdf, coated_pdf_at,
    coated_sample, coated_sample_at,
};
use conductor::{conductor_eval, conductor_pdf, conductor_sample};
use dielectric::{dielectric_eval, dielectric_is_smooth, dielectric_pdf, dielectric_sample};
use diffuse::{diffuse_eval, diffuse_pdf, diffuse_sample};
use metallic::{
    metallic_coat_at_wo, metallic_eval, metallic_eval_at, metallic_pdf, metallic_pdf_at,
    metallic_sample, metallic_sample_at,
};
use plastic::{PlasticParams, plastic_eval, plastic_pdf, plastic_sample};
use roughplastic::{RoughPlasticParams, roughplastic_eval, roughplastic_pdf, roughplastic_sample};
use thin::thin_sample;

/// Smith shadowing-masking form for rough models.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Shadowing {
    /// Height-correlated Smith G2 (Heitz 2014): the default.
    #[default]
    Correlated,
    /// G1(wo) * G1(wi): what Mitsuba 3 uses.
    Separable,
}

/// GGX alphas below this are rendered as the smooth (delta) counterpart
/// (pbrt-v4's choice; alpha = 0.01 is still rough).
pub use crate::abi::SMOOTH_ALPHA_THRESHOLD;

/// A rough dielectric whose relative IOR is within this of 1 is rendered as
/// the smooth interface. The generalised half vector eta wi + wo of a
/// transmitted pair is only |eta - 1| long, so f32 rounding of the
/// directions moves the microfacet normal by ~6e-8 / |eta - 1|: against a
/// lobe alpha wide, sample and pdf disagree by 6e-8 / (alpha |eta - 1|),
/// over 1e-3 for alpha = 0.01 once |eta - 1| < 6e-3 (`glint stability`
/// shows it at 1e-3). The transmission lobe is then at most |eta - 1| wide
/// (alpha <= 1): as narrow as what the alpha threshold already treats as a
/// delta. IOR exactly 1 gave NaN in Unity's and Blender's GGX BTDFs, and
/// Cycles' sampled pdf disagreed with its evaluated pdf near equal IORs.
pub use crate::abi::ETA_SMOOTH_THRESHOLD;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Roughness {
    /// GGX alpha along the shading frame's s axis (the surface tangent).
    pub alpha_u: f32,
    /// GGX alpha along t.
    pub alpha_v: f32,
    pub shadowing: Shadowing,
    /// Energy-compensated GGX (`multiscatter`, default false): Kulla &
    /// Conty 2017 for conductors, Turquin 2019 for dielectrics (see
    /// `multiscatter.rs`).
    pub multiscatter: bool,
}

impl Roughness {
    pub const SMOOTH: Self = Self {
        alpha_u: 0.0,
        alpha_v: 0.0,
        shadowing: Shadowing::Correlated,
        multiscatter: false,
    };
    pub fn is_smooth(&self) -> bool {
        self.alpha_u.max(self.alpha_v) < SMOOTH_ALPHA_THRESHOLD
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConductorParams {
    /// Real part of the complex index of refraction, per RGB channel
    /// (relative to the outside medium).
    pub eta: Vec3,
    /// Imaginary part (extinction coefficient).
    pub k: Vec3,
    /// Mitsuba's `specular_reflectance`: a multiplier on the Fresnel term.
    pub specular_reflectance: Vec3,
    pub roughness: Roughness,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bsdf {
    /// Lambertian, f = reflectance / pi. Two-sided.
    Diffuse { reflectance: Vec3 },
    /// Smooth (delta) or GGX rough conductor. Two-sided.
    Conductor(ConductorParams),
    /// Smooth or GGX rough dielectric; `eta` = int_ior / ext_ior, the
    /// outside being the side the geometric normal points to; `tint`
    /// Mitsuba's `specular_reflectance` and `specular_transmittance`.
    Dielectric {
        eta: f32,
        roughness: Roughness,
        tint: Tint,
    },
    /// Mitsuba 3's smooth `plastic` (`plastic.rs`). Two-sided.
    Plastic(PlasticParams),
    /// Mitsuba 3's `roughplastic` (`roughplastic.rs`). Two-sided.
    RoughPlastic(RoughPlasticParams),
    /// Mitsuba 3's `thindielectric`: reflection or straight-through
    /// transmission of a thin slab, both Dirac deltas (`thin.rs`).
    ThinDielectric {
        /// int_ior / ext_ior.
        eta: f32,
        /// Its `specular_reflectance` and `specular_transmittance`.
        tint: Tint,
    },
    /// The glTF non-metal: a GGX dielectric coat over a Lambertian `base`,
    /// energy conserving by albedo scaling (`coated.rs`). Two-sided.
    Coated {
        base: Vec3,
        coat: CoatParams,
        roughness: Roughness,
    },
    /// glTF metallic-roughness with 0 < metallic < 1 (and every textured
    /// metallic-roughness material): the conductor with probability
    /// `metallic`, the [`Bsdf::Coated`] non-metal of `base` and `coat` with
    /// the conductor's roughness with 1 - metallic (Mitsuba 3's
    /// `blendbsdf`). Two-sided.
    Metallic {
        metallic: f32,
        base: Vec3,
        conductor: ConductorParams,
        coat: CoatParams,
    },
}

/// The result of [`Bsdf::sample`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// Sampled incident direction (local frame).
    pub wi: Vec3,
    /// f(wo, wi) |cos theta_i| / pdf; for delta lobes the lobe's throughput.
    pub weight: Vec3,
    /// Solid-angle pdf; for delta lobes the discrete probability of the lobe.
    pub pdf: f32,
    /// The sampled lobe is a Dirac delta (no MIS, no light sampling).
    pub delta: bool,
    /// Relative IOR eta_t/eta_i crossed by a transmission, 1 for reflection.
    pub eta: f32,
}

/// A sample of the lane-generic BSDFs (`bsdf::*::lanes`): a
/// [`BsdfSample`] per lane where `valid` holds; `delta` is the same in
/// every lane (a smooth or a rough model).
#[derive(Clone, Copy, Debug)]
pub struct LaneSample<L: Lane> {
    pub valid: L::Mask,
    pub wi: V3<L>,
    pub weight: V3<L>,
    pub pdf: L,
    pub eta: L,
    pub delta: bool,
}

impl LaneSample<f32> {
    /// The one lane's sample.
    #[inline(always)]
    pub fn single(self) -> Option<BsdfSample> {
        self.valid.then(|| BsdfSample {
            wi: self.wi.into(),
            weight: self.weight.into(),
            pdf: self.pdf,
            delta: self.delta,
            eta: self.eta,
        })
    }
}

/// Mitsuba 3's `specular_reflectance` and `specular_transmittance` of a
/// dielectric: factors on the reflected and on the transmitted part of
/// its value (and of a sample's weight), its sampling unchanged, as
/// Mitsuba's `dielectric`, `roughdielectric` and `thindielectric` apply
/// them. 1 (none) by
/// default; not physical unless 1, but Mitsuba scenes use them (tinted
/// glass without a medium).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tint {
    pub reflect: Vec3,
    pub transmit: Vec3,
}

impl Tint {
    pub const NONE: Tint = Tint {
        reflect: Vec3::ONE,
        transmit: Vec3::ONE,
    };

    /// The factor for the pair (wo, wi): reflection where both lie on
    /// one side of the surface.
    #[inline]
    pub fn between(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if wo.z * wi.z > 0.0 {
            self.reflect
        } else {
            self.transmit
        }
    }
}

impl Bsdf {
    /// f(wo, wi), without the cosine; zero for delta lobes.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        match self {
            Bsdf::Diffuse { reflectance } => diffuse_eval(*reflectance, wo, wi),
            Bsdf::Conductor(c) => conductor_eval(c, wo, wi),
            Bsdf::Dielectric {
                eta,
                roughness,
                tint,
            } => dielectric_eval(*eta, roughness, wo, wi) * tint.between(wo, wi),
            Bsdf::Plastic(p) => plastic_eval(p, wo, wi),
            Bsdf::RoughPlastic(p) => roughplastic_eval(p, wo, wi),
            Bsdf::ThinDielectric { .. } => Vec3::ZERO,
            Bsdf::Coated {
                base,
                coat,
                roughness,
            } => with_clearcoat_eval(coat, wo, wi, coated_eval(*base, coat, roughness, wo, wi)),
            Bsdf::Metallic {
                metallic,
                base,
                conductor,
                coat,
            } => with_clearcoat_eval(
                coat,
                wo,
                wi,
                metallic_eval(*metallic, *base, conductor, coat, wo, wi),
            ),
        }
    }

    /// Solid-angle density of [`Bsdf::sample`] producing `wi`; zero for delta lobes.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Bsdf::Diffuse { .. } => diffuse_pdf(wo, wi),
            Bsdf::Conductor(c) => conductor_pdf(c, wo, wi),
            Bsdf::Dielectric { eta, roughness, .. } => dielectric_pdf(*eta, roughness, wo, wi),
            Bsdf::Plastic(p) => plastic_pdf(p, wo, wi),
            Bsdf::RoughPlastic(p) => roughplastic_pdf(p, wo, wi),
            Bsdf::ThinDielectric { .. } => 0.0,
            Bsdf::Coated {
                base,
                coat,
                roughness,
            } => with_clearcoat_pdf(coat, wo, wi, coated_pdf(*base, coat, roughness, wo, wi)),
            Bsdf::Metallic {
                metallic,
                base,
                conductor,
                coat,
            } => with_clearcoat_pdf(
                coat,
                wo,
                wi,
                metallic_pdf(*metallic, *base, conductor, coat, wo, wi),
            ),
        }
    }

    /// Sample wi given wo. `uc` picks the lobe (reflection vs transmission,
    /// conductor vs diffuse), `u` samples the direction.
    pub fn sample(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<BsdfSample> {
        match self {
            Bsdf::Diffuse { reflectance } => diffuse_sample(*reflectance, wo, u),
            Bsdf::Conductor(c) => conductor_sample(c, wo, u),
            Bsdf::Dielectric {
                eta,
                roughness,
                tint,
            } => dielectric_sample(*eta, roughness, wo, uc, u).map(|mut s| {
                s.weight *= tint.between(wo, s.wi);
                s
            }),
            Bsdf::Plastic(p) => plastic_sample(p, wo, uc, u),
            Bsdf::RoughPlastic(p) => roughplastic_sample(p, wo, uc, u),
            Bsdf::ThinDielectric { eta, tint } => {
                thin_sample(*eta, tint.reflect, tint.transmit, wo, uc, u)
            }
            Bsdf::Coated { coat, .. } | Bsdf::Metallic { coat, .. } => match coat.clearcoat() {
                None => self.sample_under_clearcoat(wo, uc, u),
                Some(cc) => clearcoat::clearcoat_sample(
                    &cc,
                    wo,
                    uc,
                    u,
                    &|uc| self.sample_under_clearcoat(wo, uc, u),
                    &|wi| self.eval_under_clearcoat(wo, wi),
                    &|wi| self.pdf_under_clearcoat(wo, wi),
                ),
            },
        }
    }

    /// The glTF material under its clear coat (the coat left out).
    fn sample_under_clearcoat(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<BsdfSample> {
        match self {
            Bsdf::Coated {
                base,
                coat,
                roughness,
            } => coated_sample(*base, coat, roughness, wo, uc, u),
            Bsdf::Metallic {
                metallic,
                base,
                conductor,
                coat,
            } => metallic_sample(*metallic, *base, conductor, coat, wo, uc, u),
            _ => self.sample(wo, uc, u),
        }
    }

    fn eval_under_clearcoat(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        match self {
            Bsdf::Coated {
                base,
                coat,
                roughness,
            } => coated_eval(*base, coat, roughness, wo, wi),
            Bsdf::Metallic {
                metallic,
                base,
                conductor,
                coat,
            } => metallic_eval(*metallic, *base, conductor, coat, wo, wi),
            _ => self.eval(wo, wi),
        }
    }

    fn pdf_under_clearcoat(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Bsdf::Coated {
                base,
                coat,
                roughness,
            } => coated_pdf(*base, coat, roughness, wo, wi),
            Bsdf::Metallic {
                metallic,
                base,
                conductor,
                coat,
            } => metallic_pdf(*metallic, *base, conductor, coat, wo, wi),
            _ => self.pdf(wo, wi),
        }
    }

    /// Every lobe is a Dirac delta: the integrator skips light sampling.
    pub fn is_delta(&self) -> bool {
        match self {
            Bsdf::Diffuse { .. } => false,
            Bsdf::Conductor(c) => c.roughness.is_smooth(),
            Bsdf::Dielectric { eta, roughness, .. } => dielectric_is_smooth(*eta, roughness),
            // The Lambertian base is never a delta: only a smooth, fully
            // transmissive (thin-walled) non-metal is.
            Bsdf::Coated {
                coat, roughness, ..
            } => roughness.is_smooth() && coat.transmission >= 1.0 && clearcoat_is_smooth(coat),
            Bsdf::Plastic(_) | Bsdf::RoughPlastic(_) => false,
            Bsdf::ThinDielectric { .. } => true,
            Bsdf::Metallic {
                metallic,
                conductor,
                coat,
                ..
            } => conductor.roughness.is_smooth() && (*metallic >= 1.0 || coat.transmission >= 1.0),
        }
    }

    /// Whether some direction pair with wo.z and wi.z of opposite signs has f > 0.
    pub fn has_transmission(&self) -> bool {
        match self {
            Bsdf::Dielectric { .. } | Bsdf::ThinDielectric { .. } => true,
            Bsdf::Coated { coat, .. } | Bsdf::Metallic { coat, .. } => coat.transmission > 0.0,
            _ => false,
        }
    }
}

/// A BSDF seen from one outgoing direction `wo`: what its eval, pdf and
/// sample share at `wo` (the coat's albedo table lookups) found once. A
/// path vertex asks its BSDF all three with the same wo; the answers are
/// [`Bsdf::eval`]'s, [`Bsdf::pdf`]'s and [`Bsdf::sample`]'s bit for bit.
#[derive(Clone, Copy, Debug)]
pub struct BsdfAt<'a> {
    bsdf: &'a Bsdf,
    wo: Vec3,
    /// The coat at wo, for the glTF models without a clear coat (a clear
    /// coat's layering evaluates the model under it at other directions).
    coat: Option<CoatAtWo>,
}

impl Bsdf {
    /// This BSDF seen from `wo`.
    #[inline]
    pub fn at(&self, wo: Vec3) -> BsdfAt<'_> {
        let coat = match self {
            Bsdf::Coated {
                base,
                coat,
                roughness,
            } if coat.clearcoat <= 0.0 => Some(coat_at_wo(*base, coat, roughness, wo)),
            Bsdf::Metallic {
                metallic,
                base,
                conductor,
                coat,
            } if coat.clearcoat <= 0.0 => {
                Some(metallic_coat_at_wo(*metallic, *base, conductor, coat, wo))
            }
            _ => None,
        };
        BsdfAt {
            bsdf: self,
            wo,
            coat,
        }
    }
}

impl<'a> BsdfAt<'a> {
    /// The BSDF.
    pub fn bsdf(&self) -> &'a Bsdf {
        self.bsdf
    }

    /// [`Bsdf::eval`] at (wo, wi).
    /// (Lambertian inline: the most common case pays no call.)
    #[inline]
    pub fn eval(&self, wi: Vec3) -> Vec3 {
        if let Bsdf::Diffuse { reflectance } = self.bsdf {
            return diffuse_eval(*reflectance, self.wo, wi);
        }
        self.eval_any(wi)
    }

    /// [`Self::eval`] for every model.
    fn eval_any(&self, wi: Vec3) -> Vec3 {
        let wo = self.wo;
        match (self.bsdf, &self.coat) {
            (
                Bsdf::Coated {
                    base,
                    coat,
                    roughness,
                },
                Some(w),
            ) => coated_eval_at(*base, coat, roughness, w, wo, wi),
            (
                Bsdf::Metallic {
                    metallic,
                    base,
                    conductor,
                    coat,
                },
                Some(w),
            ) => metallic_eval_at(*metallic, *base, conductor, coat, w, wo, wi),
            (bsdf, _) => bsdf.eval(wo, wi),
        }
    }

    /// [`Bsdf::pdf`] at (wo, wi).
    /// (Lambertian inline: the most common case pays no call.)
    #[inline]
    pub fn pdf(&self, wi: Vec3) -> f32 {
        if let Bsdf::Diffuse { .. } = self.bsdf {
            return diffuse_pdf(self.wo, wi);
        }
        self.pdf_any(wi)
    }

    /// [`Self::pdf`] for every model.
    fn pdf_any(&self, wi: Vec3) -> f32 {
        let wo = self.wo;
        match (self.bsdf, &self.coat) {
            (
                Bsdf::Coated {
                    coat, roughness, ..
                },
                Some(w),
            ) => coated_pdf_at(coat, roughness, w, wo, wi),
            (
                Bsdf::Metallic {
                    metallic,
                    conductor,
                    coat,
                    ..
                },
                Some(w),
            ) => metallic_pdf_at(*metallic, conductor, coat, w, wo, wi),
            (bsdf, _) => bsdf.pdf(wo, wi),
        }
    }

    /// [`Bsdf::sample`] at wo.
    /// (Lambertian inline: the most common case pays no call.)
    #[inline]
    pub fn sample(&self, uc: f32, u: Vec2) -> Option<BsdfSample> {
        if let Bsdf::Diffuse { reflectance } = self.bsdf {
            return diffuse_sample(*reflectance, self.wo, u);
        }
        self.sample_any(uc, u)
    }

    /// [`Self::sample`] for every model.
    fn sample_any(&self, uc: f32, u: Vec2) -> Option<BsdfSample> {
        let wo = self.wo;
        match (self.bsdf, &self.coat) {
            (
                Bsdf::Coated {
                    base,
                    coat,
                    roughness,
                },
                Some(w),
            ) => coated_sample_at(*base, coat, roughness, w, wo, uc, u),
            (
                Bsdf::Metallic {
                    metallic,
                    base,
                    conductor,
                    coat,
                },
                Some(w),
            ) => metallic_sample_at(*metallic, *base, conductor, coat, w, wo, uc, u),
            (bsdf, _) => bsdf.sample(wo, uc, u),
        }
    }
}

/// No clear coat, or a smooth one (a delta lobe).
fn clearcoat_is_smooth(coat: &CoatParams) -> bool {
    coat.clearcoat <= 0.0 || coat.clearcoat_alpha < SMOOTH_ALPHA_THRESHOLD
}

fn with_clearcoat_eval(coat: &CoatParams, wo: Vec3, wi: Vec3, inner: Vec3) -> Vec3 {
    match coat.clearcoat() {
        Some(cc) => clearcoat::clearcoat_eval(&cc, inner, wo, wi),
        None => inner,
    }
}

fn with_clearcoat_pdf(coat: &CoatParams, wo: Vec3, wi: Vec3, inner: f32) -> f32 {
    match coat.clearcoat() {
        Some(cc) => clearcoat::clearcoat_pdf(&cc, inner, wo, wi),
        None => inner,
    }
}

/// Named indices of refraction (the contract's table, at least: vacuum, air,
/// water ice / ice, water, bk7 / crown glass, diamond). Case-insensitive.
pub fn named_ior(name: &str) -> Option<f32> {
    tables::ior(name)
}

/// Named metals' RGB complex IOR (eta, k), at least Au, Ag, Cu, Al, Cr;
/// each value and its source documented where the table is written.
/// (Table and sources: `cpu/src/bsdf/tables.rs`.)
pub fn named_metal(name: &str) -> Option<(Vec3, Vec3)> {
    tables::metal(name)
}
