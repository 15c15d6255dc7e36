//! Directional albedo by deterministic quadrature of `Bsdf::eval` alone,
//! independent of the BSDFs' samplers: the reference the stability sweep
//! (`glint stability`) and `cpu/tests/bsdf_albedo.rs` check sampled
//! albedos against.
//!
//! [`hv_two`] integrates over microfacet normals (half-vector space):
//! every wi on wo's side is the mirror image of wo about one normal wm of
//! the upper hemisphere, every transmitted wi its refraction through one
//! (Walter et al. 2007, eqs. 13-17), with the Jacobians dwi/dwm =
//! 4 |wo.wm| (reflection) and (wi.wm + wo.wm / eta_rel)^2 / |wi.wm|
//! (refraction). The hemisphere of wm is the image of the unit hemisphere
//! v under wm = A v / |A v|, A = diag(alpha_u, alpha_v, 1), dwm =
//! alpha_u alpha_v / |A v|^3 dv, which spreads a GGX lobe of those alphas
//! over the whole v hemisphere, so alpha = 0.05 is integrated as
//! accurately as alpha = 1. The curves where a piece of the integrand
//! starts or stops (a direction reaching the horizon; the critical angle)
//! and, for a conductor with k = 0 and eta < 1, its Fresnel term's own
//! critical angle) are located by scan and bisection and the domain is
//! cut along them;
//! each piece is integrated by Gauss-Legendre graded towards its ends.
//! The error estimate is the difference between 8 and 12 nodes a
//! direction (at 16 and 32 the values move by ~1e-6). Transmission counts
//! as flux (times eta_rel^2). [`hemisphere_integrate`] is a plain
//! (cos theta, phi) Gauss-Legendre grid for diffuse-like lobes.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use glam::{DVec3, Vec3};

use crate::bsdf::Bsdf;

/// Half-vector quadrature: reflection per channel and transmission
/// (flux, first channel), over the full sphere of wi.
#[derive(Clone, Copy, Default, Debug)]
pub struct HvSum {
    /// Reflection, per channel.
    pub r: DVec3,
    /// Transmission (flux), first channel.
    pub t: f64,
}

/// Index of refraction ratio eta_t / eta_i for a transmission from wo's
/// side (`eta` = inside / outside, outside = +z).
pub fn eta_rel(eta: f32, wo: Vec3) -> f64 {
    if wo.z > 0.0 {
        eta as f64
    } else {
        1.0 / eta as f64
    }
}

/// The geometry of one microfacet normal for a given wo: the reflected
/// direction (if on wo's side) and the refracted one (if any, and on the
/// far side).
struct Facet {
    wm: DVec3,
    c: f64,
    refl: Option<DVec3>,
    trans: Option<DVec3>,
    tir: bool,
    /// Per channel, bit set where a conductor with k = 0 and eta < 1 is
    /// past its critical angle at this normal (its Fresnel term is 1
    /// there and has a square-root edge at the boundary).
    fresnel_tir: u8,
}

fn facet(wod: DVec3, wm: DVec3, etap: Option<f64>) -> Facet {
    let side = wod.z.signum();
    let c = wod.dot(wm);
    let mut f = Facet {
        wm,
        c,
        refl: None,
        trans: None,
        tir: false,
        fresnel_tir: 0,
    };
    // Only normals facing wo's side: the others reflect or refract into
    // directions whose half vector is this one's opposite (eval gives 0).
    if c * side <= 0.0 {
        return f;
    }
    let wi = 2.0 * c * wm - wod;
    if wi.z * wod.z > 0.0 {
        f.refl = Some(wi);
    }
    if let Some(etap) = etap {
        // Refraction through n = wm turned to wo's side (Snell).
        let ci = c.abs();
        let sin2_t = (1.0 - ci * ci) / (etap * etap);
        if sin2_t >= 1.0 {
            f.tir = true;
        } else {
            let ct = (1.0 - sin2_t).sqrt();
            let wt = (-wod / etap + (ci / etap - ct) * (wm * side)).normalize();
            if wt.z * wod.z < 0.0 {
                f.trans = Some(wt);
            }
        }
    }
    f
}

/// Which pieces of the integrand are present at a normal: the integrand
/// is smooth where this stays the same and only there may have kinks or
/// square-root edges (support boundaries, the critical angle).
fn facet_state(f: &Facet) -> (bool, bool, bool, bool, u8) {
    (
        f.c > 0.0,
        f.refl.is_some(),
        f.trans.is_some(),
        f.tir,
        f.fresnel_tir,
    )
}

