//! Shared support for the root package's GPU tests.
//!
//! `context()` creates a context under the Khronos validation layer whenever
//! it is installed; `ValidatedContext` derefs to the context and, when
//! dropped, destroys it and then asserts that the layer reported no error
//! and no warning, including leaks reported at vkDestroyDevice.

#![allow(dead_code)]

use std::ops::Deref;
use std::sync::Arc;

use glint::gpu::{Context, ContextDesc, Validation, ValidationLog};

pub struct ValidatedContext {
    ctx: Option<Context>,
    log: Option<Arc<ValidationLog>>,
}

impl Deref for ValidatedContext {
    type Target = Context;
    fn deref(&self) -> &Context {
        self.ctx.as_ref().expect("context is alive until drop")
    }
}

impl ValidatedContext {
    /// Destroy the context now and return the validation messages (empty
    /// when the layer is not installed).
    pub fn finish(mut self) -> Vec<String> {
        self.ctx.take();
        self.log.take().map(|l| l.messages()).unwrap_or_default()
    }

    pub fn validated(&self) -> bool {
        self.log.is_some()
    }
}

impl Drop for ValidatedContext {
    fn drop(&mut self) {
        self.ctx.take();
        if let Some(log) = self.log.take()
            && !std::thread::panicking()
        {
            let messages = log.messages();
            assert!(
                messages.is_empty(),
                "validation layer reported {} error(s), {} warning(s):\n{}",
                log.errors(),
                log.warnings(),
                messages.join("\n")
            );
        }
    }
}

/// Validation for tests: required under scripts/test.sh (which sets
/// GLINT_VALIDATION and installs the layer), else used when installed.
pub fn validation() -> Validation {
    match Validation::from_env() {
        Validation::Off => Validation::IfAvailable,
        _ => Validation::Required,
    }
}

/// A context on the default device, validated when the layer is installed
/// (always under scripts/test.sh).
pub fn context() -> ValidatedContext {
    context_with(false)
}

/// [`context`] with uploads and readbacks forced through staging buffers
/// (the path of GPUs whose device-local memory is not host-visible).
pub fn staging_context() -> ValidatedContext {
    context_with(true)
}

fn context_with(force_staging: bool) -> ValidatedContext {
    let mut ctx = Context::new(&ContextDesc {
        device: None,
        validation: validation(),
        loader: None,
    })
    .unwrap_or_else(|e| panic!("cannot create a Vulkan context: {e}"));
    ctx.set_force_staging(force_staging);
    let log = ctx.validation_log();
    ValidatedContext {
        ctx: Some(ctx),
        log,
    }
}
