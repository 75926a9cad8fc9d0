//! `occlude bench --paper gvq --backend wgpu`, Table 3 on the GPU: the
//! heavy object of [`crate::gvq_parts`] culled per prism by the wgpu
//! backend's own passes, and each frame timed on the device.
//!
//! The scene uploaded is the wall (instance [`WALL`]), the conservatively
//! extruded mesh (the prisms' top faces, [`PROXY`]) and one instance per
//! prism (its 12 tetrahedron triangles, from [`FIRST_PRISM`] on). A frame
//! draws the wall, then the prisms the method keeps, each prism its own
//! draw call (the soft backend's clock charges the heavy object as one
//! draw). Methods, as the soft rows:
//! - `none`: every prism drawn.
//! - `predicates-N`: one hardware occlusion query per draw of `N` prisms
//!   (their bounding box, after the wall), and the draw issued when its
//!   query passed (the CPU waits for the answers: wgpu has no predicated
//!   draws).
//! - `item-buffer-NxN`: the wgpu item pass (`WgpuBackend::item_buffer`) of
//!   the wall and the extruded mesh with `N x N` tiles, its histogram's
//!   bins of the extruded mesh read back, and a prism kept when a tile its
//!   pixel rectangle overlaps has a visible pixel. The item buffer's tiles
//!   are `2^t` per side (the paper's ID encoding), so the paper's 90 x 90 is
//!   run as 128 x 128.
//! - `sat`: `GpuSat` draws the wall and the extruded mesh coloured by the
//!   mesh's region set and sums them on the GPU; `GpuSat` answers one count
//!   per object, so the per-prism lookups are made on the CPU in the
//!   summed area table of its read-back channel image.
//!
//! `frame_ms` is the wall-clock time of the whole frame (the culling pass,
//! its read-back, the CPU test and the frame drawn and waited for), the mean
//! over the frames after one warm-up frame; on lavapipe that is CPU time of
//! its software rasterizer, not a GPU's. Every row counts the prisms whose
//! decision differs from the soft backend's for the same method and tiling
//! (`differing_from_soft`): the two rasterizers may cover a pixel on a
//! triangle's edge differently.

use crate::error::{Error, Result};
use crate::gvq_parts::{self, Heavy, PartsRow, ViewPasses};
use crate::published::PublishedTable;
use glam::{Mat4, Vec3};
use occlude_core::gvq::{plan, SatConfig, SummedAreaTable};
use occlude_core::item_buffer::ItemLayout;
use occlude_core::query_box::BOX_TRIANGLES;
use occlude_core::{Aabb, Backend, Camera, Mesh, Scene};
use occlude_wgpu::{GpuContext, GpuSat, GpuScene, WgpuBackend};
use std::sync::Arc;
use std::time::Instant;

/// The wall's instance.
pub const WALL: u32 = 0;

/// The extruded mesh's instance.
pub const PROXY: u32 = 1;

/// The first prism's instance; prism `i` is `FIRST_PRISM + i`.
pub const FIRST_PRISM: u32 = 2;

/// Frames timed per row at most (after a warm-up frame): `--frames` counts
/// the walkthrough's frames of Table 2, and Table 3's views are static.
pub const FRAMES: usize = 5;

/// Item-buffer tile levels run (`2^t` tiles per side): 8, 16, 32 and 128
/// (for the paper's 90).
pub const LEVELS: [u32; 4] = [3, 4, 5, 7];

/// A mesh of a box's 12 triangles.
fn box_mesh(b: &Aabb) -> Mesh {
    Mesh::new(b.corners().to_vec(), BOX_TRIANGLES.iter().flatten().map(|&k| u32::from(k)).collect())
}

/// The extruded mesh: every prism's top face.
fn proxy_mesh(heavy: &Heavy) -> Mesh {
    let positions: Vec<Vec3> = (0..heavy.triangles.len()).flat_map(|i| heavy.prism(i)[3..].to_vec()).collect();
    Mesh::new(positions, (0..heavy.triangles.len() as u32 * 3).collect())
}

/// Prism `i`'s three tetrahedra as a mesh of its six corners.
fn prism_mesh(heavy: &Heavy, i: usize) -> Mesh {
    let indices = [[0, 1, 2, 3], [1, 2, 3, 4], [2, 3, 4, 5]]
        .into_iter()
        .flat_map(|[p, q, r, s]| [p, q, r, p, q, s, p, r, s, q, r, s])
        .collect();
    Mesh::new(heavy.prism(i).to_vec(), indices)
}

