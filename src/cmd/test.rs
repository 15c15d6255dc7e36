//! `glint test SUITE.toml`: an image-regression suite (contract, "Second
//! additions"). Each scene is rendered by glint's own `render` (a child
//! process of this binary, so what is tested is the files glint writes) and
//! judged by its own `diff` (the block z-tests at the suite's alpha).
//! `--update` rewrites the references instead. Exit 0 all agree, 1 any
//! differs, 2 bad input (the suite, a missing or mismatched reference).

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use anyhow::{Context, Result, anyhow, bail};
use glint::cpu::exr_file::RadianceImage;
use glint::cpu::film::MIN_VARIANCE_BATCHES;
use serde::Deserialize;

use super::{BadInput, detect, report};
use crate::cli::TestArgs;

/// Samples of the pilot render behind `detect`.
const PILOT_SPP: u32 = 16;
/// `detect`'s floor: fewer samples make the per-pixel variance estimate
/// too rough for the z-test's normal approximation.
const DETECT_MIN: u32 = 16;
/// `detect`'s cap when the scene gives no `spp`.
const DETECT_CAP: u32 = 4096;
/// Seeds: the references' and the pilots' (tests take `--seed`).
const REF_SEED: u64 = 0x5eed_0000_0001;
const PILOT_SEED: u64 = 0x5eed_0000_0002;
/// XORed into a test's seed for the render `detect` asks for again.
const RESIZE_SEED: u64 = 0x5eed_0000_0003;

/// One table of the manifest: `[defaults]` or a `[[scene]]`.
#[derive(Deserialize, Default, Clone, Debug)]
#[serde(deny_unknown_fields)]
pub struct Entry {
    name: Option<String>,
    file: Option<PathBuf>,
    reference: Option<PathBuf>,
    backend: Option<String>,
    width: Option<u32>,
    height: Option<u32>,
    spp: Option<u32>,
    detect: Option<f64>,
    alpha: Option<f64>,
    max_depth: Option<i32>,
    camera: Option<String>,
    nee: Option<String>,
    mis: Option<String>,
    sampler: Option<String>,
    multiscatter: Option<String>,
    kernel: Option<String>,
    options: Option<Vec<String>>,
}

#[derive(Deserialize, Debug)]
#[serde(deny_unknown_fields)]
struct Manifest {
    defaults: Option<Entry>,
    #[serde(default)]
    scene: Vec<Entry>,
}

/// A scene of the suite, its settings settled.
#[derive(Clone, Debug)]
pub struct Case {
    pub name: String,
    file: PathBuf,
    reference: PathBuf,
    spp: Option<u32>,
    pub detect: Option<f64>,
    pub alpha: f64,
    /// `render` options other than spp, seed and outputs.
    render_opts: Vec<String>,
}

/// How one scene went.
#[derive(Debug, Clone, PartialEq)]
pub enum Verdict {
    Pass,
    Fail(String),
    Error(String),
}

