//! A wave's vertices shaded eight paths per instruction (issue 24 item
//! 3): where several of a wave's live paths stand on surfaces of one
//! model the lanes know ([`WideBsdf`]: the Lambertian, the glTF coated
//! non-metal with a rough, opaque coat, alone or as the metallic blend at
//! metallic 0, the rough conductor, alone or as the blend at metallic 1,
//! and the rough dielectric without
//! energy compensation; a textured material's model found per hit from
//! its textured BSDF; a normal-mapped hit's frame found lane by lane as
//! the scalar vertex finds it, and its fold ([`crate::bsdf::fold`]) run
//! in lanes, [`NormalMapped`]), their vertices'
//! arithmetic runs in lanes: the geometric and shading normals, the
//! frame, the emitter light samples (the punctual lights' and the
//! background's are drawn lane by lane), the BSDF's value, density and
//! sample (what the three share at wo found once), the MIS weight, the
//! next direction and the light-leak rule, the shadow rays and the next
//! rays with their offset origins. It runs the lane-generic functions
//! whose one-lane instantiations the scalar [`PathTracer::vertex`] calls
//! (the ray offset's scalar form keeps its branches, the same bits); then
//! the shadow rays' traversal and Russian roulette run path by path as
//! [`PathTracer::vertex`] runs them. Every path gets the same numbers, so
//! the same bits, as the scalar vertex gives it (`cpu/tests/lanes.rs`
//! renders every bundled scene both ways).

use glam::Vec3;

use super::{Arrival, PathState, PathTracer, SurfaceFrame, offset_origin_lanes, shadow_ray_lanes};
use crate::abi::ONE_MINUS_EPS;
use crate::bsdf::coated::{self, Coat};
use crate::bsdf::conductor::{self, RoughConductor};
use crate::bsdf::dielectric::{self, RoughDielectric, dielectric_is_smooth};
use crate::bsdf::diffuse::lanes::{diffuse_eval, diffuse_pdf, diffuse_sample};
use crate::bsdf::fold::lanes::Fold;
use crate::bsdf::{Bsdf, LaneSample, Shadowing, Tint};
use crate::bvh::Ray;
use crate::film::Mis;
use crate::frame::lanes::Frame;
use crate::lanes::{F32x8, Lane, Mask8, V2, V3, live_lanes};
use crate::lights::{EmitterSamples, LightSample, Lights, background_direction_frame};
use crate::sampling::lanes::mis_light;
use crate::scene::{Scene, TRI_NORMALS, TRI_SHADING_SHIFT, TRI_TANGENTS};
use crate::sobol::lanes::BounceLanes;
use crate::texture::textured_bsdf;

/// The fewest eligible paths for which a wave shades its vertices of one
/// model in lanes (measured: docs/benchmarks.md).
pub const WIDE_MIN: u32 = 3;

/// Whether this build's lanes are AVX2 instructions (`lanes.rs`'s
/// `ymm_or!`: a build for the machine's CPU, scripts/build.sh): only then
/// do the wave's vertices in lanes pay. In a baseline build LLVM leaves
/// two to four instructions per lane operation in a function this large,
/// and the vertices cost 1-9% more than one at a time (docs/benchmarks.md).
pub const LANES_IN_REGISTERS: bool = cfg!(all(target_arch = "x86_64", target_feature = "avx2"));

/// Eight lanes of `f(lane's input)`.
macro_rules! gather {
    ($inp:expr, |$d:ident| $e:expr) => {
        F32x8(crate::lanes::build8(|l| {
            let $d = &$inp[l];
            $e
        }))
    };
}

macro_rules! gather3 {
    ($inp:expr, |$d:ident| $e:expr) => {
        V3::new(
            gather!($inp, |$d| $e.x),
            gather!($inp, |$d| $e.y),
            gather!($inp, |$d| $e.z),
        )
    };
}

/// A BSDF whose vertices a wave shades in lanes: its parameters, read
/// lane by lane from the material, then what its value, density and
/// sample share at wo, and the three, eight lanes per instruction. Each
/// is the lane-generic function whose one-lane instantiation the scalar
/// [`crate::bsdf::BsdfAt`] runs for the material, so the lanes give the
/// scalar bits (`cpu/tests/lanes.rs`).
pub(super) trait WideBsdf {
    /// One lane's parameters.
    type Params: Copy;
    /// Whether it transmits ([`Bsdf::has_transmission`]).
    const TRANSMITS: bool = false;
    /// Whether some lanes are normal-mapped ([`NormalMapped`]): their
    /// frames come from [`MappedFrames`], and they may fold.
    const MAPPED: bool = false;
    /// The lanes' BSDF at wo.
    type At;
    /// The material's parameters where the lanes shade it.
    fn params(bsdf: &Bsdf) -> Option<Self::Params>;
    /// The lanes' BSDF seen from `wo` (local).
    fn at(p: &[Self::Params; 8], wo: V3<F32x8>) -> Self::At;
    fn eval(at: &Self::At, wo: V3<F32x8>, wi: V3<F32x8>) -> V3<F32x8>;
    fn pdf(at: &Self::At, wo: V3<F32x8>, wi: V3<F32x8>) -> F32x8;
    fn sample(at: &Self::At, wo: V3<F32x8>, uc: F32x8, u: V2<F32x8>) -> LaneSample<F32x8>;
}

