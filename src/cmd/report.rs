//! `glint test`'s outputs: the images beside the report, JUnit XML (one
//! `testcase` per scene, `failure` for a difference, `error` for bad
//! input) and the offline HTML report (no scripts, fonts or remote files).

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result, anyhow};
use glint::cpu::exr_file::RadianceImage;
use glint::cpu::metrics::{ImageRef, srgb8};

use super::test::{Outcome, Verdict};

/// XML/HTML text escaping (attributes and text alike).
pub fn escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&apos;"),
            c if c.is_control() && c != '\n' && c != '\t' => o.push(' '),
            c => o.push(c),
        }
    }
    o
}

fn write_png(path: &Path, img: &RadianceImage) -> Result<()> {
    let bytes = srgb8(&ImageRef::new(img.width, img.height, &img.mean)?);
    image::RgbImage::from_raw(img.width, img.height, bytes)
        .ok_or_else(|| anyhow!("image size"))?
        .save(path)
        .with_context(|| path.display().to_string())
}

/// The render, the reference and the relative difference as PNGs in `dir`
/// (the z map is diff's own `--diff` image), listed in `images`.
pub fn images(
    name: &str,
    img: &RadianceImage,
    reference: &RadianceImage,
    dir: &Path,
    images: &mut Vec<(&'static str, String)>,
) -> Result<()> {
    let (r, f, d) = (
        format!("{name}-render.png"),
        format!("{name}-reference.png"),
        format!("{name}-difference.png"),
    );
    write_png(&dir.join(&r), img)?;
    write_png(&dir.join(&f), reference)?;
    images.push(("render", r));
    images.push(("reference", f));
    if (img.width, img.height) == (reference.width, reference.height) {
        let png = super::diff::relative_difference_png(img, reference)?;
        std::fs::write(dir.join(&d), png).with_context(|| d.clone())?;
        images.push(("difference", d));
    }
    Ok(())
}

fn counts(results: &[Outcome]) -> (usize, usize) {
    let f = results
        .iter()
        .filter(|o| matches!(o.verdict, Verdict::Fail(_)))
        .count();
    let e = results
        .iter()
        .filter(|o| matches!(o.verdict, Verdict::Error(_)))
        .count();
    (f, e)
}

/// Per scene, the figures a dashboard shows: spp, detect, alpha, metrics.
fn properties(o: &Outcome) -> Vec<(String, String)> {
    let mut p = vec![("alpha".to_string(), o.case.alpha.to_string())];
    if let Some(s) = o.spp {
        p.push(("spp".into(), s.to_string()));
    }
    if let Some(d) = o.case.detect {
        p.push(("detect".into(), d.to_string()));
        let by = o.detect_by.as_deref().unwrap_or("the whole image");
        p.push(("detect_by".into(), by.to_string()));
        if o.detect_capped {
            p.push(("detect_capped".into(), "true".into()));
        }
        if !o.detect_materials.is_empty() {
            p.push(("detect_materials".into(), o.detect_materials.join("; ")));
        }
    }
    if let Some(m) = &o.metrics {
        for k in ["relmse", "rmse", "flip", "verdict"] {
            if let Some(v) = m.get(k).filter(|v| !v.is_null()) {
                p.push((k.into(), v.to_string().trim_matches('"').to_string()));
            }
        }
        if let Some(z) = m.pointer("/test/z_max") {
            p.push(("z_max".into(), z.to_string()));
        }
    }
    p
}

/// JUnit XML (the schema GitHub, GitLab and Jenkins read).
pub fn junit(path: &Path, suite: &str, results: &[Outcome], seconds: f64) -> Result<()> {
    let (failed, errors) = counts(results);
    let mut x = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let head = format!(
        "tests=\"{}\" failures=\"{failed}\" errors=\"{errors}\" time=\"{seconds:.3}\"",
        results.len()
    );
    let s = escape(suite);
    let _ = writeln!(x, "<testsuites name=\"glint test\" {head}>");
    let _ = writeln!(x, "  <testsuite name=\"{s}\" {head} skipped=\"0\">");
    for o in results {
        let _ = writeln!(
            x,
            "    <testcase name=\"{}\" classname=\"{s}\" time=\"{:.3}\">",
            escape(&o.case.name),
            o.seconds
        );
        let _ = writeln!(x, "      <properties>");
        for (k, v) in properties(o) {
            let _ = writeln!(
                x,
                "        <property name=\"{}\" value=\"{}\"/>",
                escape(&k),
                escape(&v)
            );
        }
        let _ = writeln!(x, "      </properties>");
        match &o.verdict {
            Verdict::Pass => {}
            Verdict::Fail(m) => {
                let _ = writeln!(x, "      <failure message=\"{}\"/>", escape(m));
            }
            Verdict::Error(m) => {
                let _ = writeln!(x, "      <error message=\"{}\"/>", escape(m));
            }
        }
        if !o.warnings.is_empty() {
            let _ = writeln!(
                x,
                "      <system-err>{}</system-err>",
                escape(&o.warnings.join("\n"))
            );
        }
        let _ = writeln!(x, "    </testcase>");
    }
    x.push_str("  </testsuite>\n</testsuites>\n");
    std::fs::write(path, x).with_context(|| path.display().to_string())
}

const STYLE: &str = "body{font-family:sans-serif;margin:1em;background:#fff;color:#222}\
table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:2px 8px;text-align:left}\
.fail{color:#b00}.error{color:#a60}.pass{color:#070}\
figure{display:inline-block;margin:4px}img{width:256px;image-rendering:pixelated;\
border:1px solid #888}section{border-top:2px solid #ddd;margin-top:1em}";

fn section(h: &mut String, o: &Outcome) {
    let (class, word, msg) = match &o.verdict {
        Verdict::Pass => ("pass", "passed", String::new()),
        Verdict::Fail(m) => ("fail", "FAILED", m.clone()),
        Verdict::Error(m) => ("error", "ERROR", m.clone()),
    };
    let name = escape(&o.case.name);
    let _ = writeln!(
        h,
        "<section id=\"{name}\"><h2>{name}: <span class=\"{class}\">{word}</span></h2>"
    );
    if !msg.is_empty() {
        let _ = writeln!(h, "<p class=\"{class}\">{}</p>", escape(&msg));
    }
    for (label, file) in &o.images {
        let f = escape(file);
        let _ = writeln!(
            h,
            "<figure><img src=\"{f}\" alt=\"{label}\"><figcaption>{label}</figcaption></figure>"
        );
    }
    let _ = writeln!(h, "<table>");
    let _ = writeln!(h, "<tr><th>time</th><td>{:.2} s</td></tr>", o.seconds);
    for (k, v) in properties(o) {
        let _ = writeln!(h, "<tr><th>{}</th><td>{}</td></tr>", escape(&k), escape(&v));
    }
    let _ = writeln!(h, "</table></section>");
}

/// `DIR/index.html`: the summary, then each scene, failed ones first.
pub fn html(dir: &Path, suite: &str, results: &[Outcome], seconds: f64) -> Result<()> {
    let (failed, errors) = counts(results);
    let passed = results.len() - failed - errors;
    let mut h = String::new();
    let _ = writeln!(
        h,
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\">\
         <title>glint test: {0}</title><style>{STYLE}</style></head><body>\
         <h1>glint test: {0}</h1>",
        escape(suite)
    );
    let _ = writeln!(
        h,
        "<p><span class=\"pass\">{passed} passed</span>, <span class=\"fail\">{failed} failed\
         </span>, <span class=\"error\">{errors} errors</span>, {seconds:.1} s</p>"
    );
    let rank = |v: &Verdict| match v {
        Verdict::Fail(_) => 0,
        Verdict::Error(_) => 1,
        Verdict::Pass => 2,
    };
    let mut order: Vec<&Outcome> = results.iter().collect();
    order.sort_by_key(|o| rank(&o.verdict));
    for o in order {
        section(&mut h, o);
    }
    h.push_str("</body></html>\n");
    let path = dir.join("index.html");
    std::fs::write(&path, h).with_context(|| path.display().to_string())
}
