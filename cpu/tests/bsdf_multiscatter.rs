//! Energy-compensated GGX (`multiscatter`): the white furnace of an F = 1
//! conductor is 1 within 1% up to alpha = 1 (its albedo, and a rendered
//! furnace), sampling stays consistent with eval and pdf (chi-square and
//! per-sample checks), reciprocity holds, and the embedded tables equal
//! their GLSL twin and glint's own single-scattering albedo.

mod common;
mod render_common;

use common::*;
use glam::Vec3;
use glint_cpu::bsdf::ms_tables::{MS_E, MS_E_AVG, MS_N};
use glint_cpu::bsdf::multiscatter::{ms_albedo, ms_albedo_reference};
use glint_cpu::bsdf::{Bsdf, ConductorParams, Roughness, Shadowing};
use rayon::prelude::*;

const SHADOWINGS: [Shadowing; 2] = [Shadowing::Correlated, Shadowing::Separable];

/// eta = 0, k = 1 (Mitsuba's "none"): F = 1 at every angle.
fn white(alpha_u: f32, alpha_v: f32, sh: Shadowing, ms: bool) -> Bsdf {
    Bsdf::Conductor(ConductorParams {
        eta: Vec3::ZERO,
        k: Vec3::ONE,
        specular_reflectance: Vec3::ONE,
        roughness: Roughness {
            alpha_u,
            alpha_v,
            shadowing: sh,
            multiscatter: ms,
        },
    })
}

fn albedo(b: &Bsdf, wo: Vec3, n: usize, seed: u64) -> (f64, f64) {
    let mut rng = Pcg32::new(seed, 9);
    let (mut s1, mut s2) = (0.0f64, 0.0f64);
    for _ in 0..n {
        let v = b
            .sample(wo, rng.f32(), rng.vec2())
            .map_or(0.0, |s| s.weight.max_element() as f64);
        s1 += v;
        s2 += v * v;
    }
    let m = s1 / n as f64;
    (m, ((s2 / n as f64 - m * m).max(0.0) / n as f64).sqrt())
}

