//! The glTF non-metal: a GGX dielectric coat over a Lambertian base, made
//! energy conserving by albedo scaling (Kulla and Conty 2017, "Revisiting
//! Physically Based Shading at Imageworks"; the layering the glTF PBR
//! extensions and OpenPBR use). The contract fixes the model:
//!
//!   f(wo, wi) = s f_coat(wo, wi)
//!             + base (1 - s E(mu_o)) (1 - s E(mu_i)) / (pi (1 - s E_avg)),
//!
//! f_coat the single-scattering GGX reflection (height-correlated Smith,
//! the exact dielectric Fresnel of `eta` against air taken as 1.0), s the
//! `KHR_materials_specular` scale (specularFactor x specularColorFactor,
//! per channel, at most 1), E(mu) the coat's directional albedo with s = 1
//! and E_avg = 2 int E(mu) mu dmu. Below the smooth threshold the coat is
//! the ideal mirror weighted by s F(mu), and E(mu) = F(mu) exactly.
//!
//! Why it conserves energy: the base term integrates over wi to
//! base (1 - s E(mu_o)) (the cosine-weighted integral of 1 - s E(mu_i) is
//! 1 - s E_avg), so the albedo is s E(mu_o) + base (1 - s E(mu_o)): 1 for a
//! white base and a white specular, E(mu_o) for a black base. Both terms
//! are symmetric in (wo, wi): the model is reciprocal. Two-sided.
//!
//! E and E_avg come from glint's own coat ([`coat_albedo_reference`]),
//! tabulated by `cargo run --release -p glint-cpu --example coat_tables`
//! into `coat_tables.bin` (binary data beside this file, read once), on
//! grids uniform in mu^(1/4) (E changes fastest at grazing angles, where
//! it depends on alpha / mu: for alpha = 1e-3 it still moves between
//! mu = 1e-6 and 1e-4), in sqrt(alpha) (glTF's perceptual roughness; E
//! changes fastest near the smooth end) and in x = (eta - 1) / (eta + 1) (every eta >= 1 has a place
//! on the grid, and F0 = x^2 varies smoothly along it; nodes uniform in
//! sqrt(x), crowded towards eta = 1). The
//! GPU reads the same numbers from the tables' storage buffer
//! (`multiscatter::gpu_tables`, `shaders/bsdf/coated.glsl`).
//!
//! Sampling: the coat's visible normals with probability P, the cosine
//! lobe with 1 - P, P the coat's share of the albedo at wo (channel means
//! of s E(mu_o) against base (1 - s E(mu_o))); eval and pdf are the
//! mixture's, so MIS sees one density.

use std::f32::consts::FRAC_1_PI;
use std::sync::LazyLock;

use glam::{Vec2, Vec3};

use super::conductor::{rough_alphas, two_sided};
use super::fresnel::fresnel_dielectric;
use super::microfacet::{MIN_ALPHA, ggx_g1, ggx_g2, ggx_sample_visible, reflect_dir};
use super::thinwall::{thinwall_eval, thinwall_pdf, thinwall_sample};
use super::warp::square_to_cosine_hemisphere;
use super::{BsdfSample, Roughness};
use crate::lanes::{Lane, V3};

/// The coat of a [`super::Bsdf::Coated`] non-metal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoatParams {
    /// The coat's index of refraction against air taken as 1.0
    /// (`KHR_materials_ior`, default 1.5); at least 1.
    pub eta: f32,
    /// `KHR_materials_specular`'s scale on the coat's Fresnel term
    /// (specularFactor x specularColorFactor), per channel, in [0, 1].
    pub specular: Vec3,
    /// `KHR_materials_transmission` (factor): the probability of the
    /// thin-walled transmission lobe (`thinwall.rs`, tinted by the base
    /// colour) in place of the coat over the base.
    pub transmission: f32,
    /// `KHR_materials_clearcoat`: clearcoatFactor (0: none) and the clear
    /// coat's GGX alpha (clearcoatRoughness^2), over the whole material
    /// (`clearcoat.rs`).
    pub clearcoat: f32,
    pub clearcoat_alpha: f32,
    /// The clear coat's normal (`clearcoatNormalTexture`) in the shading
    /// frame, as its (x, y) on the grid of
    /// [`super::clearcoat::decode_coat_normal`]; ZERO: the shading normal.
    /// Set per hit by the integrator.
    pub clearcoat_normal: Vec2,
}

impl CoatParams {
    /// glTF's default coat: IOR 1.5, no specular scaling, opaque, no clear coat.
    pub const GLTF_DEFAULT: Self = Self {
        eta: 1.5,
        specular: Vec3::ONE,
        transmission: 0.0,
        clearcoat: 0.0,
        clearcoat_alpha: 0.0,
        clearcoat_normal: Vec2::ZERO,
    };

    /// The clear coat, if any.
    pub fn clearcoat(&self) -> Option<super::clearcoat::Clearcoat> {
        (self.clearcoat > 0.0).then(|| {
            super::clearcoat::Clearcoat::new(
                self.clearcoat,
                self.clearcoat_alpha,
                self.clearcoat_normal,
            )
        })
    }
}

// Grid sizes of the coat tables: mu^(1/4), sqrt(alpha) and
// x = (eta - 1) / (eta + 1), each uniform over [0, 1]; floats in the E
// table (`[x][alpha][mu]`) and in the E_avg table (`[x][alpha]`), which
// follows it.
pub use crate::abi::{COAT_E_AVG_LEN, COAT_E_LEN, COAT_N_ALPHA, COAT_N_ETA, COAT_N_MU};

