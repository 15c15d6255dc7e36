//! `glint stability -o DIR`: the BSDF stability sweep (`glint::stability`)
//! on both backends; writes DIR/stability.md, .csv, and the pass/fail map
//! as .svg and .png, whole or not at all.

use std::io::Write;

use anyhow::{Context as _, Result, bail};
use glint::gpu::{Context, ContextDesc};
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
    let dir = &args.dir;
    let mut outputs = Outputs::new();
    let md_slot = outputs.reserve(&dir.join("stability.md"))?;
    let csv_slot = outputs.reserve(&dir.join("stability.csv"))?;
    let svg_slot = outputs.reserve(&dir.join("stability.svg"))?;
    let png_slot = outputs.reserve(&dir.join("stability.png"))?;
    let size = if args.quick { Size::Quick } else { Size::Full };
    let ctx = if args.cpu_only {
        None
    } else {
        Some(
            Context::new(&ContextDesc {
                device: args.device.as_deref(),
                ..Default::default()
            })
            .context("the GPU half of the sweep needs a Vulkan device (--cpu-only skips it)")?,
        )
    };
    let device = ctx.as_ref().map(|c| c.info().name.clone());
    let rows = stability::run(size, ctx.as_ref())?;
    drop(ctx);
    let md = stability::markdown(&rows, size, device.as_deref());
    let maps = stability::heatmaps(&rows);
    let labels: Vec<String> = COS.iter().map(|c| format!("{c:e}")).collect();
    let title = "glint stability: each BSDF over (parameter, cos theta_o)";
    let svg = glint::chart::heatmaps_svg(title, &labels, &maps)?;
    let png = glint::chart::heatmaps_png(title, &labels, &maps)?;
    outputs.write(md_slot, |w| Ok(w.write_all(md.as_bytes())?))?;
    outputs.write(csv_slot, |w| {
        Ok(w.write_all(stability::csv(&rows).as_bytes())?)
    })?;
    outputs.write(svg_slot, |w| Ok(w.write_all(svg.as_bytes())?))?;
    outputs.write(png_slot, |w| Ok(w.write_all(&png)?))?;
    outputs.commit()?;
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