#[test]
fn white_furnace_albedo_is_one_within_one_percent() {
    let mut failures = Vec::new();
    let mut lines = Vec::new();
    for sh in SHADOWINGS {
        for alpha in [0.05f32, 0.2, 0.5, 0.8, 1.0] {
            for c in [1.0f32, 0.5, 0.1, -0.7] {
                let wo = dir_cos(c, PHI_O);
                let (m, se) = albedo(&white(alpha, alpha, sh, true), wo, 100_000, 1);
                let (m0, _) = albedo(&white(alpha, alpha, sh, false), wo, 100_000, 1);
                lines.push(format!(
                    "{sh:?} alpha {alpha} cos {c}: {m0:.4} -> {m:.4} +- {se:.4}"
                ));
                // 1% except at grazing angles with small alpha, where the
                // 32 x 32 table's bilinear interpolation errs by up to 2%.
                let tol = if alpha < 0.1 && c.abs() < 0.2 {
                    0.02
                } else {
                    0.01
                };
                if (m - 1.0).abs() > tol + 3.0 * se {
                    failures.push(lines.last().unwrap().clone());
                }
            }
        }
        // Anisotropic: looked up at sqrt(alpha_u alpha_v), an
        // approximation (92% .. 94% for a 1:4 ratio, up from 86%).
        let (m, se) = albedo(&white(0.2, 0.8, sh, true), dir_cos(0.5, PHI_O), 100_000, 2);
        if (m - 1.0).abs() > 0.09 + 3.0 * se {
            failures.push(format!("{sh:?} anisotropic 0.2/0.8: {m}"));
        }
    }
    eprintln!("{}", lines.join("\n"));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn multiscatter_sampling_matches_eval_and_pdf() {
    let mut bad = Vec::new();
    for sh in SHADOWINGS {
        for (au, av) in [(0.05, 0.05), (0.3, 0.3), (1.0, 1.0), (0.1, 0.6)] {
            let mut r = rough(au, av, sh);
            r.multiscatter = true;
            let b = Bsdf::Conductor(gold(r));
            let mut rng = Pcg32::new(3, 3);
            for c in [1.0f32, 0.4, 0.05, -0.5] {
                let wo = dir_cos(c, PHI_O);
                for _ in 0..3000 {
                    let Some(s) = b.sample(wo, rng.f32(), rng.vec2()) else {
                        continue;
                    };
                    let pdf = b.pdf(wo, s.wi);
                    let w = b.eval(wo, s.wi) * s.wi.z.abs() / pdf;
                    if (pdf - s.pdf).abs() > 1e-3 * pdf
                        || (w - s.weight).abs().max_element() > 1e-3 * w.max_element() + 1e-6
                    {
                        bad.push(format!("{b:?} wo {wo}: {s:?} vs pdf {pdf} w {w}"));
                    }
                }
                // Reciprocity: f_ss and f_ms are both symmetric.
                for _ in 0..300 {
                    let wi = dir_cos(rng.f32() * c.signum(), std::f32::consts::TAU * rng.f32());
                    let (a, bb) = (b.eval(wo, wi), b.eval(wi, wo));
                    if (a - bb).abs().max_element()
                        > 1e-3 * a.max_element().max(bb.max_element()) + 1e-6
                    {
                        bad.push(format!("reciprocity {wo} {wi}: {a} vs {bb}"));
                    }
                }
            }
        }
    }
    assert!(
        bad.len() <= 3,
        "{}\n{}",
        bad.len(),
        bad[..bad.len().min(6)].join("\n")
    );
}

#[test]
fn multiscatter_chi2() {
    let level = sidak(0.01, 8);
    let cases: Vec<(Bsdf, Vec3)> = SHADOWINGS
        .iter()
        .flat_map(|&sh| {
            [(0.3f32, 0.5f32), (1.0, 1.0), (0.1, 0.6), (0.6, 0.05)].map(move |(a, c)| {
                let mut r = rough(a, a, sh);
                r.multiscatter = true;
                (Bsdf::Conductor(gold(r)), dir_cos(c, PHI_O))
            })
        })
        .collect();
    let fails: Vec<String> = cases
        .par_iter()
        .enumerate()
        .filter_map(|(i, (b, wo))| {
            let r = chi2_test(
                &|uc, u| b.sample(*wo, uc, u).map(|s| (s.wi, s.delta)),
                &|wi| b.pdf(*wo, wi) as f64,
                &[],
                300_000,
                77 + i as u64,
                &Grid::for_case(b, *wo),
            );
            match r {
                Ok(r) if r.p_value >= level => None,
                other => Some(format!("{b:?} {wo}: {other:?}")),
            }
        })
        .collect();
    assert!(fails.is_empty(), "{}", fails.join("\n"));
}

/// The embedded tables: the GLSL reads them from the storage buffer
/// `gpu_tables()` at the device ABI's offsets (`glint_cpu::abi`, from
/// which its `#define`s are generated), which must partition it; a few
/// entries recomputed from the single-scattering lobe agree.
#[test]
fn tables_match_their_offsets_and_recomputation() {
    use glint_cpu::bsdf::coated::{COAT_E_AVG_LEN, COAT_E_LEN, coat_tables};
    use glint_cpu::bsdf::ms_tables::MS_T;
    use glint_cpu::bsdf::multiscatter::{
        MS_OFF_COAT, MS_OFF_E_AVG, MS_OFF_RP, MS_OFF_T, gpu_tables,
    };
    use glint_cpu::bsdf::roughplastic::{RP_LEN, roughplastic_tables};
    assert_eq!(coat_tables().len(), COAT_E_LEN + COAT_E_AVG_LEN);
    assert_eq!(roughplastic_tables().len(), RP_LEN);
    assert_eq!(gpu_tables().len(), MS_OFF_RP + RP_LEN);
    let t = gpu_tables();
    assert_eq!(&t[..MS_N * MS_N], &MS_E[0][..]);
    assert_eq!(&t[MS_N * MS_N..MS_OFF_E_AVG], &MS_E[1][..]);
    assert_eq!(&t[MS_OFF_E_AVG..MS_OFF_E_AVG + MS_N], &MS_E_AVG[0][..]);
    assert_eq!(&t[MS_OFF_T..MS_OFF_COAT], &MS_T.concat()[..]);
    assert_eq!(&t[MS_OFF_COAT..MS_OFF_RP], coat_tables());
    assert_eq!(&t[MS_OFF_RP..], roughplastic_tables());
    for sep in [false, true] {
        for (i, j) in [(31, 31), (10, 20), (3, 31), (31, 5), (16, 16)] {
            let mu = i as f32 / (MS_N - 1) as f32;
            let alpha = j as f32 / (MS_N - 1) as f32;
            let r = ms_albedo_reference(mu, alpha, sep, 128);
            let t = ms_albedo(mu, alpha, sep) as f64;
            assert!(
                (r - t).abs() < 3e-3,
                "sep {sep} mu {mu} alpha {alpha}: {t} vs {r}"
            );
        }
    }
    // E decreases with alpha; E_avg in (0, 1].
    for t in MS_E_AVG.iter() {
        for j in 1..MS_N {
            assert!(t[j] <= t[j - 1] + 1e-3);
            assert!(t[j] > 0.0 && t[j] <= 1.0 + 1e-3);
        }
    }
}

const FURNACE_SIZE: u32 = 24;

/// The camera of [`rendered_furnace`] (the unit sphere seen from z = 3).
fn furnace_camera() -> glint_cpu::Camera {
    render_common::look_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, Vec3::Y, 45.0)
}