/// The binary tables ([`decode_table`]'s format, tag "GLCT"): E, then E_avg.
const COAT_TABLE_BYTES: &[u8] = include_bytes!("coat_tables.bin");

/// The tables as read from [`COAT_TABLE_BYTES`]: E followed by E_avg.
pub fn coat_tables() -> &'static [f32] {
    static TABLES: LazyLock<Vec<f32>> = LazyLock::new(|| {
        decode_coat_tables(COAT_TABLE_BYTES).expect("cpu/src/bsdf/coat_tables.bin is corrupt")
    });
    &TABLES
}

/// Check the header against the compiled-in grid and decode the floats.
pub fn decode_coat_tables(bytes: &[u8]) -> Result<Vec<f32>, String> {
    decode_table(
        bytes,
        b"GLCT",
        [COAT_N_MU, COAT_N_ALPHA, COAT_N_ETA],
        COAT_E_LEN + COAT_E_AVG_LEN,
    )
}

/// Encode tables the way [`decode_coat_tables`] reads them (the
/// generator's writer).
pub fn encode_coat_tables(e: &[f32], e_avg: &[f32]) -> Vec<u8> {
    assert_eq!((e.len(), e_avg.len()), (COAT_E_LEN, COAT_E_AVG_LEN));
    let v: Vec<f32> = e.iter().chain(e_avg).copied().collect();
    encode_table(b"GLCT", [COAT_N_MU, COAT_N_ALPHA, COAT_N_ETA], &v)
}

