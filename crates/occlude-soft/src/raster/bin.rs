//! Binning: which set-up triangles touch which screen tile, so that a tile visits
//! only its own triangles. Each chunk of the input bins its triangles by itself (in
//! parallel with the others), with a counting sort that copies each triangle next to
//! the others of every tile its bounding box touches: a tile then reads its
//! triangles one after the other in memory. A tile walks the chunks in order, which
//! keeps its triangles in command order.

use super::span::RasterTri;
use super::tile::TILE;

/// The grid of screen tiles.
#[derive(Clone, Copy, Debug)]
pub(super) struct TileGrid {
    /// Tiles per row.
    pub tiles_x: usize,
    /// Tile rows.
    pub tiles_y: usize,
}

impl TileGrid {
    /// The tiles of a `width` x `height` buffer.
    pub fn new(width: u32, height: u32) -> Self {
        Self { tiles_x: width.div_ceil(TILE) as usize, tiles_y: height.div_ceil(TILE) as usize }
    }

    /// Number of tiles.
    pub fn len(self) -> usize {
        self.tiles_x * self.tiles_y
    }
}

/// The set-up triangles of one chunk of the input, binned by tile.
#[derive(Debug, Default)]
pub(super) struct Chunk {
    /// The triangles in input order, until [`Chunk::bin`].
    staged: Vec<RasterTri>,
    /// After [`Chunk::bin`], `starts[tile]..starts[tile + 1]` is the range of
    /// `binned` holding the triangles touching `tile`.
    starts: Vec<u32>,
    /// The triangles grouped by tile (a triangle is copied to every tile its bounding
    /// box touches), in order within each tile.
    binned: Vec<RasterTri>,
    /// The fragments of the triangles counted instead of added (hidden behind the
    /// hierarchical depth: `hidden`), per command in runs, in command order.
    hidden: Vec<(u32, u64)>,
}

impl Chunk {
    /// Empties the chunk for binning to the tiles of `grid` (keeping its memory).
    pub fn clear(&mut self, grid: TileGrid) {
        self.staged.clear();
        self.hidden.clear();
        // Counts go to starts[tile + 2], so that after the prefix sum in `bin`
        // starts[tile + 1] is the tile's first entry; filling then advances it to the
        // tile's end, which is the next tile's start.
        self.starts.clear();
        self.starts.resize(grid.len() + 2, 0);
    }

    /// Adds `t`, after the triangles added before.
    pub fn push(&mut self, grid: TileGrid, t: RasterTri) {
        for_each_tile(grid, &t, |tile| self.starts[tile + 2] += 1);
        self.staged.push(t);
    }

    /// Adds `fragments` to command `cmd`'s count, for a triangle counted instead of
    /// added.
    #[inline(always)]
    pub fn count_hidden(&mut self, cmd: u32, fragments: u64) {
        match self.hidden.last_mut() {
            Some((last, sum)) if *last == cmd => *sum += fragments,
            _ => self.hidden.push((cmd, fragments)),
        }
    }

    /// The commands' fragments counted instead of added, per command (in runs).
    pub fn hidden(&self) -> &[(u32, u64)] {
        &self.hidden
    }

    /// Groups the triangles added by tile, for [`Chunk::tile`].
    pub fn bin(&mut self, grid: TileGrid) {
        for i in 1..self.starts.len() {
            self.starts[i] += self.starts[i - 1];
        }
        self.binned.clear();
        self.binned.resize(self.starts[grid.len() + 1] as usize, RasterTri::PLACEHOLDER);
        for t in &self.staged {
            for_each_tile(grid, t, |tile| {
                let slot = &mut self.starts[tile + 1];
                self.binned[*slot as usize] = *t;
                *slot += 1;
            });
        }
    }

    /// The triangles touching `tile`, in order.
    pub fn tile(&self, tile: usize) -> &[RasterTri] {
        &self.binned[self.starts[tile] as usize..self.starts[tile + 1] as usize]
    }
}

/// Calls `f` with the index of every tile of `grid` that `t`'s bounding box touches.
#[inline(always)]
fn for_each_tile(grid: TileGrid, t: &RasterTri, mut f: impl FnMut(usize)) {
    let (tx0, tx1) = ((t.x0 as u32 / TILE) as usize, (t.x1 as u32 / TILE) as usize);
    let (ty0, ty1) = ((t.y0 as u32 / TILE) as usize, (t.y1 as u32 / TILE) as usize);
    for ty in ty0..=ty1 {
        for tile in ty * grid.tiles_x + tx0..=ty * grid.tiles_x + tx1 {
            f(tile);
        }
    }
}
