//! The emitter set for next-event estimation: emissive triangles, punctual
//! lights and the constant background, with their GPU layouts.
//!
//! Choosing a light (mirrored in `shaders/integrator/lights.glsl`):
//! 1. a category, uniformly among those present: area emitters (any emissive
//!    triangle), punctual lights (any KHR_lights_punctual light), the
//!    background (when not black). Uniform, because powers of an infinite
//!    background, a directional irradiance and a finite emitter are not
//!    comparable without scene-dependent guesses;
//! 2. within the area emitters, one triangle with probability proportional
//!    to its power, luminance(emission) x area (x 2 when double-sided; by
//!    area alone if every emitter has zero luminance) (a CDF), then a point
//!    on it: uniformly in the solid angle it subtends from the shading
//!    point when that is within [`SPHERICAL_SAMPLING_MIN`,
//!    `SPHERICAL_SAMPLING_MAX`] and the triangle is no sliver from there
//!    ([`spherical_sampling_angle`]; Arvo 1995, [`crate::spherical`]),
//!    p = P(category) P(triangle) / omega, else uniformly by area, the
//!    area density converted to solid angle,
//!    p = P(category) P(triangle) / area * d^2 / |cos theta_light|;
//!    within the punctual lights, one uniformly (delta lights: no MIS);
//!    the background is sampled in direction space (see
//!    [`background_direction_frame`]); an environment map (`--envmap`)
//!    replaces it and is sampled by its own 2D distribution
//!    ([`crate::envmap`]).
//!
//! Every light sample draws exactly four uniform numbers (category, index,
//! 2D position), whatever is chosen, so the GPU consumes the same stream.

// `!(x > 0.0)` on floats is meant: it rejects NaN too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use glam::{Vec2, Vec3};

use crate::envmap::EnvMap;
use crate::film::LightSampling;
use crate::lanes::{Lane, V2, V3};
use crate::sampling::{UNIFORM_SPHERE_PDF, cosine_hemisphere_pdf, sample_cdf};
use crate::scene::{PunctualLight, Scene, TRI_DOUBLE_SIDED};
use crate::texture::emission_factor;

/// Rec. 709 / sRGB luminance.
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

use crate::abi;
pub use crate::abi::{
    GpuEmitter, GpuLight, SOLID_ANGLE_BOUND_MARGIN, SPHERICAL_SAMPLING_HEIGHT,
    SPHERICAL_SAMPLING_MAX, SPHERICAL_SAMPLING_MIN, SPHERICAL_SAMPLING_SHAPE,
};

impl GpuEmitter {
    /// Emitter `tri` (vertices `v`) with its power distribution entry.
    pub fn new(tri: u32, v: [Vec3; 3], cdf: f32, pmf: f32) -> Self {
        let c = (v[0] + v[1] + v[2]) / 3.0;
        let r2 = (v[0] - c)
            .length_squared()
            .max((v[1] - c).length_squared())
            .max((v[2] - c).length_squared());
        GpuEmitter {
            tri,
            cdf,
            pmf,
            area: 0.5 * (v[1] - v[0]).cross(v[2] - v[0]).length(),
            center: c.into(),
            radius: r2.sqrt(),
        }
    }
}

/// The solid angle emitter triangle `v` (emitter entry `e`) subtends from
/// `p` when light sampling picks its point by solid angle there (between
/// [`SPHERICAL_SAMPLING_MIN`] and [`SPHERICAL_SAMPLING_MAX`], not a sliver:
/// shape at least [`SPHERICAL_SAMPLING_SHAPE`], and off its plane: height at
/// least [`SPHERICAL_SAMPLING_HEIGHT`]), `None` when by area. A pure
/// function of the triangle and the point, so a BSDF sample that hits the
/// triangle finds the density the light sample used.
#[inline]
pub fn spherical_sampling_angle(v: [Vec3; 3], e: &GpuEmitter, p: Vec3) -> Option<f32> {
    let p = V3::from(p);
    let (far, d_min) = lanes::far(Vec3::from(e.center).into(), e.radius, e.area, p);
    if far {
        return None;
    }
    let n = (v[1] - v[0]).cross(v[2] - v[0]);
    let (ok, omega) = lanes::near_angle(v.map(V3::from), n.into(), p, d_min);
    ok.then_some(omega)
}