/// Model `M` where some of the lanes are normal-mapped: the same BSDF,
/// the vertex's code for the mapped frames and the fold compiled in (a
/// wave without mapped lanes runs `M` itself, which has none of it).
pub(super) struct NormalMapped<M>(std::marker::PhantomData<M>);

impl<M: WideBsdf> WideBsdf for NormalMapped<M> {
    type Params = M::Params;
    const TRANSMITS: bool = M::TRANSMITS;
    const MAPPED: bool = true;
    type At = M::At;

    #[inline(always)]
    fn params(bsdf: &Bsdf) -> Option<M::Params> {
        M::params(bsdf)
    }

    #[inline(always)]
    fn at(p: &[M::Params; 8], wo: V3<F32x8>) -> M::At {
        M::at(p, wo)
    }

    #[inline(always)]
    fn eval(at: &M::At, wo: V3<F32x8>, wi: V3<F32x8>) -> V3<F32x8> {
        M::eval(at, wo, wi)
    }

    #[inline(always)]
    fn pdf(at: &M::At, wo: V3<F32x8>, wi: V3<F32x8>) -> F32x8 {
        M::pdf(at, wo, wi)
    }

    #[inline(always)]
    fn sample(at: &M::At, wo: V3<F32x8>, uc: F32x8, u: V2<F32x8>) -> LaneSample<F32x8> {
        M::sample(at, wo, uc, u)
    }
}

/// The Lambertian ([`Bsdf::Diffuse`]).
pub(super) struct Lambertian;

impl WideBsdf for Lambertian {
    type Params = Vec3;
    type At = V3<F32x8>;

    #[inline(always)]
    fn params(bsdf: &Bsdf) -> Option<Vec3> {
        match bsdf {
            Bsdf::Diffuse { reflectance } => Some(*reflectance),
            _ => None,
        }
    }

    #[inline(always)]
    fn at(p: &[Vec3; 8], _wo: V3<F32x8>) -> V3<F32x8> {
        gather3!(p, |rho| rho)
    }

    #[inline(always)]
    fn eval(rho: &V3<F32x8>, wo: V3<F32x8>, wi: V3<F32x8>) -> V3<F32x8> {
        diffuse_eval(*rho, wo, wi)
    }

    #[inline(always)]
    fn pdf(_rho: &V3<F32x8>, wo: V3<F32x8>, wi: V3<F32x8>) -> F32x8 {
        diffuse_pdf(wo, wi)
    }

    #[inline(always)]
    fn sample(rho: &V3<F32x8>, wo: V3<F32x8>, _uc: F32x8, u: V2<F32x8>) -> LaneSample<F32x8> {
        diffuse_sample(*rho, wo, u)
    }
}

/// The glTF coated non-metal ([`Bsdf::Coated`]) whose coat is rough and
/// opaque, without a clear coat: [`coated::lanes`]' opaque part, which
/// [`crate::bsdf::BsdfAt`] runs for it one lane at a time. (A smooth
/// coat's mirror is a delta lobe that the lanes do not sample.)
pub(super) struct CoatedOpaque;

impl WideBsdf for CoatedOpaque {
    type Params = Coat<f32>;
    type At = (Coat<F32x8>, coated::lanes::AtWo<F32x8>);

    #[inline(always)]
    fn params(bsdf: &Bsdf) -> Option<Coat<f32>> {
        match bsdf {
            Bsdf::Coated {
                base,
                coat,
                roughness,
            } if coat.clearcoat <= 0.0 && coat.transmission <= 0.0 && !roughness.is_smooth() => {
                Some(Coat::of(*base, coat, roughness))
            }
            _ => None,
        }
    }

    #[inline(always)]
    fn at(p: &[Coat<f32>; 8], wo: V3<F32x8>) -> Self::At {
        let c = Coat {
            base: gather3!(p, |c| c.base),
            specular: gather3!(p, |c| c.specular),
            eta: gather!(p, |c| c.eta),
            ax: gather!(p, |c| c.ax),
            ay: gather!(p, |c| c.ay),
            smooth: Mask8::from_bits((0..8).fold(0, |b, l| b | u8::from(p[l].smooth) << l)),
        };
        let w = coated::lanes::at_wo(&c, wo.z.abs());
        (c, w)
    }

    #[inline(always)]
    fn eval((c, w): &Self::At, wo: V3<F32x8>, wi: V3<F32x8>) -> V3<F32x8> {
        coated::lanes::opaque_eval(c, w, wo, wi)
    }

    #[inline(always)]
    fn pdf((c, w): &Self::At, wo: V3<F32x8>, wi: V3<F32x8>) -> F32x8 {
        coated::lanes::opaque_pdf(c, w, wo, wi)
    }

    #[inline(always)]
    fn sample((c, w): &Self::At, wo: V3<F32x8>, uc: F32x8, u: V2<F32x8>) -> LaneSample<F32x8> {
        coated::lanes::opaque_sample(c, w, wo, uc, u)
    }
}

/// The rough conductor ([`Bsdf::Conductor`]) with the correlated Smith
/// term and without energy compensation: [`conductor::lanes`]'
/// single-scattering lobe, which `conductor_eval`, `conductor_pdf` and
/// `conductor_sample` run for it one lane at a time.
pub(super) struct RoughMetal;

impl WideBsdf for RoughMetal {
    type Params = RoughConductor<f32>;
    type At = RoughConductor<F32x8>;

