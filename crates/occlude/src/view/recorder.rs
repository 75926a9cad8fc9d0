//! [`RecordingBackend`]: a [`Backend`] that forwards every call to another
//! and, while recording, keeps each occlusion query's boxes and the result
//! the method read, so that the viewer can draw them (the CHC paper's
//! Figure 4) without any method knowing.

use occlude_core::{Aabb, Backend, Camera, FrameStats, OracleView, QueryHandle};
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

/// Forwards to `inner`, recording the frame's queries when asked to.
pub struct RecordingBackend<B> {
    inner: B,
    recording: bool,
    queries: Vec<RecordedQuery>,
    /// This frame's query handles, to the index of their record.
    index: HashMap<QueryHandle, usize>,
}

impl<B: Backend> RecordingBackend<B> {
    /// A wrapper around `inner`, not recording.
    pub fn new(inner: B) -> Self {
        Self { inner, recording: false, queries: Vec::new(), index: HashMap::new() }
    }

    /// Records the queries of the frames that begin from now on (`true`) or
    /// stops (`false`; nothing is kept, so recording costs nothing when off).
    pub fn set_recording(&mut self, on: bool) {
        self.recording = on;
    }

    /// The queries of the last frame begun while recording, in issue order.
    pub fn queries(&self) -> &[RecordedQuery] {
        &self.queries
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
}

impl<B: Backend> Backend for RecordingBackend<B> {
    fn begin_frame(&mut self, camera: &Camera) {
        self.queries.clear();
        self.index.clear();
        self.inner.begin_frame(camera);
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

    fn cpu_culling(&mut self, work: occlude_core::CpuCullingWork) {
        self.inner.cpu_culling(work);
    }

    fn end_frame(&mut self) -> FrameStats {
        self.inner.end_frame()
    }

    fn depth_image(&mut self, out: &mut Vec<f32>) {
        self.inner.depth_image(out);
    }

    fn oracle(&mut self, camera: &Camera, candidates: &[u32]) -> OracleView {
        self.inner.oracle(camera, candidates)
    }

    fn failure(&self) -> Option<String> {
        self.inner.failure()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::config::NEAR_PLANE;
    use crate::bench::runner::render_frame;
    use occlude_core::methods::{create, DrawnSet, MethodOptions};
    use occlude_core::{Hierarchy, HierarchyKind};
    use occlude_soft::{GpuModel, SoftBackend};

    /// CHC on the soft backend through the recorder: every query is
    /// recorded, every one CHC read has its result, and the statistics are
    /// those of the unwrapped backend.
    #[test]
    fn records_every_query_and_changes_nothing() {
        let scene = occlude_scenes::generate("city", occlude_scenes::Size::Small, 1).unwrap();
        let hierarchy = Hierarchy::build(&scene, HierarchyKind::Bvh, Default::default());
        let cameras = scene.path.sample(4, 4.0 / 3.0, NEAR_PLANE, 2000.0);
        let soft = || SoftBackend::new(&scene, 160, 120, GpuModel::modern());
        let mut plain = (create("chc", &MethodOptions::default()).unwrap(), soft(), DrawnSet::default());
        let mut wrapped =
            (create("chc", &MethodOptions::default()).unwrap(), RecordingBackend::new(soft()), DrawnSet::default());
        let (mut visible, mut occluded) = (0, 0);
        for (k, camera) in cameras.iter().enumerate() {
            wrapped.1.set_recording(k % 2 == 1);
            let a = render_frame(plain.0.method.as_mut(), &mut plain.1, &scene, &hierarchy, camera, &mut plain.2);
            let b = render_frame(wrapped.0.method.as_mut(), &mut wrapped.1, &scene, &hierarchy, camera, &mut wrapped.2);
            assert_eq!((a.queries, a.draw_calls, a.triangles), (b.queries, b.draw_calls, b.triangles));
            let recorded = wrapped.1.queries();
            if k % 2 == 0 {
                assert!(recorded.is_empty(), "frame {k} was not recorded");
                continue;
            }
            assert_eq!(recorded.len() as u64, b.queries, "frame {k}");
            assert_eq!(recorded.iter().map(|q| q.boxes.len() as u64).sum::<u64>(), b.query_boxes);
            for q in recorded {
                match q.outcome() {
                    QueryOutcome::Visible => visible += 1,
                    QueryOutcome::Occluded => occluded += 1,
                    QueryOutcome::Unread => panic!("CHC reads every query it issues"),
                }
            }
        }
        assert!(visible > 0 && occluded > 0, "visible {visible}, occluded {occluded}");
    }
}
