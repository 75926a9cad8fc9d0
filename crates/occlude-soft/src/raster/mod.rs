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
//!   pixel's coordinates, identical whatever the tile, thread, command order or
//!   instruction set.
//!
//! [`Rasterizer::execute`] runs a list of [`Command`]s (draws and occlusion queries)
//! in three steps:
//!
//! 1. `setup` and `bin`, in parallel over chunks of the input: count whole the
//!    commands set up beforehand that the hierarchical depth at the call's start
//!    hides (`hidden`), clip and set up each other triangle, count the small ones
//!    that depth hides, then index the chunk's other triangles by the
//!    64x64-pixel tiles their bounding boxes touch;
//! 2. `tile`, in parallel over tiles: each tile runs its triangles in command order,
//!    on its own pixels; per triangle, `hiz` rejects the 8x8 blocks whose stored
//!    depths it cannot pass; with AVX2 `avx2` then tests the window's pixels 8
//!    at a time, otherwise (and for the windows `avx2` declines) `span` walks
//!    its exact row spans incrementally and `shade` depth-tests them one pixel
//!    at a time, with identical results;
//! 3. the tiles' fragment counts and the hidden triangles' are summed per
//!    command.

#[cfg(target_arch = "x86_64")]
mod avx2;
mod bin;
mod clip;
mod fragments;
mod hidden;
mod hiz;
mod setup;
#[cfg(target_arch = "x86_64")]
mod setup_avx2;
mod shade;
mod span;
mod split;
mod tile;

#[cfg(test)]
mod tests;

use std::cell::RefCell;
use std::ops::Range;
use std::sync::atomic::AtomicBool;
use std::sync::OnceLock;

use glam::Vec4;
use rayon::prelude::*;

#[cfg(target_arch = "x86_64")]
use avx2::Avx2;
use bin::{Chunk, TileGrid};
use hidden::{Extent, HiddenTest};
use hiz::TileHiZ;
use setup::{setup_triangle, SetupTri, Viewport};
use span::RasterTri;
use split::Tiles;
use tile::{raster_tile, Commands, Kernel, TILE};

pub use fragments::Fragments;
pub use setup::SUBPIXEL_BITS;

/// Largest supported depth-buffer width and height, in pixels. Keeps the fixed-point
/// coordinates (guard band included) far from `i64` overflow in the edge functions.
pub const MAX_DIMENSION: u32 = 16384;

/// Most triangles set up per parallel work item. Each tile reads its triangles chunk
/// by chunk, so larger chunks mean longer runs of consecutive reads; smaller ones
/// share the setup between threads.
const SETUP_CHUNK: usize = 4096;
/// Fewest triangles set up per parallel work item.
const MIN_SETUP_CHUNK: usize = 256;

/// A depth image, row 0 at the top, cleared to 1.0 (the far plane), with the
/// hierarchical depth (per 8x8 block, a bound of its depths) that lets the rasterizer
/// skip blocks a triangle cannot pass.
///
/// The pixels are stored tile by tile (each 64x64 tile contiguous, padded at the
/// buffer's right and bottom edges), so that a tile fills the caches evenly whatever
/// the width; [`Self::to_vec`], [`Self::get`] and [`Self::set`] give the row-major
/// view.
#[derive(Clone, Debug)]
pub struct DepthBuffer {
    width: u32,
    height: u32,
    /// Tile after tile, row by row of tiles; within a tile, `TILE` rows of `TILE`
    /// pixels ([`Self::pixels`]).
    data: Vec<Line>,
    /// One per tile, in the same order.
    hiz: Vec<TileHiZ>,
}

/// Pixels stored per tile.
const TILE_PIXELS: usize = (TILE * TILE) as usize;

/// One cache line of pixels: the depth buffer's storage unit, so that every 8-pixel
/// group of a tile row lies within one cache line (a vector load or store that
/// crosses two costs more).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Line([f32; LINE_PIXELS]);

