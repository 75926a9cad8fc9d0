//! `occlude bench --paper gvq`, Table 3: culling parts of one heavy object
//! (Engelhardt and Dachsbacher, section 4.2, "Image Space Culling:
//! Displacement Mapping").
//!
//! The heavy object is a finely tessellated sphere ([`SPHERE_SEGMENTS`]
//! squared times two triangles, near the paper's lizard of 7132) whose
//! triangles are displaced as the paper's geometry shader does it: each is
//! extruded along its vertex normals by [`DISPLACEMENT`] into a prism, split
//! into three tetrahedra (12 triangles) that are rasterized. A wall (the
//! static scene) stands in front of it; three views see the sphere fully,
//! partly (the wall covers about half of it) and not at all.
//!
//! Methods, as the paper's rows:
//! - `none`: every prism drawn.
//! - `predicates-N`: the triangles in draws of `N` (12 and 8, the paper's
//!   594 x 12 and 891 x 8), each draw predicated on an occlusion query of
//!   its prisms' bounding box against the static scene.
//! - `item-buffer-NxN`: the conservatively extruded mesh (the prisms' top
//!   faces, enclosing every prism) drawn first into an item buffer whose IDs
//!   name `N x N` screen tiles; its histogram gives each tile's visible
//!   pixels, and a prism is drawn when a tile its screen rectangle overlaps
//!   has one (the paper's geometry-shader test).
//! - `sat`: the same first pass coloured by the object's region set
//!   (`occlude_core::gvq::plan`), its summed area table, and a prism drawn
//!   when its rectangle, intersected with the region set's lookups (section
//!   3.1.3), holds a visible pixel.
//!
//! Every culling method is conservative: a prism with a visible fragment is
//! drawn (tests check it). Fragments come from the soft rasterizer's exact
//! walk ([`Fragments`]); `frame_ms` is the soft backend's simulated clock
//! ([`SimFrame`]) charged with the GPU model's costs: draws, triangles,
//! fragments, queries, the first pass, the histogram or prefix-sum
//! dispatches over every pixel, and one texel read
//! (`gpu_hiz_texel_ns`) per tile or summed-area-table read a prism's test
//! makes. The model has no cost for the paper's ray-casting fragment shader
//! beyond `gpu_fragment_ns`, so the heavy object is only as heavy as its
//! 12 triangles and their fragments per prism make it.

use crate::published::PublishedTable;
use crate::sim_gpu::SimFrame;
use glam::{DVec2, Mat4, Vec3, Vec4};
use occlude_core::depth_pyramid::{project_corner, PIXEL_MARGIN};
use occlude_core::gvq::{plan, Lookup, PixelRect, SatConfig, Silhouette, SummedAreaTable, NO_CHANNEL};
use occlude_core::query_box::BOX_TRIANGLES;
use occlude_core::{Aabb, Camera};
use occlude_soft::raster::Fragments;
use occlude_soft::GpuModel;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Segments of the sphere around and rings from pole to pole.
pub const SPHERE_SEGMENTS: u32 = 60;

/// How far the displaced surface reaches above the sphere (radius 1).
pub const DISPLACEMENT: f32 = 0.08;

/// The item buffer's tilings (tiles per side), the paper's.
pub const TILINGS: [u32; 4] = [8, 16, 32, 90];

/// Triangles per predicated draw, the paper's.
pub const DRAW_SIZES: [usize; 2] = [12, 8];

/// The views: what of the sphere the wall leaves visible.
pub const VIEWS: [&str; 3] = ["full", "partial", "occluded"];

