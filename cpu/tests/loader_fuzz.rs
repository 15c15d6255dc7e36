//! A seeded corruption loop over real files: the bundled scenes
//! (`assets/`) and the shared sample models (`../shared/assets`, read when
//! present). Each iteration copies one model's folder state, corrupts one
//! of its files (the .gltf/.glb, a buffer, a texture) with a random
//! mutation, and loads it: every corrupted input must give `Ok` or one
//! clean error, never a panic. EXR images (`RadianceImage::read`) and
//! environment maps (`EnvMap::load`) get the same treatment.
//!
//! Bounded so that CI's debug-profile test run pays well under a minute:
//! `GLINT_FUZZ_SECONDS` (default 12) of loading, at most
//! `GLINT_FUZZ_ITERATIONS` (default 3000); `GLINT_FUZZ_SEED` picks the
//! stream (default: fixed, so a failure reproduces). A failure names the
//! seed, the iteration, the file and the mutation.

use glint_cpu::sampling::Pcg32;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use glam::Vec3;
use glint_cpu::envmap::EnvMap;
use glint_cpu::exr_file::RadianceImage;

fn env_or<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// One model: its folder's files (name, bytes) and which one is the scene.
struct Model {
    name: String,
    files: Vec<(String, Vec<u8>)>,
    scene: usize,
}

/// Files of `dir` (not recursive) no larger than `limit` bytes.
fn folder_files(dir: &Path, limit: u64) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return out;
    };
    let mut paths: Vec<PathBuf> = entries.filter_map(|e| Some(e.ok()?.path())).collect();
    paths.sort();
    for p in paths {
        let Ok(m) = std::fs::metadata(&p) else {
            continue;
        };
        if m.is_file() && m.len() <= limit {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            out.push((name, std::fs::read(&p).unwrap()));
        }
    }
    out
}

fn is_scene(name: &str) -> bool {
    name.ends_with(".gltf") || name.ends_with(".glb")
}

/// Every scene found: each bundled scene with its folder's buffers and
/// images, each shared sample's glTF folder, the shared .glb files.
fn models() -> Vec<Model> {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut folders: Vec<PathBuf> = vec![repo.join("assets")];
    let shared = repo.join("../shared/assets");
    folders.push(shared.clone());
    if let Ok(samples) = std::fs::read_dir(shared.join("gltf-samples")) {
        let mut s: Vec<PathBuf> = samples
            .filter_map(|e| Some(e.ok()?.path().join("glTF")))
            .filter(|p| p.is_dir())
            .collect();
        s.sort();
        folders.extend(s);
    }
    let mut out = Vec::new();
    for dir in folders {
        // Big meshes (the 1.7 MB bunny) and 2K textures cost a BVH build
        // or a decode per iteration; 1 MB keeps each load fast (a texture
        // left out is a missing image: a warning, still a load).
        let files = folder_files(&dir, 1 << 20);
        for (i, (name, _)) in files.iter().enumerate() {
            if is_scene(name) {
                // Only the scene and what is not another scene.
                let mut own: Vec<(String, Vec<u8>)> = Vec::new();
                let mut scene = 0;
                for (j, f) in files.iter().enumerate() {
                    if j == i {
                        scene = own.len();
                    } else if is_scene(&f.0) {
                        continue;
                    }
                    own.push(f.clone());
                }
                out.push(Model {
                    name: format!("{}/{name}", dir.display()),
                    files: own,
                    scene,
                });
            }
        }
    }
    out
}

/// Numbers that break careless code: negative, zero, huge, past f32 and
/// u32, non-integer where an index is expected.
const NUMBERS: &[&str] = &[
    "-1",
    "0",
    "1",
    "3",
    "255",
    "65536",
    "4294967295",
    "4294967296",
    "2147483648",
    "9223372036854775807",
    "1e38",
    "3.5e38",
    "-3.5e38",
    "1e-45",
    "0.5",
    "-0",
    "1e308",
];

/// Strings a URI, name or enum might become.
const STRINGS: &[&str] = &[
    "",
    "../x.bin",
    "/etc/passwd",
    "data:application/octet-stream;base64,AAAA",
    "data:,",
    "file://host/x",
    "%ZZ",
    "x\\u0000y",
    "MASK",
    "BLEND",
    "VEC4",
    "MAT4",
    "SCALAR",
];