    #[inline(always)]
    fn params(bsdf: &Bsdf) -> Option<RoughConductor<f32>> {
        match bsdf {
            Bsdf::Conductor(c)
                if !c.roughness.is_smooth()
                    && !c.roughness.multiscatter
                    && c.roughness.shadowing == Shadowing::Correlated =>
            {
                Some(RoughConductor::of(c))
            }
            _ => None,
        }
    }

    #[inline(always)]
    fn at(p: &[RoughConductor<f32>; 8], _wo: V3<F32x8>) -> RoughConductor<F32x8> {
        RoughConductor {
            eta: gather3!(p, |c| c.eta),
            k: gather3!(p, |c| c.k),
            specular_reflectance: gather3!(p, |c| c.specular_reflectance),
            ax: gather!(p, |c| c.ax),
            ay: gather!(p, |c| c.ay),
            separable: false,
        }
    }

    #[inline(always)]
    fn eval(c: &RoughConductor<F32x8>, wo: V3<F32x8>, wi: V3<F32x8>) -> V3<F32x8> {
        conductor::lanes::rough_eval(c, wo, wi)
    }

    #[inline(always)]
    fn pdf(c: &RoughConductor<F32x8>, wo: V3<F32x8>, wi: V3<F32x8>) -> F32x8 {
        conductor::lanes::rough_pdf(c, wo, wi)
    }

    #[inline(always)]
    fn sample(
        c: &RoughConductor<F32x8>,
        wo: V3<F32x8>,
        _uc: F32x8,
        u: V2<F32x8>,
    ) -> LaneSample<F32x8> {
        conductor::lanes::rough_sample(c, wo, u)
    }
}

/// The rough dielectric ([`Bsdf::Dielectric`]) with the correlated Smith
/// term, without energy compensation or tints: [`dielectric::lanes`]'
/// model, which `dielectric_eval`, `dielectric_pdf` and
/// `dielectric_sample` run for it one lane at a time (the sample with
/// its selects as branches, the same bits).
pub(super) struct RoughGlass;

impl WideBsdf for RoughGlass {
    type Params = RoughDielectric<f32>;
    const TRANSMITS: bool = true;
    type At = RoughDielectric<F32x8>;

    #[inline(always)]
    fn params(bsdf: &Bsdf) -> Option<RoughDielectric<f32>> {
        match bsdf {
            Bsdf::Dielectric {
                eta,
                roughness,
                tint,
            } if !dielectric_is_smooth(*eta, roughness)
                && !roughness.multiscatter
                && roughness.shadowing == Shadowing::Correlated
                && *tint == Tint::NONE =>
            {
                Some(RoughDielectric::of(*eta, roughness))
            }
            _ => None,
        }
    }

    #[inline(always)]
    fn at(p: &[RoughDielectric<f32>; 8], _wo: V3<F32x8>) -> RoughDielectric<F32x8> {
        RoughDielectric {
            eta: gather!(p, |c| c.eta),
            ax: gather!(p, |c| c.ax),
            ay: gather!(p, |c| c.ay),
            separable: false,
        }
    }

    #[inline(always)]
    fn eval(c: &RoughDielectric<F32x8>, wo: V3<F32x8>, wi: V3<F32x8>) -> V3<F32x8> {
        let f = dielectric::lanes::rough_eval(c, wo, wi);
        V3::new(f, f, f)
    }

    #[inline(always)]
    fn pdf(c: &RoughDielectric<F32x8>, wo: V3<F32x8>, wi: V3<F32x8>) -> F32x8 {
        dielectric::lanes::rough_pdf(c, wo, wi)
    }

    #[inline(always)]
    fn sample(
        c: &RoughDielectric<F32x8>,
        wo: V3<F32x8>,
        uc: F32x8,
        u: V2<F32x8>,
    ) -> LaneSample<F32x8> {
        dielectric::lanes::rough_sample(c, wo, uc, u)
    }
}

/// The glTF metallic-roughness blend ([`Bsdf::Metallic`]) at metallic 0
/// (every texel of a textured non-metal), its non-metal as
/// [`CoatedOpaque`]'s: `metallic_eval_at`, `metallic_pdf_at` and
/// `metallic_sample_at` with the metal's weight zero, their sums and the
/// sample's weight recomputed from f and the density as they do it.
pub(super) struct NonMetalBlend;

impl WideBsdf for NonMetalBlend {
    type Params = Coat<f32>;
    type At = <CoatedOpaque as WideBsdf>::At;

    #[inline(always)]
    fn params(bsdf: &Bsdf) -> Option<Coat<f32>> {
        match bsdf {
            Bsdf::Metallic {
                metallic,
                base,
                conductor,
                coat,
            } if *metallic == 0.0 => CoatedOpaque::params(&Bsdf::Coated {
                base: *base,
                coat: *coat,
                roughness: conductor.roughness,
            }),
            _ => None,
        }
    }

    #[inline(always)]
    fn at(p: &[Coat<f32>; 8], wo: V3<F32x8>) -> Self::At {
        CoatedOpaque::at(p, wo)
    }

    // The blend m f_metal + (1 - m) f at m = 0: 0 x 0 + 1 x f, which is
    // +0 + f (1 x f is f).
    #[inline(always)]
    fn eval(at: &Self::At, wo: V3<F32x8>, wi: V3<F32x8>) -> V3<F32x8> {
        V3::splat(Vec3::ZERO) + CoatedOpaque::eval(at, wo, wi)
    }

    #[inline(always)]
    fn pdf(at: &Self::At, wo: V3<F32x8>, wi: V3<F32x8>) -> F32x8 {
        F32x8::zero() + CoatedOpaque::pdf(at, wo, wi)
    }

