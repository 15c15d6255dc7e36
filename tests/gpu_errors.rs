//! Without a usable Vulkan installation the GPU backend must fail with a
//! clear error, never a panic or a crash.

mod common;

use std::path::Path;
use std::process::Command;

use glint::gpu::{Context, ContextDesc, GpuError, Validation};

#[test]
fn missing_loader_is_a_clear_error() {
    let err = Context::new(&ContextDesc {
        device: None,
        validation: Validation::Off,
        loader: Some(Path::new("/nonexistent/libvulkan.so.1")),
    })
    .err()
    .expect("a context without a loader");
    assert!(matches!(err, GpuError::Loader(_)), "{err:?}");
    let msg = err.to_string();
    assert!(
        msg.contains("Vulkan loader") && msg.contains("--backend cpu"),
        "{msg}"
    );
}

const CHILD: &str = "GLINT_TEST_NO_DRIVER_CHILD";

/// The loader only reads VK_DRIVER_FILES / VK_ICD_FILENAMES at start-up, so
/// the driver-less case runs in a child process: this test binary again,
/// filtered to this test, with the variables pointing at nothing.
#[test]
fn no_driver_is_a_clear_error() {
    if std::env::var_os(CHILD).is_some() {
        let err = Context::new(&ContextDesc {
            device: None,
            validation: common::validation(),
            loader: None,
        })
        .err()
        .expect("a context without drivers");
        assert!(
            matches!(err, GpuError::NoDriver | GpuError::NoDevice),
            "{err:?}"
        );
        println!("child error: {err}");
        return;
    }
    let out = Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "no_driver_is_a_clear_error",
            "--nocapture",
            "--test-threads=1",
        ])
        .env(CHILD, "1")
        .env("VK_DRIVER_FILES", "/nonexistent/icd.json")
        .env("VK_ICD_FILENAMES", "/nonexistent/icd.json")
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "child failed:\n{stdout}\n{stderr}");
    assert!(
        stdout.contains("child error: no Vulkan driver")
            || stdout.contains("child error: no Vulkan device"),
        "{stdout}"
    );
}
