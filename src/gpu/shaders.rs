//! The SPIR-V of every `shaders/**/*.comp`, compiled by build.rs.
//!
//! A kernel's name is its path under `shaders/` without `.comp`:
//! `"pathtrace"`, `"tests/smoke"`, `"tests/bsdf_test"`.

include!(concat!(env!("OUT_DIR"), "/shaders.rs"));

/// The SPIR-V words of kernel `name`, or `None` when no such kernel exists.
pub fn spirv(name: &str) -> Option<&'static [u32]> {
    KERNELS
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, bytes)| bytemuck::cast_slice(&bytes.0))
}

/// Names of all compiled kernels, sorted.
pub fn names() -> impl Iterator<Item = &'static str> {
    KERNELS.iter().map(|(n, _)| *n)
}
