//! The hierarchical item buffer of Engelhardt and Dachsbacher, "Granular
//! Visibility Queries on the GPU" (I3D 2009), section 3.2: exact visible-pixel
//! counts per object, per instance and per screen tile from one pass.
//!
//! The screen is divided into `2^t x 2^t` tiles. Every instance of every
//! object gets a square of `2^t x 2^t` bins, and a pixel's item ID names the
//! instance drawn there and the tile the pixel lies in (the paper's
//! equation):
//!
//! `ID = baseID + instanceIndex * 2^(2t) + x + y * 2^t`
//!
//! An object is a mesh, drawn as one instanced draw of all its instances;
//! `baseID` is its first instance's slot times `2^(2t)`. Counting the IDs of
//! the image gives the 2D histogram (the paper's Figure 4), and summing its
//! bins gives every instance's, object's and tile's visible pixels: the
//! paper's mip levels of the histogram, summed here directly.
//!
//! This module is the layout and the CPU reference of the counting; the
//! backends render the item image (the soft backend with its exact
//! rasterizer, the wgpu backend in a render pass) and count it (on the CPU,
//! or with atomics in compute).

use crate::scene::Scene;
use std::ops::Range;
use thiserror::Error;

/// The item ID of a pixel no instance covers.
pub const NO_ITEM: u32 = u32::MAX;

/// Largest tile level `t`: `256 x 256` tiles.
pub const MAX_LEVEL: u32 = 8;

/// Why an item-buffer layout cannot be made.
#[derive(Debug, Error, PartialEq, Eq)]
pub enum ItemBufferError {
    /// The tile level is above [`MAX_LEVEL`].
    #[error("item-buffer tile level {0} is above {MAX_LEVEL} (at most 2^{MAX_LEVEL} tiles per side)")]
    Level(u32),
    /// The histogram would need IDs beyond 32 bits.
    #[error("{instances} instances with {tiles} tiles each need more item IDs than 32 bits hold")]
    TooManyBins {
        /// Instances in the layout.
        instances: u64,
        /// Tiles per instance.
        tiles: u64,
    },
    /// A candidate names no instance of the scene.
    #[error("instance {0} is not in the scene")]
    NoInstance(u32),
}

/// How a backend counts the pixels of occlusion queries (`occlude bench
/// --queries`). Both give every query its exact count of box fragments that
/// pass the depth test; they differ in how the GPU is asked, and so in cost.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum QueryMode {
    /// One hardware occlusion query per query.
    #[default]
    Hardware,
    /// The queries recorded between two submissions counted as one batch:
    /// their boxes drawn as one pass without depth writes, each fragment
    /// passing the depth test adding one to its query's bin with an atomic
    /// (the item buffer's histogram, counted at the fragment because the
    /// boxes of a batch overlap), the bins read back together.
    Hib,
}

impl std::str::FromStr for QueryMode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "hardware" => Ok(Self::Hardware),
            "hib" => Ok(Self::Hib),
            _ => Err(format!("unknown query mode '{s}': expected 'hardware' or 'hib'")),
        }
    }
}

impl std::fmt::Display for QueryMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Hardware => "hardware",
            Self::Hib => "hib",
        })
    }
}

/// Which instances an item pass draws, grouped into objects (one per mesh,
/// in mesh order; its instances in the order given), and the tile level:
/// the meaning of every item ID.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ItemLayout {
    level: u32,
    /// Scene instance of each slot, the slots of one object consecutive.
    slots: Vec<u32>,
    /// Object of each slot.
    slot_object: Vec<u32>,
    /// First slot of each object, then the slot count.
    object_first: Vec<u32>,
    /// Mesh of each object.
    object_mesh: Vec<u32>,
}

