//! The environment light: the direction mapping, importance sampling
//! against its own pdf (chi-square over texels), the estimate of its
//! integral, and a constant envmap rendering exactly like the same
//! constant background.

use glint_cpu::sampling::Pcg32;
use std::f32::consts::PI;
use std::sync::Arc;

use glam::{Vec2, Vec3};
use glint_cpu::envmap::EnvMap;
use glint_cpu::{Material, RenderOptions, Scene};
use statrs::distribution::{ChiSquared, ContinuousCDF};

mod render_common;

/// A 16x8 map with a smooth sky, a bright spot and some black texels.
fn test_map(rotation: f32) -> EnvMap {
    let (w, h) = (16u32, 8u32);
    let mut rgb = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let base = 0.2 + 0.1 * ((x * 7 + y * 3) % 5) as f32;
            let c = if (x, y) == (5, 2) {
                [30.0, 25.0, 20.0]
            } else if x % 7 == 3 {
                [0.0; 3]
            } else {
                [base, base * 0.8, base * 1.2]
            };
            rgb.push(c);
        }
    }
    EnvMap::new(w, h, &rgb, 1.0, rotation)
}

#[test]
fn direction_mapping_round_trips_and_is_documented() {
    let e = test_map(0.0);
    // The image's left edge looks down -Z, a quarter across +X, the
    // centre +Z, the top row up.
    let d = |u: f32, v: f32| e.uv_to_direction(Vec2::new(u, v));
    assert!((d(0.0, 0.5) - Vec3::NEG_Z).length() < 1e-5);
    assert!((d(0.25, 0.5) - Vec3::X).length() < 1e-5);
    assert!((d(0.5, 0.5) - Vec3::Z).length() < 1e-5);
    assert!((d(0.3, 0.0) - Vec3::Y).length() < 1e-5);
    for rot in [0.0, 0.7, -2.0] {
        let e = test_map(rot);
        let mut rng = Pcg32::from_state(5);
        for _ in 0..1000 {
            let uv = Vec2::new(rng.f32(), 0.01 + 0.98 * rng.f32());
            let back = e.direction_to_uv(e.uv_to_direction(uv));
            // u wraps: 0 and 1 are the same seam.
            let du = (back.x - uv.x).abs();
            let err = Vec2::new(du.min(1.0 - du), back.y - uv.y);
            assert!(err.length() < 1e-4, "{uv} -> {back}");
        }
    }
    // Rotation turns the map about +Y: +90 degrees carries -Z to -X.
    let r = test_map(PI / 2.0);
    assert!((r.uv_to_direction(Vec2::new(0.0, 0.5)) - Vec3::NEG_X).length() < 1e-5);
}