/// Light sampling's emitter math over any [`crate::lanes::Lane`] type: one
/// source with the scalar forms ([`spherical_sampling_angle`],
/// [`Lights::sample_emitter_lanes`]), their one-lane instantiation bit for
/// bit.
pub mod lanes {
    use super::{
        SOLID_ANGLE_BOUND_MARGIN, SPHERICAL_SAMPLING_HEIGHT, SPHERICAL_SAMPLING_MAX,
        SPHERICAL_SAMPLING_MIN, SPHERICAL_SAMPLING_SHAPE,
    };
    use crate::lanes::{Lane, V3};
    use crate::spherical::lanes::spherical_triangle_shape;

    /// [`super::background_direction_frame`] over lanes.
    #[inline(always)]
    pub fn background_direction_frame<L: Lane>(ns: V3<L>, wo: V3<L>, transmits: bool) -> V3<L> {
        if transmits {
            V3::splat(glam::Vec3::ZERO)
        } else {
            V3::select(ns.dot(wo).ge(L::zero()), ns, -ns)
        }
    }

    /// [`super::spot_falloff`] over lanes.
    #[inline(always)]
    pub fn spot_falloff<L: Lane>(cos_angle: L, cos_inner: L, cos_outer: L) -> L {
        let scale = L::one() / (cos_inner - cos_outer).max(L::splat(0.001));
        let t = ((cos_angle - cos_outer) * scale).clamp(0.0, 1.0);
        t * t
    }

    /// [`super::spherical_sampling_angle`]'s first exit: the emitter
    /// (centroid `center`, bounding radius `radius`, area `area`) is far
    /// for its size from `p`: omega <= area / d_min^2, and d_min >= the
    /// distance to the centroid less the bounding radius. Exact as a
    /// bound, it spares most light samples the solid angle. Returns the
    /// mask and that d_min (for [`near_angle`]'s tighter bound).
    #[inline(always)]
    pub fn far<L: Lane>(center: V3<L>, radius: L, area: L, p: V3<L>) -> (L::Mask, L) {
        let d2 = (p - center).length_squared();
        let d_min = d2.sqrt() - radius;
        let far =
            d2.gt(radius * radius) & area.lt(L::splat(SPHERICAL_SAMPLING_MIN) * d_min * d_min);
        (far, d_min)
    }

    /// The rest of [`super::spherical_sampling_angle`] for an emitter
    /// that is not [`far`] (`n`: (v1 - v0) x (v2 - v0), the triangle's
    /// geometric normal; `d_min`: [`far`]'s bound on the distance to it):
    /// whether it is sampled by solid angle from `p`, and the solid
    /// angle where it is.
    #[inline(always)]
    pub fn near_angle<L: Lane>(v: [V3<L>; 3], n: V3<L>, p: V3<L>, d_min: L) -> (L::Mask, L) {
        // Nearly in the triangle's plane (height over the farthest
        // vertex's distance): the sampled directions graze the plane, where
        // f32 loses the point they hit.
        let far2 = (v[0] - p)
            .length_squared()
            .max((v[1] - p).length_squared())
            .max((v[2] - p).length_squared());
        let height = n.dot(p - v[0]).abs();
        let n_len = n.length();
        let high = height.ge(L::splat(SPHERICAL_SAMPLING_HEIGHT) * n_len * far2.sqrt());
        // Too small for its height: every point of the plane at distance
        // r subtends cos / r^2 = h / r^3 per area, so
        // omega <= h area / d^3 = height / (2 d^3) for any d <= r over the
        // triangle (`height` is h |n| and area |n| / 2): here the larger of
        // the plane's distance h and `d_min`. Where that is under the
        // minimum, with SOLID_ANGLE_BOUND_MARGIN for the rounding of
        // omega's own formula, the test below would fail: the same
        // decisions without the solid angle.
        let h = L::select(n_len.gt(L::zero()), height / n_len, L::zero());
        let d = h.max(d_min);
        let small = d.gt(L::zero())
            & height.lt(
                L::splat(2.0 * SPHERICAL_SAMPLING_MIN * (1.0 - SOLID_ANGLE_BOUND_MARGIN))
                    * (d * d * d),
            );
        let want = high & !small;
        if L::none(want) {
            return (want, L::zero());
        }
        let (omega, shape) = spherical_triangle_shape(v, p);
        let ok = want
            & omega.ge(L::splat(SPHERICAL_SAMPLING_MIN))
            & omega.le(L::splat(SPHERICAL_SAMPLING_MAX))
            & shape.ge(L::splat(SPHERICAL_SAMPLING_SHAPE));
        (ok, omega)
    }
}