/// cos theta_o at the unit sphere where `ray` hits it, or None.
fn sphere_mu(ray: &glint_cpu::Ray, radius: f32) -> Option<f32> {
    let b = ray.o.dot(ray.d);
    let disc = b * b - (ray.o.length_squared() - radius * radius);
    (disc > 0.0).then(|| {
        let p = ray.o + ray.d * (-b - disc.sqrt());
        (-ray.d).dot(p.normalize())
    })
}

/// The sphere's pixels that the furnace measures: those whose whole
/// footprint (4 x 4 offsets) lies on a sphere slightly inside the
/// tessellated one, with the mean cos theta_o over the footprint's
/// offsets per pixel (background pixels, exactly 1, would dilute the
/// error: 43% of the image).
fn sphere_pixels() -> Vec<(usize, Vec<f32>)> {
    let cam = glint_cpu::camera::PinholeCamera::new(&furnace_camera(), FURNACE_SIZE, FURNACE_SIZE);
    let mut out = Vec::new();
    for y in 0..FURNACE_SIZE {
        for x in 0..FURNACE_SIZE {
            let mus: Option<Vec<f32>> = (0..16)
                .map(|k| {
                    let u = glam::Vec2::new((k % 4) as f32 + 0.5, (k / 4) as f32 + 0.5) / 4.0;
                    let ray = cam.ray(x, y, u);
                    sphere_mu(&ray, 0.97).and(sphere_mu(&ray, 1.0))
                })
                .collect();
            if let Some(mus) = mus {
                out.push(((y * FURNACE_SIZE + x) as usize, mus));
            }
        }
    }
    assert!(out.len() > 150, "{} sphere pixels", out.len());
    out
}

/// A 24x24, 64 spp render of a sphere of `bsdf` under a background of
/// radiance 1 (a white furnace): the mean radiance over the sphere's
/// pixels ([`sphere_pixels`]).
fn rendered_furnace(bsdf: Bsdf, seed: u64) -> f64 {
    use render_common::*;
    let mut mats = vec![diffuse("unused", 0.5)];
    mats[0].bsdf = bsdf;
    let sc = scene(
        uv_sphere(Vec3::ZERO, 1.0, 48, 24, 0),
        mats,
        vec![],
        furnace_camera(),
        Vec3::ONE,
    );
    let film = render(&sc, &opts(FURNACE_SIZE, 64, -1, seed));
    let px = sphere_pixels();
    px.iter().map(|(i, _)| film.mean(*i).x as f64).sum::<f64>() / px.len() as f64
}

/// What a convex sphere of the uncompensated F = 1 conductor renders in
/// the furnace: one bounce, so each pixel is the directional albedo
/// E(mu_o), here by quadrature (`ms_albedo_reference`, interpolated on 65
/// nodes in mu) averaged over the same pixels and footprints.
fn single_scattering_prediction(alpha: f32) -> f64 {
    let nodes: Vec<f64> = (0..=64)
        .into_par_iter()
        .map(|j| ms_albedo_reference(j as f32 / 64.0, alpha, false, 128))
        .collect();
    let e = |mu: f32| {
        let x = (mu.clamp(0.0, 1.0) * 64.0).min(63.999);
        let j = x as usize;
        let f = (x - j as f32) as f64;
        nodes[j] * (1.0 - f) + nodes[j + 1] * f
    };
    let px = sphere_pixels();
    px.iter()
        .map(|(_, mus)| mus.iter().map(|&m| e(m)).sum::<f64>() / mus.len() as f64)
        .sum::<f64>()
        / px.len() as f64
}

/// A rendered white furnace: a sphere of the F = 1 conductor in a uniform
/// background of radiance 1 renders 1 on its pixels with `multiscatter`
/// (statistically, to 1%), and without it exactly what the single
/// scattering lobe's albedo predicts (to 1%: the loss is bounded from both
/// sides, not only "darker").
#[test]
fn rendered_furnace_is_one() {
    for (alpha, ms) in [(1.0f32, true), (0.5, true), (1.0, false), (0.5, false)] {
        let mean = rendered_furnace(white(alpha, alpha, Shadowing::Correlated, ms), 9);
        eprintln!("furnace alpha {alpha} multiscatter {ms}: sphere mean {mean:.4}");
        if ms {
            assert!((mean - 1.0).abs() < 0.01, "alpha {alpha}: {mean}");
        } else {
            let want = single_scattering_prediction(alpha);
            eprintln!("  single scattering predicts {want:.4}");
            assert!(want < 0.97, "alpha {alpha}: the lobe loses energy: {want}");
            assert!(
                (mean / want - 1.0).abs() < 0.01,
                "alpha {alpha} single scattering: {mean} vs quadrature {want}"
            );
        }
    }
}

