//! A masked software occlusion buffer, after Hasselgren, Andersson and
//! Akenine-Möller, "Masked Software Occlusion Culling" (HPG 2016).
//!
//! The screen is cut into 32x8-pixel tiles of eight 8x4-pixel subtiles. Each
//! subtile keeps a 32-bit coverage mask and two depths (section 3 of the paper):
//! a reference layer bounding the pixels whose mask bit is clear and a working
//! layer bounding the pixels whose bit is set.
//!
//! # Depth
//! Depth is NDC `z / w` (wgpu: 0 near, 1 far), affine in screen space after the
//! perspective divide, so a triangle's farthest depth over a subtile is reached
//! at one of the subtile's corners. A larger value is farther.
//!
//! # Why a test never says "occluded" wrongly
//! Let `E(p)` be the depth of pixel `p` in an exact depth buffer of the same
//! occluders (pixel centres, far plane 1 where nothing is drawn). The buffer
//! keeps, for every on-screen pixel, a bound `B(p) >= E(p)`:
//! - Coverage: a pixel enters a triangle's mask only if its centre is inside
//!   all three edges (on an edge: for one of its two directions only, so shared
//!   edges leave no holes), evaluated in `f64` from the screen positions, so a
//!   mask never claims a pixel whose centre the triangle does not cover.
//! - Depth per subtile: the triangle's depth over the subtile is bounded by the
//!   largest of its plane's values at the subtile's four corners (computed in
//!   `f64`, nudged farther by a relative epsilon), capped by its farthest vertex.
//! - Layer merge: a merge of a triangle (mask `C`, depth `t`) into the working
//!   layer (mask `M`, depth `w`) gives `M | C` the depth `max(w, t)`, which bounds
//!   both; the working layer is only discarded (its pixels falling back to the
//!   reference depth) while `w <= reference`, and a triangle at or beyond the
//!   reference depth is ignored, so the invariant `w <= reference` holds. A full
//!   mask moves the working depth into the reference layer.
//! - Pixels outside the screen (padding of the last tiles) count as covered by
//!   every triangle touching their subtile; tests never read them.
//! - Near-plane clipping: triangles are clipped to `z >= 0` in clip space before
//!   the divide, so no vertex behind the eye is projected.
//! - Tests: a rectangle's pixels are rounded outward, and it is visible when its
//!   nearest depth is strictly less than any bound it overlaps. If an exact
//!   buffer shows a pixel, `nearest < E(p) <= B(p)`, so the test says visible.
//!
//! # Rasterization
//! Per subtile row of a triangle, each edge's x-intercepts on the four pixel
//! rows are computed at once, then the masks and depth bounds of eight
//! neighbouring subtiles at once by shifts and one plane evaluation per subtile
//! (the `raster::lanes` module: only rows whose intercept lies within its proven
//! rounding band of a pixel boundary are decided pixel by pixel, so masks are
//! exactly the per-pixel definition above), and merged into them in lanes: the
//! subtiles are stored in groups of eight (64x4 pixels), field by field, and
//! each lane applies the merge rule above. These steps run in AVX2 where the
//! CPU has it (detected at run time) and in portable code otherwise, with
//! bit-identical results. Inside a rayon pool of several threads, large
//! triangle sets are set up and binned to bands of subtile rows in parallel
//! chunks, then drawn in parallel bands, each band taking its triangles in
//! order: the buffer is the same whatever the threads.

mod buffer;
mod clip;
mod raster;
mod test;

pub use buffer::{Error, MaskedBuffer, MergeMode};
pub use raster::{CullMode, RenderWork};
pub use test::Visibility;

/// Subtile width in pixels.
pub const SUBTILE_W: u32 = 8;
/// Subtile height in pixels.
pub const SUBTILE_H: u32 = 4;