/// A generated table as binary data: a 4-byte tag, three grid sizes
/// (little-endian u32), then `len` little-endian f32s. Checked against the
/// tag and grid compiled in, so a stale file is an error, not wrong numbers.
pub fn decode_table(
    bytes: &[u8],
    tag: &[u8; 4],
    dims: [usize; 3],
    len: usize,
) -> Result<Vec<f32>, String> {
    let word = |i: usize| {
        bytes
            .get(4 * i..4 * i + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    };
    if bytes.get(..4) != Some(&tag[..]) {
        return Err("wrong or missing header tag".into());
    }
    let got = [word(1), word(2), word(3)];
    if got != dims.map(Some) {
        return Err(format!("grid {got:?}, compiled for {dims:?}"));
    }
    let body = &bytes[16..];
    if body.len() != 4 * len {
        return Err(format!("{} bytes of floats, want {}", body.len(), 4 * len));
    }
    Ok(body
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect())
}

/// The writer of [`decode_table`]'s format.
pub fn encode_table(tag: &[u8; 4], dims: [usize; 3], v: &[f32]) -> Vec<u8> {
    let mut out = tag.to_vec();
    for n in dims {
        out.extend_from_slice(&(n as u32).to_le_bytes());
    }
    for x in v {
        out.extend_from_slice(&x.to_le_bytes());
    }
    out
}

/// The grid coordinate of eta: sqrt(x), x = (eta - 1) / (eta + 1) = sqrt(F0).
/// The square root crowds the nodes towards eta = 1, where the Fresnel
/// term's rise at grazing angles narrows to nothing (E is discontinuous at
/// eta = 1: F = 0 there, F -> 1 at grazing for any eta > 1).
#[inline(always)]
pub fn coat_eta_coord<L: Lane>(eta: L) -> L {
    ((eta - L::one()) / (eta + L::one())).clamp(0.0, 1.0).sqrt()
}

/// The eta of grid coordinate t (the inverse of [`coat_eta_coord`]).
pub fn coat_eta_of(t: f32) -> f32 {
    let x = t * t;
    (1.0 + x) / (1.0 - x).max(1e-6)
}

/// Table coordinate of mu: mu^(1/4).
#[inline(always)]
pub fn coat_mu_coord<L: Lane>(mu: L) -> L {
    mu.clamp(0.0, 1.0).sqrt().sqrt()
}

/// The mu of grid coordinate t: t^4.
pub fn coat_mu_value(t: f32) -> f32 {
    (t * t) * (t * t)
}

/// Table coordinate of alpha: its square root (glTF's roughness).
#[inline(always)]
pub fn coat_alpha_coord<L: Lane>(alpha: L) -> L {
    alpha.clamp(0.0, 1.0).sqrt()
}

/// The alpha of grid coordinate t: t^2.
pub fn coat_alpha_value(t: f32) -> f32 {
    t * t
}

/// Grid position of t in [0, 1] on an n-point grid: the lower index and
/// the fraction towards the next ([`lanes::cell`] in one lane).
pub(crate) fn cell(t: f32, n: usize) -> (usize, f32) {
    let (i, f) = lanes::cell(t, n);
    (i as usize, f)
}

/// The trilinear interpolation of a table `t[k][j][i]` (`nx` nodes along
/// i, `ny` along j) from its corners, `at(o)` the entry `o` past the lower
/// corner, at the fractions `fx`, `fy`, `fz` (i fastest): the lookups of
/// [`trilinear`] and of the coat's lanes.
#[inline(always)]
pub(crate) fn trilerp<L: Lane>(
    at: impl Fn(usize) -> L,
    (nx, ny): (usize, usize),
    fx: L,
    fy: L,
    fz: L,
) -> L {
    // Both planes written out: as a closure called twice, the plane was
    // left out of line, its four offsets checked one by one.
    let z = ny * nx;
    let (a0, a1, b0, b1) = (at(0), at(1), at(nx), at(nx + 1));
    let (c0, c1, d0, d1) = (at(z), at(z + 1), at(z + nx), at(z + nx + 1));
    let a = a0 + (a1 - a0) * fx;
    let b = b0 + (b1 - b0) * fx;
    let p0 = a + (b - a) * fy;
    let c = c0 + (c1 - c0) * fx;
    let d = d0 + (d1 - d0) * fx;
    let p1 = c + (d - c) * fy;
    p0 + (p1 - p0) * fz
}

/// How many entries from the lower corner [`trilerp`] reads: its last
/// corner is `ny * nx + nx + 1` past it.
pub(crate) const fn trilerp_span((nx, ny): (usize, usize)) -> usize {
    ny * nx + nx + 2
}

/// How many entries from the lower corner [`bilerp`] reads: its last
/// corner is `ny + 1` past it.
pub(crate) const fn bilerp_span(ny: usize) -> usize {
    ny + 2
}

/// The bilinear interpolation of a table `t[k][j]` (`ny` nodes along j)
/// from its corners, `at(o)` the entry `o` past the lower corner.
#[inline(always)]
pub(crate) fn bilerp<L: Lane>(at: impl Fn(usize) -> L, ny: usize, fy: L, fz: L) -> L {
    let (a0, a1, b0, b1) = (at(0), at(1), at(ny), at(ny + 1));
    let a = a0 + (a1 - a0) * fy;
    let b = b0 + (b1 - b0) * fy;
    a + (b - a) * fz
}

/// Trilinear lookup in `t[k][j][i]` (`nx` nodes along i, `ny` along j) at
/// the cells `x`, `y`, `z` ([`cell`]'s answers): the coat's and
/// `roughplastic`'s tables.
pub(crate) fn trilinear(
    t: &[f32],
    (nx, ny): (usize, usize),
    (i, fx): (usize, f32),
    (j, fy): (usize, f32),
    (k, fz): (usize, f32),
) -> f32 {
    let base = (k * ny + j) * nx + i;
    trilerp(|o| t[base + o], (nx, ny), fx, fy, fz)
}

/// Bilinear lookup in `t[k][j]` (`ny` nodes along j).
pub(crate) fn bilinear(t: &[f32], ny: usize, (j, fy): (usize, f32), (k, fz): (usize, f32)) -> f32 {
    let base = k * ny + j;
    bilerp(|o| t[base + o], ny, fy, fz)
}

/// E(mu, alpha, eta) of the coat with s = 1: trilinear in the tables, and
/// the exact Fresnel term below the smooth threshold (`smooth`).
pub fn coat_albedo(mu: f32, alpha: f32, eta: f32, smooth: bool) -> f32 {
    if smooth {
        return fresnel_dielectric(mu.clamp(0.0, 1.0), eta);
    }
    trilinear(
        coat_tables(),
        (COAT_N_MU, COAT_N_ALPHA),
        cell(coat_mu_coord(mu), COAT_N_MU),
        cell(coat_alpha_coord(alpha), COAT_N_ALPHA),
        cell(coat_eta_coord(eta), COAT_N_ETA),
    )
}

/// E_avg(alpha, eta) = 2 int E(mu) mu dmu (bilinear; the smooth coat's is
/// the alpha = 0 row, 2 int F(mu) mu dmu).
pub fn coat_albedo_avg(alpha: f32, eta: f32, smooth: bool) -> f32 {
    let alpha = if smooth { 0.0 } else { alpha };
    bilinear(
        &coat_tables()[COAT_E_LEN..],
        COAT_N_ALPHA,
        cell(coat_alpha_coord(alpha), COAT_N_ALPHA),
        cell(coat_eta_coord(eta), COAT_N_ETA),
    )
}

/// E(mu) of the single-scattering coat (s = 1) by visible-normal sampling
/// on an n x n stratified grid: the mean of F(wo . wm) G2 / G1 over the
/// reflected directions above the surface (Heitz 2018 eq. 19). alpha = 0
/// gives F(mu). The generator's integrand, public so that tests recompute
/// table entries.
pub fn coat_albedo_reference(mu: f32, alpha: f32, eta: f32, n: usize) -> f64 {
    let mu = mu.max(1e-7);
    if alpha <= 0.0 {
        return fresnel_dielectric(mu, eta) as f64;
    }
    let wo = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let a = alpha.max(MIN_ALPHA);
    let g1 = ggx_g1(wo, a, a);
    let mut sum = 0.0f64;
    for i in 0..n {
        for j in 0..n {
            let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
            let wm = ggx_sample_visible(wo, a, a, u);
            let wi = reflect_dir(wo, wm);
            if wi.z > 0.0 && g1 > 0.0 {
                let f = fresnel_dielectric(wo.dot(wm), eta);
                sum += (f * ggx_g2(wo, wi, a, a, false) / g1) as f64;
            }
        }
    }
    sum / (n * n) as f64
}

/// What eval, pdf and sample share for one wo (above the surface): the
/// tables' alpha, E(mu_o) and E_avg scaled by s, and the coat's sampling
/// probability. [`coat_at_wo`] makes it; the `*_at` functions take it, so
/// that a path vertex looks its tables up once ([`super::BsdfAt`]).
#[derive(Clone, Copy, Debug)]
pub struct CoatAtWo {
    /// The one lane of what [`lanes::at_wo`] finds.
    at: lanes::AtWo<f32>,
    smooth: bool,
}

impl CoatAtWo {
    /// A coat no one reads: a pure metal's, in the metallic blend
    /// (`metallic::metallic_coat_at_wo`), whose non-metal has weight zero.
    pub const UNREAD: Self = {
        let zero = V3 {
            x: 0.0,
            y: 0.0,
            z: 0.0,
        };
        Self {
            at: lanes::AtWo {
                alpha: 0.0,
                grid: lanes::Grid {
                    row: 0.0,
                    fa: 0.0,
                    fe: 0.0,
                },
                eo: zero,
                e_avg: zero,
                p_coat: 0.0,
                p_base: 0.0,
            },
            smooth: false,
        }
    };
}

/// The coat at `wo` (either side: the model is two-sided).
pub fn coat_at_wo(base: Vec3, coat: &CoatParams, r: &Roughness, wo: Vec3) -> CoatAtWo {
    at_wo(base, coat, r, wo.z.abs())
}

fn at_wo(base: Vec3, coat: &CoatParams, r: &Roughness, mu_o: f32) -> CoatAtWo {
    CoatAtWo {
        at: lanes::at_wo(&Coat::of(base, coat, r), mu_o),
        smooth: r.is_smooth(),
    }
}

/// The opaque part's f, `w` being [`coat_at_wo`] of `wo`.
fn opaque_eval(
    base: Vec3,
    coat: &CoatParams,
    r: &Roughness,
    w: &CoatAtWo,
    wo: Vec3,
    wi: Vec3,
) -> Vec3 {
    // [`lanes::opaque_eval`] with its selects as branches: one path skips
    // what the other side of a select would compute.
    let (wo, wi) = two_sided(wo, wi);
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return Vec3::ZERO;
    }
    let c = Coat::of(base, coat, r);
    let mut f: Vec3 = lanes::base_term(&c, &w.at, wi.z).into();
    if !w.smooth {
        f += Vec3::from(lanes::coat_lobe(
            &c,
            wo.into(),
            wi.into(),
            (wo + wi).normalize().into(),
        ));
    }
    f
}

