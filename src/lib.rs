//! glint: the host side. CLI glue and the Vulkan compute backend.

pub use glint_cpu as cpu;

pub mod backend;
pub mod build_id;
pub mod cache;
pub mod chart;
pub mod gpu;
pub mod heatmap;
pub mod methods;
pub mod mitsuba;
pub mod stability;
