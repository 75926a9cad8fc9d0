//! Occluder rasterization (portable scalar path): per subtile coverage masks from
//! edge functions at pixel centres, and the triangle's farthest depth there.

use crate::buffer::MaskedBuffer;
use crate::clip::clip_near;
use glam::{DVec3, Mat4, Vec3};

/// What a [`MaskedBuffer::render_triangles`] call rasterized: the measure of
/// its cost.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RenderWork {
    /// Triangles set up after near-plane clipping (a clipped triangle may
    /// become two), before back-face and empty-area rejection.
    pub triangles: u64,
    /// 32x8-pixel tiles overlapped by the screen bounding boxes of the
    /// triangles that were rasterized.
    pub tiles: u64,
}

/// Which triangles are drawn, by winding on screen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum CullMode {
    /// Skip triangles whose vertices run clockwise in NDC (y up): wgpu's default
    /// front face is counter-clockwise.
    #[default]
    Back,
    /// Draw both windings.
    None,
}

impl MaskedBuffer {
    /// Renders indexed occluder triangles, `model_to_clip` taking `positions` to
    /// clip space (wgpu conventions). Triangles crossing the near plane are
    /// clipped; index triples with an out-of-range index, NaN vertices and
    /// zero-area triangles are skipped. Cost: per triangle, the subtiles of its
    /// bounding box. Returns the work done, for callers that account for it
    /// (a simulated clock).
    pub fn render_triangles(
        &mut self,
        positions: &[Vec3],
        indices: &[u32],
        model_to_clip: Mat4,
        cull: CullMode,
    ) -> RenderWork {
        let mut work = RenderWork::default();
        for tri in indices.chunks_exact(3) {
            let Some(v) = tri.iter().map(|&i| positions.get(i as usize)).collect::<Option<Vec<_>>>() else {
                continue;
            };
            let clip = [v[0], v[1], v[2]].map(|p| model_to_clip * p.extend(1.0));
            let mut poly = [glam::Vec4::ZERO; 4];
            let n = clip_near(clip, &mut poly);
            if n < 3 {
                continue;
            }
            let (w, h) = (self.width as f64, self.height as f64);
            let screen: Vec<DVec3> = poly[..n]
                .iter()
                .map(|c| {
                    let (x, y, z, cw) = (c.x as f64, c.y as f64, c.z as f64, c.w as f64);
                    DVec3::new((x / cw + 1.0) * 0.5 * w, (1.0 - y / cw) * 0.5 * h, z / cw)
                })
                .collect();
            for k in 1..n - 1 {
                work.tiles += self.draw_screen([screen[0], screen[k], screen[k + 1]], cull);
                work.triangles += 1;
            }
        }
        work
    }