fn opaque_pdf(r: &Roughness, w: &CoatAtWo, wo: Vec3, wi: Vec3) -> f32 {
    // [`lanes::opaque_pdf`] with its selects as branches. Only the
    // roughness enters the density besides P at wo (in `w`).
    let (wo, wi) = two_sided(wo, wi);
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return 0.0;
    }
    let rough = if w.smooth {
        0.0
    } else {
        let c = Coat::of(Vec3::ZERO, &CoatParams::GLTF_DEFAULT, r);
        lanes::coat_pdf_rough(&c, wo.into(), wi.into())
    };
    w.at.p_base * wi.z * FRAC_1_PI + w.at.p_coat * rough
}

/// `uc` picks the lobe (coat with probability P), `u` samples it: the
/// smooth coat's mirror here, the rough lobes' math in [`lanes`].
fn opaque_sample(
    base: Vec3,
    coat: &CoatParams,
    r: &Roughness,
    w: &CoatAtWo,
    wo: Vec3,
    uc: f32,
    u: Vec2,
) -> Option<BsdfSample> {
    if wo.z == 0.0 {
        return None;
    }
    let flip = wo.z < 0.0;
    let wo = Vec3::new(wo.x, wo.y, wo.z.abs());
    if uc < w.at.p_coat && w.smooth {
        // The mirror lobe, s F delta / |cos|, picked with probability P:
        // throughput s F / P, discrete probability P.
        let f = coat.specular * fresnel_dielectric(wo.z, coat.eta);
        return Some(BsdfSample {
            wi: Vec3::new(-wo.x, -wo.y, if flip { -wo.z } else { wo.z }),
            weight: f / w.at.p_coat,
            pdf: w.at.p_coat,
            delta: true,
            eta: 1.0,
        });
    }
    // The lanes' lobes with their selects as branches: a direction that
    // is not valid returns before its values are computed.
    let (c, a, wo) = (Coat::of(base, coat, r), &w.at, V3::from(wo));
    let (wi, (f, pdf)) = if uc < a.p_coat {
        let (wm, dot, wi) = lanes::coat_lobe_dir(&c, wo, u.into());
        if wi.z <= 0.0 || dot <= 0.0 {
            return None;
        }
        (wi, lanes::coat_lobe_values(&c, a, wo, wm, dot, wi))
    } else {
        let wi: V3<f32> = square_to_cosine_hemisphere(u).into();
        if wi.z <= 0.0 {
            return None;
        }
        (wi, lanes::base_lobe_values(&c, a, wo, wi))
    };
    let lobe = lanes::Lobe {
        valid: true,
        wi,
        f,
        pdf,
    };
    lanes::finish(lobe, flip).single()
}

/// The non-metal: the opaque coat over the base with probability 1 - t,
/// the thin-walled transmission with t (`CoatParams::transmission`).
pub fn coated_eval(base: Vec3, coat: &CoatParams, r: &Roughness, wo: Vec3, wi: Vec3) -> Vec3 {
    coated_eval_at(base, coat, r, &coat_at_wo(base, coat, r, wo), wo, wi)
}

pub fn coated_pdf(base: Vec3, coat: &CoatParams, r: &Roughness, wo: Vec3, wi: Vec3) -> f32 {
    coated_pdf_at(coat, r, &coat_at_wo(base, coat, r, wo), wo, wi)
}

