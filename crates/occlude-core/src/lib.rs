//! Core of `occlude`: geometry, the scene model, spatial hierarchies, the
//! visibility-backend interface and the culling methods written once against it.
//!
//! Data flows top to bottom (see `docs/architecture.md`):
//! scene -> hierarchy -> culling method -> backend -> frame statistics.

#![warn(missing_docs)]

pub mod backend;
pub mod camera;
pub mod depth_pyramid;
pub mod geometry;
pub mod gpu_culling;
pub mod gvq;
pub mod hierarchy;
pub mod methods;
pub mod path;
pub mod query_box;
pub mod rng;
pub mod scene;
pub mod stats;

pub use backend::{Backend, CpuCullingWork, FrameCounter, OracleView, QueryHandle, RenderState, StateTracker};
pub use camera::{Camera, Frustum, Visibility};
pub use geometry::Aabb;
pub use gpu_culling::{
    BoxSet, ExpandInto, Flags, GpuCulling, GpuCullingUnsupported, IdList, ItemRange, Pyramid, RangeTable,
};
pub use hierarchy::{Hierarchy, HierarchyKind, NodeId};
pub use methods::{CullingMethod, FrameContext};

pub use path::{CameraPath, Keyframe, Sampling};
pub use scene::{Instance, Mesh, Scene, SceneError};
pub use stats::FrameStats;
