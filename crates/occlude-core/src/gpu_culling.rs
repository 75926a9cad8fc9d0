//! The GPU-resident culling interface: visibility that lives on the device
//! and never comes back to the CPU (IOC poster, sections 1-2; nvpro's
//! `gl_occlusion_culling`, "raster" technique).
//!
//! [`Backend`](crate::Backend) answers one occlusion query at a time to the
//! CPU. Raster occlusion culling instead rasterizes many boxes in one batch
//! with depth writes off and lets each passing fragment set a flag in a
//! device buffer; compute passes turn the flags into lists of ids and into
//! indirect draw arguments, and the GPU draws from those without the CPU
//! seeing a single result. This trait is that pipeline as a handful of
//! device resources and commands:
//!
//! - [`BoxSet`]: boxes uploaded once (instance or node bounds), box `k` in
//!   slot `k`;
//! - [`Flags`]: one `u32` flag per slot, kept across frames (the visibility
//!   buffer);
//! - [`IdList`]: a list of ids with its length, both on the device;
//! - [`RangeTable`]: for each id a range of a static item array (a node's
//!   children, a leaf's instances, all instances of a subtree);
//! - [`Pyramid`]: a depth pyramid over the backend's image (two-phase Hi-Z;
//!   its construction and box test are `depth_pyramid`'s).
//!
//! Commands run in the order they are recorded, interleaved with the
//! backend's draws, on the GPU queue: [`GpuCulling::test_boxes`] (batched box
//! tests against the current depth), [`GpuCulling::expand`] and
//! [`GpuCulling::compact`] (compute passes building lists and flags),
//! [`GpuCulling::build_pyramid`] and [`GpuCulling::test_boxes_pyramid`]
//! (a depth pyramid of the current depth and box tests against it, compute
//! passes too) and [`GpuCulling::draw_list`] (one indirect multi-draw). Only
//! [`GpuCulling::read_count`] brings anything back to a method, and it is
//! counted as a read-back in
//! [`FrameStats::readbacks`](crate::FrameStats::readbacks);
//! [`GpuCulling::read_list`] and [`GpuCulling::read_flags`] are instruments
//! for the viewer and tests, counted the same way.
//!
//! The resources live as long as the backend, or until
//! [`GpuCulling::release_all`]; methods create them in
//! `CullingMethod::prepare` of their first frame, outside the frame's clock,
//! as a renderer uploads its scene once, and rewrite the boxes that moved
//! ([`GpuCulling::update_boxes`]).

use crate::geometry::Aabb;
use thiserror::Error;

/// Boxes on the device; slot `k` holds the `k`-th box given at creation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct BoxSet(pub u32);

/// One `u32` visibility flag per slot on the device (0: hidden, 1: visible).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Flags(pub u32);

/// A list of ids and its length on the device, up to a fixed capacity.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct IdList(pub u32);

/// For each id, a range of a static item array on the device.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct RangeTable(pub u32);

/// A depth pyramid of the backend's image size on the device
/// ([`crate::depth_pyramid`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Pyramid(pub u32);

/// Where [`GpuCulling::expand`] puts the items it gathers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExpandInto {
    /// Replace the list's contents with the items (in no particular order).
    List(IdList),
    /// Set the items' flags (other flags are left as they are).
    Flags(Flags),
}

/// A range of a [`RangeTable`]'s items: `items[first..first + count]`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ItemRange {
    /// First item.
    pub first: u32,
    /// Number of items.
    pub count: u32,
}

/// A range table's contents before upload: id `k`'s items are
/// `items[ranges[k]]` ([`GpuCulling::create_table`]).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TableData {
    /// Per id, its range of `items`.
    pub ranges: Vec<ItemRange>,
    /// The items.
    pub items: Vec<u32>,
}

/// Why a backend cannot run GPU-resident culling: the device lacks a
/// feature, named in the message. Like a missing adapter, a user's matter
/// (the command line maps it to exit code 2).
#[derive(Clone, Debug, Error, PartialEq, Eq)]
#[error("{0}")]
pub struct GpuCullingUnsupported(pub String);

/// The device side of GPU-driven culling (module documentation). Ids out of
/// a resource's range are a caller's bug and may panic.
pub trait GpuCulling {
    /// Uploads `boxes` once. Tests rasterize them grown by
    /// [`QUERY_BOX_PAD`](crate::query_box::QUERY_BOX_PAD), as queries do.
    fn create_boxes(&mut self, boxes: &[Aabb]) -> BoxSet;

    /// Rewrites slots of `boxes`, `(slot, box)` each: the boxes that moved
    /// since they were uploaded (a refit, [`crate::motion`]). One upload of
    /// what changed.
    fn update_boxes(&mut self, boxes: BoxSet, changed: &[(u32, Aabb)]);

    /// Drops every resource created so far: their handles mean nothing
    /// after. A method whose hierarchy was rebuilt (other node ids, other
    /// sizes) makes its resources anew, without leaving the old ones
    /// behind.
    fn release_all(&mut self);

