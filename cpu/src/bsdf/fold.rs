//! A reflecting BSDF about a normal-mapped shading normal, folded at the
//! geometric surface so that it loses no energy.
//!
//! A normal map tilts the shading normal away from the geometric one, so
//! part of a lobe built about it points into the surface. Discarding that
//! part (the light-leak rule, `integrator` module notes) darkens every
//! bump: a white Lambertian tilted 35 degrees keeps only about 0.94 of the
//! light. Folding mirrors it instead: a direction `w` below the geometric
//! surface leaves as its mirror image `M w = w - 2 (w . ng) ng` above it.
//! The folded BSDF, over the upper hemisphere of `ng` (wo's side), is
//!
//! ```text
//!   f_fold(wo, wi) |cos_s wi| = f(wo, wi) |cos_s wi| + f(wo, M wi) |cos_s M wi|
//!   pdf_fold(wi)              = pdf(wi) + pdf(M wi)
//! ```
//!
//! (cos_s against the shading normal, as the integrator weighs every
//! lobe), so it reflects exactly what the lobe does over the whole sphere:
//! its albedo is the unmapped BSDF's at wo's angle to the mapped normal,
//! at most 1, and a white furnace stays white. Sampling is the BSDF's own
//! sample, mirrored when it lands below: its density is `pdf_fold`
//! exactly, so MIS and the chi-square tests hold as for any BSDF. This is
//! the "flip" of Schüssler et al. 2017 (sec. 3, "Microfacet-based Normal
//! Mapping for Robust Monte Carlo Path Tracing") applied to the whole lobe
//! and evaluated deterministically; it keeps the mapped lobe's shape
//! where it is above the surface, which their microfacet model does not.
//! Only BSDFs without transmission fold (a transmitted direction belongs
//! below the surface); the integrator applies it at normal-mapped hits.

use glam::{Vec2, Vec3};

use super::{BsdfAt, BsdfSample};

/// The geometric normal in the shading frame, on wo's side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fold {
    n: Vec3,
}

impl Fold {
    /// `ng` the unit geometric normal and `wo` the outgoing direction,
    /// both in the shading frame.
    pub fn new(ng: Vec3, wo: Vec3) -> Fold {
        Fold {
            n: if wo.dot(ng) < 0.0 { -ng } else { ng },
        }
    }

    /// `w` mirrored at the geometric tangent plane.
    pub fn mirror(&self, w: Vec3) -> Vec3 {
        w - 2.0 * w.dot(self.n) * self.n
    }

    /// Whether `w` leaves on wo's side of the geometric surface (where
    /// every folded direction lies).
    pub fn above(&self, w: Vec3) -> bool {
        w.dot(self.n) > 0.0
    }

    /// f_fold(wo, wi) |cos_s wi| and pdf_fold(wi) for `wi` above the
    /// geometric surface; zero below it.
    pub fn eval_pdf(&self, bsdf: &BsdfAt, wi: Vec3) -> (Vec3, f32) {
        if !self.above(wi) {
            return (Vec3::ZERO, 0.0);
        }
        let m = self.mirror(wi);
        let f = bsdf.eval(wi) * wi.z.abs() + bsdf.eval(m) * m.z.abs();
        (f, bsdf.pdf(wi) + bsdf.pdf(m))
    }

    /// The BSDF's sample, folded ([`Fold::reweigh`], its mirror image
    /// evaluated here).
    pub fn sample(&self, bsdf: &BsdfAt, uc: f32, u: Vec2) -> Option<BsdfSample> {
        let bs = bsdf.sample(uc, u)?;
        if bs.delta {
            return self.reweigh(bs, Vec3::ZERO, 0.0);
        }
        let r = self.mirror(bs.wi);
        self.reweigh(bs, bsdf.eval(r) * r.z.abs(), bsdf.pdf(r))
    }

    /// A BSDF sample folded: mirrored above the surface where it falls
    /// below; a non-delta one weighed by the folded f and pdf, from the
    /// sampled direction's f |cos| (its weight times its pdf) and its
    /// mirror image's, `partner_f` and `partner_pdf`. A delta lobe keeps its
    /// weight: its mirror image carries the same energy. None where the
    /// folded pdf vanishes. (The GPU kernel evaluates the mirror image in
    /// its light sample's loop, so that it holds one copy of the BSDFs.)
    pub fn reweigh(
        &self,
        mut bs: BsdfSample,
        partner_f: Vec3,
        partner_pdf: f32,
    ) -> Option<BsdfSample> {
        let a = bs.wi;
        if !bs.delta {
            let pdf = bs.pdf + partner_pdf;
            if pdf.is_nan() || pdf <= 0.0 {
                return None;
            }
            bs.weight = (bs.weight * bs.pdf + partner_f) / pdf;
            bs.pdf = pdf;
        }
        if !self.above(a) {
            bs.wi = self.mirror(a);
        }
        Some(bs)
    }
}
