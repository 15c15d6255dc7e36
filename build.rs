//! Compiles every `shaders/**/*.comp` to SPIR-V with shaderc and generates
//! `$OUT_DIR/shaders.rs`, which `glint::gpu::shaders` includes: one aligned
//! static per kernel, looked up by name (the path under `shaders/` without
//! `.comp`, e.g. `"pathtrace"`, `"tests/bsdf_test"`), plus the
//! [`VARIANTS`]: a kernel compiled again with a macro defined.
//!
//! It first writes the GLSL side of the device ABI (`cpu/src/abi.rs`,
//! compiled into this script too): `$OUT_DIR/glsl/glint_abi.glsl` (every
//! shared struct and constant) and `glint_bindings.glsl` (the path
//! tracer's binding table and push constants).
//!
//! `#include "x.glsl"` resolves relative to the including file first, then
//! relative to `shaders/`, then to the generated folder; `#include <x.glsl>`
//! skips the first.
//! A GLSL error fails the build with shaderc's message, which names the file
//! and line.

use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};

#[path = "cpu/src/abi.rs"]
#[allow(dead_code)]
mod abi;

/// Compile-time variants: (kernel, variant name, macro defined for it).
/// `pathtrace_rq` is pathtrace.comp with ray queries in place of the
/// software BVH traversal (`--traversal hardware`; shaders/ray_query.glsl).
const VARIANTS: &[(&str, &str, &str)] = &[("pathtrace", "pathtrace_rq", "GLINT_RAY_QUERY")];

fn main() {
    let manifest = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets it"));
    let out_dir = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets it"));
    let shader_root = manifest.join("shaders");

    // A directory argument makes cargo scan the whole tree, which also
    // catches new files; the per-file lines keep the intent explicit.
    println!("cargo:rerun-if-changed=shaders");
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=cpu/src/abi.rs");
    let generated_dir = out_dir.join("glsl");
    fs::create_dir_all(&generated_dir).expect("create OUT_DIR/glsl");
    write_if_changed(&generated_dir.join("glint_abi.glsl"), &abi::glsl_types());
    write_if_changed(
        &generated_dir.join("glint_bindings.glsl"),
        &abi::glsl_bindings(),
    );
    let mut files = Vec::new();
    if shader_root.is_dir() {
        walk(&shader_root, &mut files);
    }
    files.sort();
    for f in &files {
        println!("cargo:rerun-if-changed={}", f.display());
    }

    let kernels: Vec<&PathBuf> = files
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "comp"))
        .collect();

    let compiler = shaderc::Compiler::new().expect("shaderc compiler");
    let mut errors = Vec::new();
    let mut table = String::new();
    let spv_dir = out_dir.join("spirv");
    fs::create_dir_all(&spv_dir).expect("create OUT_DIR/spirv");

    let mut jobs = Vec::new();
    for path in &kernels {
        let rel = path.strip_prefix(&shader_root).expect("under shaders/");
        let name = rel
            .with_extension("")
            .components()
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect::<Vec<_>>()
            .join("/");
        for &(base, variant, define) in VARIANTS {
            if name == base {
                jobs.push((variant.to_string(), path, rel, Some(define)));
            }
        }
        jobs.push((name, path, rel, None));
    }

    for (i, (name, path, rel, define)) in jobs.iter().enumerate() {
        let display = format!("shaders/{}", rel.display());
        let source = match fs::read_to_string(path) {
            Ok(s) => s,
            Err(e) => {
                errors.push(format!("{display}: {e}"));
                continue;
            }
        };
        let mut options = shaderc::CompileOptions::new().expect("shaderc options");
        options.set_target_env(
            shaderc::TargetEnv::Vulkan,
            shaderc::EnvVersion::Vulkan1_2 as u32,
        );
        options.set_target_spirv(shaderc::SpirvVersion::V1_5);
        options.set_source_language(shaderc::SourceLanguage::GLSL);
        if let Some(d) = define {
            options.add_macro_definition(d, None);
        }
        options.set_optimization_level(shaderc::OptimizationLevel::Performance);
        let roots = [shader_root.clone(), generated_dir.clone()];
        let manifest_dir = manifest.clone();
        options.set_include_callback(move |requested, kind, requester, _depth| {
            resolve_include(&roots, &manifest_dir, requested, kind, requester)
        });
        match compiler.compile_into_spirv(
            &source,
            shaderc::ShaderKind::Compute,
            &display,
            "main",
            Some(&options),
        ) {
            Ok(artifact) => {
                if artifact.get_num_warnings() > 0 {
                    for line in artifact.get_warning_messages().lines() {
                        println!("cargo:warning={line}");
                    }
                }
                let spv_path = spv_dir.join(format!("k{i}.spv"));
                fs::write(&spv_path, artifact.as_binary_u8()).expect("write SPIR-V");
                writeln!(
                    table,
                    "    ({name:?}, &Aligned(*include_bytes!({:?}))),",
                    spv_path.display().to_string()
                )
                .unwrap();
            }
            Err(e) => errors.push(e.to_string()),
        }
    }

    if !errors.is_empty() {
        // Each shaderc message reads "shaders/file.comp:LINE: error: ...".
        for e in &errors {
            for line in e.lines() {
                println!("cargo:warning={line}");
            }
        }
        eprintln!("GLSL compilation failed:\n{}", errors.join("\n"));
        std::process::exit(1);
    }

    let generated = format!(
        "// Generated by build.rs: the SPIR-V of every shaders/**/*.comp.\n\
         /// Forces 4-byte alignment on the embedded bytes so they can be read as `u32` words.\n\
         #[repr(C, align(4))]\n\
         struct Aligned<B: ?Sized>(B);\n\
         static KERNELS: &[(&str, &Aligned<[u8]>)] = &[\n{table}];\n"
    );
    fs::write(out_dir.join("shaders.rs"), generated).expect("write shaders.rs");
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let p = entry.path();
        if p.is_dir() {
            walk(&p, out);
        } else {
            out.push(p);
        }
    }
}

/// Writes `text` unless the file already holds it (keeps its time stamp).
fn write_if_changed(path: &Path, text: &str) {
    if fs::read_to_string(path).ok().as_deref() != Some(text) {
        fs::write(path, text).expect("write generated GLSL");
    }
}

/// `requester` is the display name of the including file: `shaders/...` for
/// a kernel, or the `resolved_name` we returned for a nested include.
fn resolve_include(
    roots: &[PathBuf],
    manifest: &Path,
    requested: &str,
    kind: shaderc::IncludeType,
    requester: &str,
) -> shaderc::IncludeCallbackResult {
    let mut candidates = Vec::new();
    if kind == shaderc::IncludeType::Relative {
        if let Some(dir) = manifest.join(requester).parent() {
            candidates.push(dir.join(requested));
        }
    }
    candidates.extend(roots.iter().map(|r| r.join(requested)));
    for c in candidates {
        if let Ok(content) = fs::read_to_string(&c) {
            let resolved_name = c
                .strip_prefix(manifest)
                .map(|p| p.display().to_string())
                .unwrap_or_else(|_| c.display().to_string());
            return Ok(shaderc::ResolvedInclude {
                resolved_name,
                content,
            });
        }
    }
    Err(format!(
        "cannot find \"{requested}\" (included from {requester}) relative to it, to shaders/ or to the generated GLSL"
    ))
}