/// The wall and the extruded mesh, with the prisms after them if `prisms`.
fn parts_scene(heavy: &Heavy, prisms: bool) -> Scene {
    let mut scene = Scene::new("gvq-parts");
    scene.material_count = 1;
    for mesh in [box_mesh(&gvq_parts::wall()), proxy_mesh(heavy)] {
        let m = scene.add_mesh(mesh);
        scene.add_instance(m, Mat4::IDENTITY, 0);
    }
    if prisms {
        for i in 0..heavy.triangles.len() {
            let m = scene.add_mesh(prism_mesh(heavy, i));
            scene.add_instance(m, Mat4::IDENTITY, 0);
        }
    }
    scene
}

/// Draws the wall and the prisms `drawn` keeps from `camera`, and waits
/// for the frame.
fn draw_frame(backend: &mut WgpuBackend, camera: &Camera, drawn: &[bool]) -> Result<()> {
    backend.begin_frame(camera);
    backend.draw(&[WALL]);
    let kept: Vec<u32> = drawn.iter().enumerate().filter(|(_, &d)| d).map(|(i, _)| FIRST_PRISM + i as u32).collect();
    backend.draw(&kept);
    end_frame(backend)
}

/// Ends the frame, waiting for the GPU; an error if the backend failed.
fn end_frame(backend: &mut WgpuBackend) -> Result<()> {
    backend.end_frame();
    match backend.failure() {
        Some(e) => Err(Error::Backend(format!("wgpu backend failed: {e}"))),
        None => Ok(()),
    }
}

/// The mean wall-clock ms of `frames` runs of `frame` after one warm-up
/// run, and the prisms the last run drew.
fn timed(frames: usize, mut frame: impl FnMut() -> Result<Vec<bool>>) -> Result<(f64, Vec<bool>)> {
    let mut drawn = frame()?;
    let start = Instant::now();
    for _ in 0..frames {
        drawn = frame()?;
    }
    Ok((start.elapsed().as_secs_f64() * 1e3 / frames.max(1) as f64, drawn))
}

/// One method's row in one view: its mean frame time and, per prism,
/// whether the GPU drew it and whether the soft backend's same method does.
struct GpuRow {
    method: String,
    frame_ms: f64,
    drawn: Vec<bool>,
    soft: Vec<bool>,
}

/// What the rows of one view run on: the uploaded scene and its backend,
/// and `GpuSat` with the scene it draws.
struct GpuView<'a> {
    heavy: &'a Heavy,
    scene: &'a Scene,
    backend: &'a mut WgpuBackend,
    sat: &'a GpuSat,
    sat_scene: &'a Scene,
    frames: usize,
}

impl GpuView<'_> {
    /// Every method's row in the view of `camera`, whose soft passes are
    /// `passes`.
    fn rows(&mut self, camera: &Camera, passes: &ViewPasses) -> Result<Vec<GpuRow>> {
        let n = self.heavy.triangles.len();
        // The soft backend's decisions (which the GPU model's costs do not change).
        let soft = gvq_parts::view_rows(passes, &occlude_soft::GpuModel::modern());
        let row = |method: String, (frame_ms, drawn): (f64, Vec<bool>)| {
            let soft = soft.iter().find(|r| r.0 == method).expect("soft runs every method").2.clone();
            GpuRow { method, frame_ms, drawn, soft }
        };
        let mut rows = Vec::new();
        let backend = &mut *self.backend;

        let timing = timed(self.frames, || {
            let all = vec![true; n];
            draw_frame(backend, camera, &all)?;
            Ok(all)
        })?;
        rows.push(row("none".into(), timing));

        for size in gvq_parts::DRAW_SIZES {
            let boxes: Vec<Aabb> = (0..n)
                .collect::<Vec<_>>()
                .chunks(size)
                .map(|chunk| Aabb::from_points(&chunk.iter().flat_map(|&i| self.heavy.prism(i)).collect::<Vec<_>>()))
                .collect();
            let timing = timed(self.frames, || {
                backend.begin_frame(camera);
                backend.draw(&[WALL]);
                let queries: Vec<_> = boxes.iter().map(|b| backend.issue_query(std::slice::from_ref(b))).collect();
                let mut drawn = vec![false; n];
                for (k, q) in queries.into_iter().enumerate() {
                    if backend.result(q) > 0 {
                        let range = k * size..((k + 1) * size).min(n);
                        backend.draw(&range.clone().map(|i| FIRST_PRISM + i as u32).collect::<Vec<_>>());
                        drawn[range].iter_mut().for_each(|d| *d = true);
                    }
                }
                end_frame(backend)?;
                Ok(drawn)
            })?;
            rows.push(row(format!("predicates-{size}"), timing));
        }

        let (w, h) = (passes.width, passes.height);
        for level in LEVELS {
            let layout = ItemLayout::new(self.scene, &[WALL, PROXY], level)?;
            let slot = layout.slots().iter().position(|&i| i == PROXY).expect("the proxy has a slot") as u32;
            let tiles = layout.tiles_per_side();
            let (frame_ms, drawn) = timed(self.frames, || {
                let counts = backend.item_buffer(camera, &layout)?;
                let (drawn, _) = gvq_parts::cull_by_rect(passes, |r| {
                    let (t0, t1) = (layout.tile_of(r.x0, r.y0, w, h), layout.tile_of(r.x1 - 1, r.y1 - 1, w, h));
                    let seen = (t0 / tiles..=t1 / tiles).any(|ty| {
                        (t0 % tiles..=t1 % tiles).any(|tx| counts.bins[layout.id(slot, ty * tiles + tx) as usize] > 0)
                    });
                    (seen, 0)
                });
                draw_frame(backend, camera, &drawn)?;
                Ok(drawn)
            })?;
            // The soft backend's item buffer at the same tiling (its rows
            // have 90 tiles a side where this has 128).
            let soft = gvq_parts::item_buffer_drawn(passes, tiles).0;
            rows.push(GpuRow { method: format!("item-buffer-{tiles}x{tiles}"), frame_ms, drawn, soft });
        }

        let timing = timed(self.frames, || {
            let regions = plan(&[None, passes.silhouette], &SatConfig::default());
            let frame = self.sat.query(self.sat_scene, camera, &regions).map_err(Error::Backend)?;
            let sat = SummedAreaTable::from_channel_image(w, h, regions.channels, &frame.channel_image);
            let drawn = gvq_parts::sat_drawn(passes, &regions.sets[PROXY as usize].lookups, &sat).0;
            draw_frame(backend, camera, &drawn)?;
            Ok(drawn)
        })?;
        rows.push(row("sat".into(), timing));
        Ok(rows)
    }
}

