//! The CPU path tracer: unidirectional path tracing with next-event
//! estimation and multiple importance sampling, Mitsuba 3's `path`
//! integrator semantics. `shaders/pathtrace.comp` mirrors [`PathTracer::sample`]
//! step by step, with the same names.
//!
//! - MIS: the power heuristic, beta = 2 (Veach 1997, sec. 9.2.4), between
//!   light sampling and BSDF sampling for area emitters and the background;
//!   punctual lights are deltas and take no MIS weight. An emitter found
//!   by a BSDF sample is weighted only when the vertex that sampled it also
//!   sampled lights and the BSDF sample was not a delta (else weight 1).
//! - Depth (Mitsuba's `max_depth`): 1 = emitters seen directly, 2 = direct
//!   lighting, -1 = unbounded. `depth` counts the scattering vertices behind
//!   the current ray; a vertex scatters (light sample + BSDF sample) only
//!   while `depth + 1 < max_depth`.
//! - Russian roulette once `depth >= 5` (Mitsuba's `rr_depth`), continuing
//!   with q = min(max(throughput) * eta^2, 0.95), eta the product of the
//!   relative IORs crossed (removing the 1/eta^2 radiance scaling from the
//!   survival odds, as Mitsuba does).
//! - Random numbers: a fixed budget per vertex (2 for the pixel position,
//!   then 4 light + 3 BSDF + 1 roulette per bounce) whether used or not, so
//!   both backends walk the same stream; `sobol::PathSampler` gives them
//!   from independent numbers or Owen-scrambled Sobol pairs (`--sampler`).
//! - Ray offsets from the floating-point error of the hit point (pbrt-v4's
//!   `OffsetRayOrigin`, Pharr et al. 4th ed. sec. 6.8.6): a hit point
//!   interpolated from its triangle's vertices lies within
//!   `err = gamma(7) max(|p0|, |p1|, |p2|)` (componentwise) of the plane,
//!   the bound of pbrt-v4 sec. 6.8.5 taken over the whole triangle, plus
//!   64 ulps of the triangle's extent for the rounding of the next
//!   intersection test (pbrt-v4's triangle test rejects t < deltaT, a
//!   bound of that size; ours has no such margin, so the offset carries
//!   it: a huge single triangle gets offsets of ~4e-6 of its size). New
//!   rays start at `p + ng * (|ng| . err)`
//!   on the side `wi` points to, each component then rounded one float
//!   away from p. Nothing depends on the scene's extent or on |p| beyond
//!   what its own triangle's float precision needs, so a scene renders the
//!   same far from the origin, at any scale, and beside a large ground
//!   plane. Shadow rays end `SHADOW_EPS` of their length (pbrt-v4's
//!   `ShadowEpsilon`) plus the light point's own error bound short of it.
//! - Light leaks: a direction whose side of the geometric normal differs
//!   from its side of the shading normal is discarded (light sample) or
//!   ends the path (BSDF sample), since it would pass through the surface
//!   the interpolated normal pretends is not there (Veach 1996's
//!   shading-normal asymmetry; pbrt-v3 sec. 16.1 discusses the same leak).
//!   A normal-mapped normal is first adapted as Cycles does
//!   (`texture::valid_reflection_normal`) so that the mirror direction of
//!   wo stays above the geometric surface: glossy lobes keep their energy
//!   instead of ending in black rims where the map tilts far. On a
//!   normal-mapped BSDF without transmission the rule gives way to the
//!   fold ([`crate::bsdf::fold`]): what the lobe sends below the geometric
//!   surface leaves mirrored above it, so the map loses no energy.

// `!(x > 0.0)` on floats is meant: it rejects NaN too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod gpu;
mod wave;
mod wide;

pub use wave::WaveSampler;

use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;

pub use gpu::{GpuParams, GpuSceneData, gpu_scene_data};

use crate::bsdf::fold::Fold;
use crate::bsdf::{Bsdf, BsdfAt};
use crate::bvh::Ray;
use crate::camera::{PinholeCamera, scene_camera};
use crate::film::{Film, Mis, RenderOptions, RenderStats, SamplerKind, add_sample};
use crate::frame::Frame;
use crate::lanes::{Lane, SimdLevel, V3};
use crate::lights::{LightSample, Lights, background_direction_frame, emitted};
use crate::sampling::{mis_bsdf, mis_light, seed_key};
use crate::scene::{NO_LIGHT, Scene, TRI_NORMALS, TRI_SHADING_SHIFT, TRI_TANGENTS};
use crate::schedule::{Pacing, PassPlan, Schedule};
use crate::sobol::{PathSampler, SampleBatch};
use crate::texture::{MaterialTextures, clearcoat_normal, normal_mapped, textured_bsdf};

