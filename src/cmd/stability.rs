//! `glint stability -o DIR`: the BSDF stability sweep (`glint::stability`)
//! on both backends; writes DIR/stability.md, .csv, and the pass/fail map
//! as .svg and .png, whole or not at all.

use std::io::Write;

use anyhow::{Context as _, Result, bail};
use glint::backend::{Backend, GpuOptions, Renderer};
use glint::cpu::Film;
use glint::gpu::{Context, ContextDesc};
use glint::methods;
use glint::stability::{self, COS, Size};

use super::outputs::Outputs;
use crate::cli::StabilityArgs;

pub fn run(args: &StabilityArgs) -> Result<()> {
    let dir = &args.dir;
    if dir.exists() && !dir.is_dir() {
        bail!("{}: exists and is not a folder", dir.display());
    }
    let created = !dir.exists();
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    let result = run_in(args);
    if result.is_err() && created {
        let _ = std::fs::remove_dir(dir);
    }
    result
}

fn run_in(args: &StabilityArgs) -> Result<()> {
    if args.methods {
        return run_methods(args);
    }
    let dir = &args.dir;
    let report = Report::reserve(dir, "stability")?;
    let size = if args.quick { Size::Quick } else { Size::Full };
    let ctx = gpu_context(args)?;
    let device = ctx.as_ref().map(|c| c.info().name.clone());
    let rows = stability::run(size, ctx.as_ref())?;
    drop(ctx);
    let md = stability::markdown(&rows, size, device.as_deref());
    let maps = stability::heatmaps(&rows);
    let labels: Vec<String> = COS.iter().map(|c| format!("{c:e}")).collect();
    let title = "glint stability: each BSDF over (parameter, cos theta_o)";
    let legend = format!(
        "columns: cos theta_o = {}; green pass (darker: larger error), amber degrade, red fail",
        labels.join(" ")
    );
    report.write(&md, &stability::csv(&rows), title, &legend, &maps)?;
    let fails = rows
        .iter()
        .filter(|(_, r)| r.status == stability::Status::Fail)
        .count();
    eprintln!(
        "glint: wrote {} ({} points, {fails} failing)",
        dir.join("stability.md").display(),
        rows.len()
    );
    Ok(())
}

/// The Vulkan context of the GPU half, unless `--cpu-only`.
fn gpu_context(args: &StabilityArgs) -> Result<Option<Context>> {
    if args.cpu_only {
        return Ok(None);
    }
    Ok(Some(
        Context::new(&ContextDesc {
            device: args.device.as_deref(),
            ..Default::default()
        })
        .context("the GPU half of the sweep needs a Vulkan device (--cpu-only skips it)")?,
    ))
}

/// `--methods`: the sampling methods' sweep (`glint::methods`) on the CPU
/// and, unless `--cpu-only`, the GPU.
fn run_methods(args: &StabilityArgs) -> Result<()> {
    let dir = &args.dir;
    let report = Report::reserve(dir, "methods")?;
    let sweep = methods::Sweep::new(args.quick);
    // Every cell renders through the backend interface, on one renderer
    // per backend made once.
    fn through(
        r: &Renderer,
    ) -> impl Fn(&glint::cpu::Scene, &glint::cpu::RenderOptions) -> Result<(Film, f64), String> + '_
    {
        move |s, o| {
            r.render(s, o, &|_, _| {})
                .map(|b| (b.film, b.render_seconds))
                .map_err(|e| e.to_string())
        }
    }
    let cpu = Renderer::new(Backend::Cpu, &GpuOptions::default())?;
    let threads = rayon::current_num_threads();
    let mut devices = vec![("cpu".to_string(), format!("{threads} threads"))];
    let mut rows = methods::run(&sweep, "cpu", &through(&cpu)).map_err(anyhow::Error::msg)?;
    if !args.cpu_only {
        let gpu_opts = GpuOptions {
            device: args.device.clone(),
            ..Default::default()
        };
        let gpu = Renderer::new(Backend::Gpu, &gpu_opts)
            .context("the GPU half of the sweep needs a Vulkan device (--cpu-only skips it)")?;
        devices.push(("gpu".to_string(), gpu.device_name()));
        rows.extend(methods::run(&sweep, "gpu", &through(&gpu)).map_err(anyhow::Error::msg)?);
        gpu.finish()?;
    }
    let md = methods::markdown(&rows, &sweep, &devices);
    let backends: Vec<String> = devices.iter().map(|d| d.0.clone()).collect();
    let maps = methods::heatmaps(&rows, &sweep, &backends);
    let title = "glint stability --methods: each technique over (GGX alpha, light radius)";
    let radii: Vec<String> = sweep.radii.iter().map(|r| r.to_string()).collect();
    let legend = format!(
        "columns: light radius {}; green within 1.25x of the cell's best relMSE at equal time, amber within 2x, red beyond",
        radii.join(" ")
    );
    report.write(&md, &methods::csv(&rows), title, &legend, &maps)?;
    eprintln!(
        "glint: wrote {} ({} cells, {} measurements)",
        dir.join("methods.md").display(),
        sweep.cells().len(),
        rows.len()
    );
    Ok(())
}

/// A sweep's four outputs, DIR/STEM.md, .csv, .svg and .png: reserved
/// before the sweep runs, written together (whole or not at all).
struct Report {
    outputs: Outputs,
    slots: [usize; 4],
}

impl Report {
    fn reserve(dir: &std::path::Path, stem: &str) -> Result<Report> {
        let mut outputs = Outputs::new();
        let mut slots = [0; 4];
        for (slot, ext) in slots.iter_mut().zip(["md", "csv", "svg", "png"]) {
            *slot = outputs.reserve(&dir.join(format!("{stem}.{ext}")))?;
        }
        Ok(Report { outputs, slots })
    }

    fn write(
        mut self,
        md: &str,
        csv: &str,
        title: &str,
        legend: &str,
        maps: &[glint::chart::Heatmap],
    ) -> Result<()> {
        let svg = glint::chart::heatmaps_svg(title, legend, maps)?;
        let png = glint::chart::heatmaps_png(title, legend, maps)?;
        let files: [&[u8]; 4] = [md.as_bytes(), csv.as_bytes(), svg.as_bytes(), &png];
        for (slot, bytes) in self.slots.into_iter().zip(files) {
            self.outputs.write(slot, |w| Ok(w.write_all(bytes)?))?;
        }
        self.outputs.commit()
    }
}