/// Pixels per [`Line`].
const LINE_PIXELS: usize = 16;
const _: () = assert!(std::mem::size_of::<Line>() == 4 * LINE_PIXELS && TILE_PIXELS.is_multiple_of(LINE_PIXELS));

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
        let tiles = TileGrid::new(width, height).len();
        let data = vec![Line([1.0; LINE_PIXELS]); tiles * TILE_PIXELS / LINE_PIXELS];
        Self { width, height, data, hiz: vec![TileHiZ::cleared(); tiles] }
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The stored pixels, tile after tile.
    fn pixels(&self) -> &[f32] {
        // SAFETY: a `Line` is `LINE_PIXELS` `f32`s without padding (`repr(C)`).
        unsafe { std::slice::from_raw_parts(self.data.as_ptr().cast(), self.data.len() * LINE_PIXELS) }
    }

    /// The stored pixels, for writing.
    fn pixels_mut(&mut self) -> &mut [f32] {
        // SAFETY: as in `pixels`.
        unsafe { std::slice::from_raw_parts_mut(self.data.as_mut_ptr().cast(), self.data.len() * LINE_PIXELS) }
    }

    /// Index in [`Self::pixels`] of the pixel `(x, y)`.
    fn index(&self, x: u32, y: u32) -> usize {
        assert!(x < self.width && y < self.height, "pixel {x},{y} outside {}x{}", self.width, self.height);
        let tile = (y / TILE) as usize * TileGrid::new(self.width, self.height).tiles_x + (x / TILE) as usize;
        tile * TILE_PIXELS + ((y % TILE) * TILE + x % TILE) as usize
    }

    /// The depth of the pixel `(x, y)`.
    ///
    /// # Panics
    /// If the pixel is outside the buffer.
    pub fn get(&self, x: u32, y: u32) -> f32 {
        self.pixels()[self.index(x, y)]
    }

    /// Writes the depth of the pixel `(x, y)` from outside the rasterizer.
    ///
    /// # Panics
    /// If the pixel is outside the buffer.
    pub fn set(&mut self, x: u32, y: u32, depth: f32) {
        let i = self.index(x, y);
        self.pixels_mut()[i] = depth;
        self.hiz[i / TILE_PIXELS].invalidate();
    }

    /// The `width * height` depth values, row by row from the top.
    pub fn to_vec(&self) -> Vec<f32> {
        let mut out = Vec::new();
        self.copy_to(&mut out);
        out
    }

    /// Writes [`Self::to_vec`]'s values into `out`, replacing what it held and
    /// reusing its memory.
    pub fn copy_to(&self, out: &mut Vec<f32>) {
        let grid = TileGrid::new(self.width, self.height);
        let (width, tile) = (self.width as usize, TILE as usize);
        out.clear();
        out.reserve(width * self.height as usize);
        for y in 0..self.height as usize {
            for tx in 0..grid.tiles_x {
                let start = ((y / tile) * grid.tiles_x + tx) * TILE_PIXELS + (y % tile) * tile;
                out.extend_from_slice(&self.pixels()[start..start + tile.min(width - tx * tile)]);
            }
        }
    }

    /// Makes the hierarchical depth of the blocks that draws wrote exact again
    /// (in parallel over tiles), for the binning of the next rasterizer call
    /// (`hidden`). A cleared buffer's bounds are exact already.
    fn refresh_hiz(&mut self, grid: TileGrid) {
        let dirty: Vec<usize> = (0..grid.len()).filter(|&i| self.hiz[i].is_dirty()).collect();
        if dirty.is_empty() {
            return;
        }
        let tiles = Tiles::new(self, grid);
        dirty.into_par_iter().for_each(|i| {
            // SAFETY: each tile index appears once, so its view is the only one.
            let view = unsafe { tiles.view(i) };
            view.hiz.refresh(&view.rows, !0);
        });
    }

    /// Resets every pixel to the far plane (1.0), for the next frame.
    pub fn clear(&mut self) {
        self.pixels_mut().fill(1.0);
        self.hiz.fill(TileHiZ::cleared());
    }
}