/// One row of Table 3.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PartsRow {
    /// Culling method (module documentation).
    pub method: String,
    /// `full`, `partial` or `occluded`.
    pub view: String,
    /// The backend that ran it: `soft` (simulated clock) or `wgpu`
    /// (measured on the device, `crate::gvq_parts_gpu`).
    #[serde(default)]
    pub backend: String,
    /// Frame time, ms: the soft backend's simulated clock, or the wgpu
    /// backend's measured wall-clock time.
    pub frame_ms: f64,
    /// Heavy triangles (prisms) drawn, of [`Self::triangles`].
    pub drawn: u32,
    /// Heavy triangles in all.
    pub triangles: u32,
    /// Heavy triangles with a visible fragment (what an exact test draws).
    pub visible: u32,
    /// Heavy triangles whose decision (drawn or culled) differs from the
    /// soft backend's by the same method (0 on the soft backend).
    #[serde(default)]
    pub differing_from_soft: u32,
    /// The paper's frame time on the NVIDIA 280GTX (1000 / its fps), ms.
    pub published_frame_ms: Option<f64>,
    /// The paper's frames per second, NVIDIA 280GTX.
    pub published_fps_gtx280: Option<f64>,
    /// The paper's frames per second, ATI HD3870.
    pub published_fps_hd3870: Option<f64>,
}

/// The heavy object: base triangles with their vertex normals.
pub(super) struct Heavy {
    /// Per triangle, its three vertices and their normals.
    pub(super) triangles: Vec<[(Vec3, Vec3); 3]>,
}

impl Heavy {
    /// The unit sphere at the origin, `segments` around and rings.
    pub(super) fn sphere(segments: u32) -> Self {
        let point = |i: u32, j: u32| {
            let (theta, phi) =
                (std::f32::consts::TAU * i as f32 / segments as f32, std::f32::consts::PI * j as f32 / segments as f32);
            let p = Vec3::new(phi.sin() * theta.cos(), phi.cos(), phi.sin() * theta.sin());
            (p, p)
        };
        let mut triangles = Vec::new();
        for j in 0..segments {
            for i in 0..segments {
                let (a, b, c, d) = (point(i, j), point(i + 1, j), point(i + 1, j + 1), point(i, j + 1));
                triangles.push([a, b, c]);
                triangles.push([a, c, d]);
            }
        }
        Self { triangles }
    }

    /// Triangle `i`'s prism corners: the base, then the base moved out by
    /// [`DISPLACEMENT`] along the normals.
    pub(super) fn prism(&self, i: usize) -> [Vec3; 6] {
        let t = &self.triangles[i];
        std::array::from_fn(|k| if k < 3 { t[k].0 } else { t[k - 3].0 + t[k - 3].1 * DISPLACEMENT })
    }

    /// The 12 triangles of the three tetrahedra the prism is split into.
    fn tetrahedra(&self, i: usize) -> Vec<[Vec3; 3]> {
        let [a0, b0, c0, a1, b1, c1] = self.prism(i);
        [[a0, b0, c0, a1], [b0, c0, a1, b1], [c0, a1, b1, c1]]
            .into_iter()
            .flat_map(|[p, q, r, s]| [[p, q, r], [p, q, s], [p, r, s], [q, r, s]])
            .collect()
    }
}

/// The wall in front of the sphere (the static scene).
pub(super) fn wall() -> Aabb {
    Aabb::new(Vec3::new(-4.0, -3.0, 2.0), Vec3::new(0.3, 3.0, 2.2))
}

/// The camera of `view`.
pub(super) fn camera(view: &str, aspect: f32) -> Camera {
    let position = match view {
        "full" => Vec3::new(0.0, 0.0, -6.0),
        "partial" => Vec3::new(0.0, 0.0, 6.0),
        _ => Vec3::new(-3.0, 0.0, 6.0),
    };
    Camera { position, target: Vec3::ZERO, up: Vec3::Y, fov_y_deg: 40.0, aspect, near: 0.1, far: 100.0, matrices: None }
}

/// What one view's passes found, for every method's cost.
pub(super) struct ViewPasses {
    pub(super) width: u32,
    pub(super) height: u32,
    /// Fragments of the static scene.
    static_fragments: u64,
    /// Per pixel, whether the extruded mesh is in front of the static scene.
    visible: Vec<bool>,
    /// Triangles and fragments of the first pass (the extruded mesh).
    proxy_fragments: u64,
    /// Per heavy triangle: its prism's fragments, pixel rectangle, and
    /// whether one of its fragments is in front of the static scene.
    pub(super) prisms: Vec<(u64, Option<PixelRect>, bool)>,
    /// Per predicated draw size, per draw: its box's fragments and whether
    /// one passed.
    draws: Vec<Vec<(u64, bool)>>,
    /// The extruded mesh's silhouette, for its region set.
    pub(super) silhouette: Option<Silhouette>,
}