/// What an emitter sends, found once for [`emission_lanes`]: its
/// material's emission (emissive: `Scene::assign_emitters` makes emitters
/// of emissive triangles only), the triangle's two sides, and whether a
/// texture scales the emission (then it is looked up per lane,
/// [`emitted_facing`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct EmitterRadiance {
    le: Vec3,
    two_sided: bool,
    textured: bool,
}

impl EmitterRadiance {
    fn new(scene: &Scene, tri: u32) -> Self {
        let t = &scene.triangles[tri as usize];
        let m = &scene.materials[t.material as usize];
        debug_assert!(m.is_emissive());
        Self {
            le: m.emission,
            two_sided: t.flags & TRI_DOUBLE_SIDED != 0,
            textured: scene
                .textures
                .material(t.material)
                .is_some_and(|mt| mt.emissive.is_some()),
        }
    }
}

/// The radiance each lane's emitter (`ems`, what they send `rad`,
/// geometric normals `ng`) sends from barycentrics `b` toward -`wi` where
/// `valid`: where it sends any, and that radiance (zero elsewhere). The
/// same numbers as [`emitted_facing`] lane by lane (an untextured
/// emission's factor is one); without textures, in lanes.
#[inline(always)]
fn emission_lanes<L: Lane>(
    scene: &Scene,
    ems: &[GpuEmitter; 8],
    rad: &[EmitterRadiance; 8],
    ng: V3<L>,
    valid: L::Mask,
    b: V2<L>,
    wi: V3<L>,
) -> (L::Mask, V3<L>) {
    let front = ng.dot(-wi).gt(L::zero());
    if !rad[..L::LANES].iter().any(|r| r.textured) {
        let flag = |f: fn(&EmitterRadiance) -> bool| {
            L::from_fn(|l| if f(&rad[l]) { 1.0 } else { 0.0 }).gt(L::zero())
        };
        let sends = valid & (front | flag(|r| r.two_sided));
        let le = V3::new(
            L::from_fn(|l| rad[l].le.x),
            L::from_fn(|l| rad[l].le.y),
            L::from_fn(|l| rad[l].le.z),
        );
        return (sends, V3::select(sends, le, V3::splat(Vec3::ZERO)));
    }
    let mut le = [Vec3::ZERO; 8];
    let emits = L::from_fn(|l| {
        let e = L::mask_lane(valid, l)
            .then(|| {
                let front = L::mask_lane(front, l);
                emitted_facing(scene, ems[l].tri, b.x.lane(l), b.y.lane(l), front)
            })
            .flatten();
        le[l] = e.unwrap_or(Vec3::ZERO);
        if e.is_some() { 1.0 } else { 0.0 }
    });
    let le = V3::new(
        L::from_fn(|l| le[l].x),
        L::from_fn(|l| le[l].y),
        L::from_fn(|l| le[l].z),
    );
    (valid & emits.gt(L::zero()), le)
}

/// Light samples in lanes ([`Lights::sample_emitter_lanes`],
/// [`Lights::sample_punctual_lanes`],
/// [`Lights::sample_constant_background_lanes`]): where each is valid, its
/// direction, distance, radiance (or intensity) / pdf and density.
#[derive(Clone, Copy, Debug)]
pub struct EmitterSamples<L: Lane> {
    pub valid: L::Mask,
    pub wi: V3<L>,
    pub dist: L,
    pub weight: V3<L>,
    pub pdf: L,
}

impl<L: Lane> EmitterSamples<L> {
    /// `t`'s samples in the lanes of `m`, this one's in the others.
    #[inline(always)]
    pub fn select(self, m: L::Mask, t: Self) -> Self {
        Self {
            valid: L::select_mask(m, t.valid, self.valid),
            wi: V3::select(m, t.wi, self.wi),
            dist: L::select(m, t.dist, self.dist),
            weight: V3::select(m, t.weight, self.weight),
            pdf: L::select(m, t.pdf, self.pdf),
        }
    }

    /// Lane `i`'s sample, where it is valid.
    #[inline(always)]
    pub fn lane(&self, i: usize) -> Option<LightSample> {
        L::mask_lane(self.valid, i).then(|| LightSample {
            wi: self.wi.lane(i),
            dist: self.dist.lane(i),
            weight: self.weight.lane(i),
            pdf: self.pdf.lane(i),
            delta: false,
        })
    }
}

