//! The buffer: per-subtile coverage masks and two depth layers, and their
//! update.
//!
//! A merge of a triangle (mask `C`, depth `t`) into the working layer (mask
//! `M`, depth `w`) gives `M | C` the depth `max(w, t)`, which bounds both; the
//! working layer is only discarded (its pixels falling back to the reference
//! depth) while `w <= reference`, and a triangle at or beyond the reference
//! depth is ignored, so the invariant `w <= reference` holds. A full mask moves
//! the working depth into the reference layer.
//!
//! Pixels outside the screen (padding of the last tiles) count as covered by
//! every triangle touching their subtile; tests never read them.

/// How a subtile takes in a triangle's coverage.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum MergeMode {
    /// The paper's heuristic (section 3): when the triangle is farther from the
    /// working layer than the working layer is from the reference, the working
    /// layer is discarded before the merge. Tighter bounds on layered scenes.
    #[default]
    LayerMerge,
    /// Always merge into the working layer; simpler, never discards.
    QuickMask,
}

impl MergeMode {
    /// The mode's short name: `layer` or `quick`.
    pub fn name(self) -> &'static str {
        match self {
            MergeMode::LayerMerge => "layer",
            MergeMode::QuickMask => "quick",
        }
    }
}

impl std::fmt::Display for MergeMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for MergeMode {
    type Err = ();
    /// Parses [`MergeMode::name`].
    fn from_str(s: &str) -> Result<Self, ()> {
        [MergeMode::LayerMerge, MergeMode::QuickMask].into_iter().find(|m| m.name() == s).ok_or(())
    }
}

/// Errors from building or configuring a buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Error {
    /// Width or height was zero.
    ZeroSize,
    /// Sub-pixel bits above [`MAX_SUBPIXEL_BITS`](crate::MAX_SUBPIXEL_BITS).
    SubpixelBits(u32),
}

impl std::fmt::Display for Error {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Error::ZeroSize => write!(f, "occlusion buffer width and height must be at least 1"),
            Error::SubpixelBits(bits) => {
                write!(f, "{bits} sub-pixel bits requested, the buffer snaps to at most {}", crate::MAX_SUBPIXEL_BITS)
            }
        }
    }
}

impl std::error::Error for Error {}

/// One 8x4-pixel subtile: bit `x + 8 * y` of `mask` set means the pixel is bounded
/// by `working`, clear means by `reference`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Subtile {
    pub mask: u32,
    pub working: f32,
    pub reference: f32,
}

impl Subtile {
    /// Merges a triangle covering `cover` of this subtile (pixels outside the
    /// screen included) with its depth bounded by `depth` there.
    #[inline]
    pub(crate) fn merge(&mut self, cover: u32, depth: f32, mode: MergeMode) {
        if depth.is_nan() || depth >= self.reference {
            return;
        }
        if mode == MergeMode::LayerMerge
            && self.mask != 0
            && (depth - self.working).abs() > self.reference - self.working
        {
            self.mask = 0;
        }
        self.working = if self.mask != 0 && self.working > depth { self.working } else { depth };
        self.mask |= cover;
        if self.mask == u32::MAX {
            self.reference = self.working;
            self.mask = 0;
        }
    }
}

/// The eight subtiles of a 32x8-pixel tile: lanes 0-3 the upper subtile row's
/// four from left to right, lanes 4-7 the lower row's. Stored field by field,
/// each field 32 bytes and the tile 96, so that the rasterizer loads, merges
/// and stores a tile as three registers (one a field), and a tile touches
/// two cache lines.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub(crate) struct Tile {
    pub mask: [u32; 8],
    pub working: [f32; 8],
    pub reference: [f32; 8],
}

impl Tile {
    /// The lane of subtile (`sx`, `sy`) in its tile.
    #[inline]
    pub(crate) fn lane(sx: u32, sy: u32) -> usize {
        (sx % 4 + 4 * (sy % 2)) as usize
    }

    /// Subtile `l` of the tile.
    #[inline]
    pub(crate) fn get(&self, l: usize) -> Subtile {
        Subtile { mask: self.mask[l], working: self.working[l], reference: self.reference[l] }
    }

    /// Replaces subtile `l` of the tile.
    #[inline]
    pub(crate) fn set(&mut self, l: usize, s: Subtile) {
        (self.mask[l], self.working[l], self.reference[l]) = (s.mask, s.working, s.reference);
    }

    /// [`Subtile::merge`] of each lane whose `cover` is not empty.
    #[inline]
    pub(crate) fn merge(&mut self, cover: &[u32; 8], depth: &[f32; 8], mode: MergeMode) {
        for l in 0..8 {
            if cover[l] != 0 {
                let mut s = self.get(l);
                s.merge(cover[l], depth[l], mode);
                self.set(l, s);
            }
        }
    }
}

/// Mask of the pixels of subtile (`sx`, `sy`) outside a `width` x `height`
/// screen.
#[inline]
pub(crate) fn outside_mask(width: u32, height: u32, sx: u32, sy: u32) -> u32 {
    let cols = width.saturating_sub(sx * 8).min(8);
    let rows = height.saturating_sub(sy * 4).min(4);
    let row = (1u32 << cols) - 1;
    !(0..rows).fold(0, |m, r| m | row << (8 * r))
}

const CLEAR: Tile = Tile { mask: [0; 8], working: [0.0; 8], reference: [1.0; 8] };