/// Clip-space triangles of world triangles.
fn clip(vp: &Mat4, tris: &[[Vec3; 3]]) -> Vec<[Vec4; 3]> {
    tris.iter().map(|t| t.map(|p| *vp * p.extend(1.0))).collect()
}

/// The pixel rectangle holding every pixel centre the convex hull of
/// `points` can cover (their projections' bounds grown by the margin),
/// `None` when it holds none (or a point is behind the near plane: then
/// the whole image).
fn points_rect(vp: &Mat4, width: u32, height: u32, points: &[Vec3]) -> Option<PixelRect> {
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for &p in points {
        let Some((s, _)) = project_corner(vp, width, height, p) else {
            return Some(PixelRect::new(0, 0, width, height));
        };
        lo = lo.min(s);
        hi = hi.max(s);
    }
    let first = (lo - 0.5 - PIXEL_MARGIN).ceil().max(DVec2::ZERO);
    let last = (hi - 0.5 + PIXEL_MARGIN).floor().min(DVec2::new(f64::from(width) - 1.0, f64::from(height) - 1.0));
    (first.x <= last.x && first.y <= last.y)
        .then(|| PixelRect::new(first.x as u32, first.y as u32, last.x as u32 + 1, last.y as u32 + 1))
}

impl ViewPasses {
    pub(super) fn new(heavy: &Heavy, camera: &Camera, width: u32, height: u32) -> Self {
        let vp = camera.view_projection();
        let mut fragments = Fragments::new(width, height);
        let pixels = width as usize * height as usize;
        let index = |x: u32, y: u32| y as usize * width as usize + x as usize;
        let box_triangles = |b: &Aabb| {
            let c = b.corners();
            BOX_TRIANGLES.iter().map(|t| t.map(|k| c[k as usize])).collect::<Vec<_>>()
        };

        let mut depth = vec![1.0f32; pixels];
        let mut static_fragments = 0;
        for t in clip(&vp, &box_triangles(&wall())) {
            fragments.each(&t, false, |x, y, z| {
                static_fragments += 1;
                let d = &mut depth[index(x, y)];
                *d = d.min(z);
            });
        }

        let tops: Vec<[Vec3; 3]> = (0..heavy.triangles.len())
            .map(|i| {
                let p = heavy.prism(i);
                [p[3], p[4], p[5]]
            })
            .collect();
        let mut proxy = vec![1.0f32; pixels];
        let mut proxy_fragments = 0;
        for t in clip(&vp, &tops) {
            fragments.each(&t, false, |x, y, z| {
                proxy_fragments += 1;
                let d = &mut proxy[index(x, y)];
                *d = d.min(z);
            });
        }
        let visible: Vec<bool> = proxy.iter().zip(&depth).map(|(p, d)| p < d).collect();

        let prisms = (0..heavy.triangles.len())
            .map(|i| {
                let (mut count, mut seen) = (0u64, false);
                for t in clip(&vp, &heavy.tetrahedra(i)) {
                    fragments.each(&t, false, |x, y, z| {
                        count += 1;
                        seen |= z < depth[index(x, y)];
                    });
                }
                (count, points_rect(&vp, width, height, &heavy.prism(i)), seen)
            })
            .collect();

        let draws = DRAW_SIZES
            .iter()
            .map(|&size| {
                let indices: Vec<usize> = (0..heavy.triangles.len()).collect();
                indices
                    .chunks(size)
                    .map(|chunk| {
                        let corners: Vec<Vec3> = chunk.iter().flat_map(|&i| heavy.prism(i)).collect();
                        let b = occlude_core::query_box::padded(&Aabb::from_points(&corners));
                        let (mut count, mut passed) = (0u64, false);
                        for t in clip(&vp, &box_triangles(&b)) {
                            fragments.each(&t, false, |x, y, z| {
                                count += 1;
                                passed |= z < depth[index(x, y)];
                            });
                        }
                        (count, passed)
                    })
                    .collect()
            })
            .collect();

        let all_tops: Vec<Vec3> = tops.iter().flatten().copied().collect();
        let silhouette = Silhouette::of_box(&vp, width, height, &Aabb::from_points(&all_tops));
        Self { width, height, static_fragments, visible, proxy_fragments, prisms, draws, silhouette }
    }

