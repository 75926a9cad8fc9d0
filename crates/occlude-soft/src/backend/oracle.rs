//! The oracle pass behind `opt` ([`Instruments::oracle`]) on the soft
//! backend: every candidate drawn, then an equal-depth query of each
//! counting its pixels in the final image. Nothing here is on a frame's
//! clock; what matters is that the image and the counts are exact, and that
//! they come at a fraction of drawing every candidate twice.
//!
//! **Culled as it goes.** Candidates whose padded box
//! ([`query_box::padded`]) the depth image already hides are not rasterized,
//! by the depth-pyramid test of [`occlude_core::depth_pyramid`] (`hiz`'s,
//! with its footprint of the exact rasterizer's pixels, depth bias and
//! slack):
//!
//! - In the drawing pass the candidates go nearest box first, and before
//!   each rasterizer call of about `part` triangles the pyramid is rebuilt
//!   from the image so far. A candidate the test hides has every fragment
//!   behind what the buffer holds at its pixel, and the buffer only comes
//!   nearer, so its fragments would fail the `LESS` depth test whenever
//!   they were drawn: the final image, the per-pixel minimum of the drawn
//!   fragments whatever their order, is the same without it.
//! - In the query pass the pyramid is that of the final image. A hidden
//!   candidate has every fragment strictly behind the image's depth at its
//!   pixel, so no fragment equals it: its count is 0 without rasterizing.
//!
//! Why a hidden box hides what it holds: the instance's triangles lie in
//! its box, so their pixels lie in the box's footprint (grown by
//! `PIXEL_MARGIN` for the vertex snapping) and their depths are at least
//! the box's nearest corner depth, less the `f32` rounding of the depth
//! plane; the test takes that depth pulled towards the eye by the query
//! bias and `DEPTH_SLACK`, and a box with a corner near the eye is never
//! hidden. It is the argument by which a hidden query box hides a node's
//! contents in every query-based method, here applied to one instance; the
//! test `culling_changes_no_image_and_no_count` checks it against the
//! uncompromising oracle on random scenes and views.
//!
//! **Set up once.** A backend sharing its set-ups (`SharedSetup`, the
//! lanes of a benchmark run) takes its candidates' triangles from the table
//! of the oracle's camera: view-frustum culling's lane sets up every
//! instance in the frustum for that camera anyway, and the oracle's two
//! passes then neither project nor set up a triangle of their own. The
//! rasterizer gives a prepared command the results of setting it up in the
//! call.
//!
//! [`query_box::padded`]: occlude_core::query_box::padded

use super::shared_setup::FrameSetup;
use super::SoftBackend;
use crate::raster::{Command, CommandKind, DepthBuffer, DepthTest, Prepared};
use glam::Mat4;
use occlude_core::depth_pyramid::{box_footprint, DepthPyramid};
use occlude_core::query_box::padded;
use occlude_core::{Aabb, Camera, OracleView};

/// Texels a candidate's pyramid test reads at most, `REACH` x `REACH`: a
/// finer level than the usual 2 x 2 hides more candidates, for a few dozen
/// reads against the set-up of each of their triangles.
const REACH: u32 = 8;

/// The candidate test of a culled oracle pass: a depth pyramid of the image
/// as it was after the last rasterizer call.
struct Culling {
    camera: Camera,
    view_projection: Mat4,
    pyramid: DepthPyramid,
    /// The image the pyramid was built from, in memory reused call after call.
    image: Vec<f32>,
}

impl Culling {
    fn new(camera: &Camera, depth: &DepthBuffer) -> Self {
        let pyramid = DepthPyramid::new(depth.width(), depth.height());
        Self { camera: *camera, view_projection: camera.view_projection(), pyramid, image: Vec::new() }
    }

    /// Rebuilds the pyramid from `depth`.
    fn refresh(&mut self, depth: &DepthBuffer) {
        depth.copy_to(&mut self.image);
        self.pyramid.build(&self.image);
    }

    /// Whether every fragment of what lies in `bounds` is behind the image
    /// (module documentation).
    fn hides(&self, bounds: &Aabb) -> bool {
        let b = padded(bounds);
        if self.camera.box_touches_near_region(&b) {
            return false;
        }
        let (width, height) = self.pyramid.sizes()[0];
        !self.pyramid.test(&box_footprint(&self.view_projection, width, height, &b), REACH).visible
    }
}

impl SoftBackend {
    /// The oracle pass, each pass in rasterizer calls of about `part`
    /// triangles (at least one candidate each), so that a view of tens of
    /// millions of triangles holds a bounded number of them at once;
    /// candidates the image hides are culled when `cull` (module
    /// documentation). Image and counts are the same whatever `part` and
    /// `cull`.
    pub(super) fn oracle_in_parts(
        &mut self,
        camera: &Camera,
        candidates: &[u32],
        part: usize,
        cull: bool,
    ) -> OracleView {
        self.view_projection = camera.view_projection();
        self.depth.clear();
        let (width, height, instances) = (self.depth.width(), self.depth.height(), self.scene.instances.len());
        let setup = self
            .shared_setup
            .as_ref()
            .map(|s| s.frame(self.view_projection, width, height, instances, self.scene.revision()));
        let setup = setup.as_deref();
        let mut culling = cull.then(|| Culling::new(camera, &self.depth));
        // Hidden instances draw nothing: 0 pixels.
        let shown = |&k: &usize| self.scene.instances[candidates[k] as usize].enabled;
        let mut order: Vec<usize> = (0..candidates.len()).filter(shown).collect();
        if cull {
            // Nearest first, so that the near ones hide the far ones.
            let distance =
                |k: usize| self.scene.instances[candidates[k] as usize].bounds.distance_squared(camera.position);
            order.sort_by(|&a, &b| distance(a).total_cmp(&distance(b)).then(a.cmp(&b)));
        }
        self.oracle_pass(CommandKind::Draw, candidates, &order, part, setup, culling.as_mut());
        // The drawing pass refreshed the pyramid after its last call: it is
        // the final image's.
        order.sort_unstable();
        let kind = CommandKind::Query(DepthTest::Equal);
        let mut pixels = vec![0; candidates.len()];
        for (k, passed) in self.oracle_pass(kind, candidates, &order, part, setup, culling.as_mut()) {
            pixels[k] = passed;
        }
        OracleView::new(candidates, pixels, self.depth.to_vec(), self.depth.width(), self.depth.height())
    }