    #[inline(always)]
    fn sample(at: &Self::At, wo: V3<F32x8>, uc: F32x8, u: V2<F32x8>) -> LaneSample<F32x8> {
        type L = F32x8;
        // The non-metal's number, rescaled: (uc - 0) / (1 - 0) is uc.
        let s = CoatedOpaque::sample(at, wo, uc.clamp(0.0, ONE_MINUS_EPS), u);
        let cos = s.wi.z.abs();
        let f = V3::splat(Vec3::ZERO) + s.weight.scale(s.pdf / cos);
        let pdf = L::zero() + s.pdf;
        LaneSample {
            valid: s.valid & pdf.gt(L::zero()) & pdf.lt(L::splat(f32::INFINITY)),
            weight: f.scale(cos / pdf),
            pdf,
            ..s
        }
    }
}

/// The glTF metallic-roughness blend ([`Bsdf::Metallic`]) at metallic 1
/// (a textured metal's texels), opaque: its metal as [`RoughMetal`]'s,
/// with the blend's sums and sample weight as `metallic_*_at` compute
/// them with the non-metal's weight zero.
pub(super) struct MetalBlend;

impl WideBsdf for MetalBlend {
    type Params = RoughConductor<f32>;
    type At = RoughConductor<F32x8>;

    #[inline(always)]
    fn params(bsdf: &Bsdf) -> Option<RoughConductor<f32>> {
        match bsdf {
            // The coat's transmission would make the blend transmit
            // (`Bsdf::has_transmission`) and its clear coat would layer it.
            Bsdf::Metallic {
                metallic,
                conductor,
                coat,
                ..
            } if *metallic == 1.0 && coat.transmission <= 0.0 && coat.clearcoat <= 0.0 => {
                RoughMetal::params(&Bsdf::Conductor(*conductor))
            }
            _ => None,
        }
    }

    #[inline(always)]
    fn at(p: &[RoughConductor<f32>; 8], wo: V3<F32x8>) -> RoughConductor<F32x8> {
        RoughMetal::at(p, wo)
    }

    // 1 x f + 0 x 0 is f + 0.
    #[inline(always)]
    fn eval(c: &RoughConductor<F32x8>, wo: V3<F32x8>, wi: V3<F32x8>) -> V3<F32x8> {
        RoughMetal::eval(c, wo, wi) + V3::splat(Vec3::ZERO)
    }

    #[inline(always)]
    fn pdf(c: &RoughConductor<F32x8>, wo: V3<F32x8>, wi: V3<F32x8>) -> F32x8 {
        RoughMetal::pdf(c, wo, wi) + F32x8::zero()
    }

    #[inline(always)]
    fn sample(
        c: &RoughConductor<F32x8>,
        wo: V3<F32x8>,
        uc: F32x8,
        u: V2<F32x8>,
    ) -> LaneSample<F32x8> {
        type L = F32x8;
        // uc < 1 picks the metal.
        let s = RoughMetal::sample(c, wo, uc, u);
        let cos = s.wi.z.abs();
        let f = s.weight.scale(s.pdf / cos) + V3::splat(Vec3::ZERO);
        let pdf = s.pdf + L::zero();
        LaneSample {
            valid: s.valid & pdf.gt(L::zero()) & pdf.lt(L::splat(f32::INFINITY)),
            weight: f.scale(cos / pdf),
            pdf,
            ..s
        }
    }
}

/// The model in the lanes of a BSDF: 1 [`Lambertian`], 2
/// [`CoatedOpaque`], 3 [`RoughMetal`], 4 [`RoughGlass`], 5
/// [`NonMetalBlend`], 6 [`MetalBlend`], 0 none (shaded one path at a
/// time).
fn model_of(bsdf: &Bsdf) -> u8 {
    if Lambertian::params(bsdf).is_some() {
        1
    } else if CoatedOpaque::params(bsdf).is_some() {
        2
    } else if RoughMetal::params(bsdf).is_some() {
        3
    } else if RoughGlass::params(bsdf).is_some() {
        4
    } else if NonMetalBlend::params(bsdf).is_some() {
        5
    } else if MetalBlend::params(bsdf).is_some() {
        6
    } else {
        0
    }
}

/// [`PathTracer::wide_kinds`]' number of a textured material whose
/// textures set only the BSDF's parameters (no normal map): its model is
/// found per hit, from the textured BSDF.
const TEXTURED: u8 = 7;

/// [`PathTracer::wide_kinds`]' number of a normal-mapped material: its
/// model is found per hit from the textured BSDF, and its shading frame
/// and fold ([`PathTracer::apply_textures`]) lane by lane.
const MAPPED: u8 = 8;

/// Each material's model in the lanes ([`model_of`]), or [`TEXTURED`] or
/// [`MAPPED`]. (A clear coat's own normal needs no kind: the models have
/// no clear coat, so its lanes go one by one.)
pub(super) fn kinds(scene: &Scene) -> Vec<u8> {
    (0..scene.materials.len())
        .map(|m| match scene.textures.material(m as u32) {
            None => model_of(&scene.materials[m].bsdf),
            Some(mt) if mt.normal.is_some() => MAPPED,
            Some(_) => TEXTURED,
        })
        .collect()
}

