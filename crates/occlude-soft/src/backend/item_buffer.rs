//! The hierarchical item buffer (Engelhardt and Dachsbacher 2009, section
//! 3.2; layout and counting in [`occlude_core::item_buffer`]) on the soft
//! backend: the item pass walks every fragment with the rasterizer's rules
//! ([`Fragments`]), keeps the nearest one's item ID per pixel (depth test
//! less, slots in layout order), and counts the image on the CPU. Its counts
//! are the exact reference the GPU's are checked against.

use super::SoftBackend;
use crate::raster::Fragments;
use occlude_core::{Camera, ItemCounts, ItemLayout, NO_ITEM};

impl SoftBackend {
    /// Item pass, outside any frame's clock: draws `layout`'s instances from
    /// `camera` into an item image and a depth image of their own and counts
    /// the image: every slot's, object's and tile's visible pixels. The
    /// depth image replaces the backend's ([`occlude_core::Instruments::depth_image`]
    /// reads it), as after an oracle pass.
    pub fn item_buffer(&mut self, camera: &Camera, layout: &ItemLayout) -> ItemCounts {
        self.flush();
        self.view_projection = camera.view_projection();
        let (width, height) = (self.depth.width(), self.depth.height());
        let mut depth = vec![1.0f32; width as usize * height as usize];
        let mut items = vec![NO_ITEM; depth.len()];
        let mut fragments = Fragments::new(width, height);
        for (slot, &instance) in layout.slots().iter().enumerate() {
            self.push_instance_triangles(instance);
            for tri in &self.triangles {
                fragments.each(tri, false, |x, y, z| {
                    let p = y as usize * width as usize + x as usize;
                    if z < depth[p] {
                        depth[p] = z;
                        items[p] = layout.id(slot as u32, layout.tile_of(x, y, width, height));
                    }
                });
            }
            self.triangles.clear();
        }
        self.depth.clear();
        for (p, &d) in depth.iter().enumerate() {
            self.depth.set(p as u32 % width, p as u32 / width, d);
        }
        ItemCounts::count(layout, &items)
    }
}