impl ItemLayout {
    /// The layout of `candidates` (instances of `scene`) at tile level
    /// `level` (`2^level x 2^level` tiles).
    pub fn new(scene: &Scene, candidates: &[u32], level: u32) -> Result<Self, ItemBufferError> {
        if level > MAX_LEVEL {
            return Err(ItemBufferError::Level(level));
        }
        let tiles = 1u64 << (2 * level);
        if (candidates.len() as u64) * tiles >= u64::from(NO_ITEM) {
            return Err(ItemBufferError::TooManyBins { instances: candidates.len() as u64, tiles });
        }
        let mut by_mesh: Vec<(u32, u32)> = Vec::with_capacity(candidates.len());
        for (k, &i) in candidates.iter().enumerate() {
            let instance = scene.instances.get(i as usize).ok_or(ItemBufferError::NoInstance(i))?;
            by_mesh.push((instance.mesh, k as u32));
        }
        by_mesh.sort_unstable();
        let mut layout = Self {
            level,
            slots: Vec::new(),
            slot_object: Vec::new(),
            object_first: Vec::new(),
            object_mesh: Vec::new(),
        };
        for (mesh, k) in by_mesh {
            if layout.object_mesh.last() != Some(&mesh) {
                layout.object_first.push(layout.slots.len() as u32);
                layout.object_mesh.push(mesh);
            }
            layout.slot_object.push(layout.object_mesh.len() as u32 - 1);
            layout.slots.push(candidates[k as usize]);
        }
        layout.object_first.push(layout.slots.len() as u32);
        Ok(layout)
    }

    /// The tile level `t`.
    pub fn level(&self) -> u32 {
        self.level
    }

    /// Tiles per side of the screen, `2^t`.
    pub fn tiles_per_side(&self) -> u32 {
        1 << self.level
    }

    /// Tiles of the screen, `2^(2t)`: bins per instance.
    pub fn tiles(&self) -> u32 {
        1 << (2 * self.level)
    }

    /// The scene instance in each slot, slot by slot: the order the item
    /// pass draws them in (so that of two fragments at equal depth, both
    /// backends keep the earlier slot's).
    pub fn slots(&self) -> &[u32] {
        &self.slots
    }

    /// Objects (meshes with instances in the layout).
    pub fn objects(&self) -> usize {
        self.object_mesh.len()
    }

    /// The slots of object `object`: its instances, drawn by one instanced
    /// draw.
    pub fn object_slots(&self, object: usize) -> Range<u32> {
        self.object_first[object]..self.object_first[object + 1]
    }

    /// The mesh object `object` draws.
    pub fn object_mesh(&self, object: usize) -> u32 {
        self.object_mesh[object]
    }

    /// Bins of the histogram: slots times tiles.
    pub fn bins(&self) -> usize {
        self.slots.len() << (2 * self.level)
    }

    /// The item ID of slot `slot` in tile `tile` (`x + y * 2^t`): the
    /// paper's `baseID + instanceIndex * 2^(2t) + x + y * 2^t`.
    pub fn id(&self, slot: u32, tile: u32) -> u32 {
        (slot << (2 * self.level)) + tile
    }

    /// The tile (`x + y * 2^t`) of pixel `(x, y)` of a `width` x `height`
    /// image: tile column `x * 2^t / width`, row `y * 2^t / height`.
    pub fn tile_of(&self, x: u32, y: u32, width: u32, height: u32) -> u32 {
        let tx = (u64::from(x) << self.level) / u64::from(width);
        let ty = (u64::from(y) << self.level) / u64::from(height);
        (tx + (ty << self.level)) as u32
    }
}

/// The counts of one item pass: the histogram and its sums.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ItemCounts {
    /// The 2D histogram: visible pixels of each slot in each tile, at
    /// [`ItemLayout::id`].
    pub bins: Vec<u32>,
    /// Visible pixels of each slot (instance).
    pub instances: Vec<u64>,
    /// Visible pixels of each object (all its instances).
    pub objects: Vec<u64>,
    /// Visible pixels in each tile (all instances).
    pub tiles: Vec<u64>,
}

impl ItemCounts {
    /// Counts the item image `items` (one ID per pixel, [`NO_ITEM`] where
    /// nothing was drawn) into `layout`'s histogram and sums it.
    ///
    /// # Panics
    /// If an ID is outside the layout.
    pub fn count(layout: &ItemLayout, items: &[u32]) -> Self {
        let mut bins = vec![0u32; layout.bins()];
        for &id in items.iter().filter(|&&id| id != NO_ITEM) {
            bins[id as usize] += 1;
        }
        Self::reduce(layout, bins)
    }

