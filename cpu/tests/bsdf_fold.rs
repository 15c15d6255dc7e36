//! The folded BSDF of a normal-mapped hit (`glint_cpu::bsdf::fold`):
//! its sampling against its density (chi-square, on a grid about the
//! geometric normal, where the fold's support is the upper hemisphere),
//! and its energy: the fold reflects what the BSDF reflects over the whole
//! sphere, no more, no less.

mod common;

use common::*;
use glam::Vec3;
use glint_cpu::bsdf::Bsdf;
use glint_cpu::bsdf::fold::Fold;
use rayon::prelude::*;

const SAMPLES: usize = 1_000_000;
const ALPHA: f64 = 0.01;

/// A shading normal tilted by `t` from the geometric one: the rotation
/// taking the geometric frame (ng = +z) to the shading frame, and back.
#[derive(Clone, Copy)]
struct Tilt {
    c: f32,
    s: f32,
}

impl Tilt {
    fn new(degrees: f32) -> Self {
        let t = degrees.to_radians();
        Tilt {
            c: t.cos(),
            s: t.sin(),
        }
    }
    /// A geometric-frame direction in the shading frame.
    fn to_shading(self, w: Vec3) -> Vec3 {
        Vec3::new(
            w.x * self.c + w.z * self.s,
            w.y,
            -w.x * self.s + w.z * self.c,
        )
    }
    fn to_geometric(self, w: Vec3) -> Vec3 {
        Vec3::new(
            w.x * self.c - w.z * self.s,
            w.y,
            w.x * self.s + w.z * self.c,
        )
    }
    /// The geometric normal in the shading frame.
    fn ng(self) -> Vec3 {
        self.to_shading(Vec3::Z)
    }
}

/// The chi-square cases' reflection-only BSDFs (one outgoing direction of
/// each, the cases' own directions do not matter here), each under tilts
/// of 35 and 60 degrees, seen from directions above the geometric surface
/// at either side of the tilt.
fn fold_cases() -> Vec<(String, Bsdf, Tilt, Vec3)> {
    let mut seen = Vec::new();
    let mut out = Vec::new();
    for c in chi2_cases() {
        let kind = c.name.split(" cos=").next().unwrap().to_string();
        if c.bsdf.has_transmission() || c.bsdf.is_delta() || seen.contains(&kind) {
            continue;
        }
        seen.push(kind.clone());
        for deg in [35.0, 60.0] {
            // (0.8, 0.3) leans away from the tilted normal: at 60 degrees
            // it is below the shading horizon, the two-sided lobe lies on
            // the far side and most of it folds. (0.15, 3.1) grazes the
            // geometric surface near the tilted normal.
            for (cos, phi) in [(0.8f32, 0.3f32), (0.15, 3.1)] {
                let wo = dir_cos(cos, phi);
                out.push((
                    format!("{kind} tilt={deg} wo=({cos},{phi})"),
                    c.bsdf,
                    Tilt::new(deg),
                    wo,
                ));
            }
        }
    }
    out
}

fn chi2_of(bsdf: &Bsdf, tilt: Tilt, wo_g: Vec3, seed: u64) -> Result<Chi2Report, String> {
    let wo = tilt.to_shading(wo_g);
    let fold = Fold::new(tilt.ng(), wo);
    // A delta lobe lands where the fold sends its direction.
    let deltas: Vec<DeltaLobe> = delta_lobes(bsdf, wo)
        .into_iter()
        .map(|d| DeltaLobe {
            dir: tilt.to_geometric(if fold.above(d.dir) {
                d.dir
            } else {
                fold.mirror(d.dir)
            }),
            mass: d.mass,
        })
        .collect();
    chi2_test(
        &|uc, u| {
            fold.sample(&bsdf.at(wo), uc, u)
                .map(|s| (tilt.to_geometric(s.wi), s.delta))
        },
        &|w| fold.eval_pdf(&bsdf.at(wo), tilt.to_shading(w)).1 as f64,
        &deltas,
        SAMPLES,
        seed,
        &Grid::for_case(bsdf, wo_g),
    )
}

