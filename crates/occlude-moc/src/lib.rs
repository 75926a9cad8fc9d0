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
//! Let `E(p)` be the depth of pixel `p` in the depth buffer that a rasterizer
//! with [`SUBPIXEL_BITS`] sub-pixel bits and the top-left fill rule draws of
//! the same occluders, from the same clip-space vertices (the soft backend of
//! `occlude`; far plane 1 where nothing is drawn). The buffer keeps, for every
//! on-screen pixel, a bound `B(p) >= E(p)` (up to the rasterizer's own `f32`
//! rounding of depth, which the tests' relative `1e-6` covers):
//! - Coverage: a triangle's mask holds exactly the pixels the rasterizer covers
//!   with it, whatever the scene. Its vertices are projected as the rasterizer
//!   projects them (`f64` divide of the `f32` clip coordinates) and snapped to
//!   the same grid, the nearest multiple of `1 / 2^bits` pixel (halves away from
//!   zero); a pixel is covered when its centre passes the three edge functions
//!   of the snapped vertices, with the top-left rule on an edge (exactly one of
//!   two triangles sharing an edge takes a centre on it). With coordinates
//!   below `2^15` pixels and at most [`MAX_SUBPIXEL_BITS`] bits every such edge
//!   function needs at most 49 significant bits, so `f64` evaluates it exactly:
//!   the buffer's test is the rasterizer's, decided identically. This holds for
//!   triangles in front of the near plane with their vertices within 8000
//!   pixels of the screen (inside the soft backend's guard band, so that it
//!   does not clip them either). Any other triangle (crossing the near plane,
//!   or reaching farther out) is drawn unsnapped with its edges moved inward by
//!   1/32 pixel, more than a rasterizer's own clipping and snapping move its
//!   edges on screen, so its mask lies within the rasterizer's coverage of its
//!   clipped polygon; it is rare (geometry at the camera) and its few cracks
//!   cost little culling.
//! - What a GPU must share for this: its vertices on the same grid points. A
//!   GPU computes clip coordinates and the projection in its own `f32`
//!   arithmetic, a few units in the last place (about `1e-4` pixel) from the
//!   buffer's; where that straddles a rounding tie of the grid, it snaps the
//!   vertex to the neighbouring point, and pixel centres within 1/256 pixel of
//!   that vertex's outer edges can then differ. The depth bounds below allow
//!   for such a step; coverage there is the one thing this argument assumes of
//!   a GPU rather than proves.
//! - Depth per subtile: the depth plane is the one through the snapped
//!   vertices, raised by `(|dz/dx| + |dz/dy|) s` for a vertex displacement `s`
//!   of one grid step (1/32 pixel unsnapped). A rasterizer whose vertices lie
//!   within `s` of the buffer's interpolates, at a pixel `p` inside its
//!   triangle, the buffer's plane at the point whose barycentric weights in the
//!   buffer's triangle are `p`'s in its own (a convex combination of the vertex
//!   displacements away from `p`, so within `s` in x and in y): at most the
//!   raised plane at `p`. Over a subtile that is bounded by the raised plane's
//!   largest value at the subtile's four corners, capped by the farthest vertex
//!   (the depth is a convex combination of the vertices'). The buffer takes
//!   that bound for every subtile of a triangle's subtile row from one anchor,
//!   the first subtile of the triangle's window: the plane at the anchor's
//!   corner in `f64`, nudged farther by `2^-22` of itself (more than its
//!   rounding to the nearest `f32` can take back), plus, for the subtile `m`
//!   places to the right, `m` steps of an `f32` step never less than the
//!   plane's rise `8 dz/dx` from one corner to the next, with as many low
//!   significand bits zero as make `m` steps exact for every `m` on the
//!   screen (8 on a 1920-pixel-wide screen); that sum is rounded to `f32` and
//!   nudged farther by `2^-22` of itself, more than the sum's rounding took,
//!   and capped by the farthest vertex, itself rounded far.
//! - Layer merge: a merge of a triangle (mask `C`, depth `t`) into the working
//!   layer (mask `M`, depth `w`) gives `M | C` the depth `max(w, t)`, which bounds
//!   both; the working layer is only discarded (its pixels falling back to the
//!   reference depth) while `w <= reference`, and a triangle at or beyond the
//!   reference depth is ignored, so the invariant `w <= reference` holds. A full
//!   mask moves the working depth into the reference layer.
//! - Pixels outside the screen (padding of the last tiles) count as covered by
//!   every triangle touching their subtile; tests never read them.
//! - Near-plane clipping: triangles are clipped to `z >= 0` in clip space before
//!   the divide, so no vertex behind the eye is projected; a clipped polygon
//!   with a vertex at `w <= 0` or beyond `10^9` pixels is not drawn (an
//!   occluder left out only makes the buffer cull less).
//! - Tests: a rectangle's pixels are rounded outward, and it is visible when its
//!   nearest depth is strictly less than any bound it overlaps. If an exact
//!   buffer shows a pixel, `nearest < E(p) <= B(p)`, so the test says visible.
//!
//! # Rasterization
//! In MOC's 32x8-pixel tiles: per tile row of a triangle (two subtile rows),
//! each edge's x-intercepts on the eight pixel rows are computed at once in
//! `f32` lanes (from the intercept of the triangle's first tile row, evaluated
//! in `f64`, with a band widened by the `f32` rounding, proven), then per tile
//! in reach (every tile of a window at most two tiles wide) the masks and
//! depth bounds of its eight subtiles at once by shifts and exact steps from
//! the window's first tile (the plane there evaluated in `f64` once per tile
//! row, then the steps in `f32`) (the `raster::lanes` module: only rows whose
//! intercept lies within its proven rounding band of a pixel boundary are
//! decided pixel by pixel, so masks are exactly the per-pixel definition
//! above; pixel rows of a tile row above or below the triangle are left empty
//! by its edges, decided so, and only the padding rows below the screen by a
//! test of their own), and merged into them in lanes: the subtiles are stored
//! tile by tile (a tile's eight, field by field: 96 bytes, loaded and stored
//! as three registers), and each lane applies the merge rule above. These
//! steps run in AVX2 where the CPU has it (detected at run time) and in
//! portable code otherwise, with bit-identical results; with AVX2,
//! four triangles are also set up at once (projection, snapping, edges, depth
//! plane, the `f32` intercepts: the `raster::setup` module), bit for bit as
//! the scalar set-up does each. Inside a rayon pool of several threads, large
//! triangle sets are binned by their vertices' rows to bands of tile rows
//! (four bands a thread) in parallel chunks, keeping only triangle indices;
//! then the bands are set up and drawn in parallel, each taking its
//! triangles in order (a triangle touching two bands is set up in both): the
//! buffer and the work counted are the same whatever the threads.

mod buffer;
mod clip;
mod project;
mod raster;
mod test;

pub use buffer::{Error, MaskedBuffer, MergeMode};
pub use raster::{CullMode, RenderWork};
pub use test::Visibility;

/// Default sub-pixel bits of occluder vertices
/// ([`MaskedBuffer::set_subpixel_bits`]): 8, a 1/256-pixel grid, as the soft
/// backend, lavapipe and Direct3D 11-class hardware snap.
pub const SUBPIXEL_BITS: u32 = 8;
/// Most sub-pixel bits the buffer snaps with: with coordinates below `2^15`
/// pixels its edge functions stay exact in `f64` (the crate doc, "Coverage").
pub const MAX_SUBPIXEL_BITS: u32 = 8;

/// Subtile width in pixels.
pub const SUBTILE_W: u32 = 8;
/// Subtile height in pixels.
pub const SUBTILE_H: u32 = 4;