impl From<&PunctualLight> for GpuLight {
    fn from(l: &PunctualLight) -> Self {
        match *l {
            PunctualLight::Point {
                position,
                intensity,
            } => GpuLight {
                position: position.into(),
                kind: abi::LIGHT_POINT,
                intensity: intensity.into(),
                ..Default::default()
            },
            PunctualLight::Spot {
                position,
                direction,
                intensity,
                inner_cone_angle,
                outer_cone_angle,
            } => GpuLight {
                position: position.into(),
                kind: abi::LIGHT_SPOT,
                direction: direction.normalize_or(Vec3::NEG_Z).into(),
                cos_outer: outer_cone_angle.cos(),
                intensity: intensity.into(),
                cos_inner: inner_cone_angle.cos(),
            },
            PunctualLight::Directional {
                direction,
                irradiance,
            } => GpuLight {
                kind: abi::LIGHT_DIRECTIONAL,
                direction: direction.normalize_or(Vec3::NEG_Z).into(),
                intensity: irradiance.into(),
                ..Default::default()
            },
        }
    }
}

/// Each lane's `f` of its light `ls[l]`, or of `ls[0]` splat across the
/// lanes where the scene has `one` light ([`Lights::sample_punctual_lanes`]).
#[inline(always)]
fn per_light<L: Lane>(ls: &[GpuLight; 8], one: bool, f: impl Fn(&GpuLight) -> f32) -> L {
    if one {
        L::splat(f(&ls[0]))
    } else {
        L::from_fn(|l| f(&ls[l]))
    }
}

/// KHR_lights_punctual's spot attenuation: a linear ramp in cos(angle) from
/// the outer cone (0) to the inner cone (1), squared (the spec's sample
/// implementation, with its 0.001 guard on the ramp width).
pub fn spot_falloff(cos_angle: f32, cos_inner: f32, cos_outer: f32) -> f32 {
    lanes::spot_falloff(cos_angle, cos_inner, cos_outer)
}

/// Probabilities of the three light categories (sum 1, or all 0 when the
/// scene has no light at all).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CategoryProbs {
    pub area: f32,
    pub punctual: f32,
    pub background: f32,
}

/// A light sample seen from a shading point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Unit direction from the shading point toward the light.
    pub wi: Vec3,
    /// Distance to the sampled point (f32::INFINITY for directional and
    /// background samples).
    pub dist: f32,
    /// Incident radiance (area, background) or radiance-equivalent
    /// (punctual: I falloff / d^2, or E) divided by the sampling density.
    pub weight: Vec3,
    /// Solid-angle density including the category choice, for MIS; zero
    /// for delta lights.
    pub pdf: f32,
    pub delta: bool,
}

/// The emitters of a scene, ready to sample.
#[derive(Clone, Debug, Default)]
pub struct Lights {
    pub emitters: Vec<GpuEmitter>,
    /// What each emitter sends (the CPU's; the GPU reads the triangle's
    /// material).
    pub radiance: Vec<EmitterRadiance>,
    pub punctual: Vec<GpuLight>,
    pub background: Vec3,
    /// The environment map, when there is one: it is the background.
    pub envmap: Option<std::sync::Arc<EnvMap>>,
    pub probs: CategoryProbs,
    /// How a point on an emissive triangle is picked (solid angle where it
    /// pays, the default, or area everywhere).
    pub sampling: LightSampling,
}