/// `uc` first picks transmission (uc < t), then, rescaled, the lobe within.
pub fn coated_sample(
    base: Vec3,
    coat: &CoatParams,
    r: &Roughness,
    wo: Vec3,
    uc: f32,
    u: Vec2,
) -> Option<BsdfSample> {
    coated_sample_at(base, coat, r, &coat_at_wo(base, coat, r, wo), wo, uc, u)
}

/// [`coated_eval`] with the coat at wo already looked up (`w`).
pub fn coated_eval_at(
    base: Vec3,
    coat: &CoatParams,
    r: &Roughness,
    w: &CoatAtWo,
    wo: Vec3,
    wi: Vec3,
) -> Vec3 {
    let t = coat.transmission;
    if t <= 0.0 {
        return opaque_eval(base, coat, r, w, wo, wi);
    }
    (1.0 - t) * opaque_eval(base, coat, r, w, wo, wi) + t * thinwall_eval(base, coat, r, wo, wi)
}

/// [`coated_pdf`] with the coat at wo already looked up (`w`).
pub fn coated_pdf_at(coat: &CoatParams, r: &Roughness, w: &CoatAtWo, wo: Vec3, wi: Vec3) -> f32 {
    let t = coat.transmission;
    if t <= 0.0 {
        return opaque_pdf(r, w, wo, wi);
    }
    (1.0 - t) * opaque_pdf(r, w, wo, wi) + t * thinwall_pdf(coat, r, wo, wi)
}

/// [`coated_sample`] with the coat at wo already looked up (`w`).
pub fn coated_sample_at(
    base: Vec3,
    coat: &CoatParams,
    r: &Roughness,
    w: &CoatAtWo,
    wo: Vec3,
    uc: f32,
    u: Vec2,
) -> Option<BsdfSample> {
    let t = coat.transmission;
    if t <= 0.0 {
        return opaque_sample(base, coat, r, w, wo, uc, u);
    }
    let thin = uc < t;
    let s = if thin {
        thinwall_sample(base, coat, r, wo, (uc / t).min(ONE_MINUS_EPS), u)?
    } else {
        let uc = ((uc - t) / (1.0 - t)).clamp(0.0, ONE_MINUS_EPS);
        opaque_sample(base, coat, r, w, wo, uc, u)?
    };
    if s.delta {
        // A delta lobe of one part: its throughput, its probability scaled.
        let p = if thin { t } else { 1.0 - t };
        return Some(BsdfSample {
            pdf: p * s.pdf,
            ..s
        });
    }
    // The sampled part's own (well-conditioned) pdf and f, the other part
    // evaluated at the sampled direction (as metallic.rs).
    let f_s = s.weight * (s.pdf / s.wi.z.abs());
    let (pdf, f) = if thin {
        (
            t * s.pdf + (1.0 - t) * opaque_pdf(r, w, wo, s.wi),
            t * f_s + (1.0 - t) * opaque_eval(base, coat, r, w, wo, s.wi),
        )
    } else {
        (
            (1.0 - t) * s.pdf + t * thinwall_pdf(coat, r, wo, s.wi),
            (1.0 - t) * f_s + t * thinwall_eval(base, coat, r, wo, s.wi),
        )
    };
    if !(pdf > 0.0) || !pdf.is_finite() {
        return None;
    }
    Some(BsdfSample {
        weight: f * (s.wi.z.abs() / pdf),
        pdf,
        ..s
    })
}

// The largest f32 below 1: a rescaled random number stays in [0, 1).
use crate::abi::ONE_MINUS_EPS;

/// The coat's selection probability at wo (for tests and the blend).
pub fn coated_coat_probability(base: Vec3, coat: &CoatParams, r: &Roughness, mu_o: f32) -> f32 {
    at_wo(base, coat, r, mu_o.abs()).at.p_coat
}

/// The glTF non-metal's directional albedo at mu_o as the model promises
/// it: s E(mu_o) + base (1 - s E(mu_o)) (the furnace tests' expectation).
pub fn coated_albedo(base: Vec3, coat: &CoatParams, r: &Roughness, mu_o: f32) -> Vec3 {
    let (ax, ay) = rough_alphas(r);
    let e = coat.specular * coat_albedo(mu_o, (ax * ay).sqrt(), coat.eta, r.is_smooth());
    e + base * (Vec3::ONE - e)
}

/// The coated non-metal's parameters, one per lane: its opaque part (no
/// transmission, no clear coat), which [`lanes`] writes once for one lane
/// (the scalar functions above) and for eight.
#[derive(Clone, Copy, Debug)]
pub struct Coat<L: Lane> {
    pub base: V3<L>,
    /// `KHR_materials_specular`'s scale.
    pub specular: V3<L>,
    pub eta: L,
    /// The clamped alphas ([`rough_alphas`]).
    pub ax: L,
    pub ay: L,
    /// Below the smooth threshold: the coat is a mirror (a delta lobe).
    pub smooth: L::Mask,
}

impl Coat<f32> {
    #[inline(always)]
    pub fn of(base: Vec3, coat: &CoatParams, r: &Roughness) -> Self {
        let (ax, ay) = rough_alphas(r);
        Self {
            base: base.into(),
            specular: coat.specular.into(),
            eta: coat.eta,
            ax,
            ay,
            smooth: r.is_smooth(),
        }
    }
}

/// The coated non-metal's opaque part over a lane type (see
/// `crate::lanes`): the coat at wo (the tables' alpha and eta cells found
/// there once, [`lanes::Grid`]; lane by lane only the tables' loads), f, the density and the two rough lobes' samples. A branch of the
/// model is a select of both sides; the smooth coat's mirror (a delta) is
/// [`opaque_sample`]'s own, so a lane with a smooth coat picking its coat
/// lobe is not sampled here.
pub mod lanes {
    use std::f32::consts::FRAC_1_PI;

