//! `glint diff A.exr B.exr [--diff OUT.png] [--json FILE]`: A measured
//! against B (the reference) with `glint_cpu::metrics`; when both files
//! carry `variance.*`, the block z-test of `glint_cpu::compare` decides
//! whether they agree. `run` returns Ok(true) for agree, Ok(false) for
//! differ; errors are bad input (exit 2), and so is no verdict at all
//! (either file without variance, a non-finite value, sizes that differ)
//! unless `--max-relmse` / `--max-flip` is given, which then decides.

use std::path::Path;

use anyhow::{Result, anyhow, bail};
use glam::Vec3;
use glint::cpu::compare::{self, CompareReport, Estimate};
use glint::cpu::exr_file::RadianceImage;
use glint::cpu::metrics::{self, ImageRef};

use super::outputs::Outputs;
use crate::cli::DiffArgs;

/// z at which the difference image saturates.
const Z_RANGE: f32 = 5.0;
/// The relative error's denominator offset (relMSE's, in linear units).
const REL_EPS: f32 = 0.1;

fn read(path: &Path) -> Result<RadianceImage> {
    super::check_input_file(path, "an EXR image")?;
    RadianceImage::read(path).map_err(|e| anyhow!("{}: {e}", path.display()))
}

/// Per pixel, the channel with the largest |value| (sign kept).
fn extreme(v: Vec3) -> f32 {
    let mut best = v.x;
    for c in [v.y, v.z] {
        if c.abs() > best.abs() || c.is_nan() {
            best = c;
        }
    }
    best
}

/// Per-pixel z = (A - B) / sqrt(var A + var B), or with no variance the
/// relative error (A - B) / (|B| + 0.1).
fn difference_values(a: &RadianceImage, b: &RadianceImage) -> (Vec<f32>, f32, String) {
    match (&a.variance, &b.variance) {
        (Some(va), Some(vb)) => {
            let v = (0..a.mean.len())
                .map(|i| {
                    let d = a.mean[i] - b.mean[i];
                    let s = (va[i] + vb[i]).to_array().map(f32::sqrt);
                    extreme(Vec3::from_array(std::array::from_fn(|c| {
                        if s[c] > 0.0 {
                            d[c] / s[c]
                        } else if d[c] == 0.0 {
                            0.0
                        } else {
                            d[c].signum() * f32::INFINITY
                        }
                    })))
                })
                .collect();
            (v, Z_RANGE, "z = (A-B)/sd".to_string())
        }
        _ => {
            let v: Vec<f32> = (0..a.mean.len())
                .map(|i| {
                    extreme((a.mean[i] - b.mean[i]) / (b.mean[i].abs() + Vec3::splat(REL_EPS)))
                })
                .collect();
            // Saturate at the 99th percentile of |error|, rounded up to a
            // 1-2-5 step (at least 1%).
            let mut mags: Vec<f32> = v
                .iter()
                .map(|x| x.abs())
                .filter(|x| x.is_finite())
                .collect();
            mags.sort_by(f32::total_cmp);
            let p99 = mags
                .get(((mags.len() as f64 * 0.99) as usize).min(mags.len().saturating_sub(1)))
                .copied()
                .unwrap_or(0.0)
                .max(0.01);
            let decade = 10f32.powf(p99.log10().floor());
            let range = [1.0, 2.0, 5.0, 10.0]
                .iter()
                .map(|m| m * decade)
                .find(|r| *r >= p99)
                .unwrap_or(10.0 * decade);
            (v, range, "(A-B)/(|B|+0.1)".to_string())
        }
    }
}

/// The relative-error colour-bar image of `a` against `b` (diff's image
/// for files without variance), as PNG bytes: `glint test`'s difference.
pub fn relative_difference_png(a: &RadianceImage, b: &RadianceImage) -> Result<Vec<u8>> {
    let strip = |i: &RadianceImage| RadianceImage {
        variance: None,
        ..i.clone()
    };
    let (values, range, label) = difference_values(&strip(a), &strip(b));
    glint::heatmap::png(a.width, a.height, &values, range, &label).map_err(|e| anyhow!("{e}"))
}

/// The largest |a - b| / max(|a|, |b|) over pixels and channels (0 where
/// both are 0): how exactly two images match (merged shards against one
/// render).
fn max_relative_difference(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(x, y)| (0..3).map(move |c| (x[c] as f64, y[c] as f64)))
        .map(|(x, y)| {
            let m = x.abs().max(y.abs());
            if m == 0.0 { 0.0 } else { (x - y).abs() / m }
        })
        .fold(0.0, f64::max)
}