#[test]
fn sampling_matches_its_pdf_chi_square() {
    let e = test_map(0.4);
    let (w, h) = (e.width as usize, e.height as usize);
    let n = 400_000;
    let mut counts = vec![0u64; w * h];
    let mut rng = Pcg32::from_state(17);
    let mut estimate = Vec3::ZERO;
    let mut edge = 0;
    for _ in 0..n {
        let s = e.sample(Vec2::new(rng.f32(), rng.f32())).expect("a sample");
        // pdf and radiance are those of the direction returned (but for
        // rounding on a texel edge).
        if (s.pdf - e.pdf(s.wi)).abs() > 1e-3 * s.pdf || s.radiance != e.radiance(s.wi) {
            edge += 1;
        }
        let uv = e.direction_to_uv(s.wi);
        let x = ((uv.x * w as f32) as usize).min(w - 1);
        let y = ((uv.y * h as f32) as usize).min(h - 1);
        counts[y * w + x] += 1;
        estimate += s.radiance / s.pdf;
    }
    assert!(
        edge < n / 1000,
        "{edge} samples disagree with pdf()/radiance()"
    );
    // Chi-square over texels (cells with expected count >= 5 each; the rest
    // pooled), significance 0.01.
    let (mut chi2, mut dof) = (0.0f64, 0usize);
    let (mut pooled_obs, mut pooled_exp) = (0.0f64, 0.0f64);
    for y in 0..h {
        for x in 0..w {
            let expected = e.texel_pmf(x as u32, y as u32) as f64 * n as f64;
            let observed = counts[y * w + x] as f64;
            if expected == 0.0 {
                assert_eq!(observed, 0.0, "a black texel was sampled");
            } else if expected < 5.0 {
                pooled_obs += observed;
                pooled_exp += expected;
            } else {
                chi2 += (observed - expected).powi(2) / expected;
                dof += 1;
            }
        }
    }
    if pooled_exp > 0.0 {
        chi2 += (pooled_obs - pooled_exp).powi(2) / pooled_exp;
        dof += 1;
    }
    let p = 1.0 - ChiSquared::new((dof - 1) as f64).unwrap().cdf(chi2);
    assert!(p > 0.01, "chi2 {chi2} with {} dof: p = {p}", dof - 1);
    // The pdf integrates to one over each texel: the estimator of the
    // integral of radiance matches the exact sum over texels.
    let mut exact = Vec3::ZERO;
    for y in 0..h {
        let (t0, t1) = (PI * y as f32 / h as f32, PI * (y + 1) as f32 / h as f32);
        let solid = 2.0 * PI / w as f32 * (t0.cos() - t1.cos());
        for x in 0..w {
            let c = e.texels[y * w + x];
            exact += Vec3::new(c[0], c[1], c[2]) * solid;
        }
    }
    let est = estimate / n as f32;
    assert!(
        ((est - exact) / exact).abs().max_element() < 0.01,
        "{est} vs {exact}"
    );
}

/// A diffuse quad (albedo 0.5) seen head-on, nothing else.
fn quad_scene() -> Scene {
    let m = Material {
        name: "grey".into(),
        bsdf: glint_cpu::Bsdf::Diffuse {
            reflectance: Vec3::splat(0.5),
        },
        emission: Vec3::ZERO,
        double_sided: false,
        absorption: glam::Vec3::ZERO,
    };
    // The quad [-1, 1]^2 at z = 0 facing +Z, seen from z = 4 with a wider
    // view, so the background shows around it.
    let tris = render_common::quad(
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(-1.0, 1.0, 0.0),
        0,
    );
    let cam = render_common::look_at(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y, 40.0);
    render_common::scene(tris, vec![m], vec![], cam, Vec3::ZERO)
}

#[test]
fn constant_envmap_equals_the_same_background() {
    let mut bg = quad_scene();
    bg.background = Vec3::splat(0.8);
    let mut env = quad_scene();
    env.background = Vec3::ZERO;
    env.envmap = Some(Arc::new(EnvMap::new(8, 4, &[[0.8; 3]; 32], 1.0, 0.3)));
    let o = RenderOptions {
        spp: 64,
        ..RenderOptions::new(16, 16)
    };
    let mean = |s: &Scene| {
        let f = glint_cpu::render(s, &o, &|_, _| {}).unwrap().0;
        f.means().iter().copied().sum::<Vec3>() / f.means().len() as f32
    };
    let (a, b) = (mean(&bg), mean(&env));
    // Albedo 0.5 under radiance 0.8 with the sky around: 0.4 on the quad,
    // 0.8 where the background shows.
    assert!(((a - b) / a).abs().max_element() < 0.01, "{a} vs {b}");
    assert!(a.min_element() > 0.39);
}

/// A texel with any non-finite channel (after the scale) emits nothing, in
/// every channel, as the load's warning says; negative channels clamp to 0.
#[test]
fn a_non_finite_texel_emits_nothing() {
    let rgb = [
        [f32::NAN, 1.0, 1.0],
        [1.0, f32::INFINITY, 1.0],
        [-1.0, 2.0, 3.0],
        [1e38, 1.0, 1.0],
    ];
    let m = EnvMap::new(4, 1, &rgb, 10.0, 0.0);
    let t: Vec<[f32; 3]> = m.texels.iter().map(|t| [t[0], t[1], t[2]]).collect();
    assert_eq!(
        t,
        [[0.0; 3], [0.0; 3], [0.0, 20.0, 30.0], [0.0; 3]],
        "1e38 x 10 overflows"
    );
}