impl Lights {
    pub fn new(scene: &Scene) -> Self {
        let tris = scene.emitter_triangles();
        let powers: Vec<f64> = tris
            .iter()
            .map(|&i| {
                let t = &scene.triangles[i as usize];
                let m = &scene.materials[t.material as usize];
                let sides = if t.flags & TRI_DOUBLE_SIDED != 0 {
                    2.0
                } else {
                    1.0
                };
                luminance(m.emission).max(0.0) as f64 * t.area() as f64 * sides
            })
            .collect();
        let mut total: f64 = powers.iter().sum();
        // A coloured emitter can have zero luminance (pure blue is not, but
        // guard anyway): fall back to area alone so it is still sampled.
        let powers: Vec<f64> = if total > 0.0 {
            powers
        } else {
            let p: Vec<f64> = tris
                .iter()
                .map(|&i| scene.triangles[i as usize].area() as f64)
                .collect();
            total = p.iter().sum();
            p
        };
        let mut acc = 0.0f64;
        let mut emitters: Vec<GpuEmitter> = tris
            .iter()
            .zip(&powers)
            .map(|(&tri, &p)| {
                acc += p;
                let v = scene.triangles[tri as usize].vertices();
                GpuEmitter::new(tri, v, (acc / total) as f32, (p / total) as f32)
            })
            .collect();
        if let Some(last) = emitters.last_mut() {
            last.cdf = 1.0;
        }
        let punctual: Vec<GpuLight> = scene.lights.iter().map(GpuLight::from).collect();
        let has_bg = scene.background.max_element() > 0.0 || scene.envmap.is_some();
        let present = [!emitters.is_empty(), !punctual.is_empty(), has_bg];
        let n = present.iter().filter(|&&b| b).count();
        let p = if n > 0 { 1.0 / n as f32 } else { 0.0 };
        let probs = CategoryProbs {
            area: if present[0] { p } else { 0.0 },
            punctual: if present[1] { p } else { 0.0 },
            background: if present[2] { p } else { 0.0 },
        };
        let radiance = emitters
            .iter()
            .map(|e| EmitterRadiance::new(scene, e.tri))
            .collect();
        Self {
            emitters,
            radiance,
            punctual,
            background: scene.background,
            envmap: scene.envmap.clone(),
            probs,
            sampling: LightSampling::default(),
        }
    }

