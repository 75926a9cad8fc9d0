//! [`SharedSetup`]: instances' triangles set up once per camera for every
//! soft backend drawing the same scene at the same resolution.
//!
//! The lanes of a benchmark run render the same frame side by side, each
//! with its own depth buffer, and most of them draw many of the same
//! instances: view-frustum culling every one in the frustum, the others
//! what they find visible. A triangle's set-up (transform, projection,
//! snapping, edges, depth plane) depends only on the instance, the camera's
//! view-projection and the buffer's size, never on what was drawn before,
//! so one lane's set-up is every lane's: the first lane to rasterize an
//! instance in a frame sets it up ([`Rasterizer::prepare_indexed`], from
//! its mesh's vertices and indices, the instances of a rasterizer call in
//! parallel) and keeps it here, the others bin and
//! rasterize it from here
//! ([`Rasterizer::execute_prepared`]). Images, counts and times are those
//! of setting it up in each lane (tested); what changes is how often the
//! CPU running the benchmark does it.

use crate::raster::{Prepared, Rasterizer};
use glam::Mat4;
use occlude_core::Scene;
use rayon::prelude::*;
use std::sync::{Arc, Mutex, OnceLock};

/// Set-ups shared by the soft backends that [`SoftBackend::share_setup`]
/// gives a clone of: a table for the latest camera any of them began a
/// frame with. Backends rendering the same frames in step (a benchmark's
/// lanes, frame after frame) share one table a frame; a backend beginning a
/// frame with another camera or buffer size starts a new table, which the
/// others find when they begin a frame with that camera, and keeps
/// setting up in it for itself meanwhile. A table holds, until the last
/// backend using it begins another frame, the set-up triangles of every
/// instance drawn through its camera that may cover a pixel centre, 64
/// bytes each: `occlude bench --paper chc --scene plant --frames 30`
/// (paper size) peaked at 447 MB resident with shared set-ups, 127 MB
/// without.
///
/// [`SoftBackend::share_setup`]: super::SoftBackend::share_setup
#[derive(Clone, Debug, Default)]
pub struct SharedSetup {
    latest: Arc<Mutex<Option<Arc<FrameSetup>>>>,
}

impl SharedSetup {
    /// A table no backend uses yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// The table for frames of `instances` instances at scene revision
    /// `revision` ([`Scene::revision`]: the same poses) seen through
    /// `view_projection` at `width` x `height`: the latest one if it is for
    /// those, else a new one, which becomes the latest.
    pub(super) fn frame(
        &self,
        view_projection: Mat4,
        width: u32,
        height: u32,
        instances: usize,
        revision: u64,
    ) -> Arc<FrameSetup> {
        let mut latest = self.latest.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let same = |f: &FrameSetup| {
            f.is_for(&view_projection)
                && (f.width, f.height, f.slots.len(), f.revision) == (width, height, instances, revision)
        };
        match latest.as_ref().filter(|f| same(f)) {
            Some(f) => Arc::clone(f),
            None => {
                let slots = (0..instances).map(|_| OnceLock::new()).collect();
                let f = Arc::new(FrameSetup { view_projection, width, height, revision, slots });
                *latest = Some(Arc::clone(&f));
                f
            }
        }
    }
}

/// The set-ups of one camera and buffer size, one slot per instance.
#[derive(Debug)]
pub(super) struct FrameSetup {
    view_projection: Mat4,
    width: u32,
    height: u32,
    revision: u64,
    slots: Vec<OnceLock<Prepared>>,
}

impl FrameSetup {
    /// The set-up of each of `instances`, in order: those no backend has set
    /// up yet set up here, in parallel (rayon), with `rasterizer`'s kernel.
    pub(super) fn prepare(&self, scene: &Scene, instances: &[u32], rasterizer: &Rasterizer) -> Vec<&Prepared> {
        instances
            .par_iter()
            .map_init(Vec::new, |clip, &i| {
                self.slots[i as usize].get_or_init(|| {
                    let indices = scene.clip_vertices(i, &self.view_projection, clip);
                    rasterizer.prepare_indexed(self.width, self.height, clip, indices, false)
                })
            })
            .collect()
    }

    /// Instance `i`'s set-up, if made (for tests: the backends take theirs
    /// from [`Self::prepare`]).
    #[cfg(test)]
    pub(super) fn get(&self, i: u32) -> Option<&Prepared> {
        self.slots[i as usize].get()
    }

    /// Whether its set-ups are for `view_projection`.
    fn is_for(&self, view_projection: &Mat4) -> bool {
        self.view_projection.to_cols_array().map(f32::to_bits) == view_projection.to_cols_array().map(f32::to_bits)
    }
}