/// One scene's result, for the JUnit file and the report.
#[derive(Debug, Clone)]
pub struct Outcome {
    pub case: Case,
    pub verdict: Verdict,
    pub seconds: f64,
    pub spp: Option<u32>,
    /// With `detect`: the material change that set the spp (`None`: the
    /// whole image).
    pub detect_by: Option<String>,
    /// With `detect`: every material change it sized for.
    pub detect_materials: Vec<String>,
    /// With `detect`: the rule reached the cap (`spp`).
    pub detect_capped: bool,
    /// `diff --json`'s figures, when diff ran.
    pub metrics: Option<serde_json::Value>,
    /// (label, file name in the report's folder).
    pub images: Vec<(&'static str, String)>,
    /// The warnings its renders printed (`FILE: ...`), each once: what
    /// glint skipped or substituted in the scene or the options.
    pub warnings: Vec<String>,
}

fn merge(d: &Entry, s: &Entry) -> Entry {
    macro_rules! pick {
        ($($f:ident),*) => { Entry { $($f: s.$f.clone().or_else(|| d.$f.clone()),)* options: None } };
    }
    let mut e = pick!(
        name,
        file,
        reference,
        backend,
        width,
        height,
        spp,
        detect,
        alpha,
        max_depth,
        camera,
        nee,
        mis,
        sampler,
        multiscatter,
        kernel
    );
    let mut opts = d.options.clone().unwrap_or_default();
    opts.extend(s.options.clone().unwrap_or_default());
    e.options = Some(opts);
    e
}

fn case(e: &Entry, dir: &Path, i: usize) -> Result<Case> {
    let name = e
        .name
        .clone()
        .ok_or_else(|| anyhow!("scene {}: no name", i + 1))?;
    if name.is_empty()
        || !name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "_-.".contains(c))
        || name.starts_with('.')
    {
        bail!("scene {name:?}: a name is letters, digits, '_', '-' and '.' (it names files)");
    }
    let file = dir.join(
        e.file
            .as_ref()
            .ok_or_else(|| anyhow!("scene {name}: no file"))?,
    );
    let reference = dir.join(
        e.reference
            .clone()
            .unwrap_or_else(|| PathBuf::from(format!("refs/{name}.exr"))),
    );
    let alpha = e.alpha.unwrap_or(1e-3);
    if !(alpha > 0.0 && alpha < 1.0) {
        bail!("scene {name}: alpha {alpha} is out of range (0, 1)");
    }
    if let Some(d) = e.detect
        && !(d > 0.0 && d < 1.0)
    {
        bail!("scene {name}: detect {d} is out of range (0, 1): a relative change");
    }
    let mut o: Vec<String> = Vec::new();
    let mut flag = |k: &str, v: Option<String>| {
        if let Some(v) = v {
            o.push(format!("--{k}"));
            o.push(v);
        }
    };
    flag("backend", e.backend.clone());
    flag("width", e.width.map(|v| v.to_string()));
    flag("height", e.height.map(|v| v.to_string()));
    flag("max-depth", e.max_depth.map(|v| v.to_string()));
    flag("camera", e.camera.clone());
    flag("nee", e.nee.clone());
    flag("mis", e.mis.clone());
    flag("sampler", e.sampler.clone());
    flag("multiscatter", e.multiscatter.clone());
    flag("kernel", e.kernel.clone());
    // A file an option names is relative to the suite, as `file` is, so
    // the suite runs from any folder.
    let mut names_file = false;
    for f in e.options.iter().flatten() {
        if ["--spp", "--seed", "-o", "--output", "--variance", "--shard"].contains(&f.as_str()) {
            bail!("scene {name}: options: {f} is set by glint test (use the spp key)");
        }
        if std::mem::take(&mut names_file) {
            o.push(dir.join(f).to_string_lossy().into_owned());
        } else if let Some(v) = f.strip_prefix("--envmap=") {
            o.push(format!("--envmap={}", dir.join(v).display()));
        } else {
            names_file = f == "--envmap";
            o.push(f.clone());
        }
    }
    Ok(Case {
        name,
        file,
        reference,
        spp: e.spp,
        detect: e.detect,
        alpha,
        render_opts: o,
    })
}

/// Read and check the manifest; every problem is bad input.
pub fn load(path: &Path) -> Result<Vec<Case>> {
    super::check_input_file(path, "a suite (.toml)")?;
    let text = std::fs::read_to_string(path).with_context(|| path.display().to_string())?;
    let m: Manifest = toml::from_str(&text)
        .map_err(|e| anyhow!("{}: {}", path.display(), super::one_line(&e.to_string())))?;
    let d = m.defaults.unwrap_or_default();
    if d.name.is_some() || d.file.is_some() || d.reference.is_some() {
        bail!(
            "{}: [defaults]: name, file and reference are per scene",
            path.display()
        );
    }
    if m.scene.is_empty() {
        bail!("{}: no [[scene]]", path.display());
    }
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut cases = Vec::new();
    for (i, s) in m.scene.iter().enumerate() {
        let c = case(&merge(&d, s), dir, i).map_err(|e| anyhow!("{}: {e}", path.display()))?;
        if cases.iter().any(|x: &Case| x.name == c.name) {
            bail!(
                "{}: scene {}: the name is used twice",
                path.display(),
                c.name
            );
        }
        cases.push(c);
    }
    Ok(cases)
}