    /// The solid angle by which emitter `e` (triangle `v`) is sampled from
    /// `p`, `None` where by area: [`spherical_sampling_angle`] under
    /// [`LightSampling::SolidAngle`], always `None` under
    /// [`LightSampling::Area`].
    #[inline]
    fn sampling_angle(&self, v: [Vec3; 3], e: &GpuEmitter, p: Vec3) -> Option<f32> {
        match self.sampling {
            LightSampling::SolidAngle => spherical_sampling_angle(v, e, p),
            LightSampling::Area => None,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.probs.area + self.probs.punctual + self.probs.background == 0.0
    }

    /// Sample a light from shading point `p`. `bg_normal` is the axis of
    /// the background's cosine lobe, or zero for uniform sphere sampling
    /// (see [`background_direction_frame`]). `u_cat`, `u_idx`, `u` are the
    /// four uniform numbers the sample consumes. `None`: the chosen light
    /// sends nothing toward `p` (back face, outside a spot cone).
    #[inline]
    pub fn sample(
        &self,
        scene: &Scene,
        p: Vec3,
        bg_normal: Vec3,
        u_cat: f32,
        u_idx: f32,
        u: Vec2,
    ) -> Option<LightSample> {
        let pr = self.probs;
        if u_cat < pr.area {
            self.sample_emitter(scene, p, u_idx, u)
        } else if u_cat < pr.area + pr.punctual {
            self.sample_punctual(p, u_idx)
        } else if pr.background > 0.0 {
            self.sample_background(bg_normal, u)
        } else {
            None
        }
    }

    /// An emissive triangle by power (`u_idx`), a point on it (`u`) by
    /// solid angle or by area ([`spherical_sampling_angle`]).
    #[inline]
    fn sample_emitter(&self, scene: &Scene, p: Vec3, u_idx: f32, u: Vec2) -> Option<LightSample> {
        self.sample_emitter_lanes::<f32>(scene, p.into(), u_idx, u.into(), true)
            .lane(0)
    }

    /// [`Self::sample_emitter`] in every lane of `live` (the others are
    /// not valid): the triangles (a search of the power CDF), their
    /// vertices and their emission gathered lane by lane, the rest in
    /// lanes. The scalar form is its one-lane instantiation.
    #[inline(always)]
    pub fn sample_emitter_lanes<L: Lane>(
        &self,
        scene: &Scene,
        p: V3<L>,
        u_idx: L,
        u: V2<L>,
        live: L::Mask,
    ) -> EmitterSamples<L> {
        const { assert!(L::LANES <= 8) };
        let pr = self.probs;
        let n = self.emitters.len() as u32;
        let mut idx = [0u32; 8];
        for (l, i) in idx.iter_mut().enumerate().take(L::LANES) {
            *i = sample_cdf(|k| self.emitters[k as usize].cdf, n, u_idx.lane(l));
        }
        // Each lane's emitter and triangle, copied once.
        let ems: [GpuEmitter; 8] = std::array::from_fn(|l| {
            if l < L::LANES {
                self.emitters[idx[l] as usize]
            } else {
                GpuEmitter::default()
            }
        });
        let tris: [crate::scene::Triangle; 8] = std::array::from_fn(|l| {
            if l < L::LANES {
                scene.triangles[ems[l].tri as usize]
            } else {
                crate::scene::Triangle::default()
            }
        });
        let em = |l: usize| &ems[l];
        let gather = |f: fn(&crate::scene::Triangle, &GpuEmitter) -> [f32; 3]| {
            let w: [[f32; 3]; 8] = std::array::from_fn(|l| f(&tris[l], &ems[l]));
            V3::new(
                L::from_fn(|l| w[l][0]),
                L::from_fn(|l| w[l][1]),
                L::from_fn(|l| w[l][2]),
            )
        };
        let v = [
            gather(|t, _| t.p0),
            gather(|t, _| t.p1),
            gather(|t, _| t.p2),
        ];
        // The geometric normal, once for the solid angle's test, the
        // emitting side and the density by area.
        let ng = (v[1] - v[0]).cross(v[2] - v[0]);
        let e_area = L::from_fn(|l| em(l).area);
        let pmf = L::from_fn(|l| em(l).pmf);
        let far = || {
            let center = gather(|_, e| e.center);
            lanes::far(center, L::from_fn(|l| em(l).radius), e_area, p)
        };
        let (found, b, solid, omega) = self.emitter_point(v, ng, far, p, u, live);
        let q = v[0].scale(L::one() - b.x - b.y) + v[1].scale(b.x) + v[2].scale(b.y);
        let d = q - p;
        let dist2 = d.length_squared();
        let dist = dist2.sqrt();
        let wi = d / dist;
        let rad: [EmitterRadiance; 8] = std::array::from_fn(|l| {
            if l < L::LANES {
                self.radiance[idx[l] as usize]
            } else {
                EmitterRadiance::default()
            }
        });
        let (emits, le) = emission_lanes(scene, &ems, &rad, ng, found & dist.gt(L::zero()), b, wi);
        let mut valid = emits;
        let area_p = L::splat(pr.area);
        let pdf_by_area = || {
            let cos_l = ng.normalize().dot(-wi).abs();
            area_p * pmf / e_area * dist2 / cos_l
        };
        let pdf = if L::all(solid) {
            area_p * pmf / omega
        } else if L::none(solid) {
            pdf_by_area()
        } else {
            L::select(solid, area_p * pmf / omega, pdf_by_area())
        };
        valid = valid & pdf.gt(L::zero()) & pdf.abs().lt(L::splat(f32::INFINITY));
        EmitterSamples {
            valid,
            wi,
            dist,
            weight: le / pdf,
            pdf,
        }
    }

    /// The point of each lane's emitter sample on triangle `v` (geometric
    /// normal `ng`) ([`Self::sample_emitter_lanes`]): by solid angle where it pays
    /// ([`spherical_sampling_angle`], `far` its first exit), else uniformly
    /// by area. Where the point stands (among `live`), its barycentrics,
    /// and where it went by solid angle, with the solid angle.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn emitter_point<L: Lane>(
        &self,
        v: [V3<L>; 3],
        ng: V3<L>,
        far: impl FnOnce() -> (L::Mask, L),
        p: V3<L>,
        u: V2<L>,
        live: L::Mask,
    ) -> (L::Mask, V2<L>, L::Mask, L) {
        let no = L::zero().lt(L::zero());
        let (solid, omega) = if self.sampling == LightSampling::Area {
            (no, L::zero())
        } else {
            let (far, d_min) = far();
            let near = live & !far;
            if L::none(near) {
                (no, L::zero())
            } else {
                let (ok, omega) = lanes::near_angle(v, ng, p, d_min);
                (ok & near, omega)
            }
        };
        let by_area = crate::sampling::lanes::square_to_uniform_triangle(u);
        if L::none(solid) {
            return (live, by_area, solid, omega);
        }
        let (found, by_angle) = crate::spherical::lanes::sample_spherical_triangle(v, p, omega, u);
        let b = V2 {
            x: L::select(solid, by_angle.x, by_area.x),
            y: L::select(solid, by_angle.y, by_area.y),
        };
        (live & L::select_mask(solid, found, !no), b, solid, omega)
    }

