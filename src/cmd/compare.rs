//! `glint compare`: both backends on one scene, the statistical test of
//! glint_cpu::compare, one line of verdict on stdout. `--gpu-options` and
//! `--cpu-options` lay further render options over one side's: two methods
//! compared (`--cpu-options '--mis balance'` must agree), or a change the
//! test must see (`--cpu-options '--max-depth 2'` must differ).

use anyhow::{Result, anyhow, bail};
use glint::backend::Backend;
use glint::cpu::{RenderOptions, Scene};

use super::converge::overlay;
use super::{
    check_opts, check_params, load, load_scene, prepare_options, render_on, render_options, spp_of,
};
use crate::cli::{CompareArgs, RenderOpts};

/// The CPU's seed in `glint compare`: any value other than the GPU's.
fn cpu_seed(seed: u64) -> u64 {
    seed ^ 0x9e37_79b9_7f4a_7c15
}

/// One side of the comparison: its render options (the shared ones with
/// that side's `--gpu-options`/`--cpu-options` laid over them), its scene
/// (prepared again only where those options change it) and its
/// `RenderOptions`.
struct Side {
    ro: RenderOpts,
    scene: Option<Scene>,
    opts: RenderOptions,
}

fn side(
    flag: &str,
    extra: Option<&str>,
    args: &CompareArgs,
    shared: &(Scene, RenderOptions),
) -> Result<Side> {
    let path = &args.scene.scene;
    let Some(extra) = extra else {
        return Ok(Side {
            ro: args.scene.opts.clone(),
            scene: None,
            opts: shared.1.clone(),
        });
    };
    let v = overlay(&args.scene.opts, extra).map_err(|e| anyhow!("{flag} '{extra}': {e}"))?;
    if v.backend != Backend::Auto
        || v.control.target_error.is_some()
        || v.control.adaptive.is_some()
    {
        bail!("{flag} '{extra}': the backend, --target-error and --adaptive are not per side");
    }
    let spp = spp_of(args.scene.spp, &v.opts);
    check_opts(spp, &v.opts).map_err(|e| anyhow!("{flag} '{extra}': {e}"))?;
    let scene = (prepare_options(&v.opts) != prepare_options(&args.scene.opts))
        .then(|| load(path, &v.opts))
        .transpose()?;
    let opts = render_options(scene.as_ref().unwrap_or(&shared.0), path, spp, &v.opts)?;
    Ok(Side {
        ro: v.opts,
        scene,
        opts,
    })
}

pub fn run(args: &CompareArgs) -> Result<()> {
    check_params(&args.scene)?;
    if !(args.alpha > 0.0 && args.alpha < 1.0) {
        bail!("--alpha {} is out of range (0, 1)", args.alpha);
    }
    if args.scene.spp.is_some_and(|n| n < 2) {
        bail!("--spp must be at least 2 to estimate the variance");
    }
    let shared = load_scene(&args.scene)?;
    let path = &args.scene.scene;
    let g = side("--gpu-options", args.gpu_options.as_deref(), args, &shared)?;
    let c = side("--cpu-options", args.cpu_options.as_deref(), args, &shared)?;
    if (g.opts.width, g.opts.height) != (c.opts.width, c.opts.height) {
        bail!(
            "the sides' images differ in size ({}x{} and {}x{})",
            g.opts.width,
            g.opts.height,
            c.opts.width,
            c.opts.height
        );
    }
    // Independent seeds: with the same seed both backends trace the same
    // paths (one random stream), and the Welch test assumes independence.
    let gpu_scene = g.scene.as_ref().unwrap_or(&shared.0);
    let gpu = render_on(Backend::Gpu, path, &g.ro, gpu_scene, &g.opts)?;
    let cpu_opts = RenderOptions {
        seed: cpu_seed(c.opts.seed),
        ..c.opts.clone()
    };
    let cpu_scene = c.scene.as_ref().unwrap_or(&shared.0);
    let cpu = render_on(Backend::Cpu, path, &c.ro, cpu_scene, &cpu_opts)?;
    let opts = &g.opts;
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
