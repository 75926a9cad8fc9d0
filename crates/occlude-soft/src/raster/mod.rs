//! An exact, deterministic depth rasterizer, parallel over screen tiles.
//!
//! Every culling method's depth image is compared bit-for-bit with view-frustum
//! culling's, so the rasterizer is exact and order-independent:
//!
//! - triangles arrive in clip space (wgpu conventions: depth `z` in `[0, w]`, NDC
//!   `y` up, front faces counter-clockwise in NDC) and are clipped against the near
//!   plane `z >= 0` and a guard band around the viewport;
//! - vertices are snapped to fixed point with [`SUBPIXEL_BITS`] sub-pixel bits, and
//!   coverage is decided by exact `i64` edge functions at pixel centres with the
//!   top-left fill rule, so triangles sharing an edge cover each pixel exactly once;
//! - the depth at a pixel is a fixed formula of the triangle's depth plane and the
//!   pixel's coordinates, identical whatever the tile, thread or command order.
//!
//! [`Rasterizer::execute`] runs a list of [`Command`]s (draws and occlusion queries):
//! it sets up the triangles in parallel, bins them to 64x64-pixel tiles, then runs
//! every tile's triangles in command order, the tiles in parallel on the current
//! rayon thread pool.

mod clip;
mod setup;
mod tile;

#[cfg(test)]
mod tests;

use std::ops::Range;

use glam::Vec4;
use rayon::prelude::*;

use setup::{setup_triangle, SetupTri, Viewport};
use tile::{raster_tile, TileView, TILE};

pub use setup::SUBPIXEL_BITS;

/// Largest supported depth-buffer width and height, in pixels. Keeps the fixed-point
/// coordinates (guard band included) far from `i64` overflow in the edge functions.
pub const MAX_DIMENSION: u32 = 16384;

/// Triangles set up per parallel work item.
const SETUP_CHUNK: usize = 1024;
/// Bits of a bin entry holding the triangle's index within its setup chunk; a chunk
/// yields at most 6 triangles per input triangle (a clipped polygon has at most 8
/// vertices), so `6 * SETUP_CHUNK` must fit.
const CHUNK_INDEX_BITS: u32 = 13;
const _: () = assert!(6 * SETUP_CHUNK < 1 << CHUNK_INDEX_BITS);

