//! `occlude bench --paper gvq --backend wgpu`, Table 1 on the GPU: the
//! shadow-volume culling of [`crate::gvq_shadows`] decided by the wgpu
//! backend's own queries, and the kept volumes drawn and timed on the
//! device.
//!
//! Every frame is the soft rows' (the same scene, light, walkthrough and
//! volume geometry: `gvq_shadows::scene_rows` runs the soft passes and
//! hands their clip-space triangles over). Per frame and method, timed:
//! - the culling step: `none` keeps every volume; `sat-conservative` and
//!   `sat-approximate` count the soft backend's region plans with `GpuSat`
//!   (drawn, summed and looked up on the GPU); `hib` runs the wgpu item
//!   pass (`WgpuBackend::item_buffer`, one tile: one bin per object) in the
//!   light's view; `hardware` draws every object's triangles into the
//!   light's depth (`DepthRaster`) and then queries each object's own
//!   triangles at depth test *equal*, one occlusion query per object (the
//!   CPU waits for the answers: wgpu has no predicated draws). A volume is
//!   kept when its object's count is not 0, read back to the CPU;
//! - the drawing: the camera's depth pass of every object, then each kept
//!   volume by its own draw call, two-sided and depth-tested without
//!   writing (`DepthRaster::draw_tested`: the fragments a stencil pass
//!   rasterizes and tests; `DepthRaster` has no stencil, so nothing is
//!   written and no shadow is shown). The lit pass, the same in every row,
//!   is left out.
//!
//! The triangles (light and camera clip space, the volumes' included) are
//! uploaded once per frame before the timing, as a renderer's geometry
//! would already be on the device. `frame_ms` is the mean wall-clock time
//! of the two steps over the frames, after one untimed warm-up of every
//! method on the first frame; on lavapipe that is CPU time of its software
//! rasterizer, not a GPU's. Every row counts the objects whose decision
//! differs from the soft backend's for the same method and frame
//! (`differing_from_soft`): the two rasterizers may cover a pixel on a
//! triangle's edge differently.

use crate::config::BenchConfig;
use crate::error::{Error, Result};
use crate::gvq_shadows::{self, keep, FramePasses, Method, MethodFrame, ShadowRow, METHODS};
use crate::progress::Progress;
use crate::published::PublishedTable;
use occlude_core::gvq::RegionMode;
use occlude_core::item_buffer::ItemLayout;
use occlude_core::{Backend, Camera, Scene};
use occlude_scenes::scattered::scattered;
use occlude_wgpu::{DepthRaster, GpuContext, GpuSat, GpuScene, WgpuBackend};
use std::sync::Arc;
use std::time::Instant;

/// The device's state for one scene's frames.
struct Device<'a, 's> {
    scene: &'s Scene,
    size: (u32, u32),
    /// The item pass's backend, over `scene`.
    backend: WgpuBackend,
    /// One bin per object.
    layout: ItemLayout,
    /// Per region mode (conservative, approximate), its summed area tables.
    sats: &'a [GpuSat],
    /// The light's depth (the `hardware` queries).
    light: &'a mut DepthRaster,
    /// The camera's depth (the volumes drawn).
    camera: &'a mut DepthRaster,
    /// Whether every method has run once (the warm-up).
    warm: bool,
}

impl Device<'_, '_> {
    /// Every method of [`METHODS`] in the frame of `p` from the light's
    /// camera `light_cam` (module documentation).
    fn methods(&mut self, light_cam: &Camera, p: &FramePasses) -> Result<Vec<MethodFrame>> {
        self.light.upload(&p.light_triangles).map_err(Error::Backend)?;
        self.camera.upload(&p.camera_triangles).map_err(Error::Backend)?;
        if !self.warm {
            for &m in &METHODS {
                self.frame(m, light_cam, p)?;
            }
            self.warm = true;
        }
        METHODS
            .iter()
            .map(|&m| {
                let start = Instant::now();
                let drawn = self.frame(m, light_cam, p)?;
                let ms = start.elapsed().as_secs_f64() * 1e3;
                let differing = drawn.iter().zip(m.drawn(p)).filter(|(g, s)| **g != *s).count() as u32;
                Ok(MethodFrame { ms, drawn, differing })
            })
            .collect()
    }

    /// Method `m`'s culling step and drawing; per object, whether its volume
    /// was drawn.
    fn frame(&mut self, m: Method, light_cam: &Camera, p: &FramePasses) -> Result<Vec<bool>> {
        let drawn = self.cull(m, light_cam, p)?;
        let kept: Vec<_> = p.volume_ranges.iter().zip(&drawn).filter(|(_, &d)| d).map(|(r, _)| r.clone()).collect();
        let (w, h) = self.size;
        self.camera.clear(w, h).map_err(Error::Backend)?;
        self.camera.draw(p.camera_objects.clone()).map_err(Error::Backend)?;
        self.camera.draw_tested(&kept).map_err(Error::Backend)?;
        Ok(drawn)
    }

