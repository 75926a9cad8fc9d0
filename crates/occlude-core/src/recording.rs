//! [`RecordingBackend`]: a [`Backend`] (and [`GpuCulling`], where the
//! wrapped backend has it) that forwards every call to another and, while
//! recording, keeps each occlusion query's boxes and the result the method
//! read, and each batched box test's boxes and outcomes (and, for a test
//! against a depth pyramid, the pyramid level each box was tested at), so
//! that a viewer can draw them (the CHC paper's Figure 4; the IOC poster's
//! levels; `hiz`'s pyramid levels) without any method knowing. `occlude view` draws them; a renderer embedding
//! occlude can wrap its own backend the same way to debug its culling.

use crate::depth_pyramid::tested_levels;
use crate::{
    Aabb, Backend, BoxSet, Camera, CostModel, CpuCullingWork, ExpandInto, Flags, FrameStats, GpuCulling,
    GpuCullingUnsupported, IdList, Instruments, ItemRange, Pyramid, QueryHandle, RangeTable, Scene,
};
use std::collections::HashMap;

/// What a query answered, as far as the method asked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QueryOutcome {
    /// The method read a visible-pixel count above zero.
    Visible,
    /// The method read zero: the boxes were hidden.
    Occluded,
    /// The method never read the result in the frame.
    Unread,
}

/// One query of the last recorded frame.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordedQuery {
    /// The boxes the query rasterized (several for a multi-query), as the
    /// method gave them.
    pub boxes: Vec<Aabb>,
    /// The visible-pixel count the method read, if it read one.
    pub result: Option<u64>,
}

impl RecordedQuery {
    /// Visible, occluded or unread.
    pub fn outcome(&self) -> QueryOutcome {
        match self.result {
            Some(0) => QueryOutcome::Occluded,
            Some(_) => QueryOutcome::Visible,
            None => QueryOutcome::Unread,
        }
    }
}

/// One batched box test ([`GpuCulling::test_boxes`]) of the last recorded
/// frame: for `ioc`, one level of the hierarchy.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RecordedBoxTest {
    /// The boxes of the ids tested, as the method created them.
    pub boxes: Vec<Aabb>,
    /// Per box, whether its flag was set after the test (by this test, or
    /// by an earlier one of the frame into the same flags).
    pub visible: Vec<bool>,
    /// Per box, for a test against a depth pyramid
    /// ([`GpuCulling::test_boxes_pyramid`]), the pyramid level it was
    /// tested at ([`tested_levels`]: the footprint and level selection of
    /// the test itself); `None` for a box the test read no level for (at
    /// the eye, outside the view, covering no pixel centre) and for every
    /// box of a full-resolution test ([`GpuCulling::test_boxes`]).
    pub levels: Vec<Option<u32>>,
}

impl RecordedBoxTest {
    /// How many of the boxes were found visible.
    pub fn visible_count(&self) -> usize {
        self.visible.iter().filter(|&&v| v).count()
    }
}

/// Forwards to `inner`, recording the frame's queries and box tests when
/// asked to.
pub struct RecordingBackend<B> {
    inner: B,
    recording: bool,
    queries: Vec<RecordedQuery>,
    /// This frame's query handles, to the index of their record.
    index: HashMap<QueryHandle, usize>,
    tests: Vec<RecordedBoxTest>,
    /// The boxes of every box set created through the recorder, by set.
    box_sets: HashMap<BoxSet, Vec<Aabb>>,
    /// The camera of the frame begun last, which pyramid tests project
    /// boxes with.
    camera: Option<Camera>,
}

impl<B: Backend> RecordingBackend<B> {
    /// A wrapper around `inner`, not recording.
    pub fn new(inner: B) -> Self {
        Self {
            inner,
            recording: false,
            queries: Vec::new(),
            index: HashMap::new(),
            tests: Vec::new(),
            box_sets: HashMap::new(),
            camera: None,
        }
    }

