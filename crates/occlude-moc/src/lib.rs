//! A masked software occlusion buffer, after Hasselgren, Andersson and
//! Akenine-Möller, "Masked Software Occlusion Culling" (HPG 2016).
//!
//! The screen is cut into 32x8-pixel tiles of eight 8x4-pixel subtiles. Each
//! subtile keeps a 32-bit coverage mask and two depths (section 3 of the
//! paper): a reference layer bounding the pixels whose mask bit is clear and
//! a working layer bounding the pixels whose bit is set.
//!
//! Depth is NDC `z / w` (wgpu: 0 near, 1 far). It is affine in screen space,
//! so a triangle's farthest depth over a subtile lies at one of its corners.
//! A larger value is farther.
//!
//! # The guarantee: a test never says "occluded" wrongly
//! Let `E(p)` be the depth of pixel `p` that a rasterizer with
//! [`SUBPIXEL_BITS`] sub-pixel bits and the top-left fill rule draws of the
//! same occluders, from the same clip-space vertices (occlude's soft
//! backend). The buffer keeps a bound `B(p) >= E(p)` on every on-screen
//! pixel. A test says visible when a box's nearest depth is below a bound it
//! overlaps; if an exact buffer shows a pixel, `nearest < E(p) <= B(p)`. The
//! argument is in parts, each beside its code:
//! - coverage, the masks are the rasterizer's pixels: `project`;
//! - depth, each subtile's bound is never nearer: `raster`;
//! - merging two layers keeps both bounds: `buffer`;
//! - triangles crossing the near plane: `clip`;
//! - rectangles rounded outward: `test`.
//!
//! Results are the same bit for bit with AVX2 or portable code and with any
//! number of threads: the masks, the bounds and the work counted.

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
/// pixels its edge functions stay exact in `f64` (`project`, "Coverage").
pub const MAX_SUBPIXEL_BITS: u32 = 8;

/// Subtile width in pixels.
pub const SUBTILE_W: u32 = 8;
/// Subtile height in pixels.
pub const SUBTILE_H: u32 = 4;