/// Two buffers are equal when their sizes and depth values are (the hierarchical
/// depth is a cache of the values).
impl PartialEq for DepthBuffer {
    fn eq(&self, other: &Self) -> bool {
        // Padding is never written, so comparing the storage compares the pixels.
        (self.width, self.height) == (other.width, other.height) && self.pixels() == other.pixels()
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
    /// An occlusion query that only asks whether any fragment passes `DepthTest`, for
    /// callers that need visibility and not a count: it stops testing as soon as one
    /// fragment passes. Its result's `passed` is 1 if one does, else 0, and its
    /// `fragments` is not counted (0).
    QueryAny(DepthTest),
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
#[derive(Debug)]
pub struct Rasterizer {
    /// The instruction set the tiles run on.
    kernel: Kernel,
    /// Set-up and binned triangles, one chunk per up to `SETUP_CHUNK` input
    /// triangles.
    chunks: Vec<Chunk>,
    /// Start of each command in the concatenation of all commands' triangles.
    starts: Vec<usize>,
    /// The command kinds, indexed by command.
    kinds: Vec<CommandKind>,
    /// Per command, whether a passing fragment of a `QueryAny` was found.
    found: Vec<AtomicBool>,
    /// The tiles some triangle touches.
    busy: Vec<usize>,
    /// Per command, whether its prepared triangles are all hidden, so counted
    /// whole and not binned.
    hidden_whole: Vec<bool>,
}

impl Default for Rasterizer {
    fn default() -> Self {
        Self::new()
    }
}

impl Rasterizer {
    /// A rasterizer with empty scratch buffers, using the widest SIMD instructions
    /// the running CPU supports.
    pub fn new() -> Self {
        Self::with_kernel(Kernel::detect())
    }

    fn with_kernel(kernel: Kernel) -> Self {
        Self {
            kernel,
            chunks: Vec::new(),
            starts: Vec::new(),
            kinds: Vec::new(),
            found: Vec::new(),
            busy: Vec::new(),
            hidden_whole: Vec::new(),
        }
    }

    /// A rasterizer that runs the portable scalar code whatever the CPU, to test it
    /// against the SIMD code.
    #[cfg(test)]
    fn scalar() -> Self {
        Self::with_kernel(Kernel::Scalar)
    }

    /// Executes `commands` in order against `depth`, as if one after the other,
    /// parallel over screen tiles (rayon, in the current thread pool, so a caller can
    /// install a 1- or 2-thread pool). Returns one result per command. The results
    /// and the depth buffer are identical whatever the number of threads.
    ///
    /// # Panics
    /// If a command's triangle range is out of bounds of `triangles`.
    pub fn execute(
        &mut self,
        depth: &mut DepthBuffer,
        triangles: &[[Vec4; 3]],
        commands: &[Command],
    ) -> Vec<CommandResult> {
        self.execute_prepared(depth, triangles, commands, &[])
    }

    /// [`Self::execute`], where the commands that `prepared` gives a
    /// [`Prepared`] for (`prepared[c]` for command `c`; an empty `prepared`
    /// for none) rasterize its set-up triangles instead of their range of
    /// `triangles` (empty, then), with the same results as if they had been
    /// set up here.
    ///
    /// # Panics
    /// As [`Self::execute`]; also if `prepared` is neither empty nor one per
    /// command, or holds a set-up for another viewport or back-face rule
    /// than its command's.
    pub fn execute_prepared(
        &mut self,
        depth: &mut DepthBuffer,
        triangles: &[[Vec4; 3]],
        commands: &[Command],
        prepared: &[Option<&Prepared>],
    ) -> Vec<CommandResult> {
        assert!(prepared.is_empty() || prepared.len() == commands.len(), "one prepared set-up or none per command");
        for (i, c) in commands.iter().enumerate() {
            assert!(
                c.triangles.start <= c.triangles.end && c.triangles.end as usize <= triangles.len(),
                "command triangle range {:?} out of bounds of {} triangles",
                c.triangles,
                triangles.len()
            );
            if let Some(p) = prepared.get(i).copied().flatten() {
                assert!(
                    (p.width, p.height, p.cull_back) == (depth.width, depth.height, c.cull_back),
                    "a set-up prepared for {}x{} drawn into {}x{}, or with another back-face rule",
                    p.width,
                    p.height,
                    depth.width,
                    depth.height
                );
            }
        }
        let mut results = vec![CommandResult::default(); commands.len()];
        let (width, height) = (depth.width, depth.height);
        if width == 0 || height == 0 {
            return results;
        }
        let grid = TileGrid::new(width, height);
        self.kinds.clear();
        self.kinds.extend(commands.iter().map(|c| c.kind));
        let kinds = std::mem::take(&mut self.kinds);
        depth.refresh_hiz(grid);
        let hidden = HiddenTest::new(&depth.hiz, grid, &kinds);
        // A prepared command whose extent is hidden: counted whole, not binned.
        self.hidden_whole.clear();
        for (i, result) in results.iter_mut().enumerate() {
            let whole = prepared
                .get(i)
                .copied()
                .flatten()
                .and_then(|p| hidden?.command_fragments(p.extent.as_ref()?, i as u32, || p.fragments()));
            result.fragments += whole.unwrap_or(0);
            self.hidden_whole.push(whole.is_some());
        }
        self.setup_and_bin(Viewport::new(width, height), grid, hidden, triangles, commands, prepared);
        self.kinds = kinds;
        self.found.clear();
        self.found.resize_with(commands.len(), AtomicBool::default);
        let chunks = &self.chunks[..];
        self.busy.clear();
        self.busy.extend((0..grid.len()).filter(|&tile| chunks.iter().any(|c| !c.tile(tile).is_empty())));

        let tiles = Tiles::new(depth, grid);
        let (kernel, n) = (self.kernel, commands.len());
        let commands_view = Commands { kinds: &self.kinds, found: &self.found };
        let busy = &self.busy[..];
        let sums = busy
            .par_iter()
            .enumerate()
            .fold(
                || vec![CommandResult::default(); n],
                |mut acc, (i, &index)| {
                    // A thread usually runs the next busy tile next: start loading its
                    // pixels (cold after a clear) while this one runs.
                    if let Some(&next) = busy.get(i + 1) {
                        tiles.prefetch(next);
                    }
                    // SAFETY: each busy tile appears once, so its view is the only one
                    // while it lives.
                    let mut view = unsafe { tiles.view(index) };
                    let tris = chunks.iter().flat_map(|c| c.tile(index));
                    raster_tile(kernel, &mut view, tris, &commands_view, &mut acc);
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
        for &(cmd, fragments) in chunks.iter().flat_map(Chunk::hidden) {
            results[cmd as usize].fragments += fragments;
        }
        for (r, c) in results.iter_mut().zip(commands) {
            if let CommandKind::QueryAny(_) = c.kind {
                r.passed = r.passed.min(1);
            }
        }
        results
    }

    /// Clips, sets up and bins every command's triangles into `self.chunks`, in
    /// command order, in parallel over chunks of consecutive triangles.
    fn setup_and_bin(
        &mut self,
        viewport: Viewport,
        grid: TileGrid,
        hidden: Option<HiddenTest<'_>>,
        triangles: &[[Vec4; 3]],
        commands: &[Command],
        prepared: &[Option<&Prepared>],
    ) {
        self.starts.clear();
        let mut total = 0usize;
        for (i, c) in commands.iter().enumerate() {
            self.starts.push(total);
            total += match prepared.get(i).copied().flatten() {
                _ if self.hidden_whole.get(i) == Some(&true) => 0,
                Some(p) => p.triangles.len(),
                None => c.triangles.len(),
            };
        }
        self.starts.push(total);
        // About four chunks per thread, for balance.
        let chunk_len = total.div_ceil(4 * rayon::current_num_threads()).clamp(MIN_SETUP_CHUNK, SETUP_CHUNK);
        let n_chunks = total.div_ceil(chunk_len);
        self.chunks.resize_with(n_chunks, Chunk::default);
        self.chunks.truncate(n_chunks);
        let starts = &self.starts[..];
        let kernel = self.kernel;
        self.chunks.par_iter_mut().enumerate().for_each(|(ci, chunk)| {
            chunk.clear(grid);
            let lo = ci * chunk_len;
            let span = SetupSpan { triangles, commands, prepared, starts, range: lo..(lo + chunk_len).min(total) };
            set_up_span(kernel, &mut Binning { chunk, grid, hidden }, viewport, &span);
            chunk.bin(grid);
        });
    }
}

/// A draw's or query's triangles set up once ([`Rasterizer::prepare`]) for
/// rasterizers that draw them into buffers of one size with one camera (the
/// lanes of a benchmark run drawing an instance in the same frame): each
/// then bins and rasterizes them without setting them up again, with the
/// results of setting them up itself.
#[derive(Clone, Debug)]
pub struct Prepared {
    width: u32,
    height: u32,
    cull_back: bool,
    /// The set-up triangles in input order, those that may cover a pixel
    /// centre; their command index is set when they are binned.
    triangles: Vec<RasterTri>,
    /// The triangles in runs of [`GROUP`], each with its extent: a call whose
    /// depth buffer hides a run counts it whole and bins none of it.
    groups: Vec<Group>,
    /// Where the triangles may cover pixels, and how near (the union of the
    /// groups' extents): a call whose depth buffer hides it counts the
    /// command whole ([`Self::fragments`]) and bins none of its triangles
    /// (`hidden`).
    extent: Option<Extent>,
}

/// The number of consecutive set-up triangles of a [`Prepared`] tested
/// together against the depth buffer's bounds before each is tested alone.
/// Where an instance is partly visible, most of its runs are still hidden,
/// and the lanes of a frame then count each such run's pixels once between
/// them instead of each triangle's once per lane. Runs of 8 took the fewest
/// instructions per frame of the power plant's `--paper chc` (4: 5.77
/// billion, 8: 5.71, 16: 5.77, 32: 5.91, 64: 6.01, 128: 6.11; 6.61 with
/// none); results are the same at any size.
const GROUP: usize = 8;

/// How many groups ahead of the one staged [`setup_span`] starts loading a
/// [`Prepared`]'s triangles: a lane reads another lane's set-ups from
/// memory, not from its caches.
const PREFETCH_GROUPS: usize = 4;

/// A run of [`GROUP`] set-up triangles of a [`Prepared`] (fewer at its end).
#[derive(Clone, Debug)]
struct Group {
    /// Where the run's triangles may cover pixels, and how near.
    extent: Option<Extent>,
    /// The pixels the run's triangles cover, once a call has counted them.
    covered: OnceLock<u64>,
}

impl Group {
    /// The pixels `triangles` (the group's) cover, counted by the first call
    /// that needs them: the lanes drawing an instance in a frame share its
    /// counts as they share its set-up.
    fn fragments(&self, triangles: &[RasterTri]) -> u64 {
        *self.covered.get_or_init(|| triangles.iter().map(RasterTri::covered).sum())
    }
}

impl Prepared {
    /// The set-up `triangles` of a command with `cull_back` for a `width` x
    /// `height` buffer.
    fn new(width: u32, height: u32, cull_back: bool, triangles: Vec<RasterTri>) -> Self {
        let groups: Vec<Group> =
            triangles.chunks(GROUP).map(|run| Group { extent: Extent::of(run), covered: OnceLock::new() }).collect();
        let extent = groups.iter().try_fold(None, |all: Option<Extent>, g| {
            let e = g.extent?;
            Some(Some(all.map_or(e, |a| a.union(&e))))
        });
        Self { width, height, cull_back, extent: extent.flatten(), triangles, groups }
    }

    /// The set-up triangles kept: those that may cover a pixel centre.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Whether no triangle may cover a pixel centre.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// Hints the CPU to start loading group `g`'s triangles into its
    /// caches, if there is such a group (no effect where there is no such
    /// hint).
    #[inline(always)]
    fn prefetch_group(&self, g: usize) {
        #[cfg(target_arch = "x86_64")]
        for t in self.triangles.get(g * GROUP..).unwrap_or_default().iter().take(GROUP) {
            // SAFETY: a prefetch reads nothing the program can observe.
            unsafe {
                use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
                _mm_prefetch::<_MM_HINT_T0>(std::ptr::from_ref(t).cast::<i8>());
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = g;
    }

    /// The triangles of group `g`.
    fn group_triangles(&self, g: usize) -> &[RasterTri] {
        &self.triangles[g * GROUP..((g + 1) * GROUP).min(self.triangles.len())]
    }

    /// The pixels the triangles cover (a pixel covered by two counts twice),
    /// summed over the groups' shared counts ([`Group::fragments`]).
    fn fragments(&self) -> u64 {
        self.groups.iter().enumerate().map(|(g, group)| group.fragments(self.group_triangles(g))).sum()
    }
}

impl Rasterizer {
    /// Sets up `triangles` for a `width` x `height` buffer as
    /// [`Self::execute`] would for a command of them with `cull_back`, for
    /// [`Self::execute_prepared`]. Runs on the calling thread.
    pub fn prepare(&self, width: u32, height: u32, triangles: &[[Vec4; 3]], cull_back: bool) -> Prepared {
        let mut out = Vec::new();
        let n = triangles.len();
        let command = Command { kind: CommandKind::Draw, triangles: 0..n as u32, cull_back };
        let span = SetupSpan {
            triangles,
            commands: std::slice::from_ref(&command),
            prepared: &[],
            starts: &[0, n],
            range: 0..n,
        };
        set_up_span(self.kernel, &mut out, Viewport::new(width, height), &span);
        Prepared::new(width, height, cull_back, out)
    }

    /// [`Self::prepare`] for the triangles that `indices` (three per triangle)
    /// make of `vertices`, with the same set-up: an indexed mesh's vertices are
    /// each projected once, however many triangles share them.
    ///
    /// # Panics
    /// If an index is out of bounds of `vertices`.
    pub fn prepare_indexed(
        &self,
        width: u32,
        height: u32,
        vertices: &[Vec4],
        indices: &[u32],
        cull_back: bool,
    ) -> Prepared {
        let largest = indices.iter().copied().max().unwrap_or(0);
        assert!(
            indices.is_empty() || (largest as usize) < vertices.len(),
            "vertex index {largest} out of bounds of {} vertices",
            vertices.len()
        );
        match self.kernel {
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx2(_) => INDEXED_SCRATCH.with_borrow_mut(|(records, out)| {
                out.clear();
                let viewport = Viewport::new(width, height);
                // SAFETY: an `Avx2` exists only where the CPU supports AVX2, and
                // the indices are checked above.
                unsafe { set_up_indexed_avx2(vertices, indices, cull_back, viewport, records, out) };
                let prepared = Prepared::new(width, height, cull_back, out.to_vec());
                // A thread keeps no more than a usual instance needs.
                if records.capacity() > SCRATCH_KEPT {
                    *records = Vec::new();
                }
                if out.capacity() > SCRATCH_KEPT {
                    *out = Vec::new();
                }
                prepared
            }),
            Kernel::Scalar => {
                let triangles: Vec<[Vec4; 3]> =
                    indices.chunks_exact(3).map(|t| [0, 1, 2].map(|k| vertices[t[k] as usize])).collect();
                self.prepare(width, height, &triangles, cull_back)
            }
        }
    }
}

/// Where [`setup_span`] puts the triangles it sets up: a chunk binning them,
/// or a list keeping them ([`Prepared`]).
trait Staging {
    fn stage(&mut self, t: RasterTri);

    /// Whether group `g` of `p`'s triangles is hidden, for command `cmd`,
    /// and so counted whole here instead of staged.
    #[inline(always)]
    fn counted_group(&mut self, _cmd: u32, _p: &Prepared, _g: usize) -> bool {
        false
    }
}

/// A chunk binning to the tiles of `grid`, but for the small triangles that
/// `hidden` finds hidden, which it counts.
struct Binning<'a> {
    chunk: &'a mut Chunk,
    grid: TileGrid,
    hidden: Option<HiddenTest<'a>>,
}

impl Staging for Binning<'_> {
    #[inline(always)]
    fn stage(&mut self, t: RasterTri) {
        match self.hidden.as_ref().and_then(|h| h.fragments_if_hidden(&t)) {
            Some(fragments) => self.chunk.count_hidden(t.cmd, fragments),
            None => self.chunk.push(self.grid, t),
        }
    }

    #[inline(always)]
    fn counted_group(&mut self, cmd: u32, p: &Prepared, g: usize) -> bool {
        let group = &p.groups[g];
        let hidden = self
            .hidden
            .as_ref()
            .and_then(|h| h.command_fragments(group.extent.as_ref()?, cmd, || group.fragments(p.group_triangles(g))));
        if let Some(fragments) = hidden {
            self.chunk.count_hidden(cmd, fragments);
        }
        hidden.is_some()
    }
}

impl Staging for Vec<RasterTri> {
    #[inline(always)]
    fn stage(&mut self, t: RasterTri) {
        self.push(t);
    }
}

/// A range of the concatenation of all commands' triangles, to set up.
struct SetupSpan<'a> {
    triangles: &'a [[Vec4; 3]],
    commands: &'a [Command],
    /// Per command, its triangles already set up, if so (or empty: none).
    prepared: &'a [Option<&'a Prepared>],
    /// Start of each command in the concatenation (and its end).
    starts: &'a [usize],
    range: Range<usize>,
}

/// Clips and sets up the triangles of `span` into `out`, in order (a command's
/// [`Prepared`] set-up copied with the command's index); with an AVX2
/// kernel, four at a time where they need no clipping (`setup_avx2`), after
/// dropping, four at a time, those whose bounding box holds no pixel centre
/// (`setup_avx2::uncovered4`, about a third of `setup4`'s work): most of the
/// triangles of a large scene at 1024x768 are smaller than a pixel.
#[inline(always)]
fn setup_span<S: Staging>(kernel: Kernel, out: &mut S, viewport: Viewport, span: &SetupSpan<'_>) {
    // Only the x86-64 kernels have a four-at-a-time set-up.
    #[cfg(not(target_arch = "x86_64"))]
    let _ = kernel;
    let mut poly = clip::Polygon::new();
    let (lo, hi) = (span.range.start, span.range.end);
    // The last command starting at or before `lo` (skipping empty ones).
    let mut cmd = span.starts.partition_point(|&s| s <= lo) - 1;
    let mut g = lo;
    while g < hi {
        let c = &span.commands[cmd];
        let end = hi.min(span.starts[cmd + 1]);
        if let Some(p) = span.prepared.get(cmd).copied().flatten() {
            // A group is staged whole by the span holding its first triangle,
            // in order: past this span's end, and none of it by the next span.
            let at = g - span.starts[cmd];
            for group in at.div_ceil(GROUP)..(at + (end - g)).div_ceil(GROUP) {
                p.prefetch_group(group + PREFETCH_GROUPS);
                if !out.counted_group(cmd as u32, p, group) {
                    for t in p.group_triangles(group) {
                        out.stage(RasterTri { cmd: cmd as u32, ..*t });
                    }
                }
            }
            g = end;
            cmd += 1;
            continue;
        }
        let first = c.triangles.start as usize + (g - span.starts[cmd]);
        let mut rest = &span.triangles[first..first + (end - g)];
        #[cfg(target_arch = "x86_64")]
        if let Kernel::Avx2(_) = kernel {
            let groups = rest.chunks_exact(4);
            rest = groups.remainder();
            let mut four = [RasterTri::PLACEHOLDER; 4];
            let mut set_up = |out: &mut S, tris: &[[Vec4; 3]; 4], n: usize| {
                // SAFETY: an `Avx2` exists only where the CPU supports AVX2.
                let lanes = unsafe { setup_avx2::setup4(tris, c.cull_back, cmd as u32, viewport, &mut four) };
                stage_four(out, lanes, &four, n, |out, i| {
                    setup_triangle(&tris[i], c.cull_back, cmd as u32, viewport, &mut poly, |t| stage_setup(out, t));
                });
            };
            // The triangles that may cover a pixel centre, set up four at a time.
            let mut pending = Pending::new();
            for group in groups {
                let group: &[[Vec4; 3]; 4] = group.try_into().expect("four triangles");
                // SAFETY: as above.
                let uncovered = unsafe { setup_avx2::uncovered4(group, viewport) };
                if uncovered == 0 && pending.is_empty() {
                    set_up(out, group, 4);
                } else {
                    pending.add(group, uncovered, |tris, n| set_up(out, tris, n));
                }
            }
            pending.finish(|tris, n| set_up(out, tris, n));
        }
        for tri in rest {
            setup_triangle(tri, c.cull_back, cmd as u32, viewport, &mut poly, |t| stage_setup(out, t));
        }
        g = end;
        cmd += 1;
    }
}

/// Stages the first `n` of four triangles set up four at a time (`lanes`,
/// their raster forms `four`): the ready ones whose rows may cover a pixel
/// centre, and, through `scalar(out, i)`, the triangles `i` handed back to the
/// scalar set-up.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn stage_four<S: Staging>(
    out: &mut S,
    lanes: setup_avx2::Lanes,
    four: &[RasterTri; 4],
    n: usize,
    mut scalar: impl FnMut(&mut S, usize),
) {
    for (i, r) in four.iter().enumerate().take(n) {
        if lanes.ready & (1 << i) != 0 {
            if let Some(r) = r.covered_rows() {
                out.stage(r);
            }
        } else if lanes.scalar & (1 << i) != 0 {
            scalar(out, i);
        }
    }
}

#[cfg(target_arch = "x86_64")]
thread_local! {
    /// The memory [`Rasterizer::prepare_indexed`] sets up in, reused call after
    /// call on each thread: the projected vertices, and the kept triangles
    /// before their copy of exact size. A frame's shared set-up prepares
    /// thousands of instances on each thread, and allocating both per
    /// instance (the triangles' vector grown by doubling) cost the plant's
    /// benchmark several percent of its CPU time in the allocator.
    static INDEXED_SCRATCH: RefCell<(Vec<setup_avx2::VertexRecord>, Vec<RasterTri>)> =
        const { RefCell::new((Vec::new(), Vec::new())) };
}

/// The most vertex records or triangles [`INDEXED_SCRATCH`] keeps for the
/// next call (2 and 4 MiB): an instance of a mesh larger than that (an
/// imported model of millions of triangles) allocates its own, so that no
/// thread holds such a mesh's memory after its set-up.
#[cfg(target_arch = "x86_64")]
const SCRATCH_KEPT: usize = 1 << 16;

/// Sets up the triangles `indices` (three per triangle) make of `vertices`
/// into `out`, in order, as [`setup_span`] sets up the same triangles given
/// vertex by vertex: every vertex projected once ([`setup_avx2::project4`])
/// into `records`, however many triangles share it, then the triangles set
/// up four at a time from the projected vertices.
///
/// # Safety
/// The CPU must support AVX2, and every index must be within `vertices`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn set_up_indexed_avx2(
    vertices: &[Vec4],
    indices: &[u32],
    cull_back: bool,
    viewport: Viewport,
    records: &mut Vec<setup_avx2::VertexRecord>,
    out: &mut Vec<RasterTri>,
) {
    records.clear();
    records.resize(vertices.len().next_multiple_of(4), [0.0; 4]);
    for (v, r) in vertices.chunks(4).zip(records.chunks_exact_mut(4)) {
        // A last group of fewer than four repeats its last vertex.
        let mut four = [v[v.len() - 1]; 4];
        four[..v.len()].copy_from_slice(v);
        setup_avx2::project4(&four, viewport, r.try_into().expect("four records"));
    }
    let (mut four, mut poly) = ([RasterTri::PLACEHOLDER; 4], clip::Polygon::new());
    // Sets up the first `n` of the four triangles `i`, their vertices `p` if
    // gathered already.
    let mut set_up = |out: &mut Vec<RasterTri>, i: &[[u32; 3]; 4], n, p: Option<_>| {
        let p = p.unwrap_or_else(|| setup_avx2::gather4(records, i));
        let lanes = setup_avx2::setup4_projected(p, cull_back, 0, viewport, &mut four);
        stage_four(out, lanes, &four, n, |out, t| {
            let clip = i[t].map(|k| vertices[k as usize]);
            setup_triangle(&clip, cull_back, 0, viewport, &mut poly, |t| stage_setup(out, t));
        });
    };
    // The triangles that may cover a pixel centre, set up four at a time.
    let mut pending = Pending::new();
    let whole = &indices[..indices.len() / 3 * 3];
    let groups = whole.chunks_exact(12);
    let rest = groups.remainder();
    for group in groups {
        let i: [[u32; 3]; 4] = std::array::from_fn(|t| [group[3 * t], group[3 * t + 1], group[3 * t + 2]]);
        let p = setup_avx2::gather4(records, &i);
        let uncovered = setup_avx2::uncovered4_projected(&p, viewport);
        if uncovered == 0 && pending.is_empty() {
            set_up(out, &i, 4, Some(p));
        } else {
            pending.add(&i, uncovered, |i, n| set_up(out, i, n, None));
        }
    }
    for t in rest.chunks_exact(3) {
        pending.push([t[0], t[1], t[2]], true, |i, n| set_up(out, i, n, None));
    }
    pending.finish(|i, n| set_up(out, i, n, None));
}