    /// A punctual light, uniformly (`u_idx`).
    #[inline]
    fn sample_punctual(&self, p: Vec3, u_idx: f32) -> Option<LightSample> {
        let s = self.sample_punctual_lanes::<f32>(p.into(), u_idx, true);
        s.lane(0).map(|s| LightSample { delta: true, ..s })
    }

    /// [`Self::sample_punctual`] in every lane of `live` (the others are
    /// not valid; every valid sample is a delta): each lane's light
    /// gathered (splat where the scene has one), the rest in lanes. The
    /// scalar form is its one-lane instantiation.
    #[inline(always)]
    pub fn sample_punctual_lanes<L: Lane>(
        &self,
        p: V3<L>,
        u_idx: L,
        live: L::Mask,
    ) -> EmitterSamples<L> {
        const { assert!(L::LANES <= 8) };
        let n = self.punctual.len();
        let sel = self.probs.punctual / n as f32;
        let one = n == 1;
        let ls: [GpuLight; 8] = std::array::from_fn(|l| {
            if l < L::LANES && !one {
                self.punctual[((u_idx.lane(l) * n as f32) as usize).min(n - 1)]
            } else {
                self.punctual[0]
            }
        });
        let scalar = |f: fn(&GpuLight) -> f32| per_light::<L>(&ls, one, f);
        let vector = |f: fn(&GpuLight) -> [f32; 3]| {
            V3::new(
                per_light(&ls, one, |g| f(g)[0]),
                per_light(&ls, one, |g| f(g)[1]),
                per_light(&ls, one, |g| f(g)[2]),
            )
        };
        let kind =
            |k: u32| per_light::<L>(&ls, one, |g| f32::from(u8::from(g.kind == k))).gt(L::zero());
        let directional = kind(abi::LIGHT_DIRECTIONAL);
        let intensity = vector(|g| g.intensity);
        let mut wi = -vector(|g| g.direction);
        let mut dist = L::splat(f32::INFINITY);
        let mut li = intensity;
        if !L::all(directional) {
            let d = vector(|g| g.position) - p;
            let dist2 = d.length_squared();
            let near = dist2.sqrt();
            let to = d / near;
            let mut falls = intensity / dist2;
            let spot = kind(abi::LIGHT_SPOT);
            if !L::none(spot) {
                let cos_a = vector(|g| g.direction).dot(-to);
                let f =
                    lanes::spot_falloff(cos_a, scalar(|g| g.cos_inner), scalar(|g| g.cos_outer));
                falls = V3::select(spot, falls.scale(f), falls);
            }
            wi = V3::select(directional, wi, to);
            dist = L::select(directional, dist, near);
            li = V3::select(directional, li, falls);
        }
        let valid = live & (directional | dist.gt(L::zero())) & !li.max_element().le(L::zero());
        EmitterSamples {
            valid,
            wi,
            dist,
            weight: li / L::splat(sel),
            pdf: L::zero(),
        }
    }

    /// The environment map by its distribution, or the constant background
    /// (cosine lobe about `bg_normal`, or the uniform sphere).
    #[inline]
    fn sample_background(&self, bg_normal: Vec3, u: Vec2) -> Option<LightSample> {
        let pr = self.probs;
        if let Some(env) = &self.envmap {
            let es = env.sample(u)?;
            let pdf = pr.background * es.pdf;
            return Some(LightSample {
                wi: es.wi,
                dist: f32::INFINITY,
                weight: es.radiance / pdf,
                pdf,
                delta: false,
            });
        }
        self.sample_constant_background_lanes::<f32>(bg_normal.into(), u.into(), true)
            .lane(0)
    }

    /// The constant background's samples ([`Self::sample_background`]
    /// without an environment map) in every lane of `live` (the others are
    /// not valid): about `bg_normal` by the cosine, or over the sphere
    /// where it is zero. The scalar form is its one-lane instantiation.
    #[inline(always)]
    pub fn sample_constant_background_lanes<L: Lane>(
        &self,
        bg_normal: V3<L>,
        u: V2<L>,
        live: L::Mask,
    ) -> EmitterSamples<L> {
        let zero = L::zero();
        let sphere = bg_normal.x.eq(zero) & bg_normal.y.eq(zero) & bg_normal.z.eq(zero);
        let (mut wi, mut dir_pdf) = (V3::splat(Vec3::ZERO), zero);
        if !L::all(sphere) {
            let local = crate::bsdf::warp::lanes::square_to_cosine_hemisphere(u);
            wi = crate::frame::lanes::Frame::from_normal(bg_normal).to_world(local);
            dir_pdf = crate::sampling::lanes::cosine_hemisphere_pdf(local.z);
        }
        if !L::none(sphere) {
            let on_sphere = crate::sampling::lanes::square_to_uniform_sphere(u);
            wi = V3::select(sphere, on_sphere, wi);
            dir_pdf = L::select(sphere, L::splat(UNIFORM_SPHERE_PDF), dir_pdf);
        }
        let pdf = L::splat(self.probs.background) * dir_pdf;
        EmitterSamples {
            valid: live & pdf.gt(zero),
            wi,
            dist: L::splat(f32::INFINITY),
            weight: V3::splat(self.background) / pdf,
            pdf,
        }
    }

