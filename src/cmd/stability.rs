//! `glint stability -o DIR`: the BSDF stability sweep (`glint::stability`)
//! on both backends; writes DIR/stability.md, .csv, and the pass/fail map
//! as .svg and .png, whole or not at all.

use std::io::Write;

use anyhow::{Context as _, Result, bail};
use glint::backend::{Backend, GpuOptions, Renderer};
use glint::cpu::Film;
use glint::gpu::{Context, ContextDesc};
use glint::methods::{self, Family};
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
    let report = Report::reserve_files(dir, &methods_files())?;
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
    let mut files = vec![md.into_bytes()];
    for family in Family::ALL {
        let maps = methods::heatmaps(&rows, &sweep, &backends, family);
        let title = format!(
            "glint stability --methods, {} light: each technique over (GGX alpha, light size)",
            family.name()
        );
        let radii: Vec<String> = sweep.radii(family).iter().map(|r| r.to_string()).collect();
        let legend = format!(
            "columns: {}, r = {}; green within 1.25x of the cell's best relMSE at equal time, amber within 2x, red beyond",
            family.radius_meaning(),
            radii.join(" ")
        );
        let (svg, png) = chart(&title, &legend, &maps)?;
        files.extend([
            methods::csv(&rows, family).into_bytes(),
            svg.into_bytes(),
            png,
        ]);
    }
    files.push(methods::light_sampling_csv(&rows).into_bytes());
    report.write_files(files)?;
    eprintln!(
        "glint: wrote {} ({} cells, {} measurements)",
        dir.join("methods.md").display(),
        sweep.cells().len(),
        rows.len()
    );
    Ok(())
}

/// The methods sweep's outputs, in the order `run_methods` writes them:
/// methods.md, then per family its CSV, SVG and PNG, then the quad
/// family's before/after CSV.
fn methods_files() -> Vec<String> {
    let mut v = vec!["methods.md".to_string()];
    for family in Family::ALL {
        for ext in ["csv", "svg", "png"] {
            v.push(format!("{}.{ext}", family.stem()));
        }
    }
    v.push("light-sampling.csv".into());
    v
}

/// A heat-map chart as SVG and PNG.
fn chart(title: &str, legend: &str, maps: &[glint::chart::Heatmap]) -> Result<(String, Vec<u8>)> {
    Ok((
        glint::chart::heatmaps_svg(title, legend, maps)?,
        glint::chart::heatmaps_png(title, legend, maps)?,
    ))
}

/// A sweep's outputs (DIR/STEM.md, .csv, .svg and .png, or a list):
/// reserved before the sweep runs, written together (whole or not at all).
struct Report {
    outputs: Outputs,
    slots: Vec<usize>,
}

impl Report {
    fn reserve(dir: &std::path::Path, stem: &str) -> Result<Report> {
        let names: Vec<String> = ["md", "csv", "svg", "png"]
            .iter()
            .map(|ext| format!("{stem}.{ext}"))
            .collect();
        Report::reserve_files(dir, &names)
    }

    fn reserve_files(dir: &std::path::Path, names: &[String]) -> Result<Report> {
        let mut outputs = Outputs::new();
        let slots = names
            .iter()
            .map(|n| outputs.reserve(&dir.join(n)))
            .collect::<Result<Vec<_>>>()?;
        Ok(Report { outputs, slots })
    }

    fn write(
        self,
        md: &str,
        csv: &str,
        title: &str,
        legend: &str,
        maps: &[glint::chart::Heatmap],
    ) -> Result<()> {
        let (svg, png) = chart(title, legend, maps)?;
        self.write_files(vec![md.into(), csv.into(), svg.into(), png])
    }

    /// The reserved files' contents, in their order.
    fn write_files(mut self, files: Vec<Vec<u8>>) -> Result<()> {
        assert_eq!(
            files.len(),
            self.slots.len(),
            "one content per reserved file"
        );
        for (slot, bytes) in self.slots.into_iter().zip(files) {
            self.outputs.write(slot, |w| Ok(w.write_all(&bytes)?))?;
        }
        self.outputs.commit()
    }
}