/// The shading normal at barycentrics (u, v) of a triangle whose vertex
/// normals are `n` (geometric normal `ng`): their interpolation,
/// normalised, turned to `ng`'s side; `ng` where it is zero (or not a
/// number). The scalar `PathTracer::surface` is its one-lane form.
#[inline(always)]
pub(super) fn shading_normal<L: Lane>(ng: V3<L>, n: [V3<L>; 3], u: L, v: L) -> V3<L> {
    let w = L::one() - u - v;
    let n = (n[0].scale(w) + n[1].scale(u) + n[2].scale(v)).normalize_or_zero();
    let zero = n.x.eq(L::zero()) & n.y.eq(L::zero()) & n.z.eq(L::zero());
    let turned = V3::select(n.dot(ng).lt(L::zero()), -n, n);
    V3::select(zero, ng, turned)
}

/// Whether two masks agree in each lane.
#[inline(always)]
fn agree<L: Lane>(a: L::Mask, b: L::Mask) -> L::Mask {
    (a & b) | (!a & !b)
}

/// One path's vertex, as the lanes read it.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct VertexIn {
    /// The triangle's vertices.
    v: [Vec3; 3],
    /// Its vertex normals (zero where it has none).
    n: [Vec3; 3],
    has_n: bool,
    /// The hit's barycentrics.
    u: f32,
    v_: f32,
    p: Vec3,
    /// The hit point's error bound.
    p_err: Vec3,
    wo: Vec3,
}

/// The vertex tangents of the lanes' triangles that have them (read only
/// where some have: most have none).
pub(super) struct Tangents {
    t: [[Vec3; 3]; 8],
    /// The lanes whose triangle has tangents (bits).
    has: u8,
}

/// The shading frames of the lanes whose material is normal-mapped (read
/// only where some are), found lane by lane as the scalar vertex finds
/// them ([`PathTracer::apply_textures`]).
pub(super) struct MappedFrames {
    /// Each lane's frame: s, t, n (n the mapped shading normal).
    frame: [[Vec3; 3]; 8],
    /// The lanes whose frame is here (bits).
    has: u8,
    /// The lanes that fold ([`crate::bsdf::fold`]): those of `has` whose
    /// BSDF does not transmit.
    folds: u8,
}

/// What [`PathTracer::wide_vertices`] found of the wave's hits before it
/// shaded them, kept for the lanes it leaves to the scalar vertex: each
/// textured hit's BSDF, and each normal-mapped hit's frame (there the
/// hit is shaded whole, [`PathTracer::shade`]).
#[derive(Default)]
pub(super) struct Shaded {
    pub(super) sf: [Option<SurfaceFrame>; 8],
    pub(super) textured: [Option<Bsdf>; 8],
}

/// What the lanes found for each path (valid in the lanes they shaded).
#[derive(Clone, Copy, Debug)]
pub(super) struct VertexOut {
    ns: [Vec3; 8],
    /// The lanes whose light sample has a nonzero f |cos|: their shadow
    /// ray (origin, direction, length) is traced.
    nee: u8,
    shadow_o: [Vec3; 8],
    shadow_d: [Vec3; 8],
    shadow_tmax: [f32; 8],
    /// f |cos| Le / pdf times the MIS weight: what a clear shadow ray adds.
    light: [Vec3; 8],
    /// The lanes whose BSDF sample goes on (valid, no leak).
    next: u8,
    /// The next ray: its origin and direction.
    next_o: [Vec3; 8],
    wi: [Vec3; 8],
    /// The BSDF sample's weight and density.
    weight: [Vec3; 8],
    pdf: [f32; 8],
    /// The relative IOR the sample crossed.
    eta: [f32; 8],
}

/// The lanes' light samples ([`Lights::sample`], the bounce's numbers
/// `u`) from points `p` (shading normals `ns`) of the vertices in `live`:
/// the emitter, punctual and constant background samples in lanes
/// (`Lights::sample_emitter_lanes`, `sample_punctual_lanes`,
/// `sample_constant_background_lanes`), an environment map's lane by lane.
/// The samples, and where each is a delta.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn light_samples(
    lights: &Lights,
    scene: &Scene,
    inp: &[VertexIn; 8],
    u: &BounceLanes<F32x8>,
    live: Mask8,
    p: V3<F32x8>,
    ns: V3<F32x8>,
    transmits: bool,
) -> (EmitterSamples<F32x8>, Mask8) {
    type L = F32x8;
    let pr = lights.probs;
    // The categories as `Lights::sample` picks them.
    let emitter = live & u.light_cat.lt(L::splat(pr.area));
    let punctual = live & !emitter & u.light_cat.lt(L::splat(pr.area + pr.punctual));
    let background = if pr.background > 0.0 {
        live & !emitter & !punctual
    } else {
        Mask8::from_bits(0)
    };
    let mut ls = if L::none(emitter) {
        let zero = V3::splat(Vec3::ZERO);
        EmitterSamples {
            valid: emitter,
            wi: zero,
            dist: L::zero(),
            weight: zero,
            pdf: L::zero(),
        }
    } else {
        lights.sample_emitter_lanes(scene, p, u.light_idx, u.light, emitter)
    };
    let mut delta = 0u8;
    if !L::none(punctual) {
        let got = lights.sample_punctual_lanes(p, u.light_idx, punctual);
        ls = ls.select(punctual, got);
        delta = L::bits(got.valid);
    }
    if L::none(background) {
        return (ls, Mask8::from_bits(delta));
    }
    // About the shading normal turned to wo, or over the sphere.
    let bg =
        crate::lights::lanes::background_direction_frame(ns, gather3!(inp, |d| d.wo), transmits);
    if lights.envmap.is_none() {
        let got = lights.sample_constant_background_lanes(bg, u.light, background);
        return (ls.select(background, got), Mask8::from_bits(delta));
    }
    // The environment map's samples, as `PathTracer::vertex` draws them.
    let mut got = [None::<LightSample>; 8];
    let mut some = 0u8;
    for k in live_lanes(L::bits(background)) {
        let n = u.lane(k);
        got[k] = lights.sample(
            scene,
            inp[k].p,
            bg.lane(k),
            n.light_cat,
            n.light_idx,
            n.light,
        );
        some |= u8::from(got[k].is_some()) << k;
    }
    let none = LightSample {
        wi: Vec3::Z,
        dist: 1.0,
        weight: Vec3::ZERO,
        pdf: 0.0,
        delta: false,
    };
    let got: [LightSample; 8] = crate::lanes::build8(|k| got[k].unwrap_or(none));
    let got = EmitterSamples {
        valid: Mask8::from_bits(some),
        wi: gather3!(got, |l| l.wi),
        dist: gather!(got, |l| l.dist),
        weight: gather3!(got, |l| l.weight),
        pdf: gather!(got, |l| l.pdf),
    };
    (ls.select(background, got), Mask8::from_bits(delta))
}