    /// Rasterizes one triangle in screen space (pixels, y down; z = NDC depth);
    /// returns how many 32x8-pixel tiles its clipped bounding box overlaps (0
    /// when it is skipped).
    fn draw_screen(&mut self, mut t: [DVec3; 3], cull: CullMode) -> u64 {
        if t.iter().any(|p| !p.is_finite() || p.z < 0.0) {
            return 0;
        }
        // Signed area, positive for counter-clockwise in NDC (clockwise on screen).
        let area = (t[1].x - t[0].x) * (t[2].y - t[0].y) - (t[2].x - t[0].x) * (t[1].y - t[0].y);
        if area == 0.0 || (cull == CullMode::Back && area > 0.0) {
            return 0;
        }
        // Edge functions below are positive inside for a positive area.
        if area < 0.0 {
            t.swap(1, 2);
        }
        let area = area.abs();
        // Edge i: e(p) > 0 inside; a pixel centre on the edge counts on one side
        // only (for one of two triangles sharing the edge, by the edge's direction),
        // so that a shared edge leaves no hole. Both inclusions are pixels whose
        // centre the triangle covers (its closure).
        let edges: Vec<(f64, f64, f64, bool)> = (0..3)
            .map(|i| {
                let (a, b) = (t[i], t[(i + 1) % 3]);
                let (ex, ey) = (a.y - b.y, b.x - a.x);
                (ex, ey, -(ex * a.x + ey * a.y), ex > 0.0 || (ex == 0.0 && ey > 0.0))
            })
            .collect();
        // Depth plane z = zx * x + zy * y + z0 (cofactors of the vertex matrix).
        let (d1, d2) = (t[1] - t[0], t[2] - t[0]);
        let n = d1.cross(d2);
        let (zx, zy) = (-n.x / n.z, -n.y / n.z);
        let z0 = t[0].z - zx * t[0].x - zy * t[0].y;
        let zmax = t[0].z.max(t[1].z).max(t[2].z);
        let lo_x = t.iter().map(|p| p.x).fold(f64::INFINITY, f64::min).max(0.0);
        let hi_x = t.iter().map(|p| p.x).fold(f64::NEG_INFINITY, f64::max).min(self.width as f64);
        let lo_y = t.iter().map(|p| p.y).fold(f64::INFINITY, f64::min).max(0.0);
        let hi_y = t.iter().map(|p| p.y).fold(f64::NEG_INFINITY, f64::max).min(self.height as f64);
        if lo_x >= hi_x || lo_y >= hi_y || area < 1e-12 {
            return 0;
        }
        let (sx0, sx1) = ((lo_x / 8.0) as u32, ((hi_x / 8.0).ceil() as u32).min(self.cols));
        let (sy0, sy1) = ((lo_y / 4.0) as u32, ((hi_y / 4.0).ceil() as u32).min(self.rows));
        let tiles = u64::from(sx1.div_ceil(4) - sx0 / 4) * u64::from(sy1.div_ceil(2) - sy0 / 2);
        for sy in sy0..sy1 {
            for sx in sx0..sx1 {
                let (bx, by) = ((sx * 8) as f64, (sy * 4) as f64);
                // Edge functions are affine: over the subtile's pixel centres they
                // are extreme at the four corner centres. All positive for an edge
                // means every centre passes it; all negative, none does.
                let centres = [(bx + 0.5, by + 0.5), (bx + 7.5, by + 0.5), (bx + 0.5, by + 3.5), (bx + 7.5, by + 3.5)];
                let extremes = edges.iter().map(|&(a, b, c, _)| {
                    centres
                        .iter()
                        .map(|&(x, y)| a * x + b * y + c)
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), e| (lo.min(e), hi.max(e)))
                });
                let mut all_inside = true;
                let mut none = false;
                for (lo, hi) in extremes {
                    all_inside &= lo > 0.0;
                    none |= hi < 0.0;
                }
                if none {
                    continue;
                }
                let mut cover = if all_inside { u32::MAX } else { 0 };
                for i in (0..32u32).filter(|_| !all_inside) {
                    let (px, py) = (bx + (i % 8) as f64 + 0.5, by + (i / 8) as f64 + 0.5);
                    if edges.iter().all(|&(a, b, c, on)| {
                        let e = a * px + b * py + c;
                        e > 0.0 || (on && e == 0.0)
                    }) {
                        cover |= 1 << i;
                    }
                }
                if cover == 0 {
                    continue;
                }
                let corner_max = [(bx, by), (bx + 8.0, by), (bx, by + 4.0), (bx + 8.0, by + 4.0)]
                    .iter()
                    .map(|&(x, y)| zx * x + zy * y + z0)
                    .fold(f64::NEG_INFINITY, f64::max);
                let depth = corner_max.min(zmax);
                // Round farther: the f64 bound nudged up, then up to the next f32.
                let depth = depth + depth.abs() * 1e-9 + 1e-12;
                let mut d = depth as f32;
                if (d as f64) < depth {
                    d = f32::from_bits(d.to_bits() + if d >= 0.0 { 1 } else { 0 });
                }
                self.merge(sx, sy, cover, d);
            }
        }
        tiles
    }
}