    /// Method `m`'s culling step: per object, whether its volume is kept.
    fn cull(&mut self, m: Method, light_cam: &Camera, p: &FramePasses) -> Result<Vec<bool>> {
        Ok(match m {
            Method::None => vec![true; p.volume_ranges.len()],
            Method::Sat(mode) => {
                let k = usize::from(mode == RegionMode::Approximate);
                keep(&self.sats[k].query(self.scene, light_cam, &p.plans[k]).map_err(Error::Backend)?.counts)
            }
            Method::Hib => {
                let items = self.backend.item_buffer(light_cam, &self.layout)?;
                if let Some(e) = self.backend.failure() {
                    return Err(Error::Backend(format!("wgpu backend failed: {e}")));
                }
                let mut counts = vec![0u64; p.volume_ranges.len()];
                for (slot, &instance) in self.layout.slots().iter().enumerate() {
                    counts[instance as usize] = items.instances[slot];
                }
                keep(&counts)
            }
            Method::Hardware => {
                let (w, h) = self.size;
                let all = 0..p.light_triangles.len() as u32;
                self.light.clear(w, h).map_err(Error::Backend)?;
                self.light.draw(all).map_err(Error::Backend)?;
                keep(&self.light.queries_at_equal_depth(&p.light_ranges).map_err(Error::Backend)?)
            }
        })
    }
}

/// Table 1 on the GPU of `ctx`: scenes of `counts` objects with `base`'s
/// seed, frames (at most [`gvq_shadows::FRAMES`]) and resolution (light
/// and camera views), beside `published` (module documentation).
pub fn table_1(
    ctx: Arc<GpuContext>,
    base: &BenchConfig,
    counts: &[u32],
    published: Option<&PublishedTable>,
    progress: &dyn Progress,
) -> Result<Vec<ShadowRow>> {
    let (w, h) = base.resolution;
    let sats: Vec<GpuSat> =
        gvq_shadows::sat_configs().iter().map(|c| GpuSat::new(Arc::clone(&ctx), w, h, c.targets)).collect();
    let (mut light, mut camera) = (DepthRaster::new(Arc::clone(&ctx)), DepthRaster::new(Arc::clone(&ctx)));
    let mut rows = Vec::new();
    for &objects in counts {
        let scene = scattered(objects, base.seed);
        let gpu = Arc::new(GpuScene::new(Arc::clone(&ctx), &scene)?);
        let all: Vec<u32> = (0..objects).collect();
        let mut device = Device {
            scene: &scene,
            size: (w, h),
            backend: WgpuBackend::new(gpu, &scene, w, h),
            layout: ItemLayout::new(&scene, &all, 0)?,
            sats: &sats,
            light: &mut light,
            camera: &mut camera,
            warm: false,
        };
        let measure = |light_cam: &Camera, p: &FramePasses| device.methods(light_cam, p);
        rows.extend(gvq_shadows::scene_rows(base, &scene, "wgpu", published, progress, measure)?);
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On the GPU every method runs, the item buffer and the occlusion
    /// queries keep exactly the soft backend's volumes, and they cull some.
    #[test]
    fn wgpu_table_1_culls_as_the_soft_backend() {
        let Some(ctx) = GpuContext::for_test("wgpu_table_1_culls_as_the_soft_backend") else {
            return;
        };
        let base = BenchConfig { frames: 2, resolution: (128, 128), ..BenchConfig::default() };
        let rows = table_1(ctx, &base, &[100], None, &()).unwrap();
        assert_eq!(rows.len(), METHODS.len());
        for r in &rows {
            assert_eq!((r.backend.as_str(), r.frames), ("wgpu", 2), "{r:?}");
            assert!(r.frame_ms.is_finite() && r.frame_ms > 0.0, "{r:?}");
        }
        let find = |m: &str| rows.iter().find(|r| r.method == m).unwrap();
        assert_eq!((find("none").volumes, find("none").differing_from_soft), (100.0, 0.0));
        for m in ["hib", "hardware"] {
            let r = find(m);
            assert_eq!(r.differing_from_soft, 0.0, "{r:?}: decisions differ from soft's");
            assert_eq!(r.lit_culled, 0.0, "{r:?}: a lit object's volume culled");
            assert!(r.volumes < 100.0, "{r:?}: nothing culled");
        }
    }
}