// Russian roulette and the ray offsets, shared with the kernel.
pub use crate::abi::{RAY_ERR_GAMMA, RAY_ERR_TRI, RR_DEPTH, RR_MAX_PROB, SHADOW_EPS};
/// A scene whose ray-offset bound at its farthest point exceeds this
/// fraction of its median triangle size gets a precision warning.
/// (A tenth: neighbouring triangles then start to shadow each other and
/// contacts open visibly.)
pub const PRECISION_WARN_FRACTION: f32 = 0.1;
/// Image tile edge for the CPU's parallel loop.
pub const TILE: u32 = 16;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum RenderError {
    #[error("invalid render option: {0}")]
    InvalidOptions(String),
}

/// Check the options against the contract's ranges.
/// Mitsuba's `max_depth` as the integrators count it: unbounded (-1, any
/// negative) as `u32::MAX`.
pub fn depth_limit(max_depth: i32) -> u32 {
    u32::try_from(max_depth).unwrap_or(u32::MAX)
}

pub fn validate_options(scene: &Scene, opts: &RenderOptions) -> Result<(), RenderError> {
    let bad = |m: String| Err(RenderError::InvalidOptions(m));
    let side = 1..=crate::film::MAX_IMAGE_SIDE;
    if !side.contains(&opts.width) || !side.contains(&opts.height) {
        return bad(format!(
            "image size {}x{} (each side must be 1..={})",
            opts.width,
            opts.height,
            crate::film::MAX_IMAGE_SIDE
        ));
    }
    if opts.spp == 0 {
        return bad("spp must be at least 1".into());
    }
    if opts.max_depth == 0 || opts.max_depth < -1 {
        return bad(format!(
            "max depth {} (must be -1 or at least 1)",
            opts.max_depth
        ));
    }
    for (name, v) in [
        ("target error", opts.target_error),
        ("adaptive", opts.adaptive),
    ] {
        if let Some(v) = v
            && !(v > 0.0 && v.is_finite())
        {
            return bad(format!("{name} {v} (must be a positive number)"));
        }
    }
    if opts.adaptive.is_some() && (opts.time_limit.is_some() || opts.sample_start != 0) {
        return bad("adaptive sampling needs the whole sample range, without a time limit".into());
    }
    if !scene.cameras.is_empty() && opts.camera >= scene.cameras.len() {
        return bad(format!(
            "camera {} (the scene has {})",
            opts.camera,
            scene.cameras.len()
        ));
    }
    Ok(())
}

/// Beer-Lambert absorption inside a solid dielectric
/// ([`crate::Material::absorption`]): a segment that reaches a surface of
/// an absorbing material from its back face (`d . n_g > 0`: winding
/// outward, as glTF's closed meshes are) travelled inside it for `t`
/// (rays are unit length), and carries exp(-sigma_a t) of its radiance.
/// Stateless, so it holds for closed, non-nested volumes; shadow rays need
/// none (a dielectric occludes them).
#[inline]
fn absorb(scene: &Scene, tri: &crate::Triangle, ray: &Ray, t: f32, throughput: &mut Vec3) {
    let sigma = scene.materials[tri.material as usize].absorption;
    if sigma != Vec3::ZERO && ray.d.dot(tri.geometric_normal()) > 0.0 {
        *throughput *= (-sigma * t).exp();
    }
}

/// Componentwise error bound of a point interpolated from the triangle
/// `p0 p1 p2` (see the module notes): gamma(7) max(|p0|, |p1|, |p2|), plus
/// `RAY_ERR_TRI` x the triangle's extent in every component for the next
/// intersection test's rounding.
#[inline]
pub fn hit_error(p0: Vec3, p1: Vec3, p2: Vec3) -> Vec3 {
    let extent = (p0.max(p1).max(p2) - p0.min(p1).min(p2)).max_element();
    RAY_ERR_GAMMA * p0.abs().max(p1.abs()).max(p2.abs()) + Vec3::splat(RAY_ERR_TRI * extent)
}

pub use crate::lanes::{next_float_down, next_float_up};

/// `p` (error bound `err`) moved off its surface to the side of `ng` that
/// `w` points to: pbrt-v4's `OffsetRayOrigin`. (Its branches, not
/// [`offset_origin_lanes`]' selects, for one path: the selects sat in front
/// of the next traversal and cost 2.5-4%, docs/benchmarks.md, twenty-third
/// session. The same bits: `cpu/tests/lanes.rs`.)
#[inline]
pub fn offset_origin(p: Vec3, err: Vec3, ng: Vec3, w: Vec3) -> Vec3 {
    let d = ng.abs().dot(err);
    let mut offset = ng * d;
    if w.dot(ng) < 0.0 {
        offset = -offset;
    }
    let mut po = p + offset;
    for i in 0..3 {
        if offset[i] > 0.0 {
            po[i] = next_float_up(po[i]);
        } else if offset[i] < 0.0 {
            po[i] = next_float_down(po[i]);
        }
    }
    po
}