/// Where `img` holds a value that is not finite (mean or variance).
fn non_finite(img: &RadianceImage) -> Option<String> {
    if let Some(at) = super::first_non_finite(img.width, &img.mean) {
        return Some(format!("a non-finite value (NaN or infinite) at {at}"));
    }
    let v = img.variance.as_ref()?;
    super::first_non_finite(img.width, v)
        .map(|at| format!("a non-finite variance (NaN or infinite) at {at}"))
}

/// The options' ranges, and outputs that would overwrite an input.
fn check_args(args: &DiffArgs) -> Result<()> {
    if !(args.alpha > 0.0 && args.alpha < 1.0) {
        bail!("--alpha {} is out of range (0, 1)", args.alpha);
    }
    for (name, v) in [("max-relmse", args.max_relmse), ("max-flip", args.max_flip)] {
        if let Some(x) = v
            && !(x.is_finite() && x >= 0.0)
        {
            bail!("--{name} {x} is out of range (a finite number >= 0)");
        }
    }
    if let Some(d) = &args.diff
        && glint::cpu::OutputFormat::from_path(d) != Some(glint::cpu::OutputFormat::Png)
    {
        bail!("{}: the difference image is a .png", d.display());
    }
    for o in args.diff.iter().chain(&args.json) {
        for input in [&args.a, &args.b] {
            if super::outputs::names_same(o, input) {
                bail!("{}: is an input; refusing to overwrite it", o.display());
            }
        }
    }
    Ok(())
}

/// The block test of `a` against `b` when both hold variances; None
/// (the thresholds decide) when either has none, or, with thresholds,
/// when the test has no power.
fn statistical_report<'a>(
    a: &'a RadianceImage,
    b: &'a RadianceImage,
    args: &DiffArgs,
    thresholds: bool,
) -> Result<Option<CompareReport>> {
    let (an, bn) = (args.a.display(), args.b.display());
    Ok(match (&a.variance, &b.variance) {
        (Some(va), Some(vb)) => {
            let estimate = |img: &'a RadianceImage, variance: &'a [Vec3]| Estimate {
                width: img.width,
                height: img.height,
                mean: &img.mean,
                variance,
                samples: img.variance_samples(),
            };
            match compare::compare_estimates(&estimate(a, va), &estimate(b, vb), args.alpha) {
                Ok(r) => Some(r),
                // No statistical verdict (no power): the thresholds decide.
                Err(e) if thresholds => {
                    println!("no statistical verdict: {an} vs {bn}: {e}");
                    None
                }
                Err(e) => bail!("{an} vs {bn}: {e}"),
            }
        }
        _ => None,
    })
}

/// The `--json` record: inputs, metrics, verdict and the test's figures.
fn json_report(
    args: &DiffArgs,
    a: &RadianceImage,
    m: &metrics::Metrics,
    max_rel: f64,
    verdict: Option<&str>,
    report: Option<&CompareReport>,
) -> serde_json::Value {
    let ratio = m.mean_ratio();
    let mut j = serde_json::json!({
        "a": args.a.display().to_string(),
        "b": args.b.display().to_string(),
        "width": a.width,
        "height": a.height,
        "relmse": m.relmse,
        "relmse_trim": m.relmse_trim,
        "rmse": m.rmse,
        "flip": m.flip,
        "mean_a": m.mean.to_array(),
        "mean_b": m.reference_mean.to_array(),
        "mean_ratio": ratio.to_array(),
        "max_relative_difference": max_rel,
        "verdict": verdict,
        "alpha": args.alpha,
        "max_relmse": args.max_relmse,
        "max_flip": args.max_flip,
    });
    if let Some(r) = report {
        j["test"] = serde_json::json!({
            "tests": r.tests,
            "z_max": r.z_max,
            "z_local": r.z_local,
            "exceed_global": r.exceed_global,
            "allowed_global": r.allowed_global,
            "skipped_blocks": r.skipped,
        });
    }
    j
}

/// Warnings from the two images' glint metadata: different scenes or
/// options, or the same seed and samples (not independent renders).
fn warn_on_metadata(a: &RadianceImage, b: &RadianceImage, an: &str, bn: &str) {
    let (Some(ma), Some(mb)) = (&a.meta, &b.meta) else {
        return;
    };
    if ma.scene.is_some() && mb.scene.is_some() && ma.scene != mb.scene {
        eprintln!("glint: warning: {an}: rendered from a different scene or options than {bn}");
    }
    let overlap = ma
        .samples
        .iter()
        .any(|x| mb.samples.iter().any(|y| x.0 < y.1 && y.0 < x.1));
    if ma.seed == mb.seed && ma.sampler == mb.sampler && overlap {
        eprintln!(
            "glint: warning: {an}: same seed and samples as {bn}: not independent renders, \
             so the test is conservative (use another --seed for the reference)"
        );
    }
}