    /// Records the queries and box tests of the frames that begin from now
    /// on (`true`) or stops (`false`; nothing is kept, so recording costs
    /// nothing when off). Recording a box test reads its ids and flags back
    /// from the device, which the frame's statistics count (read-backs,
    /// wait time).
    pub fn set_recording(&mut self, on: bool) {
        self.recording = on;
    }

    /// The queries of the last frame begun while recording, in issue order.
    pub fn queries(&self) -> &[RecordedQuery] {
        &self.queries
    }

    /// The box tests of the last frame begun while recording, in order.
    pub fn box_tests(&self) -> &[RecordedBoxTest] {
        &self.tests
    }

    /// The wrapped backend.
    pub fn inner(&self) -> &B {
        &self.inner
    }

    /// The wrapped backend, mutably.
    pub fn inner_mut(&mut self) -> &mut B {
        &mut self.inner
    }

    fn record_result(&mut self, query: QueryHandle, value: u64) {
        if let Some(&i) = self.index.get(&query) {
            self.queries[i].result = Some(value);
        }
    }

    /// While recording, the ids a box test of `boxes` just tested and the
    /// outcome each left in `flags`, read back; for a pyramid test (`Some`
    /// reach), the level each box was tested at.
    fn record_test(&mut self, boxes: BoxSet, ids: IdList, flags: Flags, pyramid_reach: Option<u32>) {
        if !self.recording {
            return;
        }
        let tested = self.culling().read_list(ids);
        let set = self.culling().read_flags(flags);
        let all = &self.box_sets[&boxes];
        let boxes: Vec<Aabb> = tested.iter().map(|&id| all[id as usize]).collect();
        let levels = match (pyramid_reach, &self.camera) {
            (Some(reach), Some(camera)) => {
                let (width, height) = self.inner.resolution();
                tested_levels(camera, width, height, &boxes, reach)
            }
            _ => vec![None; boxes.len()],
        };
        self.tests.push(RecordedBoxTest {
            boxes,
            visible: tested.iter().map(|&id| set[id as usize]).collect(),
            levels,
        });
    }

    /// The wrapped backend's GPU-resident culling, which the recorder only
    /// offers where the wrapped backend does.
    fn culling(&mut self) -> &mut dyn GpuCulling {
        self.inner.gpu_culling().expect("the recorder offers GPU culling only where its backend has it")
    }
}

impl<B: Backend> Backend for RecordingBackend<B> {
    fn begin_frame(&mut self, camera: &Camera) {
        self.queries.clear();
        self.index.clear();
        self.tests.clear();
        self.camera = Some(*camera);
        self.inner.begin_frame(camera);
    }

    fn update_instances(&mut self, scene: &Scene, changed: &[u32]) {
        self.inner.update_instances(scene, changed);
    }

    fn draw(&mut self, instances: &[u32]) {
        self.inner.draw(instances);
    }

    fn issue_query(&mut self, boxes: &[Aabb]) -> QueryHandle {
        let handle = self.inner.issue_query(boxes);
        if self.recording {
            self.index.insert(handle, self.queries.len());
            self.queries.push(RecordedQuery { boxes: boxes.to_vec(), result: None });
        }
        handle
    }

    fn is_available(&mut self, query: QueryHandle) -> bool {
        self.inner.is_available(query)
    }

    fn result(&mut self, query: QueryHandle) -> u64 {
        let value = self.inner.result(query);
        self.record_result(query, value);
        value
    }

    fn traverse(&mut self, nodes: u64) {
        self.inner.traverse(nodes);
    }

    fn resolution(&self) -> (u32, u32) {
        self.inner.resolution()
    }

    fn cpu_culling(&mut self, work: CpuCullingWork) {
        self.inner.cpu_culling(work);
    }

    fn end_frame(&mut self) -> FrameStats {
        self.inner.end_frame()
    }

    fn failure(&self) -> Option<String> {
        self.inner.failure()
    }