/// Table 3 on the GPU of `ctx` at `width` x `height`, each frame time the
/// mean of `frames` frames, beside `published` (module documentation).
pub fn table_3(
    ctx: Arc<GpuContext>,
    width: u32,
    height: u32,
    frames: usize,
    published: Option<&PublishedTable>,
) -> Result<Vec<PartsRow>> {
    let heavy = Heavy::sphere(gvq_parts::SPHERE_SEGMENTS);
    let scene = parts_scene(&heavy, true);
    // What `GpuSat` draws: the wall and the extruded mesh alone.
    let sat_scene = parts_scene(&heavy, false);
    let gpu = Arc::new(GpuScene::new(Arc::clone(&ctx), &scene)?);
    let mut backend = WgpuBackend::new(gpu, &scene, width, height);
    let sat = GpuSat::new(ctx, width, height, SatConfig::default().targets);
    let mut rows = Vec::new();
    for view in gvq_parts::VIEWS {
        let camera = gvq_parts::camera(view, width as f32 / height as f32);
        let passes = ViewPasses::new(&heavy, &camera, width, height);
        let visible = passes.prisms.iter().filter(|p| p.2).count() as u32;
        let mut gpu_view =
            GpuView { heavy: &heavy, scene: &scene, backend: &mut backend, sat: &sat, sat_scene: &sat_scene, frames };
        for r in gpu_view.rows(&camera, &passes)? {
            let mut row = gvq_parts::row(published, &r.method, view, r.frame_ms, &r.drawn, visible);
            row.backend = "wgpu".into();
            row.differing_from_soft = r.drawn.iter().zip(&r.soft).filter(|(g, s)| g != s).count() as u32;
            rows.push(row);
        }
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gvq_parts::{DRAW_SIZES, VIEWS};

    /// On the GPU every method runs in every view, the occluded sphere is
    /// culled whole by every culling method, and every prism's decision is
    /// the soft backend's.
    #[test]
    fn wgpu_table_3_culls_as_the_soft_backend() {
        let Some(ctx) = GpuContext::for_test("wgpu_table_3_culls_as_the_soft_backend") else {
            return;
        };
        let rows = table_3(ctx, 64, 64, 1, None).unwrap();
        let methods = 1 + DRAW_SIZES.len() + LEVELS.len() + 1;
        assert_eq!(rows.len(), VIEWS.len() * methods);
        for r in &rows {
            assert_eq!(r.backend, "wgpu");
            assert!(r.frame_ms.is_finite() && r.frame_ms > 0.0, "{r:?}");
            match (r.view.as_str(), r.method.as_str()) {
                (_, "none") => assert_eq!(r.drawn, r.triangles, "{r:?}"),
                ("occluded", _) => assert_eq!(r.drawn, 0, "{r:?}: the hidden sphere drawn"),
                _ => assert!(r.drawn >= r.visible, "{r:?}: fewer drawn than visible"),
            }
        }
        let differing: Vec<&PartsRow> = rows.iter().filter(|r| r.differing_from_soft > 0).collect();
        assert!(differing.is_empty(), "decisions differ from soft's: {differing:?}");
    }
}