    /// Visible pixels per tile of an `n x n` tiling, row-major.
    fn tile_counts(&self, n: u32) -> Vec<u64> {
        let mut counts = vec![0u64; (n * n) as usize];
        for (p, _) in self.visible.iter().enumerate().filter(|(_, &v)| v) {
            let (x, y) = (p as u32 % self.width, p as u32 / self.width);
            counts[self.tile(n, x, y)] += 1;
        }
        counts
    }

    /// The tile of pixel `(x, y)` in an `n x n` tiling.
    fn tile(&self, n: u32, x: u32, y: u32) -> usize {
        let (tx, ty) = (x as u64 * n as u64 / self.width as u64, y as u64 * n as u64 / self.height as u64);
        (ty * n as u64 + tx) as usize
    }
}

/// A frame of one method in one view that has drawn the static scene.
fn frame<'m>(model: &'m GpuModel, passes: &ViewPasses) -> SimFrame<'m> {
    let mut f = SimFrame::new(model);
    f.draw(12, passes.static_fragments);
    f
}

/// The heavy object in one draw, the prisms `drawn` says drawn (12
/// triangles and their fragments each; a culled one costs its input
/// triangle), after `reads` texel reads of the culling tests.
fn draw_heavy(f: &mut SimFrame, passes: &ViewPasses, drawn: &[bool], reads: u64) {
    let (mut triangles, mut fragments) = (0, 0);
    for (&(frags, _, _), &d) in passes.prisms.iter().zip(drawn) {
        triangles += if d { 12 } else { 1 };
        fragments += if d { frags } else { 0 };
    }
    f.draw(triangles, fragments);
    f.texel_reads(reads);
}

/// Per prism, whether `test` of its pixel rectangle keeps it (one without
/// a rectangle covers no pixel and is culled), and the texel reads the
/// tests made in all; `test` gives both for one rectangle.
pub(super) fn cull_by_rect(passes: &ViewPasses, mut test: impl FnMut(&PixelRect) -> (bool, u64)) -> (Vec<bool>, u64) {
    let mut reads = 0;
    let drawn = passes
        .prisms
        .iter()
        .map(|(_, rect, _)| {
            rect.is_some_and(|r| {
                let (keep, n) = test(&r);
                reads += n;
                keep
            })
        })
        .collect();
    (drawn, reads)
}

/// Per prism, whether the item buffer of `tiles x tiles` tiles keeps it,
/// and the tile reads of the tests.
pub(super) fn item_buffer_drawn(passes: &ViewPasses, tiles: u32) -> (Vec<bool>, u64) {
    let counts = passes.tile_counts(tiles);
    cull_by_rect(passes, |r| {
        let (t0, t1) = (passes.tile(tiles, r.x0, r.y0), passes.tile(tiles, r.x1 - 1, r.y1 - 1));
        let (tx0, ty0, tx1, ty1) = (t0 as u32 % tiles, t0 as u32 / tiles, t1 as u32 % tiles, t1 as u32 / tiles);
        let seen = (ty0..=ty1).any(|ty| (tx0..=tx1).any(|tx| counts[(ty * tiles + tx) as usize] > 0));
        (seen, u64::from((tx1 - tx0 + 1) * (ty1 - ty0 + 1)))
    })
}

/// Per prism, whether the summed area table `sat` of the extruded mesh,
/// read through its region set's `lookups`, keeps it, and the table reads
/// of the tests.
pub(super) fn sat_drawn(passes: &ViewPasses, lookups: &[Lookup], sat: &SummedAreaTable) -> (Vec<bool>, u64) {
    cull_by_rect(passes, |r| {
        let parts: Vec<_> = lookups.iter().filter_map(|l| l.rect.intersect(r).map(|i| (l.channel, i))).collect();
        (parts.iter().any(|(c, i)| sat.count(*c, i) > 0), 4 * parts.len() as u64)
    })
}