/// The critical |wo.wm| of a conductor's channels with k = 0 and eta < 1
/// (below it the Fresnel term is 1): sqrt(1 - eta^2); none otherwise.
fn conductor_critical(bsdf: &Bsdf) -> [Option<f64>; 3] {
    let c = match bsdf {
        Bsdf::Conductor(c) | Bsdf::Metallic { conductor: c, .. } => c,
        _ => return [None; 3],
    };
    std::array::from_fn(|i| {
        (c.k[i] == 0.0 && c.eta[i] < 1.0).then(|| (1.0 - (c.eta[i] as f64).powi(2)).sqrt())
    })
}

/// The integrand in the half-vector domain at one normal, per unit
/// dwm: [R.r, R.g, R.b, T] with the Jacobians dwi/dwm = 4 |wo.wm|
/// (reflection) and (wi.wm + wo.wm / eta_rel)^2 / |wi.wm| (refraction,
/// Walter 2007 eq. 17), and eta_rel^2 for flux.
fn hv_integrand(bsdf: &Bsdf, wo: Vec3, f: &Facet, etap: Option<f64>) -> [f64; 4] {
    let mut v = [0.0; 4];
    if let Some(wi) = f.refl {
        let e = bsdf.eval(wo, wi.as_vec3()).as_dvec3() * (wi.z.abs() * 4.0 * f.c.abs());
        v[..3].copy_from_slice(&e.to_array());
    }
    if let (Some(wt), Some(etap)) = (f.trans, etap) {
        let e = bsdf.eval(wo, wt.as_vec3()).x as f64;
        let di = wt.dot(f.wm);
        if di != 0.0 {
            v[3] = e * wt.z.abs() * (di + f.c / etap).powi(2) / di.abs() * etap * etap;
        }
    }
    v
}

/// Gauss-Legendre nodes and weights on [-1, 1] (Newton on P_n).
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 0.0;
            for _ in 0..100 {
                // P_n(x) and P_n'(x) by the three-term recurrence.
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                    p0 = p1;
                    p1 = p2;
                }
                dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let dx = p1 / dp;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            (x, 2.0 / ((1.0 - x * x) * dp * dp))
        })
        .collect()
}

/// Nodes and weights on [a, b] of an `rule` (Gauss-Legendre on [-1, 1])
/// after the substitution x = a + (b - a) (3 s^2 - 2 s^3): the Jacobian
/// 6 s (1 - s) vanishes at both ends, which turns the square-root edges
/// and kinks the integrand has at the ends of its smooth pieces into
/// analytic behaviour (Gauss-Legendre then converges fast again).
fn graded(a: f64, b: f64, rule: &[(f64, f64)]) -> impl Iterator<Item = (f64, f64)> + '_ {
    rule.iter().map(move |&(xi, w)| {
        let s = 0.5 * (1.0 + xi);
        (
            a + (b - a) * s * s * (3.0 - 2.0 * s),
            (b - a) * 6.0 * s * (1.0 - s) * 0.5 * w,
        )
    })
}

/// Points in (lo, hi) where `state` changes, by a scan of `n` steps and
/// bisection (several changes within one step are found one after the
/// other, as long as the state differs at the step's ends).
fn breaks<S: PartialEq>(lo: f64, hi: f64, n: usize, state: &dyn Fn(f64) -> S) -> Vec<f64> {
    let mut out = Vec::new();
    let x = |i: usize| lo + (hi - lo) * i as f64 / n as f64;
    let mut prev = state(lo);
    for i in 1..=n {
        let st = state(x(i));
        let mut a0 = x(i - 1);
        while st != prev {
            let (mut a, mut b) = (a0, x(i));
            for _ in 0..44 {
                let m = 0.5 * (a + b);
                if state(m) == prev {
                    a = m;
                } else {
                    b = m;
                }
            }
            out.push(0.5 * (a + b));
            prev = state(b);
            a0 = b;
        }
    }
    out
}

/// Scan resolution of the break-point search (polar and azimuthal).
const SCAN: usize = 32;

/// Gauss-Legendre orders of the coarse and fine half-vector quadratures.
const HV_COARSE: usize = 8;
const HV_FINE: usize = 12;

/// The stretched hemisphere v = (theta, phi) of the half-vector
/// quadrature for one wo: the facet at v and dwm / dv.
struct HvDomain<'a> {
    bsdf: &'a Bsdf,
    wo: Vec3,
    wod: DVec3,
    ax: f64,
    ay: f64,
    etap: Option<f64>,
    critical: [Option<f64>; 3],
}