/// The threshold line: which limits were given and whether they hold.
fn print_thresholds(args: &DiffArgs, hold: bool) {
    let limits: Vec<String> = [("relMSE", args.max_relmse), ("FLIP", args.max_flip)]
        .iter()
        .filter_map(|(n, x)| x.map(|x| format!("{n} <= {x:e}")))
        .collect();
    println!(
        "thresholds {}: {}",
        limits.join(", "),
        if hold { "met" } else { "not met" }
    );
}

pub fn run(args: &DiffArgs) -> Result<bool> {
    check_args(args)?;
    let thresholds = args.max_relmse.is_some() || args.max_flip.is_some();
    let mut outputs = Outputs::new();
    let diff_slot = args.diff.as_ref().map(|p| outputs.reserve(p)).transpose()?;
    let json_slot = args.json.as_ref().map(|p| outputs.reserve(p)).transpose()?;
    let a = read(&args.a)?;
    let b = read(&args.b)?;
    let (an, bn) = (args.a.display(), args.b.display());
    if (a.width, a.height) != (b.width, b.height) {
        let why = format!(
            "{an}: {}x{} but {bn} is {}x{}",
            a.width, a.height, b.width, b.height
        );
        if thresholds {
            println!("differ: {why} (no threshold can hold)");
            return Ok(false);
        }
        bail!("{why}");
    }
    for (img, name) in [(&a, &an), (&b, &bn)] {
        if let Some(why) = non_finite(img) {
            if thresholds {
                println!("differ: {name}: {why} (no threshold can hold)");
                return Ok(false);
            }
            bail!("{name}: {why}; no verdict");
        }
    }
    warn_on_metadata(&a, &b, &an.to_string(), &bn.to_string());
    let ia = ImageRef::new(a.width, a.height, &a.mean)?;
    let ib = ImageRef::new(b.width, b.height, &b.mean)?;
    let m = metrics::compute(&ia, &ib)?;
    let ratio = m.mean_ratio();
    let max_rel = max_relative_difference(&a.mean, &b.mean);

    let report = statistical_report(&a, &b, args, thresholds)?;

    if let Some(slot) = diff_slot {
        let (values, range, label) = difference_values(&a, &b);
        let png = glint::heatmap::png(a.width, a.height, &values, range, &label)?;
        use std::io::Write;
        outputs.write(slot, |w| Ok(w.write_all(&png)?))?;
    }
    let within = |m_: f64, max: Option<f64>| max.is_none_or(|x| m_ <= x);
    let thresholds_hold = within(m.relmse, args.max_relmse) && within(m.flip, args.max_flip);
    // The statistical verdict when there is one (and the thresholds, when
    // given, must hold too); else the thresholds alone; else none.
    let pass: Option<bool> = match &report {
        Some(r) => Some(r.pass && thresholds_hold),
        None if thresholds => Some(thresholds_hold),
        None => None,
    };
    let verdict = pass.map(|p| if p { "agree" } else { "differ" });
    if let Some(slot) = json_slot {
        let j = json_report(args, &a, &m, max_rel, verdict, report.as_ref());
        outputs.write(slot, |w| {
            serde_json::to_writer_pretty(&mut *w, &j)?;
            use std::io::Write;
            writeln!(w)?;
            Ok(())
        })?;
    }
    outputs.commit()?;

    println!(
        "{an} vs {bn}: relMSE {:.4e}, RMSE {:.4e}, FLIP {:.4}, mean ratio [{:.4}, {:.4}, {:.4}]",
        m.relmse, m.rmse, m.flip, ratio.x, ratio.y, ratio.z
    );
    if let Some(r) = &report {
        println!("{}: {r}", if r.pass { "agree" } else { "differ" });
    }
    if thresholds {
        print_thresholds(args, thresholds_hold);
    }
    match pass {
        Some(p) => Ok(p),
        None => {
            let missing = if a.variance.is_none() { &an } else { &bn };
            bail!(
                "{missing}: holds no variance, so there is no statistical verdict \
                 (render with --variance, or give --max-relmse / --max-flip)"
            )
        }
    }
}