/// Table 3's rows of one view: `(method, frame_ms, drawn per prism)`.
pub(super) fn view_rows(passes: &ViewPasses, model: &GpuModel) -> Vec<(String, f64, Vec<bool>)> {
    let n = passes.prisms.len();
    let mut rows = Vec::new();

    let mut f = frame(model, passes);
    let all = vec![true; n];
    draw_heavy(&mut f, passes, &all, 0);
    rows.push(("none".to_string(), f.ms(), all));

    for (size, draws) in DRAW_SIZES.iter().zip(&passes.draws) {
        let mut f = frame(model, passes);
        let mut drawn = vec![false; n];
        for (k, &(box_fragments, passed)) in draws.iter().enumerate() {
            f.cpu_work(model.cpu_query_us);
            f.gpu(model.gpu_query_box_us + box_fragments as f64 * model.gpu_query_fragment_ns * 1e-3);
            let range = k * size..((k + 1) * size).min(n);
            if passed {
                let (tris, frags) = passes.prisms[range.clone()].iter().fold((0, 0), |(t, g), p| (t + 12, g + p.0));
                f.draw(tris, frags);
                drawn[range].iter_mut().for_each(|d| *d = true);
            } else {
                // The predicated draw is issued; the GPU skips it.
                f.cpu_work(model.cpu_draw_call_us);
            }
        }
        rows.push((format!("predicates-{size}"), f.ms(), drawn));
    }

    let pixels = u64::from(passes.width) * u64::from(passes.height);
    for tiles in TILINGS {
        let mut f = frame(model, passes);
        f.draw(n as u64, passes.proxy_fragments);
        f.dispatch(pixels);
        let (drawn, reads) = item_buffer_drawn(passes, tiles);
        draw_heavy(&mut f, passes, &drawn, reads);
        rows.push((format!("item-buffer-{tiles}x{tiles}"), f.ms(), drawn));
    }

    let mut f = frame(model, passes);
    let start = Instant::now();
    let regions = plan(&[passes.silhouette], &SatConfig::default());
    f.cpu_work(start.elapsed().as_secs_f64() * 1e6);
    f.draw(n as u64, passes.proxy_fragments);
    let owners: Vec<u32> = passes.visible.iter().map(|&v| if v { 0 } else { u32::MAX }).collect();
    let image = regions.channel_image(&owners, passes.width);
    debug_assert!(image.iter().zip(&passes.visible).all(|(&c, &v)| (c != NO_CHANNEL) == v));
    let sat = SummedAreaTable::from_channel_image(passes.width, passes.height, regions.channels, &image);
    f.dispatch(pixels);
    f.dispatch(pixels);
    let lookups = regions.sets.first().map_or(&[][..], |s| &s.lookups[..]);
    let (drawn, reads) = sat_drawn(passes, lookups, &sat);
    draw_heavy(&mut f, passes, &drawn, reads);
    rows.push(("sat".to_string(), f.ms(), drawn));
    rows
}

/// Table 3 at `width` x `height` with `model`'s costs, beside `published`.
pub fn table_3(width: u32, height: u32, model: &GpuModel, published: Option<&PublishedTable>) -> Vec<PartsRow> {
    let heavy = Heavy::sphere(SPHERE_SEGMENTS);
    let mut rows = Vec::new();
    for view in VIEWS {
        let passes = ViewPasses::new(&heavy, &camera(view, width as f32 / height as f32), width, height);
        let visible = passes.prisms.iter().filter(|p| p.2).count() as u32;
        for (method, frame_ms, drawn) in view_rows(&passes, model) {
            rows.push(row(published, &method, view, frame_ms, &drawn, visible));
        }
    }
    rows
}

/// The soft backend's row of `method` in `view` that drew `drawn` of
/// prisms of which `visible` have a visible fragment, beside `published`.
pub(super) fn row(
    published: Option<&PublishedTable>,
    method: &str,
    view: &str,
    frame_ms: f64,
    drawn: &[bool],
    visible: u32,
) -> PartsRow {
    let p = published.and_then(|t| t.rows.iter().find(|r| r.method == method && r.view == view));
    PartsRow {
        method: method.to_string(),
        view: view.to_string(),
        backend: "soft".into(),
        frame_ms,
        drawn: drawn.iter().filter(|&&d| d).count() as u32,
        triangles: drawn.len() as u32,
        visible,
        differing_from_soft: 0,
        published_frame_ms: p.and_then(|r| r.fps_gtx280).map(|fps| 1000.0 / fps),
        published_fps_gtx280: p.and_then(|r| r.fps_gtx280),
        published_fps_hd3870: p.and_then(|r| r.fps_hd3870),
    }
}