/// Run glint with `args`: its exit status, stdout, its last line on stderr
/// that is not a warning, and its warnings (`FILE: ...`).
fn glint(args: &[OsString]) -> Result<(i32, String, String, Vec<String>)> {
    let exe = std::env::current_exe().context("locating the glint binary")?;
    let out = Command::new(exe)
        .args(args)
        .output()
        .context("running glint")?;
    let err = String::from_utf8_lossy(&out.stderr);
    let last = err
        .lines()
        .rev()
        .find(|l| !l.trim().is_empty() && !l.contains("warning:"))
        .unwrap_or("")
        .trim_start_matches("glint: ")
        .to_string();
    let warnings = err
        .lines()
        .filter_map(|l| l.strip_prefix("glint: warning: "))
        .map(str::to_string)
        .collect();
    Ok((
        out.status.code().unwrap_or(101),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        last,
        warnings,
    ))
}

/// `glint render` of the case to `out` (with variance) at `spp`, `seed`;
/// its warnings join `warnings` (each once).
fn render(c: &Case, out: &Path, spp: u32, seed: u64, warnings: &mut Vec<String>) -> Result<()> {
    let mut a: Vec<OsString> = vec!["render".into(), c.file.clone().into()];
    a.extend(c.render_opts.iter().map(OsString::from));
    for s in ["--spp", &spp.to_string(), "--seed", &seed.to_string()] {
        a.push(s.into());
    }
    for s in ["--variance", "--quiet", "-o"] {
        a.push(s.into());
    }
    a.push(out.into());
    let (code, _, err, warned) = glint(&a)?;
    for w in warned {
        if !warnings.contains(&w) {
            warnings.push(w);
        }
    }
    if code != 0 {
        bail!("render: {err}");
    }
    Ok(())
}

fn read(path: &Path) -> Result<RadianceImage> {
    RadianceImage::read(path).map_err(|e| anyhow!("{}: {e}", path.display()))
}

/// What `detect` settled for a case: the spp and the change that set it
/// (`None`: the whole image), and every material change it sized for.
struct Sized {
    spp: u32,
    by: Option<String>,
    /// The rule asked for the cap or more: the promise does not hold.
    capped: bool,
    changes: Vec<detect::Change>,
}

impl Sized {
    /// `spp`, or with `detect` the rule's from `pilot` (a render of
    /// `pilot_spp` with variance), at most `spp` (then the cap) and at
    /// least [`DETECT_MIN`]; `reference` is the test's (`None`: one of
    /// REF_FACTOR x N spp). `changes` are computed once, when `None`.
    fn new(
        c: &Case,
        pilot: &RadianceImage,
        pilot_spp: u32,
        reference: Option<&RadianceImage>,
        changes: Option<Vec<detect::Change>>,
    ) -> Result<Self> {
        let Some(delta) = c.detect else {
            return Ok(Self::fixed(c));
        };
        let changes = match changes {
            Some(ch) => ch,
            None => material_changes(c)?,
        };
        let cap = c.spp.unwrap_or(DETECT_CAP);
        let (n, by) =
            detect::required_spp(pilot, pilot_spp, reference, delta, c.alpha, cap, &changes);
        Ok(Self {
            spp: whole_batches(n.max(DETECT_MIN.min(cap))).min(cap),
            by,
            capped: n >= cap,
            changes,
        })
    }

    /// The rule again with `img` (a render of `self.spp`) as the pilot:
    /// the spp `img`'s own variance asks for, when that is more.
    fn again(
        &self,
        c: &Case,
        img: &RadianceImage,
        reference: Option<&RadianceImage>,
    ) -> Result<Option<Self>> {
        if c.detect.is_none() || img.variance.is_none() {
            return Ok(None);
        }
        let next = Self::new(c, img, self.spp, reference, Some(self.changes.clone()))?;
        Ok((next.spp > self.spp).then_some(next))
    }

