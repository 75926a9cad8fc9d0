//! Occlusion culling for renderers: the culling methods of the literature
//! (CHC, CHC++, occupancy maps with multiple queries, raster occlusion culling
//! level by level, two-phase Hi-Z, masked software occlusion) written once
//! against one [`Backend`] interface, which a renderer implements with its
//! draws and occlusion queries.
//!
//! This crate is the one to add (`cargo add occlude`): it re-exports
//! `occlude-core` (scene, hierarchy, camera, methods, the frame protocol) at
//! its root and the rest behind features. The `occlude` command (benchmarks,
//! reports, the viewer) is the separate crate `occlude-cli`.
//!
//! | feature | default | gives |
//! |---|---|---|
//! | `soft` | yes | `occlude::soft`: a deterministic software GPU with a simulated clock |
//! | `wgpu` | yes | `occlude::wgpu`: the wgpu backend (Vulkan, Metal, DX12) |
//! | `scenes` | no | `occlude::scenes`: generated test scenes, glTF and OBJ importers |
//! | `mock` | no | `occlude::mock`: a backend without pixels, answering queries as scripted, for tests |
//!
//! [`moc`] (the masked software occlusion buffer) and [`glam`] (the math types
//! of the interface) are always there. With `default-features = false` the
//! crate builds on the core alone.
//!
//! # Quick start
//!
//! A wall and, behind it, a row of boxes, seen through your own view and
//! projection matrices; CHC++ culls what the wall hides, here on the
//! software GPU (a [`Backend`] of your renderer takes its place).
//!
//! ```
//! # #[cfg(feature = "soft")]
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! use occlude::glam::{Mat4, Vec3};
//! use occlude::hierarchy::BuildOptions;
//! use occlude::methods::{check_support, chcpp::ChcppParams, Method};
//! use occlude::soft::{GpuModel, SoftBackend};
//! use occlude::{render_frame, Aabb, Camera, DrawnSet, Hierarchy, HierarchyKind, Mesh, Scene};
//!
//! // A unit cube mesh: 8 corners, 12 triangles.
//! let mut scene = Scene::new("wall");
//! let corners = Aabb::new(Vec3::ZERO, Vec3::ONE).corners().to_vec();
//! let faces = [0, 1, 3, 0, 3, 2, 4, 6, 7, 4, 7, 5, 0, 4, 5, 0, 5, 1, 2, 3, 7, 2, 7, 6, 0, 2, 6, 0, 6, 4, 1, 5, 7, 1, 7, 3];
//! let cube = scene.add_mesh(Mesh::new(corners, faces.to_vec()));
//! // The wall: the cube stretched across the view, near the camera.
//! let wall = Mat4::from_translation(Vec3::new(-20.0, -20.0, 0.0)) * Mat4::from_scale(Vec3::new(40.0, 40.0, 1.0));
//! scene.add_instance(cube, wall, 0);
//! // Eight boxes behind it.
//! for i in 0..8 {
//!     scene.add_instance(cube, Mat4::from_translation(Vec3::new(i as f32 * 2.0 - 8.0, 0.0, -10.0)), 0);
//! }
//! let hierarchy = Hierarchy::build(&scene, HierarchyKind::Bvh, BuildOptions { leaf_size: 1, ..Default::default() });
//!
//! let view = Mat4::look_at_rh(Vec3::new(0.0, 0.5, 10.0), Vec3::new(0.0, 0.5, 0.0), Vec3::Y);
//! let projection = Mat4::perspective_rh(1.0, 1.0, 0.1, 100.0);
//! let camera = Camera::from_matrices(view, projection, false)?;
//!
//! let mut backend = SoftBackend::new(&scene, 64, 64, GpuModel::modern());
//! // The paper's CHC++ with a batch of 25; `"chcpp".parse()` gives the defaults.
//! let mut method = Method::Chcpp(ChcppParams { batch: 25, ..Default::default() }).build()?;
//! check_support(method.as_ref(), &mut backend)?;
//! let mut drawn = DrawnSet::default();
//! for _ in 0..4 {
//!     let stats = render_frame(method.as_mut(), &mut backend, &scene, &hierarchy, &camera, &mut drawn);
//!     // Only the wall is drawn: every box behind it is culled.
//!     assert_eq!(stats.visible_objects, 1);
//! }
//! # Ok(())
//! # }
//! # #[cfg(not(feature = "soft"))]
//! # fn main() {}
//! ```
//!
//! A wgpu renderer need not write a [`Backend`]: `occlude::wgpu::embed`
//! (feature `wgpu`) runs the query-driven methods inside its own render
//! passes, on its device and depth buffer, with its draws; the repository's
//! `examples/own-renderer` shows it.
//!
//! `docs/architecture.md` in the repository explains the layers; each method's
//! module ([`methods`]) cites its paper and states its costs and limits.

#![warn(missing_docs)]

pub use glam;
// The core's modules a user meets, and its main types at the root. Its
// tool support (`recording`, `rng`, `host_culling`, `input_file`) stays in
// `occlude-core`; its test backend comes with feature `mock`.
#[cfg(feature = "mock")]
pub use occlude_core::mock;
pub use occlude_core::{
    backend, camera, cost_model, depth_pyramid, frame, geometry, gpu_culling, gvq, hierarchy, item_buffer, methods,
    motion, path, query_box, scene, stats,
};
pub use occlude_core::{
    differing_pixels, render_frame, Aabb, Backend, Camera, CameraError, CostModel, CullingMethod, DrawnSet,
    FrameContext, FrameStats, GpuCulling, GpuCullingUnsupported, Hierarchy, HierarchyKind, Instance, InstanceChange,
    Instruments, Keyframe, Mesh, MotionError, NodeId, QueryHandle, Scene, SceneError, UpdatePolicy, Upkeep,
};
pub use occlude_moc as moc;
#[cfg(feature = "scenes")]
pub use occlude_scenes as scenes;
#[cfg(feature = "soft")]
pub use occlude_soft as soft;
#[cfg(feature = "wgpu")]
pub use occlude_wgpu as wgpu;