/// Apply one random mutation to `b`; returns what it did.
fn mutate(rng: &mut Pcg32, b: &mut Vec<u8>, json: bool) -> String {
    let kinds = if json { 8 } else { 5 };
    match rng.below(kinds) {
        0 => {
            let n = 1 + rng.below(8);
            for _ in 0..n {
                if !b.is_empty() {
                    let i = rng.below(b.len());
                    b[i] ^= 1 << rng.below(8);
                }
            }
            format!("flip {n} bit(s)")
        }
        1 => {
            let at = rng.below(b.len() + 1);
            b.truncate(at);
            format!("truncate at {at}")
        }
        2 => {
            let at = rng.below(b.len() + 1);
            let n = 1 + rng.below(64);
            let junk: Vec<u8> = (0..n).map(|_| rng.next_u64() as u8).collect();
            b.splice(at..at, junk);
            format!("insert {n} random bytes at {at}")
        }
        3 => {
            if b.is_empty() {
                return "nothing (empty)".into();
            }
            let a = rng.below(b.len());
            let len = 1 + rng.below((b.len() - a).min(256));
            let at = rng.below(b.len() + 1);
            let copy = b[a..a + len].to_vec();
            b.splice(at..at, copy);
            format!("duplicate {len} bytes from {a} at {at}")
        }
        4 => {
            // Overwrite a 32-bit word with an extreme value (lengths,
            // counts and offsets in GLB headers, PNG chunks, buffers).
            if b.len() < 4 {
                return "nothing (short)".into();
            }
            let at = rng.below(b.len() - 3) & !3;
            let v: u32 = [0, 1, 0x7fff_ffff, 0x8000_0000, u32::MAX, 0xffff_fff0][rng.below(6)];
            b[at..at + 4].copy_from_slice(&v.to_le_bytes());
            format!("word {v:#x} at {at}")
        }
        5 | 6 => {
            // Replace a number token in the JSON.
            let starts: Vec<usize> = (0..b.len())
                .filter(|&i| {
                    (b[i].is_ascii_digit() || b[i] == b'-')
                        && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'.'))
                })
                .collect();
            if starts.is_empty() {
                return "nothing (no number)".into();
            }
            let s = starts[rng.below(starts.len())];
            let mut e = s + 1;
            while e < b.len() && (b[e].is_ascii_digit() || b"+-.eE".contains(&b[e])) {
                e += 1;
            }
            let n = NUMBERS[rng.below(NUMBERS.len())];
            b.splice(s..e, n.bytes());
            format!("number at {s} -> {n}")
        }
        _ => {
            // Replace a string value in the JSON.
            let quotes: Vec<usize> = (0..b.len()).filter(|&i| b[i] == b'"').collect();
            if quotes.len() < 2 {
                return "nothing (no string)".into();
            }
            let k = rng.below(quotes.len() / 2) * 2;
            let (s, e) = (quotes[k] + 1, quotes[k + 1]);
            let v = STRINGS[rng.below(STRINGS.len())];
            b.splice(s..e, v.bytes());
            format!("string at {s} -> {v:?}")
        }
    }
}

/// Run `f` and turn a panic into its message.
fn no_panic<T>(f: impl FnOnce() -> T + std::panic::UnwindSafe) -> Result<T, String> {
    std::panic::catch_unwind(f).map_err(|p| {
        p.downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| p.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown panic".into())
    })
}

