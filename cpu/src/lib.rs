//! glint-cpu: the CPU reference renderer.
//!
//! Everything the GPU backend must match lives here: the scene model and its
//! GPU-shared layouts, the glTF loader, the BVH, the BSDFs and the path tracer.
//! No Vulkan.

pub mod abi;
pub mod adaptive;
pub mod bsdf;
pub mod bvh;
pub mod camera;
pub mod compare;
pub mod envmap;
pub mod exr_file;
pub mod features;
pub mod film;
pub mod frame;
pub mod integrator;
pub mod lanes;
pub mod lights;
pub mod loader;
pub mod metrics;
pub mod prepare;
pub mod quadrature;
pub mod safe_fs;
pub mod sampling;
pub mod scene;
pub mod schedule;
pub mod sobol;
pub mod spherical;
pub mod texture;

pub use bsdf::{Bsdf, BsdfSample};
pub use bvh::{Bvh, Bvh4, Bvh4Node, BvhNode, Hit, Ray};
pub use film::{Film, LightSampling, Mis, OutputFormat, RenderOptions, RenderStats, SamplerKind};
pub use frame::Frame;
pub use integrator::{PathTracer, RenderError, render};
pub use scene::{
    Camera, GpuMaterial, Material, NO_LIGHT, PunctualLight, Scene, TRI_DOUBLE_SIDED, TRI_NORMALS,
    TRI_SHADING_SHIFT, TRI_TANGENTS, Triangle, TriangleShading,
};
