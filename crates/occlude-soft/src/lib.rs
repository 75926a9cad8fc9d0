//! The software backend: an exact depth rasterizer, parallel over screen tiles,
//! driven by a simulated GPU clock so that results are deterministic.

#![warn(missing_docs)]

pub mod backend;
pub mod clock;
pub mod gpu_model;
pub mod raster;
pub mod sat;
pub mod shading;
pub mod workload;

pub use backend::{DrawReplay, SharedSetup, SoftBackend};
pub use gpu_model::{GpuModel, GpuModelError};
pub use shading::Shading;
