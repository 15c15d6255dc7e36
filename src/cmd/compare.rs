//! `glint compare`: both backends on one scene, the statistical test of
//! glint_cpu::compare, one line of verdict on stdout.

use anyhow::{Result, anyhow, bail};
use glint::backend::Backend;
use glint::cpu::RenderOptions;

use super::{check_params, load_scene, render_on};
use crate::cli::CompareArgs;

/// The CPU's seed in `glint compare`: any value other than the GPU's.
fn cpu_seed(seed: u64) -> u64 {
    seed ^ 0x9e37_79b9_7f4a_7c15
}

pub fn run(args: &CompareArgs) -> Result<()> {
    check_params(&args.scene)?;
    if !(args.alpha > 0.0 && args.alpha < 1.0) {
        bail!("--alpha {} is out of range (0, 1)", args.alpha);
    }
    if args.scene.spp.is_some_and(|n| n < 2) {
        bail!("--spp must be at least 2 to estimate the variance");
    }
    let (scene, opts) = load_scene(&args.scene)?;
    let path = &args.scene.scene;
    let ro = &args.scene.opts;
    // Independent seeds: with the same seed both backends trace the same
    // paths (one random stream), and the Welch test assumes independence.
    let gpu = render_on(Backend::Gpu, path, ro, &scene, &opts)?;
    let cpu_opts = RenderOptions {
        seed: cpu_seed(opts.seed),
        ..opts.clone()
    };
    let cpu = render_on(Backend::Cpu, path, ro, &scene, &cpu_opts)?;
    let report =
        glint::cpu::compare::compare_films_masked(&gpu.film, &cpu.film, &|_, _| true, args.alpha)
            .map_err(|e| anyhow!("{}: {e}", path.display()))?;
    println!("{}: gpu ({}) vs cpu: {report}", path.display(), gpu.device);
    // The metrics module's view of the same pair (the CPU image as the
    // reference): how far apart the two noisy images are.
    let (gm, cm) = (gpu.film.means(), cpu.film.means());
    let (w, h) = (opts.width, opts.height);
    let m = glint::cpu::metrics::compute(
        &glint::cpu::metrics::ImageRef::new(w, h, &gm)?,
        &glint::cpu::metrics::ImageRef::new(w, h, &cm)?,
    )?;
    let ratio = m.mean_ratio();
    println!(
        "{}: relMSE {:.3e}, RMSE {:.3e}, FLIP {:.4}, mean ratio gpu/cpu {:.4} {:.4} {:.4}",
        path.display(),
        m.relmse,
        m.rmse,
        m.flip,
        ratio.x,
        ratio.y,
        ratio.z
    );
    if report.pass {
        Ok(())
    } else {
        bail!(
            "{}: the backends differ (see the report above)",
            path.display()
        )
    }
}
