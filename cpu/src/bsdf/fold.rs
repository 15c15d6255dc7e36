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

use super::{BsdfAt, BsdfSample, LaneSample};

/// The geometric normal in the shading frame, on wo's side. (The
/// one-lane form of [`lanes::Fold`], which the wave's lanes run.)
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fold {
    n: Vec3,
}

impl Fold {
    /// `ng` the unit geometric normal and `wo` the outgoing direction,
    /// both in the shading frame.
    pub fn new(ng: Vec3, wo: Vec3) -> Fold {
        Fold {
            n: lanes::Fold::<f32>::new(ng.into(), wo.into()).n.into(),
        }
    }

    fn lanes(&self) -> lanes::Fold<f32> {
        lanes::Fold { n: self.n.into() }
    }

    /// `w` mirrored at the geometric tangent plane.
    pub fn mirror(&self, w: Vec3) -> Vec3 {
        self.lanes().mirror(w.into()).into()
    }

    /// Whether `w` leaves on wo's side of the geometric surface (where
    /// every folded direction lies).
    pub fn above(&self, w: Vec3) -> bool {
        self.lanes().above(w.into())
    }

    /// f_fold(wo, wi) |cos_s wi| and pdf_fold(wi) for `wi` above the
    /// geometric surface; zero below it.
    pub fn eval_pdf(&self, bsdf: &BsdfAt, wi: Vec3) -> (Vec3, f32) {
        if !self.above(wi) {
            return (Vec3::ZERO, 0.0);
        }
        let m = self.mirror(wi);
        let (f, pdf) = self.lanes().eval_pdf(
            wi.into(),
            (bsdf.eval(wi) * wi.z.abs()).into(),
            bsdf.pdf(wi),
            (bsdf.eval(m) * m.z.abs()).into(),
            bsdf.pdf(m),
        );
        (f.into(), pdf)
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
    pub fn reweigh(&self, bs: BsdfSample, partner_f: Vec3, partner_pdf: f32) -> Option<BsdfSample> {
        let s = LaneSample::<f32> {
            valid: true,
            wi: bs.wi.into(),
            weight: bs.weight.into(),
            pdf: bs.pdf,
            eta: bs.eta,
            delta: bs.delta,
        };
        self.lanes()
            .reweigh(s, partner_f.into(), partner_pdf)
            .single()
    }
}

/// The fold over any [`Lane`] type: the wave's lanes run it eight paths
/// at a time, [`Fold`] is its one-lane form.
pub mod lanes {
    use crate::bsdf::LaneSample;
    use crate::lanes::{Lane, V3};

    /// The geometric normal in the shading frame, on wo's side.
    #[derive(Clone, Copy, Debug)]
    pub struct Fold<L: Lane> {
        pub n: V3<L>,
    }

    impl<L: Lane> Fold<L> {
        /// `ng` the unit geometric normal and `wo` the outgoing
        /// direction, both in the shading frame.
        #[inline(always)]
        pub fn new(ng: V3<L>, wo: V3<L>) -> Self {
            Fold {
                n: V3::select(wo.dot(ng).lt(L::zero()), -ng, ng),
            }
        }

        /// `w` mirrored at the geometric tangent plane.
        #[inline(always)]
        pub fn mirror(&self, w: V3<L>) -> V3<L> {
            w - self.n.scale(L::splat(2.0) * w.dot(self.n))
        }

        /// Where `w` leaves on wo's side of the geometric surface.
        #[inline(always)]
        pub fn above(&self, w: V3<L>) -> L::Mask {
            w.dot(self.n).gt(L::zero())
        }

        /// f_fold |cos_s wi| and pdf_fold at `wi` from the BSDF's f |cos|
        /// and density at `wi` (`f`, `pdf`) and at its mirror image (`fm`,
        /// `pdf_m`); zero below the geometric surface.
        #[inline(always)]
        pub fn eval_pdf(&self, wi: V3<L>, f: V3<L>, pdf: L, fm: V3<L>, pdf_m: L) -> (V3<L>, L) {
            let above = self.above(wi);
            (
                V3::select(above, f + fm, V3::splat(glam::Vec3::ZERO)),
                L::select(above, pdf + pdf_m, L::zero()),
            )
        }

        /// [`super::Fold::reweigh`] in lanes: not valid where the folded
        /// density vanishes (or is not a number).
        #[inline(always)]
        pub fn reweigh(
            &self,
            mut bs: LaneSample<L>,
            partner_f: V3<L>,
            partner_pdf: L,
        ) -> LaneSample<L> {
            let a = bs.wi;
            if !bs.delta {
                let pdf = bs.pdf + partner_pdf;
                bs.valid = bs.valid & pdf.gt(L::zero());
                bs.weight = (bs.weight.scale(bs.pdf) + partner_f) / pdf;
                bs.pdf = pdf;
            }
            bs.wi = V3::select(self.above(a), a, self.mirror(a));
            bs
        }
    }
}