    /// A flag buffer of `len` slots, all 0.
    fn create_flags(&mut self, len: u32) -> Flags;

    /// A list of up to `capacity` ids holding `ids` (at most `capacity`).
    fn create_list(&mut self, capacity: u32, ids: &[u32]) -> IdList;

    /// A table giving id `k` the items `items[ranges[k]]`.
    fn create_table(&mut self, ranges: &[ItemRange], items: &[u32]) -> RangeTable;

    /// Sets every flag of `flags` to 0 (one dispatch).
    fn clear_flags(&mut self, flags: Flags);

    /// Sets flag `k` of `flags` to `set[k]`, those past `set`'s end to 0:
    /// one upload, landing after the work recorded so far.
    fn write_flags(&mut self, flags: Flags, set: &[bool]);

    /// Sets the flags of `dst` to those of `src` (slot for slot, those past
    /// `src`'s end to 0): one copy on the device, counted as a dispatch, as
    /// a clear is.
    fn copy_flags(&mut self, src: Flags, dst: Flags);

    /// Tests the boxes of `boxes` named by `ids` against the current depth
    /// buffer, depth writes off (the boxes' front faces, pulled towards the
    /// eye by [`QUERY_DEPTH_BIAS`](crate::query_box::QUERY_DEPTH_BIAS)), and
    /// sets `flags[id]` to 1 where a fragment passes. A box outside the view
    /// frustum sets nothing; a box touching the camera's near region
    /// ([`Camera::box_touches_near_region`](crate::Camera::box_touches_near_region))
    /// sets its flag without rasterizing. Other flags are left as they are.
    /// A dispatch (frustum and near tests, list of boxes to draw) and one
    /// indirect draw of the boxes.
    fn test_boxes(&mut self, boxes: BoxSet, ids: IdList, flags: Flags);

    /// Whether the backend builds depth pyramids ([`Self::create_pyramid`],
    /// [`Self::build_pyramid`], [`Self::test_boxes_pyramid`]); the error
    /// names what it lacks. Those three are only called where this is `Ok`
    /// (the runner asks before the first frame).
    fn pyramid_support(&mut self) -> Result<(), GpuCullingUnsupported>;

    /// A depth pyramid over the backend's image, every texel at the far
    /// plane.
    fn create_pyramid(&mut self) -> Pyramid;

    /// Rebuilds `pyramid` from the depth buffer as everything recorded so
    /// far leaves it (one dispatch per level past level 0, which is the
    /// depth image itself).
    fn build_pyramid(&mut self, pyramid: Pyramid);

    /// [`Self::test_boxes`] against `pyramid` instead of the depth buffer:
    /// the same frustum and near-region rules, then each remaining box's
    /// footprint tested against the pyramid, reading at most `reach` x
    /// `reach` texels
    /// ([`DepthPyramid::test`](crate::depth_pyramid::DepthPyramid::test)),
    /// setting `flags[id]` to 1 where it may be visible. Never hides a box
    /// that [`Self::test_boxes`] against the depth the pyramid was built
    /// from would find visible. One dispatch, no draw.
    fn test_boxes_pyramid(&mut self, boxes: BoxSet, ids: IdList, pyramid: Pyramid, reach: u32, flags: Flags);

    /// For each id of `src` whose flag in `filter` is set, the items of its
    /// range in `table`, into `into` (one dispatch).
    fn expand(&mut self, src: IdList, filter: Flags, table: RangeTable, into: ExpandInto);

    /// Clears the set flags of `flags` whose box in `boxes` (slot for slot)
    /// lies outside the view frustum, by the same test as [`test_boxes`]
    /// (one dispatch over every slot). What `ioc` draws below its bottom
    /// level is so frustum-culled without a box test.
    ///
    /// [`test_boxes`]: GpuCulling::test_boxes
    fn drop_outside_frustum(&mut self, boxes: BoxSet, flags: Flags);

    /// Replaces `dst` with the slots of `flags` that are set, except those
    /// also set in `unless`, in no particular order (one dispatch).
    fn compact(&mut self, flags: Flags, unless: Option<Flags>, dst: IdList);

    /// Draws the instances of `list` (one indirect multi-draw; each
    /// instance is a draw call in the frame statistics).
    fn draw_list(&mut self, list: IdList);

    /// The length of `list` after everything recorded so far, read back to
    /// the CPU: the frame waits for the GPU (wait time) and counts a
    /// read-back.
    fn read_count(&mut self, list: IdList) -> u32;

    /// The ids of `list` after everything recorded so far, read back. An
    /// instrument (the viewer's box view, tests), not a culling step: it
    /// waits and counts a read-back as [`read_count`] does.
    ///
    /// [`read_count`]: GpuCulling::read_count
    fn read_list(&mut self, list: IdList) -> Vec<u32>;

    /// The flags of `flags` after everything recorded so far, read back
    /// (`true`: set). An instrument, like [`read_list`].
    ///
    /// [`read_list`]: GpuCulling::read_list
    fn read_flags(&mut self, flags: Flags) -> Vec<bool>;
}