/// [`offset_origin`] in every lane.
#[inline(always)]
pub fn offset_origin_lanes<L: Lane>(p: V3<L>, err: V3<L>, ng: V3<L>, w: V3<L>) -> V3<L> {
    let d = ng.abs().dot(err);
    let offset = ng.scale(d);
    let offset = V3::select(w.dot(ng).lt(L::zero()), -offset, offset);
    let po = p + offset;
    let step = |o: L, v: L| {
        L::select(
            o.gt(L::zero()),
            v.next_up(),
            L::select(o.lt(L::zero()), v.next_down(), v),
        )
    };
    V3::new(
        step(offset.x, po.x),
        step(offset.y, po.y),
        step(offset.z, po.z),
    )
}

/// The shadow ray's length short of a light point `q` at distance `len`
/// from the ray origin: `SHADOW_EPS` of the length plus q's own error
/// bound (twice gamma(7) |q|: an emitter's point is interpolated as a hit
/// point is).
#[inline]
pub fn shadow_tmax(len: f32, q: Vec3) -> f32 {
    shadow_tmax_lanes(len, q.into())
}

/// [`shadow_tmax`] in every lane (its one-lane form is the scalar one).
#[inline(always)]
pub fn shadow_tmax_lanes<L: Lane>(len: L, q: V3<L>) -> L {
    len * L::splat(1.0 - SHADOW_EPS) - L::splat(2.0 * RAY_ERR_GAMMA) * q.abs().max_element()
}

/// The shadow rays from `p` (error bound `err`, geometric normal `ng`)
/// toward light samples in direction `wi` at distance `dist`, in every
/// lane: [`PathTracer::shadow_ray`]'s origin, direction and length.
#[inline(always)]
pub fn shadow_ray_lanes<L: Lane>(
    p: V3<L>,
    err: V3<L>,
    ng: V3<L>,
    wi: V3<L>,
    dist: L,
) -> (V3<L>, V3<L>, L) {
    let o = offset_origin_lanes(p, err, ng, wi);
    let q = p + wi.scale(dist);
    let to = q - o;
    let len = to.length();
    let finite = dist.abs().lt(L::splat(f32::INFINITY));
    (
        o,
        V3::select(finite, to / len, wi),
        L::select(finite, shadow_tmax_lanes(len, q), L::splat(f32::MAX)),
    )
}

/// Where f32 truly runs out for this scene: the ray-offset bound at its
/// farthest point from the origin against its median triangle size.
/// Returns the warning's text (without the `glint: warning: FILE:` prefix).
pub fn precision_warning(scene: &Scene) -> Option<String> {
    if scene.triangles.is_empty() {
        return None;
    }
    let (lo, hi) = scene.bounds();
    let far = lo.abs().max(hi.abs()).max_element();
    let mut sizes: Vec<f32> = scene
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.vertices();
            (b - a).length().max((c - a).length()).max((c - b).length())
        })
        .filter(|s| s.is_finite() && *s > 0.0)
        .collect();
    if sizes.is_empty() {
        return None;
    }
    let mid = sizes.len() / 2;
    let median = *sizes.select_nth_unstable_by(mid, f32::total_cmp).1;
    let offset = RAY_ERR_GAMMA * far;
    if !far.is_finite() || offset > PRECISION_WARN_FRACTION * median {
        Some(format!(
            "float precision runs out: the scene reaches {far:.3e} from the origin, where \
             ray offsets are {offset:.2e}, {:.1}% of its median triangle ({median:.2e}); \
             move it nearer the origin",
            100.0 * offset / median
        ))
    } else {
        None
    }
}

/// One tile's output: its index, per-pixel [sum, sum_sq, batch_run,
/// batch_sq], rays traced.
type TileResult = (u32, Vec<[Vec3; 4]>, u64);

/// Everything one render needs, prepared once.
pub struct PathTracer<'a> {
    pub scene: &'a Scene,
    pub lights: Lights,
    pub camera: PinholeCamera,
    /// Mitsuba's max_depth with -1 mapped to u32::MAX.
    pub max_depth: u32,
    pub key: u32,
    /// Next-event estimation on (the default). Off: pure BSDF sampling,
    /// emitters found only by hitting them (a test of MIS correctness).
    pub nee: bool,
    /// MIS weighting of light against BSDF samples.
    pub mis: Mis,
    /// Where the random numbers come from.
    pub sampler: SamplerKind,
    /// First sample index (`RenderOptions::sample_start`).
    pub sample_start: u32,
    /// Samples per variance batch (`RenderOptions::batch`).
    pub batch: u32,
    /// The passes: a time limit, `--target-error` / `--adaptive`.
    pub plan: PassPlan,
    /// Whether traversal runs the alpha test (`Scene::textures.has_masks()`,
    /// asked once here, not per ray).
    pub masks: bool,
    /// The instructions the wide sampler runs on ([`SampleBatch`]):
    /// `SimdLevel::detect()`, settable so tests can compare the levels.
    pub simd: SimdLevel,
    /// Whether a wave shades its Lambertian vertices eight per instruction
    /// (`integrator/wide.rs`): by default where the build makes the lanes
    /// AVX2 instructions ([`wide::LANES_IN_REGISTERS`]); settable so tests
    /// run both paths in any build. The same bits either way.
    pub wide_shading: bool,
    /// Each material's model in the lanes ([`wide::kinds`]).
    wide_kinds: Vec<u8>,
}

