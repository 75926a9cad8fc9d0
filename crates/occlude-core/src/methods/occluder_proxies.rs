//! `moc.proxies`: each mesh's [inner boxes](crate::inner_box), computed once
//! per mesh when first needed (scene preparation, not charged to the frame),
//! and the check of whether an instance may be rendered into `moc`'s buffer
//! as those boxes this frame. A box too thin for its distance is left out.
//!
//! # Why a proxy never hides a visible object
//!
//! An instance `X` is rendered as an inner box `Q` of its mesh's closed part
//! `P` only when (checked each frame by [`needed_clearance`]):
//! the instance and view transforms are affine; the projection's clip `z`
//! and `w` do not depend on view `x` and `y` (perspective and orthographic
//! projections); `X`'s world box is clear of the camera's near region, with
//! every corner in front of the near plane (clip `z >= 1e-4 w`) and within
//! 7900 pixels of the screen; and
//! `Q`'s clearance `m` (mesh space: every triangle of `P` is at least `m`
//! from `Q`), carried into view space as `m' = m / |M^-1|_F` (`M` the linear
//! part of the mesh-to-view map; `1 / |M^-1|_F` is at most its smallest
//! singular value, so no distance shrinks below that factor), exceeds `2 s`,
//! where `s` is how far a point at the box's largest clip `w` moves in view
//! space when its projection moves by 1/256 pixel on each axis at fixed depth
//! (`s = w |L^-1|_F |(2/256W, 2/256H)|`, `L` the projection's upper-left 2x2).
//! Then `Q` covers only pixels where `X` itself is drawn no farther than `Q`
//! (below, `X` stands for the part `P` of it, whose triangles are `X`'s):
//!
//! - Snapping is a small motion. The buffer and the rasterizer draw the
//!   triangles of `X` and of `Q` from snapped screen vertices, each within
//!   1/512 pixel of its exact projection on each axis, plus the `f32` rounding
//!   of clip coordinates (about `1e-4` pixel): within 1/256. Depth is not
//!   snapped, and depth fixes clip `w`, so a vertex moved on screen at fixed
//!   depth is a vertex moved in view space at fixed depth, by at most `s` (clip
//!   `w` is affine, so no vertex of `X` lies deeper than the box's farthest
//!   corner). Projection keeps triangles triangles in front of the eye, so
//!   what is drawn is an exact picture of a moved mesh `X'` and a moved box
//!   `Q'`, every point of each within `s` of where it was (a point of a
//!   triangle is a convex combination of its corners). No triangle of either
//!   is clipped (in front of the near plane, inside the guard band) or drawn
//!   unsnapped by the buffer, so the buffer's coverage of `Q'` is the
//!   rasterizer's.
//! - Still inside. Along the straight motion of the vertices from `X`, `Q` to
//!   `X'`, `Q'`, the box stays more than `m' - 2s > 0` from the surface, so it
//!   never crosses it and stays inside by parity, as `Q` is inside `X`
//!   ([`crate::inner_box`]). `X'` is closed as `X` is: welded vertices have
//!   equal positions, so they project and snap alike.
//! - An odd number of crossings. In screen space (pixel `x`, `y`, depth) take a
//!   pixel centre `c` that the buffer covers with `Q'`, and the point `q` of
//!   `Q'` over `c`. Every vertex of `X'` has depth `>= 0`, so the point over `c`
//!   at depth `-1` is outside `X'`, and the segment from it to `q` crosses `X'`
//!   an odd number of times: at least one triangle of `X'` covers `c` at a depth
//!   at most `q`'s. (The top-left rule decides a centre on a shared edge for
//!   exactly one of its triangles, as if the centre were moved off the edge
//!   by an infinitesimal step, for `X'` and `Q'` alike, so the count holds
//!   there too.) Objects are drawn two-sided, so that triangle is in `X`'s
//!   image: `E(c) <= depth of Q' at c <=` the buffer's bound (`moc`'s module doc,
//!   "Depth precision"). An object visible at `c` is in front of `X` there,
//!   so in front of the bound, and is tested visible. The `f32` rounding of
//!   depth, which snapping does not move, is the rounding the tests allow
//!   for above.
//! - Where an instance's condition fails, it is rendered in full, as without
//!   proxies; a box whose clearance falls short is left out. These conditions cost a few matrix products per occluder and
//!   are not charged on the simulated clock.
//!

