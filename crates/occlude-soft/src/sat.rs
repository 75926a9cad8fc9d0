//! Granular visibility queries with summed area tables (Engelhardt and
//! Dachsbacher, section 3.1) on the CPU: the exact counterpart of the GPU's
//! render, prefix sums and lookups, and the exact per-object counts the
//! paper's Table 2 measures them against.
//!
//! Objects (the scene's instances) are drawn in index order with depth
//! test *less*, as into a colour target: a pixel's colour is the channel
//! that the last object whose fragment passed there chose for it
//! (`RegionSet::channel_at`, the paper's fragment shader). The rasterizer
//! has no colour, so each object is drawn on its own and the pixels of its
//! screen rectangle whose depth it lowered are its own: the owner image.
//! Its histogram is the exact per-object count; the channel image built
//! from it gives `occlude_core::gvq::SummedAreaTable`'s counts.

use crate::raster::{Command, CommandKind, DepthBuffer, Rasterizer};
use glam::Vec4;
use occlude_core::gvq::{
    count_errors, plan, CountErrors, PixelRect, RegionPlan, SatConfig, Silhouette, SummedAreaTable,
};
use occlude_core::{Camera, Scene};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// A pixel no object owns.
pub const NO_OWNER: u32 = u32::MAX;

/// One frame's summed-area-table queries of every instance.
#[derive(Clone, Debug)]
pub struct SatFrame {
    /// The region sets, their colouring and the CPU steps' times.
    pub plan: RegionPlan,
    /// Per instance, the count from its region set's lookups.
    pub counts: Vec<u64>,
    /// Per instance, its exact visible pixels.
    pub exact: Vec<u64>,
    /// The instances with a screen rectangle (the queries), in order.
    pub queried: Vec<usize>,
    /// Table 2's errors of `counts` against `exact`, over the instances
    /// with a screen rectangle.
    pub errors: CountErrors,
    /// Milliseconds: the summed area tables and the lookups.
    pub sat_ms: f64,
}

/// A frame's Table 2 row: objects, conflicts, errors and CPU times.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SatSummary {
    /// Instances with a screen rectangle (the queries).
    pub objects: u32,
    /// Conflict objects.
    pub conflicts: u32,
    /// Lookups in all region sets.
    pub lookups: u32,
    /// The count errors.
    pub errors: CountErrors,
    /// The CPU steps' times.
    pub timings: occlude_core::gvq::PlanTimings,
}

impl SatFrame {
    /// Table 2's errors of `counts` (one per instance, as [`Self::counts`];
    /// another backend's, say) against [`Self::exact`], over the queries.
    pub fn errors_of(&self, counts: &[u64]) -> CountErrors {
        let pick = |all: &[u64]| self.queried.iter().map(|&i| all[i]).collect::<Vec<_>>();
        count_errors(&pick(counts), &pick(&self.exact))
    }

    /// The frame's Table 2 row.
    pub fn summary(&self) -> SatSummary {
        SatSummary {
            objects: self.errors.objects,
            conflicts: self.plan.conflicts,
            lookups: self.plan.lookups,
            errors: self.errors,
            timings: self.plan.timings,
        }
    }
}

/// The soft backend's summed-area-table queries at one resolution (module
/// documentation), its buffers reused frame after frame.
#[derive(Debug)]
pub struct SoftSat {
    rasterizer: Rasterizer,
    depth: DepthBuffer,
    /// Row-major depth before the current object was drawn.
    before: Vec<f32>,
    triangles: Vec<[Vec4; 3]>,
    clip: Vec<Vec4>,
}

impl SoftSat {
    /// Queries on a `width` x `height` image.
    ///
    /// # Panics
    /// If a side exceeds the rasterizer's
    /// [`MAX_DIMENSION`](crate::raster::MAX_DIMENSION).
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            rasterizer: Rasterizer::new(),
            depth: DepthBuffer::new(width, height),
            before: Vec::new(),
            triangles: Vec::new(),
            clip: Vec::new(),
        }
    }

    /// Per pixel (row-major), the instance that owns it: the last one, in
    /// index order, whose fragment passed the depth test there, or
    /// [`NO_OWNER`]. `rects` holds each instance's screen rectangle
    /// (`None`: it covers no pixel).
    pub fn owners(&mut self, scene: &Scene, camera: &Camera, rects: &[Option<PixelRect>]) -> Vec<u32> {
        let (w, h) = (self.depth.width(), self.depth.height());
        let view_projection = camera.view_projection();
        self.depth.clear();
        self.before.clear();
        self.before.resize(w as usize * h as usize, 1.0);
        let mut owners = vec![NO_OWNER; self.before.len()];
        for (i, rect) in rects.iter().enumerate() {
            let Some(rect) = rect else { continue };
            self.triangles.clear();
            scene.push_clip_triangles(i as u32, &view_projection, &mut self.clip, &mut self.triangles);
            let draw = Command { kind: CommandKind::Draw, triangles: 0..self.triangles.len() as u32, cull_back: false };
            if self.rasterizer.execute(&mut self.depth, &self.triangles, &[draw])[0].passed == 0 {
                continue;
            }
            for y in rect.y0..rect.y1 {
                for x in rect.x0..rect.x1 {
                    let p = y as usize * w as usize + x as usize;
                    let d = self.depth.get(x, y);
                    if d < self.before[p] {
                        self.before[p] = d;
                        owners[p] = i as u32;
                    }
                }
            }
        }
        owners
    }

    /// Every instance of `scene` queried from `camera` with each of
    /// `configs` (one owner image for all of them), beside its exact count.
    pub fn query(&mut self, scene: &Scene, camera: &Camera, configs: &[SatConfig]) -> Vec<SatFrame> {
        let (w, h) = (self.depth.width(), self.depth.height());
        let view_projection = camera.view_projection();
        let shapes: Vec<Option<Silhouette>> =
            scene.instances.iter().map(|inst| Silhouette::of_box(&view_projection, w, h, &inst.bounds)).collect();
        let rects: Vec<Option<PixelRect>> = shapes.iter().map(|s| s.map(|s| s.rect)).collect();
        let owners = self.owners(scene, camera, &rects);
        let mut exact = vec![0u64; rects.len()];
        for &o in owners.iter().filter(|&&o| o != NO_OWNER) {
            exact[o as usize] += 1;
        }
        let queried: Vec<usize> = (0..rects.len()).filter(|&i| rects[i].is_some()).collect();
        configs
            .iter()
            .map(|config| {
                let plan = plan(&shapes, config);
                let start = Instant::now();
                let sat = SummedAreaTable::from_channel_image(w, h, plan.channels, &plan.channel_image(&owners, w));
                let counts: Vec<u64> = plan.sets.iter().map(|s| sat.count_set(s)).collect();
                let sat_ms = start.elapsed().as_secs_f64() * 1e3;
                let mut frame = SatFrame {
                    plan,
                    counts,
                    exact: exact.clone(),
                    queried: queried.clone(),
                    errors: CountErrors::default(),
                    sat_ms,
                };
                frame.errors = frame.errors_of(&frame.counts);
                frame
            })
            .collect()
    }
}
