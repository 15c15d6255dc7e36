//! CI image regression end to end: `render --variance` and the EXR header
//! attributes, `--shard` + `merge`, `diff` (its verdict's calibration and
//! power), and the rough edges a new user hit (signals, odd scene paths,
//! `-o` naming the scene, negative seeds and cameras, the success line).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use glam::Vec3;
use glint::cpu::exr_file::{RadianceImage, RenderMeta};
use glint::cpu::{RenderOptions, SamplerKind};

fn glint() -> Command {
    Command::new(env!("CARGO_BIN_EXE_glint"))
}

fn cornell() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell.gltf")
}

/// A fresh, empty scratch directory for one test.
fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("glint-reg-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn assert_ok(out: &Output) {
    assert!(out.status.success(), "{}", stderr(out));
}

/// Non-zero status, exactly one line on stderr, containing `needle`.
fn assert_one_line_error(out: &Output, needle: &str) {
    let err = stderr(out);
    assert!(!out.status.success(), "expected failure, stderr: {err}");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "one line on stderr, got: {err:?}");
    assert!(
        lines[0].contains(needle),
        "{:?} should mention {needle:?}",
        lines[0]
    );
}

/// `glint render cornell` on the CPU at `size`x`size` with extra args.
fn render(out: &Path, size: u32, spp: u32, extra: &[&str]) -> Output {
    glint()
        .arg("render")
        .arg(cornell())
        .arg("-o")
        .arg(out)
        .args(["--backend", "cpu", "--width", &size.to_string()])
        .args(["--spp", &spp.to_string()])
        .args(extra)
        .output()
        .unwrap()
}

fn diff(a: &Path, b: &Path, extra: &[&str]) -> Output {
    glint()
        .arg("diff")
        .arg(a)
        .arg(b)
        .args(extra)
        .output()
        .unwrap()
}

#[test]
fn exr_records_attributes_variance_and_a_success_line() {
    let dir = scratch("attrs");
    let (exr, png) = (dir.join("a.exr"), dir.join("a.png"));
    let out = glint()
        .arg("render")
        .arg(cornell())
        .arg("-o")
        .arg(&exr)
        .arg("-o")
        .arg(&png)
        .args([
            "--backend",
            "cpu",
            "--width",
            "16",
            "--spp",
            "8",
            "--seed",
            "7",
            "--variance",
        ])
        .output()
        .unwrap();
    assert_ok(&out);
    let err = stderr(&out);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("a.exr") && err.contains("a.png") && err.contains("8 spp"),
        "{err}"
    );
    let img = RadianceImage::read(&exr).unwrap();
    let meta = img.meta.clone().unwrap();
    assert_eq!(
        (
            meta.spp,
            meta.seed,
            meta.sampler.as_str(),
            meta.shard.as_str()
        ),
        (8, 7, "sobol", "0/1")
    );
    assert_eq!(meta.version, env!("CARGO_PKG_VERSION"));
    // The build that rendered it: the executable's build ID (Debian's
    // linker writes one).
    #[cfg(target_os = "linux")]
    assert!(
        meta.build
            .as_ref()
            .is_some_and(|b| b.len() == 16 && b.bytes().all(|c| c.is_ascii_hexdigit())),
        "{:?}",
        meta.build
    );
    assert_eq!(meta.samples, [(0, 8)]);
    let var = img.variance.as_ref().unwrap();
    assert!(var.iter().any(|v| v.x > 0.0) && var.iter().all(|v| v.min_element() >= 0.0));
    // The same render through the library: same means, same variances.
    let scene = glint::cpu::prepare::prepare_default(&cornell()).unwrap();
    let opts = RenderOptions {
        spp: 8,
        seed: 7,
        ..RenderOptions::new(16, 16)
    };
    let (film, _) = glint::cpu::render(&scene, &opts, &|_, _| {}).unwrap();
    assert_eq!(img.mean, film.means());
    assert_eq!(var[37], film.variance_of_mean(37));
    assert_eq!(image::open(&png).unwrap().width(), 16);

    // --quiet: nothing on stderr; without --variance no variance channels.
    let out = render(&exr, 16, 2, &["--quiet"]);
    assert_ok(&out);
    assert_eq!(stderr(&out), "");
    assert_eq!(RadianceImage::read(&exr).unwrap().variance, None);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Largest relative difference per pixel and channel (0 where both are 0).
