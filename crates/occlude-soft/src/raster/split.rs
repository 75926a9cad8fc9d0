//! The depth buffer split into tiles that threads rasterize at the same time, without
//! allocating: a tile's view is a pointer to its first pixel (tiles are stored
//! contiguously, rows `TILE` pixels apart).

use std::marker::PhantomData;

use super::bin::TileGrid;
use super::hiz::TileHiZ;
use super::tile::TILE;
use super::{DepthBuffer, TILE_PIXELS};

/// The rows of one tile: `height` rows of `width` pixels, `stride` pixels apart.
#[derive(Debug)]
pub(super) struct TileRows<'a> {
    /// The tile's top-left pixel.
    data: *mut f32,
    stride: usize,
    width: usize,
    height: usize,
    _rows: PhantomData<&'a mut [f32]>,
}

impl<'a> TileRows<'a> {
    /// The `width` x `height` rectangle at the start of `data`, whose rows are
    /// `stride` pixels apart.
    ///
    /// # Panics
    /// If `data` is too short for it, or `stride < width`.
    #[cfg(test)]
    pub fn new(data: &'a mut [f32], width: usize, height: usize, stride: usize) -> Self {
        assert!(width <= stride && (height == 0 || (height - 1) * stride + width <= data.len()));
        Self { data: data.as_mut_ptr(), stride, width, height, _rows: PhantomData }
    }

    /// Pixels per row.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Number of rows.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Pixels from the start of one row to the start of the next.
    pub fn stride(&self) -> usize {
        self.stride
    }

    /// Row `y`.
    #[inline(always)]
    pub fn row(&self, y: usize) -> &[f32] {
        assert!(y < self.height);
        // SAFETY: rows below `height` lie inside the borrowed data (`new`, `view`),
        // and `&self` allows no writes while the slice lives.
        unsafe { std::slice::from_raw_parts(self.data.add(y * self.stride), self.width) }
    }

    /// Row `y`, for writing.
    #[inline(always)]
    pub fn row_mut(&mut self, y: usize) -> &mut [f32] {
        assert!(y < self.height);
        // SAFETY: as in `row`; `&mut self` makes the slice the only access to it.
        unsafe { std::slice::from_raw_parts_mut(self.data.add(y * self.stride), self.width) }
    }
}

/// One tile of a depth buffer: its rows, from pixel `(x0, y0)`, and its hierarchical
/// depth.
#[derive(Debug)]
pub(super) struct TileView<'a> {
    /// Leftmost pixel column of the tile.
    pub x0: i32,
    /// Top pixel row of the tile.
    pub y0: i32,
    /// The tile's pixels.
    pub rows: TileRows<'a>,
    /// The tile's hierarchical depth.
    pub hiz: &'a mut TileHiZ,
}

/// A depth buffer's tiles, which different threads may view (and write) at the same
/// time, each its own.
pub(super) struct Tiles<'a> {
    data: *mut f32,
    hiz: *mut TileHiZ,
    width: usize,
    height: usize,
    grid: TileGrid,
    _buffer: PhantomData<&'a mut DepthBuffer>,
}

// SAFETY: `Tiles` borrows its buffer mutably and hands out views of disjoint tiles
// (the caller of `view` guarantees one view per tile at a time), which is what
// sharing disjoint `&mut` slices between threads amounts to.
unsafe impl Send for Tiles<'_> {}
// SAFETY: as above.
unsafe impl Sync for Tiles<'_> {}

impl<'a> Tiles<'a> {
    /// The tiles of `depth`, laid out as `grid`.
    pub fn new(depth: &'a mut DepthBuffer, grid: TileGrid) -> Self {
        let (width, height) = (depth.width as usize, depth.height as usize);
        assert_eq!(depth.pixels().len(), grid.len() * TILE_PIXELS);
        assert_eq!(depth.hiz.len(), grid.len());
        Self {
            data: depth.pixels_mut().as_mut_ptr(),
            hiz: depth.hiz.as_mut_ptr(),
            width,
            height,
            grid,
            _buffer: PhantomData,
        }
    }

    /// Hints the CPU to start loading tile `index`'s pixels into its caches, without
    /// accessing them (no effect where there is no such hint).
    ///
    /// # Panics
    /// If `index` is not a tile of the grid.
    #[inline]
    pub fn prefetch(&self, index: usize) {
        assert!(index < self.grid.len());
        #[cfg(target_arch = "x86_64")]
        for line in (0..TILE_PIXELS).step_by(16) {
            // SAFETY: the address lies inside the buffer (the tile's stored pixels),
            // and a prefetch reads nothing the program can observe.
            unsafe {
                use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T1};
                _mm_prefetch::<_MM_HINT_T1>(self.data.add(index * TILE_PIXELS + line).cast::<i8>());
            }
        }
    }

    /// The view of tile `index`.
    ///
    /// # Safety
    /// No other view of the same tile may be alive while this one is.
    ///
    /// # Panics
    /// If `index` is not a tile of the grid.
    pub unsafe fn view(&self, index: usize) -> TileView<'_> {
        assert!(index < self.grid.len());
        let tile = TILE as usize;
        let (x0, y0) = ((index % self.grid.tiles_x) * tile, (index / self.grid.tiles_x) * tile);
        // SAFETY: the tile's pixels (its TILE_PIXELS stored values) and its
        // hierarchical depth lie inside the buffer, and the caller guarantees that
        // nothing else accesses them while the view lives.
        unsafe {
            TileView {
                x0: x0 as i32,
                y0: y0 as i32,
                rows: TileRows {
                    data: self.data.add(index * TILE_PIXELS),
                    stride: tile,
                    width: tile.min(self.width - x0),
                    height: tile.min(self.height - y0),
                    _rows: PhantomData,
                },
                hiz: &mut *self.hiz.add(index),
            }
        }
    }
}