    use super::Coat;
    use crate::bsdf::LaneSample;
    use crate::bsdf::conductor::lanes::two_sided;
    use crate::bsdf::fresnel::lanes::fresnel_dielectric;
    use crate::bsdf::microfacet::lanes::{
        ggx_d, ggx_pdf_visible, ggx_sample_visible, ggx_visibility, reflect_dir,
    };
    use crate::bsdf::warp::lanes::square_to_cosine_hemisphere;
    use crate::lanes::{Lane, V2, V3};

    use super::{COAT_E_LEN, COAT_N_ALPHA, COAT_N_ETA, COAT_N_MU};

    /// What f, the density and the samples share at wo ([`super::CoatAtWo`]).
    #[derive(Clone, Copy, Debug)]
    pub struct AtWo<L: Lane> {
        pub alpha: L,
        pub grid: Grid<L>,
        pub eo: V3<L>,
        pub e_avg: V3<L>,
        pub p_coat: L,
        /// 1 - p_coat, computed without the cancellation (at grazing angles
        /// the coat takes nearly everything and 1 - p_coat would lose digits).
        pub p_base: L,
    }

    #[inline(always)]
    fn splat3<L: Lane>(v: f32) -> V3<L> {
        V3::new(L::splat(v), L::splat(v), L::splat(v))
    }

    #[inline(always)]
    fn mean<L: Lane>(v: V3<L>) -> L {
        (v.x + v.y + v.z) * L::splat(1.0 / 3.0)
    }

    #[inline(always)]
    fn max0<L: Lane>(v: V3<L>) -> V3<L> {
        V3::new(v.x.max(L::zero()), v.y.max(L::zero()), v.z.max(L::zero()))
    }

    /// Where each lane's (alpha, eta) falls on the E table's grid, found
    /// once at wo for every E(mu) of the vertex: the offset of the mu row
    /// at the lower alpha and eta nodes (a float, exact: the table has
    /// fewer than 2^24 entries) and the fractions towards the next nodes.
    #[derive(Clone, Copy, Debug)]
    pub struct Grid<L: Lane> {
        pub row: L,
        pub fa: L,
        pub fe: L,
    }

    /// [`super::cell`] in every lane: the lower node (a float) and the
    /// fraction towards the next.
    #[inline(always)]
    pub(crate) fn cell<L: Lane>(t: L, n: usize) -> (L, L) {
        let y = t.clamp(0.0, 1.0) * L::splat((n - 1) as f32);
        let i = y.trunc_i32().min(L::splat((n - 2) as f32));
        (i, y - i)
    }

    /// [`super::trilinear`] in the E table at mu, the alpha and eta cells
    /// being `g`'s: lane by lane only the loads.
    #[inline(always)]
    fn table_e<L: Lane>(g: &Grid<L>, mu: L) -> L {
        let (i, fx) = cell(super::coat_mu_coord(mu), COAT_N_MU);
        // The lower corner's offset: a sum of exact integers below 2^24.
        let first = g.row + i;
        let t = super::coat_tables();
        let n = (COAT_N_MU, COAT_N_ALPHA);
        let span = super::trilerp_span(n);
        let at = |o: usize| L::from_fn(|l| corners(t, first, l, span)[o]);
        super::trilerp(at, n, fx, g.fa, g.fe)
    }

    /// The `span` entries of table `t` from lane `l`'s lower corner
    /// `first` (a node offset made by [`cell`]s: a finite integer in a
    /// float): one bounds check for a lookup's corners, and a bare
    /// truncation for the offset, not a saturating float-to-integer
    /// conversion per corner (they were most of a lookup's instructions).
    #[inline(always)]
    fn corners<L: Lane>(t: &[f32], first: L, l: usize, span: usize) -> &[f32] {
        let x = first.lane(l);
        assert!((0.0..(1u32 << 24) as f32).contains(&x));
        // SAFETY: x is finite and within u32's range (just checked).
        let first = unsafe { x.to_int_unchecked::<u32>() } as usize;
        &t[first..first + span]
    }

    /// E(mu) of each lane's coat with s = 1 ([`super::coat_albedo`]): the
    /// table, or the exact Fresnel term for a smooth coat.
    #[inline(always)]
    fn albedo<L: Lane>(c: &Coat<L>, g: &Grid<L>, mu: L) -> L {
        if L::none(c.smooth) {
            return table_e(g, mu);
        }
        let f = fresnel_dielectric(mu.clamp(0.0, 1.0), c.eta);
        if L::all(c.smooth) {
            return f;
        }
        L::select(c.smooth, f, table_e(g, mu))
    }