/// A conservative, low-resolution-in-depth occlusion buffer.
///
/// Render occluders with [`render_triangles`](Self::render_triangles), then ask
/// whether boxes or rectangles are hidden ([`test_aabb`](Self::test_aabb),
/// [`test_rect`](Self::test_rect)). A test never says
/// [`Occluded`](crate::Visibility::Occluded) for something an exact depth buffer
/// of the same occluders would show; it may say visible for hidden things.
///
/// Memory: 12 bytes per 32 pixels (the width padded to 32 and the height to
/// 8). Cost: proportional to the subtiles each triangle's bounding box
/// touches.
///
/// ```
/// use glam::{Mat4, Vec3};
/// use occlude_moc::{CullMode, MaskedBuffer, Visibility};
/// let mut buffer = MaskedBuffer::new(64, 48).unwrap();
/// // A quad filling the screen at NDC depth 0.5.
/// let p = [Vec3::new(-1.0, -1.0, 0.5), Vec3::new(1.0, -1.0, 0.5), Vec3::new(1.0, 1.0, 0.5), Vec3::new(-1.0, 1.0, 0.5)];
/// buffer.render_triangles(&p, &[0, 1, 2, 0, 2, 3], Mat4::IDENTITY, CullMode::Back);
/// let behind = buffer.test_aabb(Vec3::new(-0.2, -0.2, 0.7), Vec3::new(0.2, 0.2, 0.8), Mat4::IDENTITY);
/// assert_eq!(behind, Visibility::Occluded);
/// let in_front = buffer.test_aabb(Vec3::new(-0.2, -0.2, 0.2), Vec3::new(0.2, 0.2, 0.3), Mat4::IDENTITY);
/// assert_eq!(in_front, Visibility::Visible);
/// ```
#[derive(Clone, Debug)]
pub struct MaskedBuffer {
    pub(crate) width: u32,
    pub(crate) height: u32,
    /// Subtiles per row (the width padded to whole 32-pixel tiles).
    pub(crate) cols: u32,
    /// Subtile rows (the height padded to whole 8-pixel tiles).
    pub(crate) rows: u32,
    /// Tile row by tile row (two subtile rows), `cols / 4` tiles a row.
    pub(crate) tiles: Vec<Tile>,
    /// The merge rule used by renders.
    pub merge: MergeMode,
    /// Fractional bits of the grid occluder vertices are snapped to
    /// ([`set_subpixel_bits`](Self::set_subpixel_bits)).
    pub(crate) subpixel_bits: u32,
}

impl MaskedBuffer {
    /// A cleared buffer of `width` x `height` pixels; an error if either is zero.
    pub fn new(width: u32, height: u32) -> Result<Self, Error> {
        let mut b = MaskedBuffer {
            width: 0,
            height: 0,
            cols: 0,
            rows: 0,
            tiles: Vec::new(),
            merge: MergeMode::default(),
            subpixel_bits: crate::SUBPIXEL_BITS,
        };
        b.resize(width, height)?;
        Ok(b)
    }

    /// Changes the resolution and clears; reuses the allocation where it fits.
    pub fn resize(&mut self, width: u32, height: u32) -> Result<(), Error> {
        if width == 0 || height == 0 {
            return Err(Error::ZeroSize);
        }
        self.width = width;
        self.height = height;
        self.cols = width.div_ceil(32) * 4;
        self.rows = height.div_ceil(8) * 2;
        self.tiles.clear();
        self.tiles.resize((self.cols / 4 * self.rows / 2) as usize, CLEAR);
        Ok(())
    }

    /// Sets the sub-pixel precision of the rasterizer whose coverage the buffer
    /// must stay within: occluder vertices are snapped to `1 / 2^bits` pixel as
    /// it snaps them ([`SUBPIXEL_BITS`](crate::SUBPIXEL_BITS), 8, by default: the
    /// soft backend, lavapipe and Direct3D 11-class GPUs). An error above
    /// [`MAX_SUBPIXEL_BITS`](crate::MAX_SUBPIXEL_BITS), where the buffer's edge
    /// functions would no longer be exact; the setting is then unchanged.
    pub fn set_subpixel_bits(&mut self, bits: u32) -> Result<(), Error> {
        if bits > crate::MAX_SUBPIXEL_BITS {
            return Err(Error::SubpixelBits(bits));
        }
        self.subpixel_bits = bits;
        Ok(())
    }

    /// The sub-pixel bits occluder vertices are snapped with.
    pub fn subpixel_bits(&self) -> u32 {
        self.subpixel_bits
    }

    /// Subtile (`sx`, `sy`).
    #[inline]
    pub(crate) fn subtile(&self, sx: u32, sy: u32) -> Subtile {
        self.tiles[self.tile_index(sx, sy)].get(Tile::lane(sx, sy))
    }

    /// The index in `tiles` of the tile of subtile (`sx`, `sy`).
    #[inline]
    pub(crate) fn tile_index(&self, sx: u32, sy: u32) -> usize {
        ((sy / 2) * (self.cols / 4) + sx / 4) as usize
    }

    /// Screen width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Screen height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Forgets every occluder: all pixels at the far plane (depth 1).
    pub fn clear(&mut self) {
        self.tiles.fill(CLEAR);
    }

    /// The bound on the stored depth of every pixel, row by row (`width * height`
    /// values, 1 where nothing was drawn): for debugging and viewers.
    pub fn depth_image(&self, out: &mut Vec<f32>) {
        out.clear();
        for y in 0..self.height {
            for x in 0..self.width {
                let s = self.subtile(x / 8, y / 4);
                let bit = (x % 8) + 8 * (y % 4);
                out.push(if s.mask >> bit & 1 == 1 { s.working } else { s.reference });
            }
        }
    }
}