/// Row-major depth image, row 0 at the top, cleared to 1.0 (the far plane).
#[derive(Clone, Debug, PartialEq)]
pub struct DepthBuffer {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height` depth values, row by row from the top.
    pub data: Vec<f32>,
}

impl DepthBuffer {
    /// A `width` x `height` buffer cleared to the far plane (1.0).
    ///
    /// # Panics
    /// If `width` or `height` exceeds [`MAX_DIMENSION`].
    pub fn new(width: u32, height: u32) -> Self {
        assert!(
            width <= MAX_DIMENSION && height <= MAX_DIMENSION,
            "depth buffer {width}x{height} exceeds {MAX_DIMENSION} pixels per side"
        );
        Self { width, height, data: vec![1.0; width as usize * height as usize] }
    }

    /// Resets every pixel to the far plane (1.0), for the next frame.
    pub fn clear(&mut self) {
        self.data.fill(1.0);
    }
}

/// Depth comparison of a query.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthTest {
    /// Passes where the fragment is nearer than the stored depth.
    Less,
    /// Passes where the fragment's depth equals the stored depth bit for bit (used
    /// to find which geometry produced the final depth).
    Equal,
}

/// What a command does with its triangles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CommandKind {
    /// Depth test LESS, depth write on (drawing scene geometry).
    Draw,
    /// No depth write: count fragments passing `DepthTest` against the current depth
    /// (an occlusion query).
    Query(DepthTest),
}

/// One draw or query: a range of triangles and how to rasterize them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Command {
    /// What to do with the triangles.
    pub kind: CommandKind,
    /// Range into the triangle slice passed to `execute`.
    pub triangles: Range<u32>,
    /// Skip back-facing triangles (query boxes use true; scene draws use false =
    /// two-sided).
    pub cull_back: bool,
}

/// Fragment counts of one command.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CommandResult {
    /// Pixels covered by the command's (non-culled) triangles inside the viewport,
    /// before the depth test (a pixel covered by two triangles counts twice).
    pub fragments: u64,
    /// Of those, fragments that passed the depth test (for Draw: that wrote depth;
    /// for Query: the query count, hardware-occlusion-query semantics).
    pub passed: u64,
}

/// A depth rasterizer holding scratch buffers that are reused between calls to
/// [`Rasterizer::execute`], so that steady-state frames allocate little.
#[derive(Debug, Default)]
pub struct Rasterizer {
    /// Set-up triangles, one vector per chunk of `SETUP_CHUNK` input triangles.
    chunks: Vec<Vec<SetupTri>>,
    /// Start of each command in the concatenation of all commands' triangles.
    starts: Vec<usize>,
    /// Per tile, the set-up triangles touching it, in command order, as
    /// `chunk << CHUNK_INDEX_BITS | index`.
    bins: Vec<Vec<u32>>,
    /// The command kinds, indexed by command.
    kinds: Vec<CommandKind>,
}

impl Rasterizer {
    /// A rasterizer with empty scratch buffers.
    pub fn new() -> Self {
        Self::default()
    }

    /// Executes `commands` in order against `depth`, as if one after the other,
    /// parallel over screen tiles (rayon, in the current thread pool, so a caller can
    /// install a 1- or 2-thread pool). Returns one result per command. The results
    /// and the depth buffer are identical whatever the number of threads.
    ///
    /// # Panics
    /// If a command's triangle range is out of bounds of `triangles`, or
    /// `depth.data` does not hold `width * height` values.
    pub fn execute(
        &mut self,
        depth: &mut DepthBuffer,
        triangles: &[[Vec4; 3]],
        commands: &[Command],
    ) -> Vec<CommandResult> {
        let (width, height) = (depth.width, depth.height);
        assert_eq!(depth.data.len(), width as usize * height as usize);
        assert!(width <= MAX_DIMENSION && height <= MAX_DIMENSION);
        for c in commands {
            assert!(
                c.triangles.start <= c.triangles.end && c.triangles.end as usize <= triangles.len(),
                "command triangle range {:?} out of bounds of {} triangles",
                c.triangles,
                triangles.len()
            );
        }
        let mut results = vec![CommandResult::default(); commands.len()];
        if width == 0 || height == 0 {
            return results;
        }
        self.setup(Viewport::new(width, height), triangles, commands);
        let tiles_x = width.div_ceil(TILE) as usize;
        let tiles_y = height.div_ceil(TILE) as usize;
        self.bin(tiles_x, tiles_y);
        self.kinds.clear();
        self.kinds.extend(commands.iter().map(|c| c.kind));

        let jobs = tile_views(depth, tiles_x, &self.bins);
        let (chunks, bins, kinds) = (&self.chunks, &self.bins, &self.kinds[..]);
        let n = commands.len();
        let sums = jobs
            .into_par_iter()
            .fold(
                || vec![CommandResult::default(); n],
                |mut acc, (index, mut view)| {
                    let tris = bins[index].iter().map(|&e| {
                        let chunk = (e >> CHUNK_INDEX_BITS) as usize;
                        &chunks[chunk][(e & ((1 << CHUNK_INDEX_BITS) - 1)) as usize]
                    });
                    raster_tile(&mut view, tris, kinds, &mut acc);
                    acc
                },
            )
            .collect::<Vec<_>>();
        for part in sums {
            for (r, p) in results.iter_mut().zip(part) {
                r.fragments += p.fragments;
                r.passed += p.passed;
            }
        }
        results
    }

    /// Clips and sets up every command's triangles into `self.chunks`, in command
    /// order, in parallel over chunks of `SETUP_CHUNK` triangles.
    fn setup(&mut self, viewport: Viewport, triangles: &[[Vec4; 3]], commands: &[Command]) {
        self.starts.clear();
        let mut total = 0usize;
        for c in commands {
            self.starts.push(total);
            total += c.triangles.len();
        }
        self.starts.push(total);
        let n_chunks = total.div_ceil(SETUP_CHUNK);
        assert!(n_chunks < 1 << (32 - CHUNK_INDEX_BITS), "too many triangles in one execute call");
        self.chunks.resize_with(n_chunks, Vec::new);
        self.chunks.truncate(n_chunks);
        let starts = &self.starts[..];
        self.chunks.par_iter_mut().enumerate().for_each(|(ci, out)| {
            out.clear();
            let mut poly = clip::Polygon::new();
            let lo = ci * SETUP_CHUNK;
            let hi = (lo + SETUP_CHUNK).min(total);
            // The last command starting at or before `lo` (skipping empty ones).
            let mut cmd = starts.partition_point(|&s| s <= lo) - 1;
            let mut g = lo;
            while g < hi {
                let c = &commands[cmd];
                let end = hi.min(starts[cmd + 1]);
                let first = c.triangles.start as usize + (g - starts[cmd]);
                for tri in &triangles[first..first + (end - g)] {
                    setup_triangle(tri, c.cull_back, cmd as u32, viewport, &mut poly, out);
                }
                g = end;
                cmd += 1;
            }
        });
    }

    /// Fills `self.bins` with, per tile, the set-up triangles whose bounding box
    /// touches it, in command order.
    fn bin(&mut self, tiles_x: usize, tiles_y: usize) {
        self.bins.resize_with(tiles_x * tiles_y, Vec::new);
        self.bins.truncate(tiles_x * tiles_y);
        for b in &mut self.bins {
            b.clear();
        }
        for (ci, chunk) in self.chunks.iter().enumerate() {
            for (i, t) in chunk.iter().enumerate() {
                let entry = ((ci as u32) << CHUNK_INDEX_BITS) | i as u32;
                let (tx0, tx1) = (t.x0 as u32 / TILE, t.x1 as u32 / TILE);
                let (ty0, ty1) = (t.y0 as u32 / TILE, t.y1 as u32 / TILE);
                for ty in ty0..=ty1 {
                    let row = ty as usize * tiles_x;
                    for tx in tx0..=tx1 {
                        self.bins[row + tx as usize].push(entry);
                    }
                }
            }
        }
    }
}

/// Executes `commands` with a fresh [`Rasterizer`]; see [`Rasterizer::execute`].
/// Callers rasterizing every frame should keep a `Rasterizer` to reuse its buffers.
pub fn execute(depth: &mut DepthBuffer, triangles: &[[Vec4; 3]], commands: &[Command]) -> Vec<CommandResult> {
    Rasterizer::new().execute(depth, triangles, commands)
}

/// Splits `depth` into disjoint per-tile views, one per tile with a non-empty bin,
/// paired with the tile's index.
fn tile_views<'a>(depth: &'a mut DepthBuffer, tiles_x: usize, bins: &[Vec<u32>]) -> Vec<(usize, TileView<'a>)> {
    let width = depth.width as usize;
    let tile = TILE as usize;
    let mut jobs = Vec::new();
    for (ty, band) in depth.data.chunks_mut(width * tile).enumerate() {
        if bins[ty * tiles_x..(ty + 1) * tiles_x].iter().all(Vec::is_empty) {
            continue;
        }
        let mut row_parts: Vec<_> = band.chunks_mut(width).map(|r| r.chunks_mut(tile)).collect();
        for tx in 0..tiles_x {
            let rows: Vec<&mut [f32]> =
                row_parts.iter_mut().map(|parts| parts.next().expect("a tile column per row")).collect();
            let index = ty * tiles_x + tx;
            if bins[index].is_empty() {
                continue;
            }
            jobs.push((index, TileView { x0: (tx * tile) as i32, y0: (ty * tile) as i32, rows }));
        }
    }
    jobs
}