    /// Without `detect`: the case's `spp`.
    fn fixed(c: &Case) -> Self {
        Self {
            spp: c.spp.unwrap_or(super::DEFAULT_SPP),
            by: None,
            capped: false,
            changes: Vec::new(),
        }
    }
}

/// `n` rounded up to a multiple of the largest power of two that leaves at
/// least [`MIN_VARIANCE_BATCHES`] batches, at most 1/16 more. A Sobol film
/// estimates its variance from batches whose size is the largest power of
/// two dividing its spp (`glint_cpu::film::variance_batch_for`); at an odd
/// spp that is 1, the plain sample variance, which overstates a scrambled
/// net's 4-6x, and a render sized from a batched estimate would then see
/// its z shrink 2x and its power collapse (measured: 54% where 95% was
/// aimed). Whole batches keep the estimate the rule sized with.
fn whole_batches(n: u32) -> u32 {
    if n < 2 * MIN_VARIANCE_BATCHES {
        return n;
    }
    let step = 1u32 << (n / MIN_VARIANCE_BATCHES).ilog2();
    n.div_ceil(step).saturating_mul(step)
}

/// With `detect`: a pilot render of [`PILOT_SPP`] (a fixed seed).
fn pilot(c: &Case, work: &Path, warnings: &mut Vec<String>) -> Result<RadianceImage> {
    let pilot_path = work.join(format!("{}-pilot.exr", c.name));
    render(c, &pilot_path, PILOT_SPP, PILOT_SEED, warnings)?;
    let pilot = read(&pilot_path)?;
    let _ = std::fs::remove_file(&pilot_path);
    Ok(pilot)
}

/// The materials `detect` sizes the spp for ([`detect::material_changes`]),
/// seen as the case's render sees them: its options parsed as `render`'s,
/// the scene loaded and the camera and image size settled the same way.
fn material_changes(c: &Case) -> Result<Vec<detect::Change>> {
    use clap::Parser;
    let v = crate::cli::VariantCli::try_parse_from(&c.render_opts)
        .map_err(|e| anyhow!("options: {}", super::one_line(&e.to_string())))?;
    let scene = super::prepare(&c.file, &v.opts)?.scene;
    let opts = super::render_options(&scene, &c.file, 1, &v.opts)?;
    detect::material_changes(&scene, &opts)
}

/// `--update`: the reference of `c`, REF_FACTOR x the tests' samples.
/// With `detect`, the pilot's 16 samples can miss a heavy tail (a caustic's
/// rare bright paths), so the rule is applied again with the reference's
/// own variance as the pilot; when that asks for more, the reference is
/// rendered again at REF_FACTOR x that.
fn update(c: &Case, work: &Path, warnings: &mut Vec<String>) -> Result<u32> {
    let sized = match c.detect {
        Some(_) => Sized::new(c, &pilot(c, work, warnings)?, PILOT_SPP, None, None)?,
        None => Sized::fixed(c),
    };
    if let Some(dir) = c.reference.parent() {
        std::fs::create_dir_all(dir).with_context(|| dir.display().to_string())?;
    }
    let mut ref_spp = sized.spp.saturating_mul(detect::REF_FACTOR);
    render(c, &c.reference, ref_spp, REF_SEED, warnings)?;
    let first = read(&c.reference)?;
    // The reference holds REF_FACTOR x the samples the rule was given.
    let as_pilot = Sized {
        spp: ref_spp,
        ..sized
    };
    if let Some(more) = as_pilot.again(c, &first, None)?
        && more.spp > ref_spp / detect::REF_FACTOR
    {
        ref_spp = more.spp.saturating_mul(detect::REF_FACTOR);
        render(c, &c.reference, ref_spp, REF_SEED, warnings)?;
    }
    Ok(ref_spp)
}