    /// The coat at mu_o = |wo.z|.
    #[inline(always)]
    pub fn at_wo<L: Lane>(c: &Coat<L>, mu_o: L) -> AtWo<L> {
        let alpha = (c.ax * c.ay).sqrt();
        // The tables' alpha: a smooth coat's E_avg is the alpha = 0 row
        // (its E is Fresnel's, no row at all).
        let table_alpha = L::select(c.smooth, L::zero(), alpha);
        let (j, fa) = cell(super::coat_alpha_coord(table_alpha), COAT_N_ALPHA);
        let (k, fe) = cell(super::coat_eta_coord(c.eta), COAT_N_ETA);
        let avg_row = k * L::splat(COAT_N_ALPHA as f32) + j;
        let grid = Grid {
            row: avg_row * L::splat(COAT_N_MU as f32),
            fa,
            fe,
        };
        let eo = c.specular.scale(albedo(c, &grid, mu_o));
        // E_avg, bilinear in its table.
        let t = &super::coat_tables()[COAT_E_LEN..];
        let at =
            |o: usize| L::from_fn(|l| corners(t, avg_row, l, super::bilerp_span(COAT_N_ALPHA))[o]);
        let e_avg = c.specular.scale(super::bilerp(at, COAT_N_ALPHA, fa, fe));
        let spec = mean(eo);
        let diff = mean(c.base * (splat3(1.0) - eo));
        let total = spec + diff;
        let some = total.gt(L::zero());
        let half = L::splat(0.5);
        AtWo {
            alpha,
            grid,
            eo,
            e_avg,
            p_coat: L::select(some, (spec / total).clamp(0.0, 1.0), half),
            p_base: L::select(some, (diff / total).clamp(0.0, 1.0), half),
        }
    }

    /// The albedo-scaled base term for wo, wi both above the surface.
    #[inline(always)]
    pub fn base_term<L: Lane>(c: &Coat<L>, w: &AtWo<L>, mu_i: L) -> V3<L> {
        let ei = c.specular.scale(albedo(c, &w.grid, mu_i));
        let denom = splat3(1.0) - w.e_avg;
        // glam's min_element: x.min(y.min(z)).
        let ok = denom.x.min(denom.y.min(denom.z)).gt(L::zero());
        let f =
            (c.base * max0(splat3(1.0) - w.eo) * max0(splat3(1.0) - ei)).scale(L::splat(FRAC_1_PI));
        let f = V3::new(f.x / denom.x, f.y / denom.y, f.z / denom.z);
        V3::select(ok, f, splat3(0.0))
    }

    /// s f_coat for wo, wi above the surface and their half vector wm.
    #[inline(always)]
    pub fn coat_lobe<L: Lane>(c: &Coat<L>, wo: V3<L>, wi: V3<L>, wm: V3<L>) -> V3<L> {
        let f = fresnel_dielectric(wo.dot(wm), c.eta);
        c.specular
            .scale(f * ggx_d(wm, c.ax, c.ay) * ggx_visibility(wo, wi, c.ax, c.ay, false))
    }

    /// f(wo, wi).
    #[inline(always)]
    pub fn opaque_eval<L: Lane>(c: &Coat<L>, w: &AtWo<L>, wo: V3<L>, wi: V3<L>) -> V3<L> {
        let (wo, wi) = two_sided(wo, wi);
        let below = wo.z.le(L::zero()) | wi.z.le(L::zero());
        let f = base_term(c, w, wi.z);
        let rough = f + coat_lobe(c, wo, wi, (wo + wi).normalize());
        V3::select(below, splat3(0.0), V3::select(c.smooth, f, rough))
    }

    /// The coat lobe's solid-angle density (0 for the smooth coat's delta).
    #[inline(always)]
    pub fn coat_pdf_rough<L: Lane>(c: &Coat<L>, wo: V3<L>, wi: V3<L>) -> L {
        let wm = (wo + wi).normalize();
        let dot = wo.dot(wm);
        let pdf = ggx_pdf_visible(wo, wm, c.ax, c.ay) / (L::splat(4.0) * dot);
        L::select(c.smooth | dot.le(L::zero()), L::zero(), pdf)
    }

    /// The density of the opaque part's samples at wi.
    #[inline(always)]
    pub fn opaque_pdf<L: Lane>(c: &Coat<L>, w: &AtWo<L>, wo: V3<L>, wi: V3<L>) -> L {
        let (wo, wi) = two_sided(wo, wi);
        let below = wo.z.le(L::zero()) | wi.z.le(L::zero());
        let pdf = w.p_base * wi.z * L::splat(FRAC_1_PI) + w.p_coat * coat_pdf_rough(c, wo, wi);
        L::select(below, L::zero(), pdf)
    }

    /// A lobe's sample before [`finish`]: where it is valid, wi, the
    /// mixture's f and density at wi.
    #[derive(Clone, Copy, Debug)]
    pub struct Lobe<L: Lane> {
        pub valid: L::Mask,
        pub wi: V3<L>,
        pub f: V3<L>,
        pub pdf: L,
    }

    /// The rough coat's visible normals (wo above the surface): f and pdf
    /// from the sampled normal (see conductor.rs: wo + wi is
    /// ill-conditioned for near-specular grazing pairs).
    #[inline(always)]
    pub fn coat_lobe_sample<L: Lane>(c: &Coat<L>, w: &AtWo<L>, wo: V3<L>, u: V2<L>) -> Lobe<L> {
        let (wm, dot, wi) = coat_lobe_dir(c, wo, u);
        let (f, pdf) = coat_lobe_values(c, w, wo, wm, dot, wi);
        Lobe {
            valid: wi.z.gt(L::zero()) & dot.gt(L::zero()),
            wi,
            f,
            pdf,
        }
    }

    /// [`coat_lobe_sample`]'s direction: the sampled normal wm, wo . wm
    /// and wi (valid where wi.z > 0 and wo . wm > 0).
    #[inline(always)]
    pub fn coat_lobe_dir<L: Lane>(c: &Coat<L>, wo: V3<L>, u: V2<L>) -> (V3<L>, L, V3<L>) {
        let wm = ggx_sample_visible(wo, c.ax, c.ay, u);
        (wm, wo.dot(wm), reflect_dir(wo, wm))
    }