fn max_rel(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(x, y)| (0..3).map(move |c| (x[c] as f64, y[c] as f64)))
        .map(|(x, y)| {
            let m = x.abs().max(y.abs());
            if m == 0.0 { 0.0 } else { (x - y).abs() / m }
        })
        .fold(0.0, f64::max)
}

#[test]
fn four_shards_merged_equal_one_render() {
    // 18 spp: too few for variance batches (independent formula); 128 spp
    // Sobol: batches of 8 samples, each shard holding four of them.
    for (spp, ranges, batch) in [
        (18u32, [(0, 4), (4, 9), (9, 13), (13, 18)], 1u32),
        (128, [(0, 32), (32, 64), (64, 96), (96, 128)], 8),
    ] {
        shards_merged_equal_one_render(spp, ranges, batch);
    }
}

fn shards_merged_equal_one_render(spp: u32, ranges: [(u32, u32); 4], batch: u32) {
    let dir = scratch(&format!("shards{spp}"));
    let whole = dir.join("whole.exr");
    assert_ok(&render(
        &whole,
        24,
        spp,
        &["--seed", "3", "--variance", "--quiet"],
    ));
    let mut shards = Vec::new();
    for i in 0..4 {
        let p = dir.join(format!("s{i}.exr"));
        let out = render(
            &p,
            24,
            spp,
            &["--seed", "3", "--variance", "--shard", &format!("{i}/4")],
        );
        assert_ok(&out);
        assert!(
            stderr(&out).contains(&format!("shard {i}/4")),
            "{}",
            stderr(&out)
        );
        shards.push(p);
    }
    let metas: Vec<RenderMeta> = shards
        .iter()
        .map(|p| RadianceImage::read(p).unwrap().meta.unwrap())
        .collect();
    assert_eq!(
        metas.iter().map(|m| m.samples[0]).collect::<Vec<_>>(),
        ranges
    );
    assert!(metas.iter().all(|m| m.variance_batch == batch), "{metas:?}");
    assert_eq!(metas[2].shard, "2/4");
    let merged = dir.join("merged.exr");
    // Order does not matter.
    let out = glint()
        .arg("merge")
        .args([&shards[2], &shards[0], &shards[3], &shards[1]])
        .arg("-o")
        .arg(&merged)
        .output()
        .unwrap();
    assert_ok(&out);
    let (m, w) = (
        RadianceImage::read(&merged).unwrap(),
        RadianceImage::read(&whole).unwrap(),
    );
    let meta = m.meta.clone().unwrap();
    assert_eq!((meta.spp, meta.shard.as_str()), (spp, "0/1"));
    assert_eq!(meta.samples, [(0, spp)]);
    assert_eq!(meta.variance_batch, batch);
    assert_eq!(w.meta.as_ref().unwrap().variance_batch, batch);
    assert_eq!(meta.scene, w.meta.as_ref().unwrap().scene);
    let mean_err = max_rel(&m.mean, &w.mean);
    // The variances: the pooled one against the single render's, both
    // from f32 sums (cancellation in sum_sq - sum^2 / n bounds agreement).
    let var_err = max_rel(m.variance.as_ref().unwrap(), w.variance.as_ref().unwrap());
    eprintln!(
        "merged vs single: max relative difference: mean {mean_err:.2e}, variance {var_err:.2e}"
    );
    assert!(mean_err <= 1e-6, "mean {mean_err}");
    // The pooled variance is rebuilt from f32 means and variances: its
    // relative error is about 2^-24 m^2 / (v (n - 1)) over n units, so 16
    // batch means lose more than 128 samples (measured 3.6e-3 against
    // 2.4e-5 at the worst pixel).
    let var_tol = if batch == 1 { 1e-3 } else { 1e-2 };
    assert!(var_err <= var_tol, "variance {var_err}");
    // The merged image diffs as identical to the single render.
    let out = diff(&merged, &whole, &[]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn merge_refuses_what_does_not_fit() {
    let dir = scratch("refuse");
    let r = |name: &str, extra: &[&str]| {
        let p = dir.join(name);
        let mut args = vec!["--variance", "--quiet"];
        args.extend_from_slice(extra);
        assert_ok(&render(&p, 8, 8, &args));
        p
    };
    let s0 = r("s0.exr", &["--shard", "0/4"]);
    let s1 = r("s1.exr", &["--shard", "1/4"]);
    let half = r("half.exr", &["--shard", "0/2"]);
    let seed = r("seed.exr", &["--shard", "2/4", "--seed", "9"]);
    let depth = r("depth.exr", &["--shard", "2/4", "--max-depth", "2"]);
    let novar = dir.join("novar.exr");
    assert_ok(&render(&novar, 8, 8, &["--shard", "2/4", "--quiet"]));
    let big = dir.join("big.exr");
    assert_ok(&render(
        &big,
        16,
        8,
        &["--shard", "2/4", "--quiet", "--variance"],
    ));
    let png = dir.join("x.png");
    assert_ok(&render(&png, 8, 8, &["--quiet"]));
    let out = dir.join("out.exr");
    let merge = |shards: &[&PathBuf]| {
        glint()
            .arg("merge")
            .args(shards)
            .arg("-o")
            .arg(&out)
            .output()
            .unwrap()
    };
    assert_one_line_error(&merge(&[&s0, &s1, &s0]), "a duplicate shard");
    assert_one_line_error(&merge(&[&s1, &half]), "overlap");
    assert_one_line_error(&merge(&[&s0, &seed]), "seed 9");
    assert_one_line_error(&merge(&[&s0, &depth]), "a different scene");
    assert_one_line_error(&merge(&[&s0, &novar]), "variance");
    assert_one_line_error(&merge(&[&s0, &big]), "16x16 but");
    assert_one_line_error(&merge(&[&s0, &png]), "x.png");
    assert!(!out.exists());
    let merged = merge(&[&s0, &s1]);
    assert_ok(&merged);
    assert!(!stderr(&merged).contains("warning"), "{}", stderr(&merged));
    let m = RadianceImage::read(&out).unwrap().meta.unwrap();
    assert_eq!(
        (m.spp, m.shard.as_str(), m.samples.clone()),
        (4, "0/1", vec![(0, 4)])
    );
    // The shards' build is the merge's; shards of another build of the same
    // version, or of another version, merge with one warning naming both,
    // and the merge then records no build.
    let build = RadianceImage::read(&s0).unwrap().meta.unwrap().build;
    assert_eq!(m.build, build);
    let rewritten = |name: &str, f: &dyn Fn(&mut RenderMeta)| {
        let mut img = RadianceImage::read(&s1).unwrap();
        f(img.meta.as_mut().unwrap());
        let p = dir.join(name);
        img.write_file(&p).unwrap();
        p
    };
    let other_build = rewritten("build.exr", &|m| m.build = Some("0123456789abcdef".into()));
    let other_version = rewritten("version.exr", &|m| m.version = "0.0.9".into());
    if let Some(b) = &build {
        let warned = merge(&[&s0, &other_build]);
        assert_ok(&warned);
        let err = stderr(&warned);
        assert_eq!(err.matches("glint: warning:").count(), 1, "{err}");
        assert!(
            err.contains("build.exr: rendered by build 0123456789abcdef")
                && err.contains(&format!("s0.exr by build {b}")),
            "{err}"
        );
        assert_eq!(RadianceImage::read(&out).unwrap().meta.unwrap().build, None);
    }
    let warned = merge(&[&s0, &other_version]);
    assert_ok(&warned);
    let err = stderr(&warned);
    assert_eq!(err.matches("glint: warning:").count(), 1, "{err}");
    assert!(err.contains("written by glint 0.0.9"), "{err}");
    assert_eq!(
        RadianceImage::read(&out).unwrap().meta.unwrap().version,
        env!("CARGO_PKG_VERSION")
    );
    // Shards all of another version keep it.
    let other_version0 = dir.join("version0.exr");
    let mut img = RadianceImage::read(&s0).unwrap();
    img.meta.as_mut().unwrap().version = "0.0.9".into();
    img.write_file(&other_version0).unwrap();
    assert_ok(&merge(&[&other_version0, &other_version]));
    assert_eq!(
        RadianceImage::read(&out).unwrap().meta.unwrap().version,
        "0.0.9"
    );
    // Shards that hold nothing, or are not I/N.
    assert_one_line_error(&render(&out, 8, 4, &["--shard", "0/8"]), "holds no samples");
    assert_one_line_error(&render(&out, 8, 4, &["--shard", "4/4"]), "is not I/N");
    assert_one_line_error(
        &render(&out, 8, 4, &["--shard", "0/2", "--time-limit", "1"]),
        "cannot be combined",
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Render cornell in-process (fast) and write it as glint does.
fn render_exr(
    scene: &glint::cpu::Scene,
    path: &Path,
    size: u32,
    spp: u32,
    seed: u64,
    sampler: SamplerKind,
) {
    let opts = RenderOptions {
        spp,
        seed,
        sampler,
        ..RenderOptions::new(size, size)
    };
    let (film, _) = glint::cpu::render(scene, &opts, &|_, _| {}).unwrap();
    let meta = RenderMeta {
        spp,
        seed,
        sampler: sampler.name().into(),
        shard: "0/1".into(),
        version: env!("CARGO_PKG_VERSION").into(),
        build: None,
        samples: vec![(0, spp)],
        scene: None,
        files: None,
        variance_batch: 1,
    };
    RadianceImage::from_film(&film, true, Some(meta))
        .write_file(path)
        .unwrap();
}

/// The samplers glint has, each at a sample count: the calibration must
/// hold for each. QMC samples are not independent: at 64 spp a Sobol film
/// estimates its variance from 16 batch means of 4 samples
/// (`Film::variance_of_mean`), the estimate this checks.
const SAMPLERS: &[(SamplerKind, u32)] = &[(SamplerKind::Independent, 16), (SamplerKind::Sobol, 64)];

#[test]
fn diff_false_positive_rate_is_calibrated() {
    // 200 pairs of independent renders of one scene: `glint diff` must
    // report "differ" no more often than its alpha allows (binomial upper
    // bound at 1e-3), at the default alpha and at 0.05 (where a rate is
    // measurable).
    let dir = scratch("calib");
    let scene = glint::cpu::prepare::prepare_default(&cornell()).unwrap();
    const PAIRS: u64 = 200;
    for &(sampler, spp) in SAMPLERS {
        let mut fails = [0usize; 2];
        let alphas = [1e-3, 0.05];
        for pair in 0..PAIRS {
            let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
            render_exr(&scene, &a, 24, spp, 2 * pair, sampler);
            render_exr(&scene, &b, 24, spp, 2 * pair + 1, sampler);
            for (k, alpha) in alphas.iter().enumerate() {
                let out = diff(&a, &b, &["--alpha", &alpha.to_string()]);
                match out.status.code() {
                    Some(0) => {}
                    Some(1) => fails[k] += 1,
                    c => panic!("diff exit {c:?}: {}", stderr(&out)),
                }
            }
        }
        for (k, alpha) in alphas.iter().enumerate() {
            let bound = glint::cpu::compare::binomial_upper_quantile(PAIRS as usize, *alpha, 1e-3);
            eprintln!(
                "diff calibration ({}): alpha {alpha}: {} of {PAIRS} pairs differ ({:.3}; bound {bound})",
                sampler.name(),
                fails[k],
                fails[k] as f64 / PAIRS as f64
            );
            assert!(
                fails[k] <= bound,
                "{} at alpha {alpha}: {} > {bound}",
                sampler.name(),
                fails[k]
            );
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A 2% change of one material on one object is caught at 256 spp (the
/// default Sobol sampler). The sphere is about 35 pixels across at 96
/// wide, some 15 of the 8x8 blocks. Two things made this reachable
/// (before: max |z| 3-4 against a threshold of 4.6 at 64 wide): Sobol
/// films estimate their variance from batch means (the independent
/// formula overestimated it 10-15x at 256 spp), and the block test also
/// tests coarser blocks, where a change spread over several 8x8 blocks
/// adds up. Measured at seeds 1, 5, 7, 11: max |z| 10.1-11.7 against 4.9.
#[test]
fn diff_catches_a_material_change() {
    let dir = scratch("power");
    let sphere = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/diffuse.gltf");
    let mut g: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&sphere).unwrap()).unwrap();
    let m = &mut g["materials"][0];
    assert_eq!(m["name"], "diffuse");
    for c in 0..3 {
        let v = m["extras"]["bsdf"]["reflectance"][c].as_f64().unwrap();
        m["extras"]["bsdf"]["reflectance"][c] = (v * 1.02).into();
    }
    let changed = dir.join("changed.gltf");
    std::fs::write(&changed, serde_json::to_vec(&g).unwrap()).unwrap();
    let (a, b) = (dir.join("a.exr"), dir.join("b.exr"));
    for (scene, out, seed) in [(&sphere, &a, "1"), (&changed, &b, "2")] {
        let o = glint()
            .arg("render")
            .arg(scene)
            .arg("-o")
            .arg(out)
            .args([
                "--backend",
                "cpu",
                "--width",
                "96",
                "--spp",
                "256",
                "--variance",
                "--quiet",
                "--seed",
                seed,
            ])
            .output()
            .unwrap();
        assert_ok(&o);
    }
    let (png, json) = (dir.join("d.png"), dir.join("d.json"));
    let out = diff(
        &b,
        &a,
        &[
            "--diff",
            png.to_str().unwrap(),
            "--json",
            json.to_str().unwrap(),
        ],
    );
    eprintln!("{}", String::from_utf8_lossy(&out.stdout));
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let j: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(j["verdict"], "differ");
    let d = image::open(&png).unwrap();
    assert!(d.width() > 96 && d.height() >= 72);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn diff_exit_status_and_guards() {
    let dir = scratch("diff");
    let (a, b, c) = (dir.join("a.exr"), dir.join("b.exr"), dir.join("c.exr"));
    assert_ok(&render(
        &a,
        16,
        16,
        &["--variance", "--quiet", "--seed", "1"],
    ));
    assert_ok(&render(
        &b,
        16,
        16,
        &["--variance", "--quiet", "--seed", "2"],
    ));
    assert_ok(&render(&c, 16, 16, &["--quiet", "--seed", "3"]));
    let out = diff(&a, &b, &[]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("relMSE") && text.contains("FLIP") && text.contains("agree"),
        "{text}"
    );
    // Without variance: metrics, no verdict, exit 2 (contract, "Second
    // additions") unless a threshold decides.
    let out = diff(&a, &c, &[]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stdout).contains("relMSE"));
    assert_one_line_error(&out, "no statistical verdict");
    assert_eq!(
        diff(&a, &c, &["--max-relmse", "1e9"]).status.code(),
        Some(0)
    );
    assert_eq!(diff(&a, &c, &["--max-relmse", "0"]).status.code(), Some(1));
    assert_eq!(diff(&a, &c, &["--max-flip", "1"]).status.code(), Some(0));
    // Bad input: 2 with one line.
    let out = diff(&a, &dir.join("missing.exr"), &[]);
    assert_eq!(out.status.code(), Some(2));
    assert_one_line_error(&out, "no such file");
    let small = dir.join("small.exr");
    assert_ok(&render(&small, 8, 16, &["--variance", "--quiet"]));
    assert_one_line_error(&diff(&a, &small, &[]), "16x16 but");
    // A 1x1 image at 4 spp: the test has no power (exit 2, not "agree").
    let write = |p: &Path, mean: Vec3, var: Vec3, w: u32, spp: u32, seed: u64| {
        let n = (w * w) as usize;
        RadianceImage {
            width: w,
            height: w,
            mean: vec![mean; n],
            variance: Some(vec![var; n]),
            meta: Some(RenderMeta {
                spp,
                seed,
                sampler: "independent".into(),
                shard: "0/1".into(),
                version: "0".into(),
                build: None,
                samples: vec![(0, spp)],
                scene: None,
                files: None,
                variance_batch: 1,
            }),
        }
        .write_file(p)
        .unwrap();
    };
    let (x, y) = (dir.join("x.exr"), dir.join("y.exr"));
    write(&x, Vec3::ONE, Vec3::splat(0.1), 1, 4, 1);
    write(&y, Vec3::splat(1.5), Vec3::splat(0.1), 1, 4, 2);
    let out = diff(&x, &y, &[]);
    assert_eq!(out.status.code(), Some(2));
    assert_one_line_error(&out, "no power");
    // Radiance near 1e37: its variance overflowed to infinity; a z of 0
    // must not pass.
    write(&x, Vec3::splat(1e37), Vec3::splat(f32::INFINITY), 16, 64, 1);
    write(&y, Vec3::splat(3e37), Vec3::splat(f32::INFINITY), 16, 64, 2);
    let out = diff(&x, &y, &[]);
    assert_eq!(out.status.code(), Some(2));
    assert_one_line_error(&out, "non-finite");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn odd_scene_paths_say_what_they_are() {
    let dir = scratch("paths");
    let out = dir.join("o.png");
    let try_scene = |scene: &Path| {
        glint()
            .arg("render")
            .arg(scene)
            .arg("-o")
            .arg(&out)
            .args(["--backend", "cpu", "--width", "8", "--spp", "1"])
            .output()
            .unwrap()
    };
    assert_one_line_error(&try_scene(&dir), "a directory");
    assert_one_line_error(&try_scene(Path::new("/dev/zero")), "a character device");
    let fifo = dir.join("fifo.gltf");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    // Must not wait for a writer.
    assert_one_line_error(&try_scene(&fifo), "a named pipe (FIFO)");
    let (l1, l2) = (dir.join("l1.gltf"), dir.join("l2.gltf"));
    std::os::unix::fs::symlink(&l2, &l1).unwrap();
    std::os::unix::fs::symlink(&l1, &l2).unwrap();
    assert_one_line_error(&try_scene(&l1), "a symbolic link loop");
    assert_one_line_error(&try_scene(&dir.join("none.gltf")), "no such file");
    assert!(!out.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn output_naming_the_scene_is_refused() {
    let dir = scratch("self");
    let scene = dir.join("scene.gltf");
    std::fs::copy(cornell(), &scene).unwrap();
    let before = std::fs::read(&scene).unwrap();
    for name in ["scene.gltf", "./scene.gltf"] {
        let out = glint()
            .current_dir(&dir)
            .args([
                "render",
                "scene.gltf",
                "-o",
                name,
                "--backend",
                "cpu",
                "--spp",
                "1",
            ])
            .output()
            .unwrap();
        assert_one_line_error(&out, "is the input scene");
    }
    // And through --stats.
    let out = glint()
        .current_dir(&dir)
        .args([
            "render",
            "scene.gltf",
            "-o",
            "a.png",
            "--stats",
            "scene.gltf",
            "--backend",
            "cpu",
        ])
        .output()
        .unwrap();
    assert_one_line_error(&out, "is the input scene");
    assert_eq!(std::fs::read(&scene).unwrap(), before);
    assert_eq!(files_in(&dir), ["scene.gltf"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn negative_seed_and_camera_are_explained() {
    let dir = scratch("neg");
    let out = dir.join("o.png");
    let o = render(&out, 8, 1, &["--seed", "-1"]);
    assert_one_line_error(&o, "a seed is a whole number from 0");
    let o = render(&out, 8, 1, &["--camera", "-1"]);
    assert_one_line_error(&o, "camera indices start at 0");
    assert!(!out.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn signals_mid_render_remove_unfinished_outputs() {
    for (signal, code) in [("INT", 130), ("TERM", 143)] {
        let dir = scratch(&format!("sig{signal}"));
        let child = glint()
            .arg("render")
            .arg(cornell())
            .arg("-o")
            .arg(dir.join("a.exr"))
            .arg("-o")
            .arg(dir.join("a.png"))
            .args([
                "--backend",
                "cpu",
                "--width",
                "128",
                "--spp",
                "100000",
                "--quiet",
            ])
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        // Wait for the temporaries (the render has begun).
        let t0 = std::time::Instant::now();
        while files_in(&dir).len() < 2 {
            assert!(
                t0.elapsed().as_secs() < 60,
                "no temporaries: {:?}",
                files_in(&dir)
            );
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
        std::thread::sleep(std::time::Duration::from_millis(300));
        let tmp = files_in(&dir);
        assert!(tmp.iter().all(|n| n.contains(".tmp-")), "{tmp:?}");
        let ok = Command::new("kill")
            .args([&format!("-{signal}"), &child.id().to_string()])
            .status()
            .unwrap();
        assert!(ok.success());
        let out = child.wait_with_output().unwrap();
        assert_eq!(out.status.code(), Some(code), "{}", stderr(&out));
        assert_one_line_error(&out, &format!("interrupted by SIG{signal}"));
        assert_eq!(files_in(&dir), Vec::<String>::new());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