impl HvDomain<'_> {
    fn at(&self, th: f64, ph: f64) -> (Facet, f64) {
        let (st, ct) = th.sin_cos();
        let (sp, cp) = ph.sin_cos();
        let v = DVec3::new(self.ax * st * cp, self.ay * st * sp, ct);
        let l = v.length();
        // dwm = ax ay / |A v|^3 dv, dv = sin theta dtheta dphi.
        let mut f = facet(self.wod, v / l, self.etap);
        for (i, crit) in self.critical.iter().enumerate() {
            if crit.is_some_and(|c| f.c.abs() < c) {
                f.fresnel_tir |= 1 << i;
            }
        }
        (f, st * self.ax * self.ay / (l * l * l))
    }
    fn polar_breaks(&self, ph: f64) -> Vec<f64> {
        breaks(0.0, FRAC_PI_2, SCAN, &|th| facet_state(&self.at(th, ph).0))
    }
    /// The azimuths where the sequence of states along the polar line
    /// changes (a state curve turning back, tangent to the polar line),
    /// and the quadrants.
    fn azimuth_breaks(&self) -> Vec<f64> {
        let signature = |ph: f64| {
            let mut v = vec![facet_state(&self.at(0.0, ph).0)];
            v.extend(
                self.polar_breaks(ph)
                    .iter()
                    .map(|&b| facet_state(&self.at(b + 1e-9, ph).0)),
            );
            v
        };
        let mut phis: Vec<f64> = (0..=4).map(|i| FRAC_PI_2 * i as f64).collect();
        phis.extend(breaks(0.0, TAU, 4 * SCAN, &signature));
        phis.sort_by(f64::total_cmp);
        phis
    }
}

/// Half-vector quadrature of `eval(wo, wi) |cos wi|` over the sphere of wi
/// (see the module doc) on the stretched hemisphere v = (theta, phi).
/// The integrand is smooth except across the curves where the facet's
/// state changes (support boundaries: kinks; the critical angle: square
/// roots): for each azimuth the polar range is split where the state
/// changes, and the azimuths at `phis`; every piece is integrated by
/// graded Gauss-Legendre of order `n` in both directions.
fn hv_integrate_n(dom: &HvDomain, phis: &[f64], n: usize) -> HvSum {
    let rule = gauss_legendre(n);
    let mut sum = [0.0f64; 4];
    for pw in phis.windows(2) {
        for (ph, wp) in graded(pw[0], pw[1], &rule) {
            let mut ths = vec![0.0];
            ths.extend(dom.polar_breaks(ph));
            ths.push(FRAC_PI_2);
            for tw in ths.windows(2) {
                for (th, wt) in graded(tw[0], tw[1], &rule) {
                    let (f, jac) = dom.at(th, ph);
                    // Normals contributing nothing need no eval.
                    if f.refl.is_none() && f.trans.is_none() {
                        continue;
                    }
                    let g = hv_integrand(dom.bsdf, dom.wo, &f, dom.etap);
                    for k in 0..4 {
                        sum[k] += g[k] * jac * wt * wp;
                    }
                }
            }
        }
    }
    HvSum {
        r: DVec3::new(sum[0], sum[1], sum[2]),
        t: sum[3],
    }
}

/// The half-vector quadrature at two orders: (fine, |fine - coarse|).
pub fn hv_two(bsdf: &Bsdf, wo: Vec3, ax: f64, ay: f64) -> (HvSum, HvSum) {
    let dom = HvDomain {
        bsdf,
        wo,
        wod: wo.as_dvec3(),
        ax,
        ay,
        etap: match bsdf {
            Bsdf::Dielectric { eta, .. } => Some(eta_rel(*eta, wo)),
            _ => None,
        },
        critical: conductor_critical(bsdf),
    };
    let phis = dom.azimuth_breaks();
    let f = hv_integrate_n(&dom, &phis, HV_FINE);
    let c = hv_integrate_n(&dom, &phis, HV_COARSE);
    let e = HvSum {
        r: (f.r - c.r).abs(),
        t: (f.t - c.t).abs(),
    };
    (f, e)
}

/// Integral of `g(wi) |cos wi|` over one hemisphere (`sign` = +1 upper,
/// -1 lower) on a (cos theta, phi) grid: `nm` x `nphi` panels of 4 x 4
/// Gauss-Legendre nodes. For the smooth, diffuse-like parts.
pub fn hemisphere_integrate(g: &dyn Fn(Vec3) -> DVec3, sign: f64, nm: usize, nphi: usize) -> DVec3 {
    let gl = gauss_legendre(4);
    let (dm, dp) = (1.0 / nm as f64, TAU / nphi as f64);
    let mut s = DVec3::ZERO;
    for i in 0..nm {
        for &(xa, wa) in &gl {
            let mu = dm * (i as f64 + 0.5 + 0.5 * xa);
            let sin = (1.0 - mu * mu).max(0.0).sqrt();
            for j in 0..nphi {
                for &(xb, wb) in &gl {
                    let ph = dp * (j as f64 + 0.5 + 0.5 * xb);
                    let wi = DVec3::new(sin * ph.cos(), sin * ph.sin(), sign * mu);
                    s += g(wi.as_vec3()) * (mu * wa * wb * 0.25 * dm * dp);
                }
            }
        }
    }
    s
}