    /// Solid-angle density with which [`Lights::sample`], called at `p`,
    /// picks the point `dist` away along `wi` on emitter triangle `tri` (for
    /// MIS of a BSDF sample from `p` that hit it).
    pub fn area_pdf(&self, scene: &Scene, tri: u32, p: Vec3, wi: Vec3, dist: f32) -> f32 {
        let t = &scene.triangles[tri as usize];
        let e = self.emitters[t.light as usize];
        if let Some(omega) = self.sampling_angle(t.vertices(), &e, p) {
            return self.probs.area * e.pmf / omega;
        }
        let cos_l = t.geometric_normal().normalize().dot(wi).abs();
        if !(cos_l > 0.0) {
            return 0.0;
        }
        self.probs.area * e.pmf / e.area * dist * dist / cos_l
    }

    /// Solid-angle density of sampling background direction `wi`.
    pub fn background_pdf(&self, bg_normal: Vec3, wi: Vec3) -> f32 {
        if let Some(env) = &self.envmap {
            return self.probs.background * env.pdf(wi);
        }
        let dir_pdf = if bg_normal == Vec3::ZERO {
            UNIFORM_SPHERE_PDF
        } else {
            cosine_hemisphere_pdf(bg_normal.dot(wi))
        };
        self.probs.background * dir_pdf
    }
}

impl Lights {
    /// Radiance from the background along `d` (away from the scene): the
    /// environment map, else the constant background.
    pub fn background_radiance(&self, d: Vec3) -> Vec3 {
        match &self.envmap {
            Some(env) => env.radiance(d),
            None => self.background,
        }
    }
}

/// Radiance an emissive triangle sends along `w` (pointing away from it):
/// its emission on the front face (the side the geometric normal points to)
/// or on both faces when double-sided; `None` when it sends nothing.
/// Times the emissive texture at barycentrics (u, v), when there is one.
#[inline]
pub fn emitted(scene: &Scene, tri: u32, u: f32, v: f32, w: Vec3) -> Option<Vec3> {
    let front = scene.triangles[tri as usize].geometric_normal().dot(w) > 0.0;
    emitted_facing(scene, tri, u, v, front)
}

/// [`emitted`] with the side known: `front` is whether `w` leaves the
/// front face (a light sample has the triangle's normal at hand).
#[inline]
fn emitted_facing(scene: &Scene, tri: u32, u: f32, v: f32, front: bool) -> Option<Vec3> {
    let t = &scene.triangles[tri as usize];
    let m = &scene.materials[t.material as usize];
    if !m.is_emissive() {
        return None;
    }
    if front || t.flags & TRI_DOUBLE_SIDED != 0 {
        Some(m.emission * emission_factor(&scene.textures, t.material, tri, u, v))
    } else {
        None
    }
}

/// The axis about which the background is sampled at a shading point:
/// cosine-weighted about the shading normal turned toward `wo` for BSDFs
/// that only reflect (this is the BSDF's own cosine factor: exact for a
/// Lambertian surface under a constant sky), or zero (uniform sphere) when
/// the BSDF transmits, so light from behind the surface is reachable too.
pub fn background_direction_frame(ns: Vec3, wo: Vec3, transmits: bool) -> Vec3 {
    lanes::background_direction_frame::<f32>(ns.into(), wo.into(), transmits).into()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spot_falloff_matches_the_khr_ramp() {
        let (ci, co) = (0.9f32, 0.8f32);
        assert_eq!(spot_falloff(0.95, ci, co), 1.0);
        assert_eq!(spot_falloff(0.7, ci, co), 0.0);
        let mid = spot_falloff(0.85, ci, co);
        assert!((mid - 0.25).abs() < 1e-5, "{mid}");
    }
}