/// Up to four triangles (or their indices) gathered for a four-wide set-up,
/// in order, from groups of four of which a pre-test drops some.
#[cfg(target_arch = "x86_64")]
struct Pending<T> {
    items: [T; 4],
    n: usize,
}

#[cfg(target_arch = "x86_64")]
impl<T: Copy + Default> Pending<T> {
    fn new() -> Self {
        Self { items: [T::default(); 4], n: 0 }
    }

    fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Adds the items of `group` whose bit in `dropped` is clear, calling
    /// `full(items, 4)` whenever four are gathered.
    #[inline(always)]
    fn add(&mut self, group: &[T; 4], dropped: u8, mut full: impl FnMut(&[T; 4], usize)) {
        for (k, &item) in group.iter().enumerate() {
            self.push(item, dropped & (1 << k) == 0, &mut full);
        }
    }

    /// Adds `item` if `keep`, calling `full(items, 4)` if four are then gathered.
    #[inline(always)]
    fn push(&mut self, item: T, keep: bool, mut full: impl FnMut(&[T; 4], usize)) {
        // Written always, kept (`n` advanced) only if `keep`: no branch.
        self.items[self.n] = item;
        self.n += usize::from(keep);
        if self.n == 4 {
            full(&self.items, 4);
            self.n = 0;
        }
    }

