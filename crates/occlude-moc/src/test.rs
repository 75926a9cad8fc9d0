//! Occlusion tests against the buffer: screen rectangles and boxes.

use crate::buffer::MaskedBuffer;
use glam::{Mat4, Vec2, Vec3};

/// A test's answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Visibility {
    /// Some part may be seen (always the answer when in doubt).
    Visible,
    /// Hidden behind occluders.
    Occluded,
    /// Entirely outside the view frustum.
    ViewCulled,
}

impl MaskedBuffer {
    /// Tests the screen rectangle from `min_px` to `max_px` (pixels, y down) whose
    /// nearest point has NDC depth `nearest_depth`. Every pixel the rectangle
    /// touches is tested (rounded outward). Cost: the subtiles it overlaps.
    pub fn test_rect(&self, min_px: Vec2, max_px: Vec2, nearest_depth: f32) -> Visibility {
        if !(min_px.is_finite() && max_px.is_finite()) || nearest_depth.is_nan() {
            return Visibility::Visible;
        }
        let x0 = min_px.x.floor().max(0.0) as u32;
        let y0 = min_px.y.floor().max(0.0) as u32;
        let x1 = (max_px.x.floor().max(-1.0) as i64).min(self.width as i64 - 1);
        let y1 = (max_px.y.floor().max(-1.0) as i64).min(self.height as i64 - 1);
        if x1 < x0 as i64 || y1 < y0 as i64 {
            return Visibility::ViewCulled;
        }
        for sy in y0 / 4..=(y1 as u32) / 4 {
            for sx in x0 / 8..=(x1 as u32) / 8 {
                let s = self.subtile(sx, sy);
                let bound = if s.mask == 0 { s.reference } else { s.reference.max(s.working) };
                if nearest_depth < bound {
                    return Visibility::Visible;
                }
            }
        }
        Visibility::Occluded
    }

    /// Tests the box from `min` to `max` seen through `view_proj` (to wgpu clip
    /// space). A box reaching the near plane is visible; one wholly outside a
    /// frustum plane is [`ViewCulled`](Visibility::ViewCulled).
    pub fn test_aabb(&self, min: Vec3, max: Vec3, view_proj: Mat4) -> Visibility {
        let corners = (0..8).map(|i| {
            let p = Vec3::new(
                if i & 1 == 0 { min.x } else { max.x },
                if i & 2 == 0 { min.y } else { max.y },
                if i & 4 == 0 { min.z } else { max.z },
            );
            view_proj * p.extend(1.0)
        });
        let c: Vec<_> = corners.collect();
        if c.iter().any(|v| !v.is_finite()) {
            return Visibility::Visible;
        }
        let out = |f: &dyn Fn(&glam::Vec4) -> bool| c.iter().all(f);
        if out(&|v| v.x < -v.w)
            || out(&|v| v.x > v.w)
            || out(&|v| v.y < -v.w)
            || out(&|v| v.y > v.w)
            || out(&|v| v.z > v.w)
        {
            return Visibility::ViewCulled;
        }
        if c.iter().any(|v| v.z <= 0.0 || v.w <= 0.0) {
            return Visibility::Visible;
        }
        let (w, h) = (self.width as f32, self.height as f32);
        let mut lo = Vec2::splat(f32::INFINITY);
        let mut hi = Vec2::splat(f32::NEG_INFINITY);
        let mut nearest = f32::INFINITY;
        for v in &c {
            let s = Vec2::new((v.x / v.w + 1.0) * 0.5 * w, (1.0 - v.y / v.w) * 0.5 * h);
            lo = lo.min(s);
            hi = hi.max(s);
            nearest = nearest.min(v.z / v.w);
        }
        // Outward by a pixel against rounding in the projection.
        let nearest = nearest - nearest.abs() * 1e-6;
        match self.test_rect(lo - 1.0, hi + 1.0, nearest) {
            Visibility::ViewCulled => Visibility::ViewCulled,
            v => v,
        }
    }
}