use crate::camera::Camera;
use crate::inner_box::{inner_boxes, InnerBox};
use crate::query_box::BOX_TRIANGLES;
use crate::scene::{Instance, Scene};
use glam::{Mat2, Mat3, Mat4, Vec3, Vec4};
use std::cell::OnceCell;

/// How far (pixels, on each axis) a rasterizer's vertex may lie from the
/// exact projection of its position: half a step of the 1/256-pixel grid
/// (1/512) for snapping, the rest for the `f32` rounding of clip
/// coordinates (about `1e-4` pixel).
const VERTEX_SHIFT_PIXELS: f32 = 1.0 / 256.0;

/// Pixels beyond the screen within which an instance's box must project:
/// inside the range the buffer snaps (8000) and the soft backend's guard
/// band (8192), so that neither clips the mesh or its box at the sides.
const SIDE_RANGE_PIXELS: f32 = 7900.0;

/// Smallest clip `z` of the instance's box corners, as a fraction of their
/// `w`: the box lies in front of the near plane (`z = 0`) with room for the
/// rounding of the corners' clip coordinates.
const NEAR_ROOM: f32 = 1e-4;

/// The 12 triangles of a box as indices into
/// [`Aabb::corners`](crate::geometry::Aabb::corners).
const BOX_INDICES: [u32; 36] = {
    let mut out = [0u32; 36];
    let mut i = 0;
    while i < 36 {
        out[i] = BOX_TRIANGLES[i / 3][i % 3] as u32;
        i += 1;
    }
    out
};

/// The inner boxes of a scene's meshes, each mesh's computed on first use,
/// and the triangles of this frame's proxy.
#[derive(Debug, Default)]
pub(super) struct OccluderProxies {
    boxes: Vec<OnceCell<Vec<InnerBox>>>,
    /// Corners (mesh space) of the boxes that apply to the last instance
    /// asked about, 8 per box.
    corners: Vec<Vec3>,
    /// Indices into `corners`.
    indices: Vec<u32>,
}

impl OccluderProxies {
    /// Makes room for `scene`'s meshes, forgetting the boxes when the mesh
    /// count changed. A method serves one scene (as `chc`'s per-node state
    /// does, the boxes belong to it); a new mesh count means a new scene.
    pub(super) fn prepare(&mut self, scene: &Scene) {
        if self.boxes.len() != scene.meshes.len() {
            self.boxes = (0..scene.meshes.len()).map(|_| OnceCell::new()).collect();
        }
    }

    /// How many meshes have been given at least one inner box so far.
    pub(super) fn meshes_with_box(&self) -> usize {
        self.boxes.iter().filter(|b| b.get().is_some_and(|b| !b.is_empty())).count()
    }

    /// The triangles (corner positions in mesh space and indices) to render
    /// for `instance` in place of its mesh this frame, or `None` to render
    /// the mesh: `None` when the mesh has no inner box or
    /// [`needed_clearance`] finds the instance unfit; else the boxes whose
    /// clearance is more than it needs, none at all when every box is too
    /// thin for its distance (a box that small on screen would hide next to
    /// nothing).
    pub(super) fn proxy(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        instance: &Instance,
        size: (u32, u32),
    ) -> Option<(&[Vec3], &[u32])> {
        let cell = self.boxes.get(instance.mesh as usize)?;
        let boxes = cell.get_or_init(|| inner_boxes(&scene.meshes[instance.mesh as usize]));
        if boxes.is_empty() {
            return None;
        }
        let needed = needed_clearance(camera, instance, size)?;
        self.corners.clear();
        self.indices.clear();
        for inner in boxes.iter().filter(|b| b.clearance > needed) {
            let base = self.corners.len() as u32;
            self.corners.extend_from_slice(&inner.bounds.corners());
            self.indices.extend(BOX_INDICES.iter().map(|i| base + i));
        }
        Some((&self.corners[..], &self.indices[..]))
    }
}