    /// [`coat_lobe_sample`]'s f and density at its direction.
    #[inline(always)]
    pub fn coat_lobe_values<L: Lane>(
        c: &Coat<L>,
        w: &AtWo<L>,
        wo: V3<L>,
        wm: V3<L>,
        dot: L,
        wi: V3<L>,
    ) -> (V3<L>, L) {
        let pdf_c = ggx_pdf_visible(wo, wm, c.ax, c.ay) / (L::splat(4.0) * dot);
        (
            coat_lobe(c, wo, wi, wm) + base_term(c, w, wi.z),
            w.p_coat * pdf_c + w.p_base * wi.z * L::splat(FRAC_1_PI),
        )
    }

    /// The base's cosine lobe (wo above the surface).
    #[inline(always)]
    pub fn base_lobe_sample<L: Lane>(c: &Coat<L>, w: &AtWo<L>, wo: V3<L>, u: V2<L>) -> Lobe<L> {
        let wi = square_to_cosine_hemisphere(u);
        let (f, pdf) = base_lobe_values(c, w, wo, wi);
        Lobe {
            valid: wi.z.gt(L::zero()),
            wi,
            f,
            pdf,
        }
    }

    /// [`base_lobe_sample`]'s f and density at wi.
    #[inline(always)]
    pub fn base_lobe_values<L: Lane>(c: &Coat<L>, w: &AtWo<L>, wo: V3<L>, wi: V3<L>) -> (V3<L>, L) {
        let f = base_term(c, w, wi.z);
        let rough = f + coat_lobe(c, wo, wi, (wo + wi).normalize());
        (
            V3::select(c.smooth, f, rough),
            w.p_coat * coat_pdf_rough(c, wo, wi) + w.p_base * wi.z * L::splat(FRAC_1_PI),
        )
    }

    /// The sample of a lobe: its throughput, valid where the density is
    /// positive and finite, wi turned back below where wo was (`flip`).
    #[inline(always)]
    pub fn finish<L: Lane>(l: Lobe<L>, flip: L::Mask) -> LaneSample<L> {
        let finite = l.pdf.abs().lt(L::splat(f32::INFINITY));
        let weight = l.f.scale(l.wi.z / l.pdf);
        let wi = V3::new(l.wi.x, l.wi.y, L::select(flip, -l.wi.z, l.wi.z));
        LaneSample {
            valid: l.valid & l.pdf.gt(L::zero()) & finite,
            wi,
            weight,
            pdf: l.pdf,
            eta: L::one(),
            delta: false,
        }
    }

    /// The opaque part's sample where every lane's pick is a rough lobe:
    /// `uc` picks the coat's visible normals (uc < P) or the base's cosine
    /// lobe. A lane whose coat is smooth and picks it, or whose wo is in
    /// the plane, is not valid ([`super::opaque_sample`] has the mirror).
    #[inline(always)]
    pub fn opaque_sample<L: Lane>(
        c: &Coat<L>,
        w: &AtWo<L>,
        wo: V3<L>,
        uc: L,
        u: V2<L>,
    ) -> LaneSample<L> {
        let flip = wo.z.lt(L::zero());
        let up = V3::new(wo.x, wo.y, wo.z.abs());
        let pick = uc.lt(w.p_coat);
        let (a, b) = (coat_lobe_sample(c, w, up, u), base_lobe_sample(c, w, up, u));
        let lobe = Lobe {
            valid: L::select_mask(pick, a.valid & !c.smooth, b.valid) & !wo.z.eq(L::zero()),
            wi: V3::select(pick, a.wi, b.wi),
            f: V3::select(pick, a.f, b.f),
            pdf: L::select(pick, a.pdf, b.pdf),
        };
        finish(lobe, flip)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_decode_and_round_trip() {
        let t = coat_tables();
        assert_eq!(t.len(), COAT_E_LEN + COAT_E_AVG_LEN);
        let bytes = encode_coat_tables(&t[..COAT_E_LEN], &t[COAT_E_LEN..]);
        assert_eq!(bytes, COAT_TABLE_BYTES);
        assert!(decode_coat_tables(&bytes[..bytes.len() - 4]).is_err());
        assert!(decode_coat_tables(b"GLCX").is_err());
    }

    #[test]
    fn eta_coordinate_inverts() {
        for eta in [1.0f32, 1.33, 1.5, 2.4, 5.0] {
            assert!((coat_eta_of(coat_eta_coord(eta)) - eta).abs() < 1e-4 * eta);
        }
    }

    /// Table entries recomputed independently of the generator's grid.
    #[test]
    fn table_entries_match_recomputation() {
        for (i, j, k) in [
            (31, 31, 15),
            (10, 20, 3),
            (3, 31, 8),
            (31, 5, 1),
            (16, 16, 12),
        ] {
            let mu = coat_mu_value(i as f32 / (COAT_N_MU - 1) as f32);
            let alpha = coat_alpha_value(j as f32 / (COAT_N_ALPHA - 1) as f32);
            let eta = coat_eta_of(k as f32 / (COAT_N_ETA - 1) as f32);
            let r = coat_albedo_reference(mu, alpha, eta, 128);
            let t = coat_albedo(mu, alpha, eta, false) as f64;
            assert!(
                (r - t).abs() < 2e-3,
                "mu {mu} alpha {alpha} eta {eta}: {t} vs {r}"
            );
        }
    }
}