/// The MIS weight of an emitter a BSDF-sampled ray found: 1 unless the
/// previous vertex could have found it by light sampling too (`prev_mis`),
/// with the density `light_pdf` gives.
fn emitter_weight(
    mis: Mis,
    prev_mis: bool,
    prev_bsdf_pdf: f32,
    light_pdf: impl FnOnce() -> f32,
) -> f32 {
    if prev_mis {
        mis_bsdf(mis, prev_bsdf_pdf, light_pdf())
    } else {
        1.0
    }
}

/// The BSDF's sample at a hit (folded where `fold` says) and its world
/// direction; None where the BSDF samples nothing or the direction breaks
/// the light-leak rule (folded, wi must leave on wo's side of the
/// geometric surface, which it does up to rounding at the horizon).
#[inline(always)]
fn next_direction(
    bsdf: &BsdfAt,
    sf: &SurfaceFrame,
    wo: Vec3,
    fold: Option<Fold>,
    uc: f32,
    u: glam::Vec2,
) -> Option<(crate::bsdf::BsdfSample, Vec3)> {
    let bs = match fold {
        Some(fd) => fd.sample(bsdf, uc, u),
        None => bsdf.sample(uc, u),
    }?;
    let wi = sf.frame.to_world(bs.wi).normalize();
    let leaks = match fold {
        Some(_) => (wi.dot(sf.ng) > 0.0) != (wo.dot(sf.ng) > 0.0),
        None => (wi.dot(sf.ng) > 0.0) != (bs.wi.z > 0.0),
    };
    (!leaks).then_some((bs, wi))
}

/// A path between its bounces: what it has gathered, what it carries,
/// and what MIS needs of the vertex it left. (Its ray is kept beside it:
/// a wave's rays in one array are its camera packet, not a copy.)
#[derive(Clone, Copy, Debug)]
struct PathState {
    radiance: Vec3,
    throughput: Vec3,
    /// The relative IORs crossed (Russian roulette undoes their scaling).
    eta: f32,
    /// Whether an emitter the current ray finds could also have been found
    /// by light sampling at the previous vertex, prev_p (it sampled lights
    /// and its BSDF sample was not a delta): only then is it MIS-weighted.
    prev_mis: bool,
    /// Whether the current ray is a delta lobe's sample (a mirror's or a
    /// smooth dielectric's): a pixel's such rays off neighbouring points
    /// stay alike, and the wave traces them as a packet.
    prev_delta: bool,
    prev_bsdf_pdf: f32,
    prev_bg_normal: Vec3,
    prev_p: Vec3,
}

impl PathState {
    const START: Self = Self {
        radiance: Vec3::ZERO,
        throughput: Vec3::ONE,
        eta: 1.0,
        prev_mis: false,
        prev_delta: false,
        prev_bsdf_pdf: 0.0,
        prev_bg_normal: Vec3::ZERO,
        prev_p: Vec3::ZERO,
    };
}

/// Where a path's ray arrived: the hit, its material, the point (error
/// bound `p_err`) and the direction back along the ray.
#[derive(Clone, Copy, Debug)]
struct Arrival {
    hit: crate::bvh::Hit,
    material: u32,
    p: Vec3,
    p_err: Vec3,
    wo: Vec3,
}

/// The interpolated shading frame at a hit, with the geometric normal.
#[derive(Clone, Copy, Debug)]
struct SurfaceFrame {
    ng: Vec3,
    ns: Vec3,
    frame: Frame,
    /// A normal-mapped hit on a BSDF without transmission: directions
    /// below the geometric surface are folded back above it ([`Fold`])
    /// instead of discarded.
    folds: bool,
}

impl SurfaceFrame {
    /// The fold of a BSDF here seen from `wo` (in the shading frame), where
    /// the hit folds.
    fn fold_for(&self, wo: Vec3) -> Option<Fold> {
        self.folds
            .then(|| Fold::new(self.frame.to_local(self.ng), wo))
    }
}