    /// Calls `last(items, n)` for the `n` items left, if any; the unused slots
    /// repeat the last of them, and their results are not read.
    fn finish(&mut self, mut last: impl FnMut(&[T; 4], usize)) {
        if self.n > 0 {
            let fill = self.items[self.n - 1];
            self.items[self.n..].fill(fill);
            last(&self.items, self.n);
            self.n = 0;
        }
    }
}

/// Stages the raster form of the scalar set-up's triangle `t`, if its rows may
/// cover a pixel centre.
fn stage_setup<S: Staging>(out: &mut S, t: SetupTri) {
    if let Some(r) = RasterTri::new(&t) {
        out.stage(r);
    }
}

/// [`setup_span`] with `kernel`'s instructions.
fn set_up_span<S: Staging>(kernel: Kernel, out: &mut S, viewport: Viewport, span: &SetupSpan<'_>) {
    match kernel {
        Kernel::Scalar => setup_span(kernel, out, viewport, span),
        #[cfg(target_arch = "x86_64")]
        // SAFETY: an `Avx2` exists only where the CPU supports AVX2.
        Kernel::Avx2(avx2) => unsafe { setup_span_avx2(avx2, out, viewport, span) },
    }
}

/// [`setup_span`] compiled for AVX2.
///
/// # Safety
/// The CPU must support AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn setup_span_avx2<S: Staging>(avx2: Avx2, out: &mut S, viewport: Viewport, span: &SetupSpan<'_>) {
    setup_span(Kernel::Avx2(avx2), out, viewport, span);
}

/// Executes `commands` with a fresh [`Rasterizer`]; see [`Rasterizer::execute`].
/// Callers rasterizing every frame should keep a `Rasterizer` to reuse its buffers.
pub fn execute(depth: &mut DepthBuffer, triangles: &[[Vec4; 3]], commands: &[Command]) -> Vec<CommandResult> {
    Rasterizer::new().execute(depth, triangles, commands)
}
