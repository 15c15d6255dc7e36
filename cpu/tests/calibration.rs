//! Calibration of the estimated relMSE, the quantity `--target-error` stops
//! on (`adaptive::estimated_relmse`): over 20 seeds of every bundled scene,
//! with both samplers, the mean estimate over the mean true relMSE (the
//! contract's, against a 16384-spp reference of the independent sampler,
//! its own estimated error subtracted) must lie in [0.5, 2]. Below 1/2 the
//! rule stops early on average; above 2 it wastes samples. 256 spp, 24 px
//! (`scripts/calibrate_error.py 20 256 24 16384` prints the same table).
//!
//! The renders are deterministic for their seeds, so this is a fixed
//! regression check of the estimator, not a draw; what it pins (0.81-1.83
//! with the few-samples rule of `estimated_relmse`, 0.30-0.99 on the
//! heavy-tailed scenes without it) is in docs/benchmarks.md.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use glint_cpu::adaptive::estimated_relmse;
use glint_cpu::metrics::{ImageRef, compute};
use glint_cpu::{Film, RenderOptions, SamplerKind, Scene};
use rayon::prelude::*;

const SEEDS: u64 = 20;
const SPP: u32 = 256;
const WIDTH: u32 = 24;
const REF_SPP: u32 = 16384;

fn assets() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets");
    let mut v: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "gltf"))
        .collect();
    v.sort();
    v
}

/// WIDTH pixels wide, the height from the first camera's aspect (as
/// `glint render`), `spp` samples of `seed`.
fn options(scene: &glint_cpu::Scene, spp: u32, seed: u64) -> RenderOptions {
    let mut o = RenderOptions::new(WIDTH, WIDTH);
    if let Some(a) = scene.cameras.first().and_then(|c| c.aspect_ratio) {
        o.height = ((WIDTH as f32 / a).round() as u32).max(1);
    }
    o.spp = spp;
    o.seed = seed;
    o
}

fn render(scene: &glint_cpu::Scene, spp: u32, seed: u64, sampler: SamplerKind) -> Film {
    let o = RenderOptions {
        sampler,
        // Whole passes with the control's batches, as `--target-error` runs.
        target_error: Some(1e-12),
        ..options(scene, spp, seed)
    };
    glint_cpu::render(scene, &o, &|_, _| {}).unwrap().0
}

fn relmse(img: &Film, reference: &Film) -> f64 {
    let (a, b) = (img.means(), reference.means());
    let m = compute(
        &ImageRef::new(img.width, img.height, &a).unwrap(),
        &ImageRef::new(reference.width, reference.height, &b).unwrap(),
    )
    .unwrap();
    m.relmse
}

/// A bundled scene with its reference (REF_SPP, independent sampler) and
/// the reference's own estimated relMSE, subtracted from the true errors.
struct Case {
    name: String,
    scene: Scene,
    reference: Film,
    ref_err: f64,
}

/// Every bundled scene's case, rendered once for both tests.
fn cases() -> &'static [Case] {
    static CASES: OnceLock<Vec<Case>> = OnceLock::new();
    CASES.get_or_init(|| {
        assets()
            .par_iter()
            .map(|path| {
                let scene = glint_cpu::prepare::prepare_default(path).unwrap();
                let reference = render(&scene, REF_SPP, 999, SamplerKind::Independent);
                Case {
                    name: path.file_stem().unwrap().to_string_lossy().into_owned(),
                    ref_err: estimated_relmse(&reference),
                    scene,
                    reference,
                }
            })
            .collect()
    })
}

#[test]
fn estimated_relmse_is_calibrated_on_every_bundled_scene() {
    let rows: Vec<(String, &str, f64)> = cases()
        .par_iter()
        .flat_map_iter(|c| {
            let (name, scene, reference, ref_err) = (&c.name, &c.scene, &c.reference, c.ref_err);
            [
                (SamplerKind::Independent, "independent"),
                (SamplerKind::Sobol, "sobol"),
            ]
            .into_iter()
            .map(|(sampler, label)| {
                let (mut est, mut truth) = (0.0, 0.0);
                for seed in 1..=SEEDS {
                    let f = render(scene, SPP, seed, sampler);
                    est += estimated_relmse(&f);
                    truth += (relmse(&f, reference) - ref_err).max(1e-30);
                }
                (name.clone(), label, est / truth)
            })
            .collect::<Vec<_>>()
        })
        .collect();
    let table: Vec<String> = rows
        .iter()
        .map(|(n, s, r)| format!("{n} {s}: estimated / true {r:.2}"))
        .collect();
    eprintln!("{}", table.join("\n"));
    let bad: Vec<&String> = rows
        .iter()
        .zip(&table)
        .filter(|((_, _, r), _)| !(0.5..=2.0).contains(r))
        .map(|(_, line)| line)
        .collect();
    assert!(bad.is_empty(), "outside [0.5, 2]: {bad:?}");
}

/// `--target-error E` meets its target in the mean over seeds: the true
/// relMSE of the renders it stops, averaged over 10 seeds, is at most
/// 1.25 E on every bundled scene (measured: at most E but on the
/// rough-glass caustic, 1.20 E at E = 0.005, the mean of ten heavy-tailed
/// errors having its own spread; 1.44 E without the stopping margin,
/// `adaptive::TARGET_MARGIN`), and a larger target stops no later.
#[test]
fn target_error_meets_its_target_in_the_mean() {
    let failures: Vec<String> = cases()
        .par_iter()
        .flat_map_iter(|c| {
            let (name, scene, reference, ref_err) = (&c.name, &c.scene, &c.reference, c.ref_err);
            let mut out = Vec::new();
            let mut spp = Vec::new();
            for target in [0.02, 0.005] {
                let (mut truth, mut total_spp) = (0.0, 0u64);
                for seed in 1..=10u64 {
                    let o = RenderOptions {
                        target_error: Some(target),
                        ..options(scene, 1 << 16, seed)
                    };
                    let f = glint_cpu::render(scene, &o, &|_, _| {}).unwrap().0;
                    truth += (relmse(&f, reference) - ref_err).max(0.0);
                    total_spp += f.spp as u64;
                }
                let mean = truth / 10.0;
                eprintln!(
                    "{name} target {target}: true relMSE {mean:.3e}, mean spp {}",
                    total_spp / 10
                );
                if mean > 1.25 * target {
                    out.push(format!("{name}: target {target}, true relMSE {mean:.3e}"));
                }
                spp.push(total_spp);
            }
            if spp[0] > spp[1] {
                out.push(format!(
                    "{name}: the larger target took more samples {spp:?}"
                ));
            }
            out
        })
        .collect();
    assert!(failures.is_empty(), "{failures:?}");
}
