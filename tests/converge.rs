//! `glint converge` end to end at tiny sizes: the CSV against the metrics
//! module recomputed from the kept images, the chart files, the reference
//! cache, and the contract's error behaviour (one line, no partial DIR).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use glam::Vec3;
use glint::cpu::metrics::{self, ImageRef};

fn glint(cache: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_glint"));
    c.env("GLINT_CACHE_DIR", cache);
    c
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("glint-converge-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn asset(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(name)
}

fn read_exr(p: &Path) -> (u32, u32, Vec<Vec3>) {
    let img = image::open(p).unwrap().into_rgb32f();
    let (w, h) = img.dimensions();
    (w, h, img.pixels().map(|p| Vec3::from_array(p.0)).collect())
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The error lines of a failed run: exactly one line starting `glint: `.
fn one_error_line(o: &Output) -> String {
    assert!(!o.status.success(), "expected failure, got success");
    let err = stderr(o);
    let lines: Vec<&str> = err
        .lines()
        .filter(|l| !l.starts_with("glint: converge:"))
        .collect();
    assert_eq!(lines.len(), 1, "expected one line, got: {err}");
    assert!(lines[0].starts_with("glint: "), "{err}");
    lines[0].to_string()
}

#[test]
fn converge_writes_a_table_that_matches_the_metrics_and_a_readable_chart() {
    let dir = scratch("ok");
    let out = dir.join("out");
    let cache = dir.join("cache");
    let scene = asset("cornell.gltf");
    let args = [
        "converge",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--reference-spp",
        "32",
        "--width",
        "16",
        "--spp",
        "2,8",
        "--variant",
        "gpu=--backend gpu",
        "--variant",
        "cpu-balance=--backend cpu --mis balance",
        "--keep-images",
    ];
    let o = glint(&cache).args(args).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));

    let csv = std::fs::read_to_string(out.join("converge.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "variant,backend,spp,seconds,relmse,relmse_trim,rmse,flip,mean_r,mean_g,mean_b"
    );
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    assert_eq!(rows.len(), 4);

    // The reference is cached: one EXR under the cache folder.
    let refs: Vec<PathBuf> = std::fs::read_dir(cache.join("references"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(refs.len(), 1, "{refs:?}");
    let (rw, rh, reference) = read_exr(&refs[0]);
    let reference = ImageRef::new(rw, rh, &reference).unwrap();

    for r in &rows {
        let img_path = out.join(format!("{}-{}.exr", r[0], r[2]));
        let (w, h, px) = read_exr(&img_path);
        let m = metrics::compute(&ImageRef::new(w, h, &px).unwrap(), &reference).unwrap();
        let close = |csv: &str, want: f64| {
            let got: f64 = csv.parse().unwrap();
            assert!(
                (got - want).abs() <= 1e-5 * want.abs().max(1e-12),
                "{img_path:?}: CSV {got} vs recomputed {want}"
            );
        };
        close(&r[4], m.relmse);
        close(&r[5], m.relmse_trim);
        close(&r[6], m.rmse);
        assert!((r[7].parse::<f64>().unwrap() - m.flip).abs() < 1e-5);
        close(&r[8], m.mean.x);
        assert!(r[3].parse::<f64>().unwrap() > 0.0);
    }
    assert_eq!(rows[0][1], "gpu");
    assert_eq!(rows[2][1], "cpu");

    // The PNG decodes and is not blank; the SVG parses and names the curves.
    let png = image::open(out.join("converge.png")).unwrap().to_rgb8();
    let mut colours: Vec<[u8; 3]> = png.pixels().map(|p| p.0).collect();
    colours.sort();
    colours.dedup();
    assert!(
        colours.len() > 16,
        "a blank chart: {} colours",
        colours.len()
    );
    let svg = std::fs::read_to_string(out.join("converge.svg")).unwrap();
    let doc = roxmltree::Document::parse(&svg).expect("the SVG parses");
    let text: String = doc
        .descendants()
        .filter_map(|n| n.text())
        .collect::<Vec<_>>()
        .join(" ");
    for want in ["gpu", "cpu-balance", "relMSE", "seconds", "cornell.gltf"] {
        assert!(text.contains(want), "SVG lacks '{want}': {text}");
    }
    let md = std::fs::read_to_string(out.join("converge.md")).unwrap();
    assert!(
        md.contains("| cpu-balance |") && md.contains("relMSE at"),
        "{md}"
    );

    // A second run reads the cached reference.
    let out2 = dir.join("out2");
    let mut args2 = args.to_vec();
    args2[3] = out2.to_str().unwrap();
    let o = glint(&cache).args(&args2[..10]).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("reference from the cache"),
        "{}",
        stderr(&o)
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn converge_refuses_bad_input_with_one_line_and_leaves_no_partial_dir() {
    let dir = scratch("bad");
    let cache = dir.join("cache");
    let scene = asset("diffuse.gltf");
    let scene = scene.to_str().unwrap();

    // A bad variant: the folder is never created.
    let out = dir.join("v");
    let o = glint(&cache)
        .args([
            "converge",
            scene,
            "-o",
            out.to_str().unwrap(),
            "--reference-spp",
            "4",
        ])
        .args([
            "--width",
            "8",
            "--spp",
            "1",
            "--variant",
            "x=--mis sometimes",
        ])
        .output()
        .unwrap();
    let line = one_error_line(&o);
    assert!(
        line.contains("--variant") && line.contains("sometimes"),
        "{line}"
    );
    assert!(!out.exists());
    let o = glint(&cache)
        .args([
            "converge",
            scene,
            "-o",
            out.to_str().unwrap(),
            "--reference-spp",
            "4",
        ])
        .args(["--variant", "no-equals-sign"])
        .output()
        .unwrap();
    assert!(one_error_line(&o).contains("NAME=OPTIONS"));

    // A reference of the wrong size: no converge.* file is left behind.
    let small = dir.join("ref.exr");
    let mut f = glint::cpu::Film::new(5, 3);
    f.spp = 1;
    f.write_image(&small).unwrap();
    let out = dir.join("r");
    let o = glint(&cache)
        .args(["converge", scene, "-o", out.to_str().unwrap()])
        .args([
            "--reference",
            small.to_str().unwrap(),
            "--width",
            "8",
            "--spp",
            "1",
        ])
        .args(["--variant", "cpu=--backend cpu"])
        .output()
        .unwrap();
    let line = one_error_line(&o);
    assert!(line.contains("5x3") && line.contains("8x"), "{line}");
    assert!(
        !out.exists(),
        "a partial DIR was left: {:?}",
        std::fs::read_dir(&out).map(|d| d.count())
    );

    // An unwritable DIR (a path under a file).
    let file = dir.join("file");
    std::fs::write(&file, b"x").unwrap();
    let o = glint(&cache)
        .args(["converge", scene, "-o", file.join("sub").to_str().unwrap()])
        .args(["--reference-spp", "4", "--width", "8", "--spp", "1"])
        .output()
        .unwrap();
    assert!(one_error_line(&o).contains("cannot create"));

    // Neither --reference nor --reference-spp.
    let o = glint(&cache)
        .args(["converge", scene, "-o", dir.join("n").to_str().unwrap()])
        .output()
        .unwrap();
    one_error_line(&o);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn time_limit_stops_at_whole_passes_and_reports_the_spp_reached() {
    let dir = scratch("time");
    let scene = asset("diffuse.gltf");
    for backend in ["cpu", "gpu"] {
        // A generous budget with --spp: the cap is reached exactly.
        let stats = dir.join(format!("{backend}-cap.json"));
        let o = glint(&dir)
            .args(["render", scene.to_str().unwrap(), "-o"])
            .arg(dir.join("a.exr"))
            .args([
                "--width",
                "16",
                "--spp",
                "3",
                "--time-limit",
                "600",
                "--backend",
                backend,
            ])
            .arg("--stats")
            .arg(&stats)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
        assert_eq!(v["spp"], 3, "{v}");
        assert_eq!(v["time_limit"], 600.0);

        // A short budget without --spp: some whole passes, far fewer than
        // the cap, and the image is the mean of exactly those.
        let stats = dir.join(format!("{backend}-short.json"));
        let o = glint(&dir)
            .args(["render", scene.to_str().unwrap(), "-o"])
            .arg(dir.join("b.exr"))
            .args(["--width", "16", "--time-limit", "0.3", "--backend", backend])
            .arg("--stats")
            .arg(&stats)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
        let spp = v["spp"].as_u64().unwrap();
        assert!((1..1 << 24).contains(&spp), "{v}");
        let samples = v["samples"].as_u64().unwrap();
        let pixels = v["width"].as_u64().unwrap() * v["height"].as_u64().unwrap();
        assert_eq!(samples, spp * pixels, "{v}");
    }
    let o = glint(&dir)
        .args(["render", scene.to_str().unwrap(), "-o"])
        .arg(dir.join("c.exr"))
        .args(["--time-limit", "-1"])
        .output()
        .unwrap();
    assert!(one_error_line(&o).contains("--time-limit"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--variant` with `--adaptive` and `--target-error` (issue 23): each
/// `--spp` budget is the cap; the CSV reports the spp reached (an adaptive
/// render's mean over pixels, below the cap; a target-error render's whole
/// passes, fewer for the looser target), and the error falls with the cap.
/// With `--time` budgets, or a bad threshold, one line and no DIR.
#[test]
fn adaptive_and_target_error_variants_report_the_spp_reached() {
    let dir = scratch("control");
    let scene = asset("cornell.gltf");
    let out = dir.join("out");
    let o = glint(&dir)
        .args(["converge", scene.to_str().unwrap(), "-o"])
        .arg(&out)
        .args([
            "--width",
            "16",
            "--spp",
            "64,256",
            "--reference-spp",
            "1024",
        ])
        .args(["--variant", "adaptive=--backend cpu --adaptive 0.1"])
        .args(["--variant", "tight=--backend cpu --target-error 0.001"])
        .args(["--variant", "loose=--backend cpu --target-error 0.05"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = std::fs::read_to_string(out.join("converge.csv")).unwrap();
    let rows: Vec<(String, f64, f64)> = csv
        .lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (
                f[0].to_string(),
                f[2].parse().unwrap(),
                f[4].parse().unwrap(),
            )
        })
        .collect();
    let of = |v: &str| -> Vec<(f64, f64)> {
        rows.iter()
            .filter(|r| r.0 == v)
            .map(|r| (r.1, r.2))
            .collect()
    };
    let (ad, tight, loose) = (of("adaptive"), of("tight"), of("loose"));
    assert_eq!((ad.len(), tight.len(), loose.len()), (2, 2, 2), "{csv}");
    for (i, cap) in [64.0, 256.0].into_iter().enumerate() {
        assert!(ad[i].0 > 0.0 && ad[i].0 <= cap, "adaptive spp {csv}");
        assert!(loose[i].0 <= tight[i].0 && tight[i].0 <= cap, "{csv}");
    }
    // At the larger cap the adaptive render stops pixels early and its
    // error is smaller than at the smaller cap.
    assert!(ad[1].0 < 256.0 && ad[1].1 < ad[0].1, "{csv}");
    assert!(
        loose[1].0 < 256.0,
        "the loose target stops before the cap: {csv}"
    );

    for (variant, budget) in [
        ("a=--backend cpu --adaptive 0.1", ["--time", "0.5"]),
        ("a=--backend cpu --adaptive 0", ["--spp", "8"]),
        ("a=--backend cpu --target-error NaN", ["--spp", "8"]),
    ] {
        let bad = dir.join("bad");
        let o = glint(&dir)
            .args(["converge", scene.to_str().unwrap(), "-o"])
            .arg(&bad)
            .args([
                "--width",
                "8",
                "--reference-spp",
                "16",
                "--variant",
                variant,
            ])
            .args(budget)
            .output()
            .unwrap();
        let line = one_error_line(&o);
        assert!(
            line.contains("--adaptive") || line.contains("--target-error"),
            "{variant}: {line}"
        );
        assert!(!bad.join("converge.csv").exists());
    }
}

/// A variant's options that change what the file loads into
/// (`--multiscatter`, `--background`) are its own: it renders its own
/// preparation of the scene (they were ignored, and the variants rendered
/// the shared scene's image bit for bit), and its kept image records that
/// scene's key, the one `glint render` with the same options records.
#[test]
fn variants_that_change_the_scene_render_their_own() {
    let dir = scratch("scene-variants");
    let (out, cache) = (dir.join("out"), dir.join("cache"));
    let scene = asset("roughconductor.gltf");
    let o = glint(&cache)
        .arg("converge")
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .args(["--reference-spp", "16", "--width", "16", "--spp", "4"])
        .arg("--keep-images")
        .args(["--variant", "off=--backend cpu --multiscatter off"])
        .args(["--variant", "on=--backend cpu --multiscatter on"])
        .args(["--variant", "white=--backend cpu --background 1,1,1"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = std::fs::read_to_string(out.join("converge.csv")).unwrap();
    let means: Vec<String> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').skip(8).collect::<Vec<_>>().join(","))
        .collect();
    assert_eq!(means.len(), 3, "{csv}");
    assert!(
        means[0] != means[1] && means[0] != means[2] && means[1] != means[2],
        "{csv}"
    );
    let key = |p: &Path| {
        let m = glint::cpu::exr_file::RadianceImage::read(p)
            .unwrap()
            .meta
            .unwrap();
        (m.scene.unwrap(), m.files.unwrap())
    };
    let white = dir.join("white.exr");
    let r = glint(&cache)
        .arg("render")
        .arg(&scene)
        .args(["--width", "16", "--spp", "4", "--backend", "cpu", "--quiet"])
        .args(["--background", "1,1,1", "-o"])
        .arg(&white)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", stderr(&r));
    assert_eq!(key(&out.join("white-4.exr")).1, key(&white).1);
    assert_ne!(key(&out.join("off-4.exr")).1, key(&white).1);
    assert_ne!(key(&out.join("on-4.exr")).1, key(&out.join("off-4.exr")).1);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--reference` made by glint from another scene, or with other image
/// options, is named in a warning (its recorded scene key is not the shared
/// options'); one of the same scene and options is not.
#[test]
fn a_reference_of_another_scene_is_warned_of() {
    let dir = scratch("reference-key");
    let cache = dir.join("cache");
    let reference = |scene: &str, out: &str| {
        let p = dir.join(out);
        let o = glint(&cache)
            .arg("render")
            .arg(asset(scene))
            .args(["--backend", "cpu", "--spp", "8", "--width", "16", "--quiet"])
            .args(["--height", "12", "-o"])
            .arg(&p)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
        p
    };
    let (same, other) = (
        reference("diffuse.gltf", "same.exr"),
        reference("conductor.gltf", "other.exr"),
    );
    let converge = |r: &Path, extra: &[&str], out: &str| {
        let o = glint(&cache)
            .arg("converge")
            .arg(asset("diffuse.gltf"))
            .arg("-o")
            .arg(dir.join(out))
            .arg("--reference")
            .arg(r)
            .args(["--width", "16", "--height", "12", "--spp", "2"])
            .args(["--variant", "c=--backend cpu"])
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
        stderr(&o)
    };
    assert!(!converge(&same, &[], "a").contains("warning"));
    let e = converge(&other, &[], "b");
    assert!(e.contains("made from other scene files"), "{e}");
    let e = converge(&same, &["--max-depth", "2"], "c");
    assert!(e.contains("made with other image options"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
