//! Core of `occlude`: geometry, the scene model, spatial hierarchies, the
//! visibility-backend interface and the culling methods written once against it.
//!
//! Data flows top to bottom (see `docs/architecture.md`):
//! scene -> hierarchy -> culling method -> backend -> frame statistics.
//!
//! # Quick start
//!
//! A method decides what to draw; a [`Backend`] draws and answers
//! occlusion queries. Implement [`Backend`] for your renderer (frames,
//! draws, queries and the image size are required; everything else has a
//! default), or try a method on `mock::MockBackend` (feature `mock`, a
//! backend without pixels that answers queries as scripted) as below: three
//! boxes in a row, the middle one scripted hidden, culled by CHC++ seen
//! through a reverse-Z camera.
//!
//! ```
//! use glam::{Mat4, Vec3};
//! use occlude_core::hierarchy::BuildOptions;
//! use occlude_core::methods::{check_support, chcpp::ChcppParams, Method};
//! use occlude_core::mock::MockBackend;
//! use occlude_core::{render_frame, Aabb, Camera, DrawnSet, Hierarchy, HierarchyKind, Mesh, Scene};
//!
//! // The scene: one mesh placed three times, a hierarchy over the placements.
//! let mut scene = Scene::new("row");
//! let corners = Aabb::new(Vec3::splat(-0.5), Vec3::splat(0.5)).corners().to_vec();
//! let mesh = scene.add_mesh(Mesh::new(corners, vec![0, 1, 3, 0, 3, 2]));
//! for x in [-2.0, 0.0, 2.0] {
//!     scene.add_instance(mesh, Mat4::from_translation(Vec3::new(x, 0.0, 0.0)), 0);
//! }
//! let options = BuildOptions { leaf_size: 1, ..Default::default() };
//! let hierarchy = Hierarchy::build(&scene, HierarchyKind::Bvh, options);
//!
//! // The renderer's own matrices.
//! let view = Mat4::look_at_rh(Vec3::new(0.0, 0.0, 8.0), Vec3::ZERO, Vec3::Y);
//! let projection = Mat4::perspective_infinite_reverse_rh(1.0, 1.0, 0.1);
//! let camera = Camera::from_matrices(view, projection, true)?;
//!
//! // A backend (yours, or the mock), and a method it can run.
//! let mut backend = MockBackend::new(&scene, 64, 64);
//! backend.set_visible(1, false);
//! // The paper's CHC++ with a batch of 25; `"chcpp".parse()` gives the defaults.
//! let mut method = Method::Chcpp(ChcppParams { batch: 25, ..Default::default() }).build()?;
//! check_support(method.as_ref(), &mut backend)?;
//!
//! // Frame after frame: the method draws what the queries find visible.
//! let mut drawn = DrawnSet::default();
//! for _ in 0..3 {
//!     let stats = render_frame(method.as_mut(), &mut backend, &scene, &hierarchy, &camera, &mut drawn);
//!     assert_eq!(stats.visible_objects, 2);
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![warn(missing_docs)]

pub mod backend;
pub mod camera;
pub mod cost_model;
pub mod depth_pyramid;
pub mod frame;
pub mod geometry;
pub mod gpu_culling;
pub mod gvq;
pub mod hierarchy;
pub mod host_culling;
pub mod inner_box;
pub mod input_file;
pub mod item_buffer;
pub mod methods;
#[cfg(feature = "mock")]
pub mod mock;
pub mod motion;
pub mod path;
pub mod query_box;
pub mod recording;
pub mod rng;
pub mod scene;
pub mod stats;

pub use backend::{
    Backend, CpuCullingWork, FrameCounter, Instruments, OracleView, QueryHandle, RenderState, StateTracker,
};
pub use camera::{Camera, CameraError, CameraMatrices, Frustum, NearRegion, Visibility};
pub use cost_model::CostModel;
pub use frame::{differing_pixels, render_frame};
pub use geometry::Aabb;
pub use gpu_culling::{
    BoxSet, ExpandInto, Flags, GpuCulling, GpuCullingUnsupported, IdList, ItemRange, Pyramid, RangeTable, TableData,
};
pub use hierarchy::{Hierarchy, HierarchyKind, NodeId, Since, UpdatePolicy, Upkeep};
pub use item_buffer::{ItemBufferError, ItemCounts, ItemLayout, QueryMode, NO_ITEM};
pub use methods::{CullingMethod, DrawnSet, FrameContext};
pub use motion::{InstanceChange, MotionError};

pub use path::{CameraPath, Keyframe, Sampling};
pub use scene::{Instance, Mesh, Scene, SceneError};
pub use stats::FrameStats;