fn glass(eta: f32, alpha: f32, ms: bool) -> Bsdf {
    Bsdf::Dielectric {
        eta,
        roughness: Roughness {
            alpha_u: alpha,
            alpha_v: alpha,
            shadowing: Shadowing::Correlated,
            multiscatter: ms,
        },
        tint: glint_cpu::bsdf::Tint::NONE,
    }
}

/// Flux albedo (transmission's 1/eta_rel^2 undone) of rough glass.
fn flux_albedo(b: &Bsdf, wo: Vec3, n: usize, seed: u64) -> (f64, f64) {
    let mut rng = Pcg32::new(seed, 11);
    let (mut s1, mut s2) = (0.0f64, 0.0f64);
    for _ in 0..n {
        let v = b
            .sample(wo, rng.f32(), rng.vec2())
            .map_or(0.0, |s| (s.weight.x * s.eta * s.eta) as f64);
        s1 += v;
        s2 += v * v;
    }
    let m = s1 / n as f64;
    (m, ((s2 / n as f64 - m * m).max(0.0) / n as f64).sqrt())
}

#[test]
fn rough_glass_furnace_is_one_from_both_sides() {
    let mut failures = Vec::new();
    let mut lines = Vec::new();
    for eta in [1.5f32, 1.333, 2.42] {
        for alpha in [0.05f32, 0.3, 0.6, 1.0] {
            for c in [1.0f32, 0.5, 0.1, -0.2, -0.7, -1.0] {
                let wo = dir_cos(c, PHI_O);
                let (m, se) = flux_albedo(&glass(eta, alpha, true), wo, 60_000, 4);
                let (m0, _) = flux_albedo(&glass(eta, alpha, false), wo, 60_000, 4);
                lines.push(format!(
                    "eta {eta} alpha {alpha} cos {c}: {m0:.4} -> {m:.4} +- {se:.4}"
                ));
                if (m - 1.0).abs() > 0.01 + 3.0 * se {
                    failures.push(lines.last().unwrap().clone());
                }
            }
        }
    }
    eprintln!("{}", lines.join("\n"));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn rough_glass_sampling_matches_eval_and_pdf() {
    let mut bad = 0;
    let mut total = 0;
    let mut rng = Pcg32::new(5, 5);
    for alpha in [0.05f32, 0.3, 1.0] {
        let b = glass(1.5, alpha, true);
        for c in [0.9f32, 0.3, -0.3, -0.9] {
            let wo = dir_cos(c, PHI_O);
            for _ in 0..3000 {
                let Some(s) = b.sample(wo, rng.f32(), rng.vec2()) else {
                    continue;
                };
                total += 1;
                let pdf = b.pdf(wo, s.wi);
                let w = b.eval(wo, s.wi) * s.wi.z.abs() / pdf;
                if (pdf - s.pdf).abs() > 1e-3 * pdf
                    || (w - s.weight).abs().max_element() > 1e-3 * w.max_element() + 1e-6
                {
                    bad += 1;
                }
            }
        }
    }
    assert!(bad * 1000 <= total, "{bad} of {total} inconsistent");
}

/// A rendered furnace of a rough glass sphere renders 1 within 1.5%: each
/// interaction's albedo is 1 within the tables' interpolation error
/// (~0.3%), which compounds over the internal bounces (on the sphere's
/// pixels 0.991 measured at alpha = 1, up from 0.342 without
/// compensation; the whole-image 0.96 this comment once gave was diluted
/// by the background, which is exactly 1).
#[test]
fn rendered_glass_furnace_is_one() {
    for (alpha, ms) in [(1.0f32, true), (0.3, true), (1.0, false)] {
        let mean = rendered_furnace(glass(1.5, alpha, ms), 10);
        eprintln!("glass furnace alpha {alpha} multiscatter {ms}: mean {mean:.4}");
        if ms {
            assert!((mean - 1.0).abs() < 0.015, "alpha {alpha}: {mean}");
        } else {
            assert!(mean < 0.9, "alpha {alpha} single scattering: {mean}");
        }
    }
}