impl<'a> PathTracer<'a> {
    pub fn new(scene: &'a Scene, opts: &RenderOptions) -> Result<Self, RenderError> {
        validate_options(scene, opts)?;
        let camera = PinholeCamera::new(&scene_camera(scene, opts.camera), opts.width, opts.height);
        Ok(Self {
            scene,
            lights: Lights {
                sampling: opts.light_sampling,
                ..Lights::new(scene)
            },
            camera,
            max_depth: depth_limit(opts.max_depth),
            key: seed_key(opts.seed),
            nee: opts.nee,
            mis: opts.mis,
            sampler: opts.sampler,
            sample_start: opts.sample_start,
            batch: opts.batch(),
            plan: PassPlan::of(opts),
            masks: scene.textures.has_masks(),
            simd: SimdLevel::detect(),
            wide_shading: wide::LANES_IN_REGISTERS,
            wide_kinds: wide::kinds(scene),
        })
    }

    fn surface(&self, tri: u32, u: f32, v: f32) -> SurfaceFrame {
        let t = &self.scene.triangles[tri as usize];
        let ng = t.geometric_normal().normalize();
        let w = 1.0 - u - v;
        let mut ns = ng;
        // The triangle's packed shading data (Scene::set_shading).
        let mut off = (t.flags >> TRI_SHADING_SHIFT) as usize;
        let at = |k: usize| Vec3::from_slice(&self.scene.shading[k][..3]);
        if t.flags & TRI_NORMALS != 0 {
            // The shading normal lives on the geometric normal's side,
            // so the BSDF's +z is a dielectric's outside.
            let n = [at(off).into(), at(off + 1).into(), at(off + 2).into()];
            ns = wide::shading_normal::<f32>(ng.into(), n, u, v).into();
            off += 3;
        }
        let lerp = |o: usize| w * at(o) + u * at(o + 1) + v * at(o + 2);
        let frame = if t.flags & TRI_TANGENTS != 0 {
            Frame::from_normal_tangent(ns, lerp(off))
        } else {
            Frame::from_normal(ns)
        };
        SurfaceFrame {
            ng,
            ns,
            frame,
            folds: false,
        }
    }