/// The clearance (mesh space) an inner box of `instance` needs to be
/// rendered in place of its mesh through `camera` on a `width` x `height`
/// screen, or `None` when no box may be: the instance and view transforms
/// must be affine, the projection's clip `z` and `w` independent of view `x`
/// and `y`, and the instance's world box clear of the near region, in front
/// of the near plane and within [`SIDE_RANGE_PIXELS`] of the screen. The
/// clearance, carried into view space, must be more than twice the farthest
/// a vertex of the mesh or of the box can move when its projection moves by
/// [`VERTEX_SHIFT_PIXELS`] on each axis at the box's farthest depth.
pub(super) fn needed_clearance(camera: &Camera, instance: &Instance, (width, height): (u32, u32)) -> Option<f32> {
    let (view, projection) = (camera.view(), camera.projection());
    let affine = |m: &Mat4| m.row(3) == Vec4::W;
    // Clip x and y at a fixed depth must be linear in view x and y.
    let lateral = projection.x_axis.z == 0.0
        && projection.y_axis.z == 0.0
        && projection.x_axis.w == 0.0
        && projection.y_axis.w == 0.0;
    if !affine(&view) || !affine(&instance.transform) || !lateral || camera.box_touches_near_region(&instance.bounds) {
        return None;
    }
    let view_projection = camera.view_projection();
    let side_x = 1.0 + 2.0 * SIDE_RANGE_PIXELS / width.max(1) as f32;
    let side_y = 1.0 + 2.0 * SIDE_RANGE_PIXELS / height.max(1) as f32;
    let mut farthest_w = 0.0f32;
    for corner in instance.bounds.corners() {
        let c = view_projection * corner.extend(1.0);
        let inside = c.w > 0.0 && c.z >= NEAR_ROOM * c.w && c.x.abs() <= side_x * c.w && c.y.abs() <= side_y * c.w;
        if !inside {
            return None;
        }
        farthest_w = farthest_w.max(c.w);
    }
    // A shift of (dx, dy) in NDC at a fixed depth is a shift of
    // w L^-1 (dx, dy) in view x and y, L the projection's upper-left 2x2.
    let l = Mat2::from_cols(projection.x_axis.truncate().truncate(), projection.y_axis.truncate().truncate());
    let ndc_shift =
        (2.0 * VERTEX_SHIFT_PIXELS / width.max(1) as f32).hypot(2.0 * VERTEX_SHIFT_PIXELS / height.max(1) as f32);
    let view_shift = farthest_w * frobenius2(l.inverse()) * ndc_shift;
    // Distances shrink by at most the smallest singular value of the
    // mesh-to-view map, which is at least 1 / |M^-1|_F.
    let mesh_to_view = Mat3::from_mat4(view) * Mat3::from_mat4(instance.transform);
    let needed = 2.0 * view_shift * frobenius3(mesh_to_view.inverse());
    needed.is_finite().then_some(needed)
}

/// Frobenius norm of a 2x2 matrix.
fn frobenius2(m: Mat2) -> f32 {
    (m.x_axis.length_squared() + m.y_axis.length_squared()).sqrt()
}

/// Frobenius norm of a 3x3 matrix.
fn frobenius3(m: Mat3) -> f32 {
    (m.x_axis.length_squared() + m.y_axis.length_squared() + m.z_axis.length_squared()).sqrt()
}