    fn gpu_culling(&mut self) -> Result<&mut dyn GpuCulling, GpuCullingUnsupported> {
        self.inner.gpu_culling()?;
        Ok(self)
    }

    fn instruments(&mut self) -> Option<&mut dyn Instruments> {
        self.inner.instruments()
    }

    fn cost_model(&self) -> Option<CostModel> {
        self.inner.cost_model()
    }
}

impl<B: Backend> GpuCulling for RecordingBackend<B> {
    fn create_boxes(&mut self, boxes: &[Aabb]) -> BoxSet {
        let set = self.culling().create_boxes(boxes);
        self.box_sets.insert(set, boxes.to_vec());
        set
    }

    fn update_boxes(&mut self, boxes: BoxSet, changed: &[(u32, Aabb)]) {
        self.culling().update_boxes(boxes, changed);
        if let Some(set) = self.box_sets.get_mut(&boxes) {
            for (slot, b) in changed {
                set[*slot as usize] = *b;
            }
        }
    }

    fn release_all(&mut self) {
        self.culling().release_all();
        self.box_sets.clear();
    }

    fn create_flags(&mut self, len: u32) -> Flags {
        self.culling().create_flags(len)
    }

    fn create_list(&mut self, capacity: u32, ids: &[u32]) -> IdList {
        self.culling().create_list(capacity, ids)
    }

    fn create_table(&mut self, ranges: &[ItemRange], items: &[u32]) -> RangeTable {
        self.culling().create_table(ranges, items)
    }

    fn clear_flags(&mut self, flags: Flags) {
        self.culling().clear_flags(flags);
    }

    fn write_flags(&mut self, flags: Flags, set: &[bool]) {
        self.culling().write_flags(flags, set);
    }

    fn copy_flags(&mut self, src: Flags, dst: Flags) {
        self.culling().copy_flags(src, dst);
    }

    fn test_boxes(&mut self, boxes: BoxSet, ids: IdList, flags: Flags) {
        self.culling().test_boxes(boxes, ids, flags);
        self.record_test(boxes, ids, flags, None);
    }

    fn pyramid_support(&mut self) -> Result<(), GpuCullingUnsupported> {
        self.culling().pyramid_support()
    }

    fn create_pyramid(&mut self) -> Pyramid {
        self.culling().create_pyramid()
    }

    fn build_pyramid(&mut self, pyramid: Pyramid) {
        self.culling().build_pyramid(pyramid);
    }

    fn test_boxes_pyramid(&mut self, boxes: BoxSet, ids: IdList, pyramid: Pyramid, reach: u32, flags: Flags) {
        self.culling().test_boxes_pyramid(boxes, ids, pyramid, reach, flags);
        self.record_test(boxes, ids, flags, Some(reach));
    }

    fn expand(&mut self, src: IdList, filter: Flags, table: RangeTable, into: ExpandInto) {
        self.culling().expand(src, filter, table, into);
    }

    fn drop_outside_frustum(&mut self, boxes: BoxSet, flags: Flags) {
        self.culling().drop_outside_frustum(boxes, flags);
    }

    fn compact(&mut self, flags: Flags, unless: Option<Flags>, dst: IdList) {
        self.culling().compact(flags, unless, dst);
    }

    fn draw_list(&mut self, list: IdList) {
        self.culling().draw_list(list);
    }

    fn read_count(&mut self, list: IdList) -> u32 {
        self.culling().read_count(list)
    }

    fn read_list(&mut self, list: IdList) -> Vec<u32> {
        self.culling().read_list(list)
    }

    fn read_flags(&mut self, flags: Flags) -> Vec<bool> {
        self.culling().read_flags(flags)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mock::assert_forwards_every_call;

    /// The recorder forwards every call of the backend interface.
    #[test]
    fn forwards_every_call() {
        assert_forwards_every_call(RecordingBackend::new);
    }
}