/// The lanes' arithmetic of the vertices in `live` (bits), BSDF `M`
/// with the lanes' parameters `params`, eight per instruction (compiled
/// for the wave's [`crate::lanes::SimdLevel`]).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn vertex_lanes<M: WideBsdf>(
    lights: &Lights,
    scene: &Scene,
    mis: Mis,
    inp: &[VertexIn; 8],
    rnd: &BounceLanes<F32x8>,
    tangents: &Tangents,
    mapped: &MappedFrames,
    params: &[M::Params; 8],
    live: u8,
) -> VertexOut {
    type L = F32x8;
    let (mapped_has, folds) = (mapped.has & live, mapped.folds & live);
    let live = Mask8::from_bits(live);
    let v = [
        gather3!(inp, |d| d.v[0]),
        gather3!(inp, |d| d.v[1]),
        gather3!(inp, |d| d.v[2]),
    ];
    let (u, vb) = (gather!(inp, |d| d.u), gather!(inp, |d| d.v_));
    let ng = (v[1] - v[0]).cross(v[2] - v[0]).normalize();
    let has_n = Mask8::from_bits((0..8).fold(0, |b, l| b | u8::from(inp[l].has_n) << l));
    let ns = if L::none(has_n) {
        ng
    } else {
        let n = [
            gather3!(inp, |d| d.n[0]),
            gather3!(inp, |d| d.n[1]),
            gather3!(inp, |d| d.n[2]),
        ];
        V3::select(has_n, shading_normal(ng, n, u, vb), ng)
    };
    let frame = if tangents.has == 0 {
        Frame::from_normal(ns)
    } else {
        // The interpolated tangent (`PathTracer::surface`'s `lerp`).
        let t = [
            gather3!(tangents.t, |d| d[0]),
            gather3!(tangents.t, |d| d[1]),
            gather3!(tangents.t, |d| d[2]),
        ];
        let has_t = Mask8::from_bits(tangents.has);
        let w = L::one() - u - vb;
        let tangent = t[0].scale(w) + t[1].scale(u) + t[2].scale(vb);
        let (with, without) = (
            Frame::from_normal_tangent(ns, tangent),
            Frame::from_normal(ns),
        );
        Frame {
            s: V3::select(has_t, with.s, without.s),
            t: V3::select(has_t, with.t, without.t),
            n: ns,
        }
    };
    // The normal-mapped lanes' frames.
    let (frame, ns) = if !M::MAPPED || mapped_has == 0 {
        (frame, ns)
    } else {
        let m = Mask8::from_bits(mapped_has);
        let n = V3::select(m, gather3!(mapped.frame, |f| f[2]), ns);
        let frame = Frame {
            s: V3::select(m, gather3!(mapped.frame, |f| f[0]), frame.s),
            t: V3::select(m, gather3!(mapped.frame, |f| f[1]), frame.t),
            n,
        };
        (frame, n)
    };
    let wo_world = gather3!(inp, |d| d.wo);
    let wo = frame.to_local(wo_world);
    let bsdf = M::at(params, wo);
    // The folding lanes' fold (`SurfaceFrame::fold_for`).
    let fold = (M::MAPPED && folds != 0).then(|| Fold::new(frame.to_local(ng), wo));
    let folds = Mask8::from_bits(folds);
    let p = gather3!(inp, |d| d.p);
    let (ls, delta) = light_samples(lights, scene, inp, rnd, live, p, ns, M::TRANSMITS);
    // Next-event estimation's arithmetic (`PathTracer::next_event`).
    let wi_l = frame.to_local(ls.wi);
    let mut sides = agree::<L>(ls.wi.dot(ng).gt(L::zero()), wi_l.z.gt(L::zero()));
    let mut f = M::eval(&bsdf, wo, wi_l).scale(wi_l.z.abs());
    let mut pdf = M::pdf(&bsdf, wo, wi_l);
    if let Some(fd) = &fold {
        // `Fold::eval_pdf`: no side test, the mirror image's share added.
        let m = fd.mirror(wi_l);
        let fm = M::eval(&bsdf, wo, m).scale(m.z.abs());
        let (ff, fp) = fd.eval_pdf(wi_l, f, pdf, fm, M::pdf(&bsdf, wo, m));
        f = V3::select(folds, ff, f);
        pdf = L::select(folds, fp, pdf);
        sides = sides | folds;
    }
    let nee = ls.valid & sides & f.max_element().gt(L::zero());
    let p_err = gather3!(inp, |d| d.p_err);
    let (shadow_o, shadow_d, shadow_tmax) = shadow_ray_lanes(p, p_err, ng, ls.wi, ls.dist);
    let w = L::select(delta, L::one(), mis_light(mis, ls.pdf, pdf));
    let light = (f * ls.weight).scale(w);
    // The BSDF's sample (`next_direction`).
    let mut bs = M::sample(&bsdf, wo, rnd.bsdf_lobe, rnd.bsdf);
    if let Some(fd) = &fold {
        // `Fold::sample`.
        let r = fd.mirror(bs.wi);
        let fr = M::eval(&bsdf, wo, r).scale(r.z.abs());
        let folded = fd.reweigh(bs, fr, M::pdf(&bsdf, wo, r));
        bs.valid = L::select_mask(folds, folded.valid, bs.valid);
        bs.wi = V3::select(folds, folded.wi, bs.wi);
        bs.weight = V3::select(folds, folded.weight, bs.weight);
        bs.pdf = L::select(folds, folded.pdf, bs.pdf);
    }
    let wi = frame.to_world(bs.wi).normalize();
    let up = wi.dot(ng).gt(L::zero());
    let mut leaks = !agree::<L>(up, bs.wi.z.gt(L::zero()));
    if fold.is_some() {
        // Folded, wi must leave on wo's side of the geometric surface.
        let folded_leaks = !agree::<L>(up, wo_world.dot(ng).gt(L::zero()));
        leaks = L::select_mask(folds, folded_leaks, leaks);
    }
    let next = live & bs.valid & !leaks;
    let next_o = offset_origin_lanes(p, p_err, ng, wi);
    let lanes3 = |x: V3<L>| -> [Vec3; 8] { crate::lanes::build8(|l| x.lane(l)) };
    VertexOut {
        ns: lanes3(ns),
        nee: L::bits(nee),
        shadow_o: lanes3(shadow_o),
        shadow_d: lanes3(shadow_d),
        shadow_tmax: shadow_tmax.0,
        light: lanes3(light),
        next: L::bits(next),
        next_o: lanes3(next_o),
        wi: lanes3(wi),
        weight: lanes3(bs.weight),
        pdf: bs.pdf.0,
        eta: bs.eta.0,
    }
}

