//! The wgpu visibility backend of `occlude`: scenes drawn on a real GPU
//! (Vulkan, Metal, DX12 or GL through wgpu), hardware occlusion queries over
//! box proxies, and their results read back with `map_async` without
//! blocking the traversal (CHC paper, section 3: the latency between issuing a
//! query and its result is what the methods hide).
//!
//! [`GpuContext`] opens the adapter once; [`GpuScene`] uploads a scene and
//! builds the pipelines once per run; each method gets its own
//! [`WgpuBackend`] (its own render target and queries) over that shared scene.
//! The backend also runs GPU-resident culling ([`occlude_core::GpuCulling`]:
//! batched box tests, compute passes over id lists, indirect multi-draws)
//! where the device has what it needs.
//! [`DepthRaster`] is bare depth rasterization of clip-space triangles, for
//! comparing the GPU with the soft rasterizer on the same triangles.
//! [`GpuSat`] is granular visibility queries' summed-area-table counts.
//! [`embed`] runs the query-driven methods inside a renderer's own passes,
//! on its device and depth buffer, with its draws.

#![warn(missing_docs)]

mod backend;
mod context;
mod culling;
mod depth_raster;
pub mod embed;
mod item_buffer;
mod pipelines;
mod queries;
mod query_book;
mod query_boxes;
mod readback;
mod sat;
mod scene_buffers;
mod target;

pub use backend::WgpuBackend;
pub use context::{best_adapter, GpuContext, GpuError, REQUIRED_DOWNLEVEL};
pub use depth_raster::DepthRaster;
pub use sat::{GpuSat, GpuSatFrame};
pub use scene_buffers::{GpuScene, COLOR_FORMAT};