/// Render and diff one case; `Err` is bad input (an error testcase).
fn check(c: &Case, work: &Path, seed: u64, o: &mut Outcome) -> Result<Verdict> {
    if !c.reference.is_file() {
        return Err(anyhow!(
            "{}: no reference; run glint test --update",
            c.reference.display()
        ));
    }
    let reference = read(&c.reference)?;
    // With detect: sized from the reference's variance (the most samples
    // of this scene there are), or a pilot's when it has none. Sobol's
    // error falls faster than 1/N, so a reference's variance per sample
    // under-states a smaller render's: the rule is applied again with the
    // test render's own variance, and when that asks for more samples a
    // new render (another seed, so the verdict rests on one independent
    // render) replaces it.
    let ref_spp = reference
        .spp()
        .filter(|_| reference.variance.is_some() && c.detect.is_some());
    let mut sized = match ref_spp {
        Some(r) => Sized::new(c, &reference, r, Some(&reference), None)?,
        None if c.detect.is_some() => Sized::new(
            c,
            &pilot(c, work, &mut o.warnings)?,
            PILOT_SPP,
            Some(&reference),
            None,
        )?,
        None => Sized::fixed(c),
    };
    let n = &c.name;
    let out = work.join(format!("{n}.exr"));
    render(c, &out, sized.spp, seed, &mut o.warnings)?;
    let mut img = read(&out)?;
    if let Some(more) = sized.again(c, &img, Some(&reference))? {
        render(c, &out, more.spp, seed ^ RESIZE_SEED, &mut o.warnings)?;
        img = read(&out)?;
        sized = more;
    }
    o.spp = Some(sized.spp);
    o.detect_by = sized.by.clone();
    o.detect_materials = sized.changes.iter().map(|ch| ch.label.clone()).collect();
    o.detect_capped = sized.capped;
    if let Some(why) = super::shard::key_mismatch(img.meta.as_ref(), reference.meta.as_ref()) {
        bail!("{}: {why}; run glint test --update", c.reference.display());
    }
    report::images(n, &img, &reference, work, &mut o.images)?;
    let json = work.join(format!("{n}.json"));
    let z = format!("{n}-z.png");
    let mut a: Vec<OsString> = vec!["diff".into(), out.into(), c.reference.clone().into()];
    a.extend(["--diff".into(), work.join(&z).into(), "--json".into()]);
    a.extend([
        json.clone().into(),
        "--alpha".into(),
        c.alpha.to_string().into(),
    ]);
    let (code, stdout, err, _) = glint(&a)?;
    if let Ok(t) = std::fs::read_to_string(&json) {
        o.metrics = serde_json::from_str(&t).ok();
        o.images.push(("z map", z));
    }
    let line = stdout
        .lines()
        .find(|l| l.starts_with("agree") || l.starts_with("differ"))
        .unwrap_or("")
        .to_string();
    match code {
        0 => Ok(Verdict::Pass),
        1 => Ok(Verdict::Fail(line)),
        _ => Err(anyhow!("diff: {err}")),
    }
}

fn run_one(c: &Case, args: &TestArgs, work: &Path) -> Outcome {
    let t = Instant::now();
    let mut o = Outcome {
        case: c.clone(),
        verdict: Verdict::Pass,
        seconds: 0.0,
        spp: None,
        detect_by: None,
        detect_materials: Vec::new(),
        detect_capped: false,
        metrics: None,
        images: Vec::new(),
        warnings: Vec::new(),
    };
    o.verdict = if args.update {
        match update(c, work, &mut o.warnings) {
            Ok(spp) => {
                o.spp = Some(spp);
                Verdict::Pass
            }
            Err(e) => Verdict::Error(super::one_line(&format!("{e:#}"))),
        }
    } else {
        check(c, work, args.seed, &mut o)
            .unwrap_or_else(|e| Verdict::Error(super::one_line(&format!("{e:#}"))))
    };
    o.seconds = t.elapsed().as_secs_f64();
    o
}