#[test]
fn corrupted_scenes_load_or_fail_cleanly() {
    let seed: u64 = env_or("GLINT_FUZZ_SEED", 0x5eed_2021);
    let budget = Duration::from_secs_f64(env_or("GLINT_FUZZ_SECONDS", 12.0));
    let max_iter: usize = env_or("GLINT_FUZZ_ITERATIONS", 3000);
    let models = models();
    assert!(
        models.len() >= 7,
        "the bundled scenes alone are 7; found {}",
        models.len()
    );
    // Silence the default hook: panics are caught and reported below.
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let mut rng = Pcg32::from_state(seed | 1);
    let work = tempfile::tempdir().unwrap();
    let start = Instant::now();
    let (mut iterations, mut ok, mut errors) = (0usize, 0usize, 0usize);
    let mut failures = Vec::new();
    while iterations < max_iter && start.elapsed() < budget {
        iterations += 1;
        let m = &models[rng.below(models.len())];
        // A fresh folder per iteration: nothing carries over.
        let dir = work.path().join(format!("i{iterations}"));
        std::fs::create_dir_all(&dir).unwrap();
        for (name, bytes) in &m.files {
            std::fs::write(dir.join(name), bytes).unwrap();
        }
        // The scene most of the time, else another file of its folder.
        let target = if m.files.len() > 1 && rng.below(4) == 0 {
            rng.below(m.files.len())
        } else {
            m.scene
        };
        let (name, original) = &m.files[target];
        let mut bytes = original.clone();
        let json = name.ends_with(".gltf");
        let mut what = Vec::new();
        for _ in 0..1 + rng.below(3) {
            what.push(mutate(&mut rng, &mut bytes, json));
        }
        std::fs::write(dir.join(name), &bytes).unwrap();
        let scene = dir.join(&m.files[m.scene].0);
        match no_panic(|| glint_cpu::loader::load(&scene)) {
            Ok(Ok(_)) => ok += 1,
            Ok(Err(e)) => {
                let msg = e.to_string();
                if msg.lines().count() != 1 {
                    failures.push(format!(
                        "{}: {name}: {what:?}: not one line: {msg:?}",
                        m.name
                    ));
                }
                errors += 1;
            }
            Err(p) => failures.push(format!(
                "seed {seed:#x} iteration {iterations}: {} ({name}: {what:?}) panicked: {p}",
                m.name
            )),
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
    std::panic::set_hook(hook);
    eprintln!(
        "loader fuzz: {iterations} corrupted loads over {} models in {:.1} s: {ok} loaded, {errors} clean errors, {} failures",
        models.len(),
        start.elapsed().as_secs_f64(),
        failures.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(iterations >= 20, "too few iterations to mean anything");
}

#[test]
fn corrupted_exr_and_envmap_files_read_or_fail_cleanly() {
    let seed: u64 = env_or("GLINT_FUZZ_SEED", 0x5eed_2021) ^ 0xe8;
    let budget = Duration::from_secs_f64(env_or("GLINT_FUZZ_SECONDS", 12.0) / 3.0);
    let work = tempfile::tempdir().unwrap();
    // A glint EXR with variance and attributes.
    let n = 24 * 16;
    let img = RadianceImage {
        width: 24,
        height: 16,
        mean: (0..n).map(|i| Vec3::splat(i as f32 / n as f32)).collect(),
        variance: Some(vec![Vec3::splat(0.01); n]),
        meta: None,
    };
    let exr = work.path().join("a.exr");
    img.write_file(&exr).unwrap();
    let mut originals = vec![("a.exr".to_string(), std::fs::read(&exr).unwrap())];
    let shared_env =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/assets/gltf-samples/env");
    originals.extend(folder_files(&shared_env, 4 << 20));
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let mut rng = Pcg32::from_state(seed | 1);
    let start = Instant::now();
    let mut failures = Vec::new();
    let mut iterations = 0;
    while iterations < 400 && start.elapsed() < budget {
        iterations += 1;
        let (name, original) = &originals[rng.below(originals.len())];
        let mut bytes = original.clone();
        let what = mutate(&mut rng, &mut bytes, false);
        let p = work.path().join(format!("x-{name}"));
        std::fs::write(&p, &bytes).unwrap();
        let r = if name.ends_with(".exr") && rng.below(2) == 0 {
            no_panic(|| {
                RadianceImage::read(&p)
                    .map(|_| ())
                    .map_err(|e| e.to_string())
            })
        } else {
            no_panic(|| EnvMap::load(&p, 1.0, 0.0).map(|_| ()))
        };
        match r {
            Ok(Ok(())) => {}
            Ok(Err(e)) if e.lines().count() <= 1 => {}
            Ok(Err(e)) => failures.push(format!("{name}: {what}: not one line: {e:?}")),
            Err(panic) => failures.push(format!(
                "seed {seed:#x} iteration {iterations}: {name}: {what}: panicked: {panic}"
            )),
        }
    }
    std::panic::set_hook(hook);
    eprintln!(
        "image fuzz: {iterations} corrupted reads in {:.1} s, {} failures",
        start.elapsed().as_secs_f64(),
        failures.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