    /// The sums of the histogram `bins` (the paper's mip levels): per slot,
    /// per object and per tile.
    pub fn reduce(layout: &ItemLayout, bins: Vec<u32>) -> Self {
        let tiles = layout.tiles() as usize;
        let instances: Vec<u64> =
            bins.chunks_exact(tiles).map(|slot| slot.iter().map(|&c| u64::from(c)).sum()).collect();
        let objects =
            (0..layout.objects()).map(|o| layout.object_slots(o).map(|s| instances[s as usize]).sum()).collect();
        let mut per_tile = vec![0u64; tiles];
        for slot in bins.chunks_exact(tiles) {
            for (t, &c) in per_tile.iter_mut().zip(slot) {
                *t += u64::from(c);
            }
        }
        Self { bins, instances, objects, tiles: per_tile }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Aabb;
    use crate::scene::{Instance, Mesh};
    use glam::{Mat4, Vec3};

    fn scene(meshes_of_instances: &[u32]) -> Scene {
        let mesh = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]);
        let mut scene = Scene::new("items");
        for _ in 0..3 {
            scene.add_mesh(mesh.clone());
        }
        scene.instances = meshes_of_instances
            .iter()
            .map(|&mesh| Instance {
                mesh,
                transform: Mat4::IDENTITY,
                material: 0,
                bounds: Aabb::default(),
                enabled: true,
            })
            .collect();
        scene.material_count = 1;
        scene
    }

    #[test]
    fn ids_follow_the_papers_figure_4() {
        // Figure 4: t = 2, objects of 5, 3 and 4 instances; the second
        // object's first instance starts at bin 80.
        let s = scene(&[0, 0, 0, 0, 0, 1, 1, 1, 2, 2, 2, 2]);
        let all: Vec<u32> = (0..12).collect();
        let layout = ItemLayout::new(&s, &all, 2).unwrap();
        assert_eq!((layout.tiles_per_side(), layout.tiles(), layout.bins(), layout.objects()), (4, 16, 192, 3));
        assert_eq!(layout.object_slots(1), 5..8);
        assert_eq!(layout.id(layout.object_slots(1).start, 0), 80);
        assert_eq!(layout.id(layout.object_slots(2).start, 0), 128);
        assert_eq!(layout.id(1, 2 + 3 * 4), 16 + 14);
        // Tiles of a 100x60 image: columns of 25 pixels, rows of 15.
        assert_eq!(layout.tile_of(0, 0, 100, 60), 0);
        assert_eq!(layout.tile_of(24, 14, 100, 60), 0);
        assert_eq!(layout.tile_of(25, 15, 100, 60), 5);
        assert_eq!(layout.tile_of(99, 59, 100, 60), 15);
    }

    #[test]
    fn candidates_are_grouped_by_mesh_in_their_order() {
        let s = scene(&[2, 0, 2, 1, 0]);
        let layout = ItemLayout::new(&s, &[4, 0, 1, 2, 3], 0).unwrap();
        assert_eq!(layout.slots(), &[4, 1, 3, 0, 2]);
        assert_eq!((layout.objects(), layout.object_mesh(2), layout.object_slots(2)), (3, 2, 3..5));
        assert_eq!(ItemLayout::new(&s, &[7], 0), Err(ItemBufferError::NoInstance(7)));
        assert_eq!(ItemLayout::new(&s, &[0], MAX_LEVEL + 1), Err(ItemBufferError::Level(MAX_LEVEL + 1)));
        assert!(matches!(ItemLayout::new(&s, &[0; 70_000], MAX_LEVEL), Err(ItemBufferError::TooManyBins { .. })));
    }

    #[test]
    fn query_modes_parse_and_print() {
        for mode in [QueryMode::Hardware, QueryMode::Hib] {
            assert_eq!(mode.to_string().parse::<QueryMode>(), Ok(mode));
        }
        assert_eq!(QueryMode::default(), QueryMode::Hardware);
        assert!("occlusion".parse::<QueryMode>().unwrap_err().contains("'hardware' or 'hib'"));
    }

    #[test]
    fn counts_sum_to_instances_objects_and_tiles() {
        let s = scene(&[0, 0, 1]);
        let layout = ItemLayout::new(&s, &[0, 1, 2], 1).unwrap();
        // A 2x2 image, one pixel per tile: slot 0 in tiles 0 and 1, slot 2
        // in tile 3, nothing in tile 2.
        let items = [layout.id(0, 0), layout.id(0, 1), NO_ITEM, layout.id(2, 3)];
        let c = ItemCounts::count(&layout, &items);
        assert_eq!(c.bins, [1, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1]);
        assert_eq!(c.instances, [2, 0, 1]);
        assert_eq!(c.objects, [2, 1]);
        assert_eq!(c.tiles, [1, 1, 0, 1]);
    }
}
