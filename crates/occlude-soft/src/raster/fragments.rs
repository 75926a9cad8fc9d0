//! Every fragment of a triangle, one pixel at a time, by the rasterizer's
//! rules in their plainest form: each set-up triangle's edge functions
//! evaluated at every pixel of its bounding box, the depth from its depth
//! plane. The fragments and depths are the ones [`super::Rasterizer`]
//! tests, bit for bit; this walk is for passes that need each fragment's
//! pixel (the item buffer) and for the rasterizer's reference in tests,
//! not for speed.

use glam::Vec4;

use super::clip::Polygon;
use super::setup::{setup_triangle, SetupTri, Viewport};

/// Walks the fragments of clip-space triangles on a `width` x `height`
/// image (pixel `(0, 0)` at the top left).
pub struct Fragments {
    viewport: Viewport,
    poly: Polygon,
    setups: Vec<SetupTri>,
}

impl Fragments {
    /// A walker for a `width` x `height` image.
    pub fn new(width: u32, height: u32) -> Self {
        Self { viewport: Viewport::new(width, height), poly: Polygon::new(), setups: Vec::new() }
    }

    /// Calls `f(x, y, depth)` for every pixel the triangle `tri` covers
    /// (after near-plane clipping; none when `cull_back` and it faces
    /// away), row by row.
    pub fn each(&mut self, tri: &[Vec4; 3], cull_back: bool, mut f: impl FnMut(u32, u32, f32)) {
        if self.viewport.width == 0 || self.viewport.height == 0 {
            return;
        }
        self.setups.clear();
        let setups = &mut self.setups;
        setup_triangle(tri, cull_back, 0, self.viewport, &mut self.poly, |t| setups.push(t));
        for s in &self.setups {
            let edges = s.edges();
            for dy in 0..=s.y1 - s.y0 {
                let plane = s.row_plane(dy);
                for dx in 0..=s.x1 - s.x0 {
                    let covered =
                        edges.iter().all(|e| e.origin + e.step_x * i64::from(dx) + e.step_y * i64::from(dy) >= 0);
                    if covered {
                        f((s.x0 + dx) as u32, (s.y0 + dy) as u32, plane.depth(dx));
                    }
                }
            }
        }
    }
}