#[test]
fn folded_sampling_matches_folded_pdf() {
    let cases = fold_cases();
    assert!(cases.len() >= 40, "{} cases", cases.len());
    let level = sidak(ALPHA, cases.len());
    let failures: Vec<String> = cases
        .par_iter()
        .enumerate()
        .filter_map(
            |(i, (name, b, t, wo))| match chi2_of(b, *t, *wo, 7000 + i as u64) {
                Err(e) => Some(format!("{name}: {e}")),
                Ok(r) if r.p_value < level => Some(format!("{name}: rejected, {r:?}")),
                Ok(_) => None,
            },
        )
        .collect();
    assert!(
        failures.is_empty(),
        "{} of {} failed (level {level:.2e}):\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}

/// Mean and standard error of `n` draws of `x`.
fn mean_se(n: usize, x: impl Fn(usize) -> Vec3 + Sync) -> (f64, f64) {
    let v: Vec<f64> = (0..n).into_par_iter().map(|i| x(i).x as f64).collect();
    let m = v.iter().sum::<f64>() / n as f64;
    let var = v.iter().map(|a| (a - m) * (a - m)).sum::<f64>() / (n - 1) as f64;
    (m, (var / n as f64).sqrt())
}

#[test]
fn folding_keeps_the_bsdfs_own_albedo() {
    // Three estimates of one integral, each independent of the others:
    // the BSDF's albedo over the whole sphere (its own sampling weights,
    // unfolded), the folded samples' mean weight, and (delta lobes aside)
    // the folded f cos integrated by uniform sampling of the geometric
    // upper hemisphere.
    // A fold that dropped the mirrored term, or sampled one density and
    // reported another, pulls one of them apart from the rest.
    let n = 100_000;
    for (name, bsdf, tilt, wo_g) in fold_cases() {
        let wo = tilt.to_shading(wo_g);
        let fold = Fold::new(tilt.ng(), wo);
        let u = |i: usize, k: u64| {
            let mut r = Pcg32::new(i as u64, k);
            (r.f32(), r.vec2())
        };
        let (albedo, se_a) = mean_se(n, |i| {
            let (uc, u2) = u(i, 1);
            bsdf.sample(wo, uc, u2).map_or(Vec3::ZERO, |s| s.weight)
        });
        // The part f describes (without the delta lobes), as the
        // quadrature below sees it.
        let (diffuse, se_d) = mean_se(n, |i| {
            let (uc, u2) = u(i, 1);
            bsdf.sample(wo, uc, u2)
                .filter(|s| !s.delta)
                .map_or(Vec3::ZERO, |s| s.weight)
        });
        let (folded, se_f) = mean_se(n, |i| {
            let (uc, u2) = u(i, 2);
            fold.sample(&bsdf.at(wo), uc, u2)
                .map_or(Vec3::ZERO, |s| s.weight)
        });
        let uniform = |i: usize| {
            let (_, u2) = u(i, 3);
            let z = u2.x;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = 2.0 * std::f32::consts::PI * u2.y;
            fold.eval_pdf(
                &bsdf.at(wo),
                tilt.to_shading(Vec3::new(r * phi.cos(), r * phi.sin(), z)),
            )
        };
        let (integral, se_i) = mean_se(n, |i| uniform(i).0 * (2.0 * std::f32::consts::PI));
        let tol = |a: f64, b: f64| 5.0 * (a * a + b * b).sqrt() + 2e-3;
        assert!(
            (folded - albedo).abs() < tol(se_f, se_a),
            "{name}: folded samples {folded} against the albedo {albedo}"
        );
        // Uniform directions resolve lobes no sharper than about a tenth
        // of the hemisphere (a peak density of 20); the sharper ones are
        // the chi-square test's and the first comparison's.
        let peak = (0..n).map(|i| uniform(i).1).fold(0.0f32, f32::max);
        if peak > 20.0 {
            eprintln!("{name}: peak density {peak}, no quadrature");
        }
        assert!(
            peak > 20.0 || (integral - diffuse).abs() < tol(se_i, se_d),
            "{name}: folded f cos integrates to {integral}, the BSDF's to {diffuse}"
        );
        assert!(albedo <= 1.0 + 5.0 * se_a, "{name}: albedo {albedo}");
    }
}