impl PathTracer<'_> {
    /// The vertices of the lanes in `pending` that the lanes shade, model
    /// by model ([`WideBsdf`]): those whose material (textured, at the
    /// hit) is the model's, where [`WIDE_MIN`] or more paths stand on one; each is [`PathTracer::vertex`], its arithmetic
    /// eight paths per instruction, at bounce `depth`. The lanes shaded
    /// leave `pending`; returns those whose path ends. (None are shaded
    /// where next-event estimation is off or the scene has no lights.)
    #[allow(clippy::too_many_arguments)]
    pub(super) fn wide_vertices(
        &self,
        paths: &mut [PathState; 8],
        rays_of: &mut [Ray; 8],
        arrivals: &[Option<Arrival>; 8],
        bounce: &BounceLanes<F32x8>,
        shaded: &mut Shaded,
        pending: &mut u8,
        depth: u32,
        rays: &mut u64,
    ) -> u8 {
        if !self.nee || self.lights.is_empty() {
            return 0;
        }
        // The lanes by model (`model_of`'s numbers); a textured
        // material's BSDF made here (`PathTracer::apply_textures` without a
        // normal map), once, for the lanes that take it.
        let scene = self.scene;
        let mut of = [0u8; 7];
        let textured = &mut shaded.textured;
        let mut mapped = MappedFrames {
            frame: [[Vec3::ZERO; 3]; 8],
            has: 0,
            folds: 0,
        };
        for k in live_lanes(*pending) {
            let Some(at) = &arrivals[k] else { continue };
            let mut kind = self.wide_kinds[at.material as usize];
            if kind == TEXTURED
                && let Some(mt) = scene.textures.material(at.material)
            {
                let base = &scene.materials[at.material as usize].bsdf;
                let bsdf = textured_bsdf(&scene.textures, mt, base, at.hit.tri, at.hit.u, at.hit.v);
                kind = model_of(&bsdf);
                textured[k] = Some(bsdf);
            } else if kind == MAPPED
                && let Some(mt) = scene.textures.material(at.material)
            {
                // The scalar vertex's textures and frame (`PathTracer::shade`).
                let (tri, u, v) = (at.hit.tri, at.hit.u, at.hit.v);
                let base = &scene.materials[at.material as usize].bsdf;
                let mut sf = self.surface(tri, u, v);
                kind = model_of(self.apply_textures(
                    mt,
                    tri,
                    u,
                    v,
                    at.wo,
                    &mut sf,
                    base,
                    &mut textured[k],
                ));
                if kind != 0 {
                    mapped.frame[k] = [sf.frame.s, sf.frame.t, sf.frame.n];
                    mapped.has |= 1 << k;
                    mapped.folds |= u8::from(sf.folds) << k;
                }
                shaded.sf[k] = Some(sf);
            }
            if kind < TEXTURED {
                of[kind as usize] |= 1 << k;
            }
        }
        let mut ended = 0u8;
        macro_rules! shade {
            ($($model:ty: $lanes:expr),*) => {$(
                if $lanes.count_ones() >= WIDE_MIN {
                    *pending &= !$lanes;
                    ended |= if mapped.has & $lanes != 0 {
                        self.vertices::<NormalMapped<$model>>(
                            paths, rays_of, arrivals, bounce, &shaded.textured, &mapped, $lanes, depth, rays,
                        )
                    } else {
                        self.vertices::<$model>(
                            paths, rays_of, arrivals, bounce, &shaded.textured, &mapped, $lanes, depth, rays,
                        )
                    };
                }
            )*};
        }
        shade!(
            Lambertian: of[1],
            CoatedOpaque: of[2],
            RoughMetal: of[3],
            RoughGlass: of[4],
            NonMetalBlend: of[5],
            MetalBlend: of[6]
        );
        ended
    }

    /// The vertices of the lanes in `wide`, all of model `M` (see
    /// [`Self::wide_vertices`]). Returns the lanes whose path ends.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn vertices<M: WideBsdf>(
        &self,
        paths: &mut [PathState; 8],
        rays_of: &mut [Ray; 8],
        arrivals: &[Option<Arrival>; 8],
        bounce: &BounceLanes<F32x8>,
        textured: &[Option<Bsdf>; 8],
        mapped: &MappedFrames,
        wide: u8,
        depth: u32,
        rays: &mut u64,
    ) -> u8 {
        let scene = self.scene;
        let mut inp = [VertexIn::default(); 8];
        let mut tangents = Tangents {
            t: [[Vec3::ZERO; 3]; 8],
            has: 0,
        };
        // Each lane's parameters, the lanes not shaded here holding the
        // first shaded lane's.
        let params_of = |k: usize| {
            let at = arrivals[k].as_ref()?;
            M::params(match &textured[k] {
                Some(b) => b,
                None => &scene.materials[at.material as usize].bsdf,
            })
        };
        let first = wide.trailing_zeros() as usize;
        // (Never: the caller chose the lanes by `M::params`.)
        let Some(first_params) = params_of(first) else {
            return 0;
        };
        let mut params = [first_params; 8];
        for k in live_lanes(wide) {
            let Some(at) = &arrivals[k] else { continue };
            let tri = &scene.triangles[at.hit.tri as usize];
            let Some(pm) = params_of(k) else {
                continue;
            };
            // The triangle's packed shading data (`Scene::set_shading`):
            // normals, then tangents.
            let has_n = tri.flags & TRI_NORMALS != 0;
            let off = (tri.flags >> TRI_SHADING_SHIFT) as usize;
            let at3 = |o: usize| Vec3::from_slice(&scene.shading[o][..3]);
            let normal = |i: usize| if has_n { at3(off + i) } else { Vec3::ZERO };
            if tri.flags & TRI_TANGENTS != 0 {
                let o = off + if has_n { 3 } else { 0 };
                tangents.t[k] = [at3(o), at3(o + 1), at3(o + 2)];
                tangents.has |= 1 << k;
            }
            params[k] = pm;
            inp[k] = VertexIn {
                v: tri.vertices(),
                n: [normal(0), normal(1), normal(2)],
                has_n,
                u: at.hit.u,
                v_: at.hit.v,
                p: at.p,
                p_err: at.p_err,
                wo: at.wo,
            };
        }
        // The lanes not shaded here compute a copy of a shaded one (and
        // are ignored): no lane's numbers are garbage.
        for k in 0..8 {
            if wide & (1 << k) == 0 {
                inp[k] = inp[first];
            }
        }
        let out = crate::simd_at!(self.simd, fn<M: WideBsdf>(
            lights: &Lights,
            scene: &Scene,
            mis: Mis,
            inp: &[VertexIn; 8],
            u: &BounceLanes<F32x8>,
            tangents: &Tangents,
            mapped: &MappedFrames,
            params: &[M::Params; 8],
            live: u8,
        ) -> VertexOut {
            vertex_lanes::<M>(lights, scene, mis, inp, u, tangents, mapped, params, live)
        }(&self.lights, scene, self.mis, &inp, bounce, &tangents, mapped, &params, wide));
        let mut ended = 0u8;
        for k in live_lanes(wide) {
            let Some(at) = &arrivals[k] else { continue };
            let path = &mut paths[k];
            if out.nee & (1 << k) != 0 {
                *rays += 1;
                let shadow = Ray {
                    o: out.shadow_o[k],
                    d: out.shadow_d[k],
                    tmax: out.shadow_tmax[k],
                };
                if shadow.tmax > 0.0 && !scene.occluded_with(&shadow, self.masks) {
                    path.radiance += path.throughput * out.light[k];
                }
            }
            if out.next & (1 << k) == 0 {
                ended |= 1 << k;
                continue;
            }
            // The models' samples are no deltas.
            path.throughput *= out.weight[k];
            if M::TRANSMITS {
                path.eta *= out.eta[k];
            }
            path.prev_mis = true;
            path.prev_delta = false;
            path.prev_bsdf_pdf = out.pdf[k];
            path.prev_bg_normal = background_direction_frame(out.ns[k], at.wo, M::TRANSMITS);
            path.prev_p = at.p;
            rays_of[k] = Ray {
                o: out.next_o[k],
                d: out.wi[k],
                tmax: f32::MAX,
            };
            if !self.roulette(path, depth + 1, bounce.rr.0[k]) {
                ended |= 1 << k;
            }
        }
        ended
    }
}