    /// A textured material (untextured BSDF `base`) at a hit seen from
    /// `wo`: the normal map tilts the shading frame (adapted so `wo`'s
    /// mirror direction stays above the surface,
    /// [`crate::texture::valid_reflection_normal`]), the other textures set
    /// the BSDF's parameters; the BSDF is made in `textured` (returned
    /// from here, it was copied into it, 100 bytes read back wider than
    /// they were written).
    #[allow(clippy::too_many_arguments)]
    fn apply_textures<'s>(
        &self,
        mt: &MaterialTextures,
        tri: u32,
        u: f32,
        v: f32,
        wo: Vec3,
        sf: &mut SurfaceFrame,
        base: &Bsdf,
        textured: &'s mut Option<Bsdf>,
    ) -> &'s Bsdf {
        let st = &self.scene.textures;
        let unmapped = sf.frame;
        let ns = normal_mapped(st, mt, tri, u, v, sf.ng, wo, &sf.frame);
        if ns != sf.ns {
            sf.frame = Frame::from_normal_tangent(ns, sf.frame.s);
            sf.ns = ns;
        }
        let bsdf = textured.insert(textured_bsdf(st, mt, base, tri, u, v));
        sf.folds = mt.normal.is_some() && !bsdf.has_transmission();
        // The clear coat's own normal (clearcoatNormalTexture, else the
        // unmapped one), where a normal map tilts either.
        if let Bsdf::Coated { coat, .. } | Bsdf::Metallic { coat, .. } = bsdf
            && coat.clearcoat > 0.0
            && (mt.normal.is_some() || mt.clearcoat_normal.is_some())
        {
            coat.clearcoat_normal =
                clearcoat_normal(st, mt, tri, u, v, sf.ng, &unmapped, &sf.frame);
        }
        bsdf
    }

    /// The shading frame and the BSDF of material `material` at a hit on
    /// triangle `tri` seen from `wo`, its textures applied: the material's
    /// own BSDF, borrowed, where it has no textures, else the textured one,
    /// made in `textured`.
    #[inline(always)]
    fn shade<'s>(
        &'s self,
        material: u32,
        tri: u32,
        u: f32,
        v: f32,
        wo: Vec3,
        textured: &'s mut Option<Bsdf>,
    ) -> (SurfaceFrame, &'s Bsdf) {
        let mut sf = self.surface(tri, u, v);
        let base = &self.scene.materials[material as usize].bsdf;
        let bsdf = match self.scene.textures.material(material) {
            Some(mt) => self.apply_textures(mt, tri, u, v, wo, &mut sf, base, textured),
            None => base,
        };
        (sf, bsdf)
    }

    /// The shadow ray from `p` (error bound `err`, geometric normal `ng`)
    /// toward a light sample: from the offset origin to just short of the
    /// light point q ([`shadow_tmax`]).
    pub fn shadow_ray(&self, p: Vec3, err: Vec3, ng: Vec3, ls: &LightSample) -> Ray {
        let o = offset_origin(p, err, ng, ls.wi);
        if ls.dist.is_finite() {
            let q = p + ls.wi * ls.dist;
            let to = q - o;
            let len = to.length();
            Ray {
                o,
                d: to / len,
                tmax: shadow_tmax(len, q),
            }
        } else {
            Ray {
                o,
                d: ls.wi,
                tmax: f32::MAX,
            }
        }
    }

    /// Next-event estimation at a hit: the light sample `ls`'s
    /// f |cos| Le / pdf, MIS-weighted, where the shadow ray from `p` (error
    /// bound `p_err`) toward it finds nothing in the way; zero where it is
    /// blocked or f |cos| is zero (then no shadow ray is traced). Directions
    /// on different sides of the geometric and shading normals are
    /// discarded (the light-leak rule), except that a folded BSDF (`fold`)
    /// takes every direction above the geometric surface. The BSDF's
    /// density for MIS is found only for a clear shadow ray (the fold finds
    /// it with f).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn next_event(
        &self,
        ls: &LightSample,
        p: Vec3,
        p_err: Vec3,
        sf: &SurfaceFrame,
        bsdf: &BsdfAt,
        fold: Option<Fold>,
        rays: &mut u64,
    ) -> Vec3 {
        let wi_local = sf.frame.to_local(ls.wi);
        let (f, folded_pdf) = match fold {
            Some(fd) => {
                let (f, pdf) = fd.eval_pdf(bsdf, wi_local);
                (f, Some(pdf))
            }
            None if (ls.wi.dot(sf.ng) > 0.0) == (wi_local.z > 0.0) => {
                (bsdf.eval(wi_local) * wi_local.z.abs(), None)
            }
            None => (Vec3::ZERO, None),
        };
        if !(f.max_element() > 0.0) {
            return Vec3::ZERO;
        }
        *rays += 1;
        let shadow = self.shadow_ray(p, p_err, sf.ng, ls);
        if !(shadow.tmax > 0.0) || self.scene.occluded_with(&shadow, self.masks) {
            return Vec3::ZERO;
        }
        let w = if ls.delta {
            1.0
        } else {
            let pdf = folded_pdf.unwrap_or_else(|| bsdf.pdf(wi_local));
            mis_light(self.mis, ls.pdf, pdf)
        };
        f * ls.weight * w
    }

    /// One radiance sample for pixel (x, y), sample index `s`; `rays`
    /// counts camera, continuation and shadow rays.
    pub fn sample(&self, x: u32, y: u32, s: u32, rays: &mut u64) -> Vec3 {
        let pixel = y * self.camera.width + x;
        self.trace(
            x,
            y,
            PathSampler::new(self.sampler, self.key, pixel, s),
            rays,
        )
    }

    /// [`PathTracer::sample`] with its random numbers from `rng` (the
    /// sample's own, from whichever source).
    pub fn trace(&self, x: u32, y: u32, mut rng: PathSampler, rays: &mut u64) -> Vec3 {
        let mut path = PathState::START;
        let mut ray = self.camera.ray(x, y, rng.pixel_2d());
        let mut depth = 0u32;
        while let Some(at) = self.arrive(&mut path, &ray, rays) {
            if depth.saturating_add(1) >= self.max_depth {
                break;
            }
            // The fixed per-bounce budget of random numbers.
            let u = rng.bounce();
            if !self.vertex(&mut path, &mut ray, &at, None, &u, depth, rays) {
                break;
            }
            depth += 1;
        }
        path.radiance
    }

    /// The path's vertex at the hit `at`, bounce `depth`, with the
    /// bounce's numbers `u`: shade it (unless `shaded` holds its frame and
    /// BSDF, [`PathTracer::shade`]'s, found already); where it samples
    /// lights, draw the light sample, trace its shadow ray and add it;
    /// then the BSDF's sample as the path's next ray (into `ray`), and
    /// Russian roulette. False where the path ends. (Its pieces stay
    /// locals of one body: a struct carrying them between steps was
    /// copied at every vertex.)
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn vertex(
        &self,
        path: &mut PathState,
        ray: &mut Ray,
        at: &Arrival,
        shaded: Option<(&SurfaceFrame, &Bsdf)>,
        u: &crate::sobol::BounceSamples,
        depth: u32,
        rays: &mut u64,
    ) -> bool {
        let mut textured = None;
        let (sf, bsdf) = match shaded {
            Some((sf, bsdf)) => (*sf, bsdf),
            None => self.shade(
                at.material,
                at.hit.tri,
                at.hit.u,
                at.hit.v,
                at.wo,
                &mut textured,
            ),
        };
        let sf = &sf;
        let (p, wo) = (at.p, at.wo);
        let wo_local = sf.frame.to_local(wo);
        let bsdf_at = bsdf.at(wo_local);
        let fold = sf.fold_for(wo_local);
        let bg_normal = background_direction_frame(sf.ns, wo, bsdf.has_transmission());
        let sample_lights = self.nee && !self.lights.is_empty() && !bsdf.is_delta();
        if sample_lights
            && let Some(ls) =
                self.lights
                    .sample(self.scene, p, bg_normal, u.light_cat, u.light_idx, u.light)
        {
            path.radiance +=
                path.throughput * self.next_event(&ls, p, at.p_err, sf, &bsdf_at, fold, rays);
        }
        // BSDF sampling: the next ray.
        let Some((bs, wi)) = next_direction(&bsdf_at, sf, wo, fold, u.bsdf_lobe, u.bsdf) else {
            return false;
        };
        path.throughput *= bs.weight;
        path.eta *= bs.eta;
        path.prev_mis = sample_lights && !bs.delta;
        path.prev_delta = bs.delta;
        path.prev_bsdf_pdf = bs.pdf;
        path.prev_bg_normal = bg_normal;
        path.prev_p = p;
        *ray = Ray {
            o: offset_origin(p, at.p_err, sf.ng, wi),
            d: wi,
            tmax: f32::MAX,
        };
        self.roulette(path, depth + 1, u.rr)
    }

    /// Trace the path's ray `ray`: what it finds (the background or an emitter,
    /// MIS-weighted, and the medium it crossed) added to the path, and the
    /// hit it arrives at; None where it escaped.
    #[inline(always)]
    fn arrive(&self, path: &mut PathState, ray: &Ray, rays: &mut u64) -> Option<Arrival> {
        let hit = self.scene.intersect_with(ray, self.masks);
        self.arrive_at(path, ray, hit, rays)
    }

    /// [`PathTracer::arrive`] with the path's ray already traced: `hit` is
    /// what it found.
    #[inline(always)]
    fn arrive_at(
        &self,
        path: &mut PathState,
        ray: &Ray,
        hit: Option<crate::bvh::Hit>,
        rays: &mut u64,
    ) -> Option<Arrival> {
        let scene = self.scene;
        *rays += 1;
        let Some(hit) = hit else {
            if self.lights.probs.background > 0.0 {
                let w = emitter_weight(self.mis, path.prev_mis, path.prev_bsdf_pdf, || {
                    self.lights.background_pdf(path.prev_bg_normal, ray.d)
                });
                path.radiance += path.throughput * w * self.lights.background_radiance(ray.d);
            }
            return None;
        };
        let tri = &scene.triangles[hit.tri as usize];
        absorb(scene, tri, ray, hit.t, &mut path.throughput);
        let [p0, p1, p2] = tri.vertices();
        // Interpolated from the vertices: its error is bounded by
        // hit_error (see the module notes on ray offsets).
        let p = (1.0 - hit.u - hit.v) * p0 + hit.u * p1 + hit.v * p2;
        let p_err = hit_error(p0, p1, p2);
        let wo = -ray.d;

        if tri.light != NO_LIGHT
            && let Some(le) = emitted(scene, hit.tri, hit.u, hit.v, wo)
        {
            let w = emitter_weight(self.mis, path.prev_mis, path.prev_bsdf_pdf, || {
                self.lights
                    .area_pdf(scene, hit.tri, path.prev_p, ray.d, hit.t)
            });
            path.radiance += path.throughput * w * le;
        }
        Some(Arrival {
            hit,
            material: tri.material,
            p,
            p_err,
            wo,
        })
    }

    /// Russian roulette after `depth` bounces, with the bounce's number
    /// `rr`; false where the path ends (or carries nothing).
    #[inline(always)]
    fn roulette(&self, path: &mut PathState, depth: u32, rr: f32) -> bool {
        if depth >= RR_DEPTH {
            let q = (path.throughput.max_element() * path.eta * path.eta).min(RR_MAX_PROB);
            if !(rr < q) {
                return false;
            }
            path.throughput /= q;
        }
        path.throughput.max_element() > 0.0
    }

    /// Render every pixel with sample indices from `sample_start`, `spp` of
    /// them, in the passes of the render's [`PassPlan`] (one pass for a
    /// plain render; see [`crate::schedule`]); a controlled render samples
    /// only the pixels its control keeps active and keeps per-pixel counts.
    /// `progress(done, total)` counts finished tiles over all `spp` (for a
    /// controlled render, samples over the cap).
    pub fn render(&self, spp: u32, progress: &(dyn Fn(u32, u32) + Sync)) -> (Film, RenderStats) {
        let start = Instant::now();
        let plan = PassPlan { spp, ..self.plan };
        let (w, h) = (self.camera.width, self.camera.height);
        let tiles = w.div_ceil(TILE) * h.div_ceil(TILE);
        let mut film = Film::with_batch(w, h, self.batch);
        let mut active = vec![1u32; film.sum.len()];
        let mut rays = 0u64;
        let mut schedule = Schedule::new(plan, Pacing::Whole);
        while let Some(count) = schedule.next() {
            let pass_start = Instant::now();
            let controlled = schedule.control().is_some();
            let adaptive = schedule.control().is_some_and(|c| c.adaptive.is_some());
            let mask = adaptive.then_some(&active[..]);
            let base = film.spp * tiles;
            let total = spp.saturating_mul(tiles);
            let tile_progress = |done: u32, _| {
                if !controlled {
                    progress(base + done * count, total)
                }
            };
            rays += self.render_pass(&mut film, count, mask, &tile_progress);
            if adaptive {
                film.spp -= count;
                crate::adaptive::count_pass(&mut film, &active, count);
            }
            let more = match schedule.control() {
                Some(c) => {
                    progress(film.spp, c.cap);
                    c.decide(&film, &mut active)
                }
                None => true,
            };
            schedule.passed(pass_start.elapsed().as_secs_f64(), more);
        }
        let stats = RenderStats {
            rays,
            render_seconds: start.elapsed().as_secs_f64(),
        };
        (film, stats)
    }

    /// Add `count` more samples to every pixel of `film` (the indices
    /// after the ones it holds), continuing each pixel's running sums in
    /// sample order so that the image does not depend on the pass sizes;
    /// with `active`, only to the pixels whose entry is not 0.
    /// Returns the rays traced.
    pub fn render_pass(
        &self,
        film: &mut Film,
        count: u32,
        active: Option<&[u32]>,
        progress: &(dyn Fn(u32, u32) + Sync),
    ) -> u64 {
        let (w, h) = (self.camera.width, self.camera.height);
        let tiles_x = w.div_ceil(TILE);
        let tiles_y = h.div_ceil(TILE);
        let total = tiles_x * tiles_y;
        let done = AtomicU32::new(0);
        let first = self.sample_start + film.spp;
        let prior: &Film = film;
        let tiles: Vec<TileResult> = (0..total)
            .into_par_iter()
            .map(|ti| {
                let (x0, y0) = ((ti % tiles_x) * TILE, (ti / tiles_x) * TILE);
                let mut rays = 0u64;
                let mut batch = SampleBatch::new(self.simd);
                let mut px = Vec::with_capacity((TILE * TILE) as usize);
                for y in y0..(y0 + TILE).min(h) {
                    for x in x0..(x0 + TILE).min(w) {
                        let i = prior.index(x, y);
                        let mut sum = prior.sum[i];
                        let mut sum_sq = prior.sum_sq[i];
                        let mut run = prior.batch_run[i];
                        let mut sq = prior.batch_sq[i];
                        let n = if active.is_some_and(|a| a[i] == 0) {
                            0
                        } else {
                            count
                        };
                        let pixel = y * w + x;
                        let mut wave = [Vec3::ZERO; 8];
                        for s in first..first + n {
                            // Eight samples side by side (for Sobol, their
                            // numbers eight per instruction).
                            let k = ((s - first) % 8) as usize;
                            if k == 0 {
                                let m = (first + n - s).min(8);
                                let rng = match self.sampler {
                                    SamplerKind::Sobol => {
                                        batch.reset(self.key, pixel, s);
                                        WaveSampler::Batch(&mut batch)
                                    }
                                    SamplerKind::Independent => {
                                        WaveSampler::Paths(std::array::from_fn(|j| {
                                            let j = s.wrapping_add(j as u32);
                                            PathSampler::new(self.sampler, self.key, pixel, j)
                                        }))
                                    }
                                };
                                wave = self.trace_wave(x, y, rng, m as usize, &mut rays);
                            }
                            let mut l = wave[k];
                            // A NaN or infinity (a degenerate pdf somewhere)
                            // would poison the pixel for good: drop it.
                            if !l.is_finite() {
                                l = Vec3::ZERO;
                            }
                            add_sample(prior.batch, s, l, &mut sum, &mut sum_sq, &mut run, &mut sq);
                        }
                        px.push([sum, sum_sq, run, sq]);
                    }
                }
                progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
                (ti, px, rays)
            })
            .collect();
        let mut rays = 0u64;
        for (ti, px, r) in tiles {
            rays += r;
            let (x0, y0) = ((ti % tiles_x) * TILE, (ti / tiles_x) * TILE);
            let mut k = 0;
            for y in y0..(y0 + TILE).min(h) {
                for x in x0..(x0 + TILE).min(w) {
                    let i = film.index(x, y);
                    [
                        film.sum[i],
                        film.sum_sq[i],
                        film.batch_run[i],
                        film.batch_sq[i],
                    ] = px[k];
                    k += 1;
                }
            }
        }
        film.spp += count;
        rays
    }
}

/// Render `scene` on the CPU: the reference the GPU must match.
pub fn render(
    scene: &Scene,
    opts: &RenderOptions,
    progress: &(dyn Fn(u32, u32) + Sync),
) -> Result<(Film, RenderStats), RenderError> {
    let pt = PathTracer::new(scene, opts)?;
    Ok(pt.render(opts.spp, progress))
}