/// Table 3's printed form, its frame times those of `clock` (which backend
/// timed them, and how).
pub fn print(rows: &[PartsRow], width: u32, height: u32, clock: &str) -> String {
    let mut text = format!(
        "Granular visibility queries — Table 3: culling parts of one heavy object ({width}x{height}, {clock}; \
         paper's fps on NVIDIA 280GTX / ATI HD3870 beside)\n\
         method               view       frame ms  (paper ms)  drawn / triangles  visible  differ from soft  (paper fps)\n"
    );
    for r in rows {
        let paper_ms = r.published_frame_ms.map_or_else(|| "-".into(), |v| format!("{v:.2}"));
        let fps = match (r.published_fps_gtx280, r.published_fps_hd3870) {
            (Some(a), Some(b)) => format!("{a} / {b}"),
            _ => "-".into(),
        };
        text.push_str(&format!(
            "{:<20} {:<9} {:>9.3} {:>11} {:>8} / {:<8} {:>7} {:>17}  {}\n",
            r.method, r.view, r.frame_ms, paper_ms, r.drawn, r.triangles, r.visible, r.differing_from_soft, fps
        ));
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::published;

    #[test]
    fn every_culling_method_draws_every_prism_with_a_visible_fragment() {
        let heavy = Heavy::sphere(16);
        let model = GpuModel::modern();
        let mut partial_culled = 0;
        for view in VIEWS {
            let passes = ViewPasses::new(&heavy, &camera(view, 1.0), 64, 64);
            let visible: Vec<bool> = passes.prisms.iter().map(|p| p.2).collect();
            match view {
                "full" | "partial" => assert!(visible.iter().any(|&v| v), "{view}: nothing visible"),
                _ => assert!(!visible.iter().any(|&v| v), "{view}: something visible"),
            }
            let rows = view_rows(&passes, &model);
            assert_eq!(rows.len(), 1 + DRAW_SIZES.len() + TILINGS.len() + 1);
            for (method, ms, drawn) in &rows {
                assert!(ms.is_finite() && *ms > 0.0, "{view} {method}: {ms} ms");
                for (i, (&v, &d)) in visible.iter().zip(drawn).enumerate() {
                    assert!(!v || d, "{view} {method}: prism {i} has a visible fragment but was culled");
                }
                if view == "partial" && method != "none" {
                    partial_culled += drawn.iter().filter(|&&d| !d).count();
                }
            }
            if view == "occluded" {
                // Every method but none culls every prism of a hidden sphere.
                assert!(rows[1..].iter().all(|(_, _, d)| d.iter().all(|&d| !d)), "{view}: a method drew something");
            }
        }
        assert!(partial_culled > 0, "no method culled a prism in the partial view");
    }

    #[test]
    fn table_3_has_every_method_and_view_beside_the_papers_figures() {
        let rows = table_3(48, 48, &GpuModel::modern(), published::table("gvq", "Table 3"));
        assert_eq!(rows.len(), VIEWS.len() * (1 + DRAW_SIZES.len() + TILINGS.len() + 1));
        let none_full = rows.iter().find(|r| r.method == "none" && r.view == "full").unwrap();
        assert_eq!((none_full.published_fps_gtx280, none_full.published_fps_hd3870), (Some(71.0), Some(22.0)));
        let ib90 = rows.iter().find(|r| r.method == "item-buffer-90x90" && r.view == "partial").unwrap();
        assert_eq!(ib90.published_fps_gtx280, Some(131.0));
        assert!(rows.iter().all(|r| r.drawn >= r.visible && r.triangles == 2 * SPHERE_SEGMENTS * SPHERE_SEGMENTS));
        let json = serde_json::to_value(&rows[0]).unwrap();
        for key in ["method", "view", "frame_ms"] {
            assert!(json.get(key).is_some(), "{key}");
        }
    }
}