    /// One pass of the oracle: `candidates[k]` for each `k` of `order`
    /// rasterized as `kind` in calls of about `part` triangles, set up in
    /// `setup` if given, those that `culling` hides skipped (its pyramid
    /// rebuilt after every call of a drawing pass). Returns the index `k` of
    /// each rasterized candidate with its passing pixels.
    fn oracle_pass(
        &mut self,
        kind: CommandKind,
        candidates: &[u32],
        order: &[usize],
        part: usize,
        setup: Option<&FrameSetup>,
        mut culling: Option<&mut Culling>,
    ) -> Vec<(usize, u64)> {
        let (mut commands, mut rasterized, mut counted) = (Vec::new(), Vec::new(), Vec::new());
        // The instances of the call's commands, and their triangles, when set up in `setup`.
        let (mut instances, mut prepared_triangles) = (Vec::new(), 0);
        for (n, &k) in order.iter().enumerate() {
            let i = candidates[k];
            if !culling.as_ref().is_some_and(|c| c.hides(&self.scene.instances[i as usize].bounds)) {
                let first = self.triangles.len() as u32;
                match setup {
                    Some(_) => {
                        instances.push(i);
                        prepared_triangles += self.scene.instance_triangles(i as usize) as usize;
                    }
                    None => self.push_instance_triangles(i),
                }
                commands.push(Command { kind, triangles: first..self.triangles.len() as u32, cull_back: false });
                rasterized.push(k);
            }
            if !commands.is_empty() && (self.triangles.len() + prepared_triangles >= part || n + 1 == order.len()) {
                let prepared: Vec<Option<&Prepared>> = match setup {
                    Some(setup) => {
                        setup.prepare(&self.scene, &instances, &self.rasterizer).into_iter().map(Some).collect()
                    }
                    None => Vec::new(),
                };
                let results = self.rasterizer.execute_prepared(&mut self.depth, &self.triangles, &commands, &prepared);
                counted.extend(rasterized.drain(..).zip(results.iter().map(|r| r.passed)));
                self.triangles.clear();
                commands.clear();
                instances.clear();
                prepared_triangles = 0;
                if let Some(c) = culling.as_deref_mut().filter(|_| kind == CommandKind::Draw) {
                    c.refresh(&self.depth);
                }
            }
        }
        counted
    }
}

#[cfg(test)]
mod tests {
    use crate::gpu_model::GpuModel;
    use crate::{SharedSetup, SoftBackend};
    use glam::Vec3;
    use occlude_core::{Aabb, Keyframe, Scene};
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]
        /// On random boxes (overlapping, touching the eye, off screen) seen
        /// from random places, the culled oracle gives the unculled one's
        /// image and counts bit for bit, whatever the size of its calls and
        /// whether it sets up its triangles in a shared table.
        #[test]
        fn culling_changes_no_image_and_no_count(
            boxes in prop::collection::vec((prop::array::uniform3(-10.0f32..10.0), prop::array::uniform3(0.02f32..4.0)), 1..80),
            eye in prop::array::uniform3(-12.0f32..12.0),
            look in prop::array::uniform3(-1.0f32..1.0),
            part in 1usize..300,
            shared in any::<bool>(),
        ) {
            let bounds: Vec<Aabb> =
                boxes.iter().map(|&(c, h)| Aabb::new(Vec3::from(c) - Vec3::from(h), Vec3::from(c) + Vec3::from(h))).collect();
            let scene = Scene::from_bounds("boxes", &bounds).unwrap();
            let position = Vec3::from(eye);
            prop_assume!(Vec3::from(look).length() > 0.1);
            let key = Keyframe { time: 0.0, position, target: position + Vec3::from(look), fov_y_deg: 60.0 };
            let camera = key.camera(4.0 / 3.0, 0.1, 100.0);
            let candidates: Vec<u32> = (0..bounds.len() as u32).collect();
            let view = |part: usize, cull: bool, shared: bool| {
                let mut backend = SoftBackend::new(&scene, 83, 61, GpuModel::modern());
                if shared {
                    backend.share_setup(SharedSetup::new());
                }
                let v = backend.oracle_in_parts(&camera, &candidates, part, cull);
                (v.pixels, v.depth.iter().map(|d| d.to_bits()).collect::<Vec<_>>())
            };
            prop_assert_eq!(view(part, true, shared), view(usize::MAX, false, false));
        }
    }
}