fn print(o: &Outcome, update: bool) {
    let capped = if o.detect_capped {
        ", capped: detect's promise does not hold"
    } else {
        ""
    };
    let spp = o
        .spp
        .map(|s| format!(", {s} spp{capped}"))
        .unwrap_or_default();
    let what = match (&o.verdict, update) {
        (Verdict::Pass, true) => format!("reference written to {}", o.case.reference.display()),
        (Verdict::Pass, false) => "agree".into(),
        (Verdict::Fail(l), _) => format!("DIFFER: {l}"),
        (Verdict::Error(e), _) => format!("ERROR: {e}"),
    };
    // One print per case, so parallel jobs' lines do not interleave.
    let mut text = format!("{}: {what} ({:.1} s{spp})", o.case.name, o.seconds);
    for w in &o.warnings {
        text += &format!("\n{}: warning: {w}", o.case.name);
    }
    println!("{text}");
}

/// The suite's exit status: 0 all agree, 1 any differs, 2 any bad input.
pub fn run(args: &TestArgs) -> Result<u8> {
    let t = Instant::now();
    let mut cases = load(&args.suite).map_err(|e| BadInput(format!("{e:#}")))?;
    if let Some(f) = &args.filter {
        cases.retain(|c| c.name.contains(f.as_str()));
        if cases.is_empty() {
            return Err(BadInput(format!("--filter {f}: matches no scene")).into());
        }
    }
    let jobs = args.jobs.unwrap_or(1).max(1) as usize;
    let temp = std::env::temp_dir().join(format!("glint-test-{}", std::process::id()));
    let work = args.html.clone().unwrap_or_else(|| temp.clone());
    std::fs::create_dir_all(&work).with_context(|| work.display().to_string())?;
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Outcome>> = Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..jobs.min(cases.len()) {
            s.spawn(|| {
                while let Some(c) = cases.get(next.fetch_add(1, Ordering::SeqCst)) {
                    let o = run_one(c, args, &work);
                    print(&o, args.update);
                    results.lock().expect("no panics hold it").push(o);
                }
            });
        }
    });
    let mut results = results.into_inner().expect("no panics hold it");
    let order = |n: &str| cases.iter().position(|c| c.name == n);
    results.sort_by_key(|o| order(&o.case.name));
    let seconds = t.elapsed().as_secs_f64();
    let suite_name = args
        .suite
        .file_stem()
        .map_or("suite".into(), |s| s.to_string_lossy().into_owned());
    if let Some(j) = &args.junit {
        report::junit(j, &suite_name, &results, seconds)?;
    }
    if let Some(h) = &args.html {
        report::html(h, &suite_name, &results, seconds)?;
    }
    if args.html.is_none() {
        let _ = std::fs::remove_dir_all(&temp);
    }
    let count = |f: fn(&Verdict) -> bool| results.iter().filter(|o| f(&o.verdict)).count();
    let (failed, errors) = (
        count(|v| matches!(v, Verdict::Fail(_))),
        count(|v| matches!(v, Verdict::Error(_))),
    );
    println!(
        "{}: {} scenes, {} passed, {failed} failed, {errors} errors ({seconds:.1} s)",
        args.suite.display(),
        results.len(),
        results.len() - failed - errors
    );
    Ok(if errors > 0 {
        2
    } else if failed > 0 {
        1
    } else {
        0
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn whole_batches_rounds_up_to_batched_counts() {
        assert_eq!(whole_batches(13205), 13312); // 26 batches of 512
        for n in [32, 33, 100, 1000, 13205, 65535, 1 << 20] {
            let r = whole_batches(n);
            assert!(r >= n && r <= n + n / MIN_VARIANCE_BATCHES, "{n} -> {r}");
            let l = glint::cpu::film::variance_batch_for(r, 1);
            assert!(
                r / l >= MIN_VARIANCE_BATCHES && l >= r / (4 * MIN_VARIANCE_BATCHES),
                "{n} -> {r}: batches of {l}"
            );
        }
        assert_eq!(whole_batches(20), 20);
    }
}
