//! [`MockBackend`]: a [`Backend`] without pixels, for testing methods and
//! decorators, a user's own included.
//!
//! It answers occlusion queries from a scripted visibility model instead of
//! rasterizing: each instance is visible (the default) or hidden
//! ([`MockBackend::set_visible`]), and a query is answered with the number
//! of visible instances in the view frustum whose boxes meet one of its
//! boxes. A node is so visible exactly when it holds a visible instance,
//! and a method that is right draws every visible instance in view and no
//! node without one. A query's result becomes available once
//! [`MockBackend::with_latency`] further commands (draws and queries) have
//! been issued after it, as a GPU's queue would delay it; reading it
//! earlier is a wait. Every call of the [`Backend`] trait is logged
//! ([`Call`]), so that tests can check the order of a method's draws and
//! queries, and that a decorator forwards every call
//! ([`assert_forwards_every_call`]).
//!
//! GPU-resident culling is off unless asked for
//! ([`MockBackend::with_gpu_culling`]); then box tests (against the depth
//! buffer or a pyramid alike) set the flag of a box that meets a visible
//! instance in the frustum or touches the camera's near region, the other
//! commands move ids and flags as the soft backend's do
//! ([`HostResources`]), and the commands that draw, test, build a pyramid
//! or read back are logged too. The mock has no [`Instruments`] (no image):
//! `opt` is refused on it by
//! [`check_support`](crate::methods::check_support), as the GPU-driven
//! methods are without GPU culling.

use crate::backend::{Backend, CpuCullingWork, FrameCounter, Instruments, QueryHandle, RenderState};
use crate::camera::Camera;
use crate::cost_model::CostModel;
use crate::geometry::Aabb;
use crate::gpu_culling::{
    BoxSet, ExpandInto, Flags, GpuCulling, GpuCullingUnsupported, IdList, ItemRange, Pyramid, RangeTable,
};
use crate::host_culling::HostResources;
use crate::scene::{Mesh, Scene};
use crate::stats::FrameStats;
use glam::{Mat4, Vec3};
use std::cell::RefCell;
use std::rc::Rc;

/// One call a [`MockBackend`] received, in the order received.
#[derive(Clone, Debug, PartialEq)]
pub enum Call {
    /// `begin_frame`.
    BeginFrame,
    /// `update_instances` of these instances.
    UpdateInstances(Vec<u32>),
    /// `draw` of these instances.
    Draw(Vec<u32>),
    /// `issue_query` over these boxes, answered by this handle.
    IssueQuery {
        /// The handle returned.
        query: QueryHandle,
        /// The boxes queried.
        boxes: Vec<Aabb>,
    },
    /// `is_available`, with its answer.
    IsAvailable {
        /// The query asked about.
        query: QueryHandle,
        /// Whether it was available.
        available: bool,
    },
    /// `result`, with whether the caller had to wait for it.
    Result {
        /// The query read.
        query: QueryHandle,
        /// The answer: visible instances the query's boxes meet.
        value: u64,
        /// True when the result was not available yet (a stall).
        waited: bool,
    },
    /// `traverse` of this many nodes.
    Traverse(u64),
    /// `resolution`.
    Resolution,
    /// `cpu_culling` with this work.
    CpuCulling(CpuCullingWork),
    /// `end_frame`.
    EndFrame,
    /// `failure`.
    Failure,
    /// `gpu_culling`.
    GpuCulling,
    /// `instruments`.
    Instruments,
    /// `cost_model`.
    CostModel,
    /// [`GpuCulling::test_boxes`] (`pyramid` false) or
    /// [`GpuCulling::test_boxes_pyramid`] (true) of these ids.
    TestBoxes {
        /// The ids of the list tested.
        ids: Vec<u32>,
        /// Whether the test was against a depth pyramid.
        pyramid: bool,
    },
    /// [`GpuCulling::build_pyramid`].
    BuildPyramid,
    /// [`GpuCulling::draw_list`] of these instances.
    DrawList(Vec<u32>),
    /// [`GpuCulling::read_count`], [`GpuCulling::read_list`] or
    /// [`GpuCulling::read_flags`].
    ReadBack,
}

impl Call {
    /// The [`Backend`] method's name, as [`BACKEND_CALLS`] lists it.
    pub fn name(&self) -> &'static str {
        match self {
            Call::BeginFrame => "begin_frame",
            Call::UpdateInstances(_) => "update_instances",
            Call::Draw(_) => "draw",
            Call::IssueQuery { .. } => "issue_query",
            Call::IsAvailable { .. } => "is_available",
            Call::Result { .. } => "result",
            Call::Traverse(_) => "traverse",
            Call::Resolution => "resolution",
            Call::CpuCulling(_) => "cpu_culling",
            Call::EndFrame => "end_frame",
            Call::Failure => "failure",
            Call::GpuCulling => "gpu_culling",
            Call::Instruments => "instruments",
            Call::CostModel => "cost_model",
            Call::TestBoxes { .. } => "test_boxes",
            Call::BuildPyramid => "build_pyramid",
            Call::DrawList(_) => "draw_list",
            Call::ReadBack => "read_back",
        }
    }
}

/// Every method of the [`Backend`] trait, in the order it declares them.
pub const BACKEND_CALLS: [&str; 14] = [
    "begin_frame",
    "update_instances",
    "draw",
    "issue_query",
    "is_available",
    "result",
    "traverse",
    "resolution",
    "cpu_culling",
    "end_frame",
    "failure",
    "gpu_culling",
    "instruments",
    "cost_model",
];

/// The calls a [`MockBackend`] received, shared with whoever holds a handle
/// ([`MockBackend::log`]), so that a test can read them through a decorator
/// that owns the mock.
pub type CallLog = Rc<RefCell<Vec<Call>>>;

/// What the mock's `gpu_culling` answers, so that a test can tell a
/// forwarded answer from a decorator's own default.
pub const NO_GPU_CULLING: &str = "the mock backend has no GPU-resident culling";

#[derive(Clone, Copy, Debug)]
struct MockQuery {
    value: u64,
    /// The command count at which the result becomes available.
    ready_at: u64,
}

/// A backend that answers queries from a scripted visibility model and logs
/// every call (module documentation).
#[derive(Debug)]
pub struct MockBackend {
    bounds: Vec<Aabb>,
    triangles: Vec<u64>,
    materials: Vec<u32>,
    visible: Vec<bool>,
    latency: u64,
    resolution: (u32, u32),
    camera: Option<Camera>,
    count: FrameCounter,
    /// GPU-resident culling's resources, when it is on.
    culling: Option<HostResources>,
    cost_model: Option<CostModel>,
    queries: Vec<MockQuery>,
    commands: u64,
    log: CallLog,
}

impl MockBackend {
    /// A mock of `scene`'s instances (their boxes, triangle counts and
    /// materials) rendering `width` x `height` images, every instance
    /// visible, results available at once.
    pub fn new(scene: &Scene, width: u32, height: u32) -> Self {
        let instances = &scene.instances;
        Self {
            bounds: instances.iter().map(|i| i.culling_bounds()).collect(),
            triangles: (0..instances.len()).map(|i| scene.instance_triangles(i)).collect(),
            materials: instances.iter().map(|i| i.material).collect(),
            visible: vec![true; instances.len()],
            latency: 0,
            resolution: (width, height),
            camera: None,
            count: FrameCounter::new(instances.len()),
            culling: None,
            cost_model: None,
            queries: Vec::new(),
            commands: 0,
            log: CallLog::default(),
        }
    }

    /// The mock with each query's result available only after `commands`
    /// further draws and queries.
    pub fn with_latency(mut self, commands: u64) -> Self {
        self.latency = commands;
        self
    }

    /// The mock with GPU-resident culling ([`GpuCulling`], depth pyramids
    /// included), answered from the same script as queries.
    pub fn with_gpu_culling(mut self) -> Self {
        self.culling = Some(HostResources::default());
        self
    }

    /// The mock answering [`Backend::cost_model`] with `model` (by default
    /// it has none, as a backend that measures its time).
    pub fn with_cost_model(mut self, model: CostModel) -> Self {
        self.cost_model = Some(model);
        self
    }

    /// Scripts instance `instance` visible or hidden, from the next query on.
    pub fn set_visible(&mut self, instance: u32, visible: bool) {
        self.visible[instance as usize] = visible;
    }

    /// A handle on the log of calls (shared, also through decorators).
    pub fn log(&self) -> CallLog {
        Rc::clone(&self.log)
    }

    /// The calls logged so far, removed from the log.
    pub fn take_log(&self) -> Vec<Call> {
        std::mem::take(&mut self.log.borrow_mut())
    }

    fn push(&self, call: Call) {
        self.log.borrow_mut().push(call);
    }

    /// The number of visible instances in the frustum whose boxes meet one
    /// of `boxes`: a query's answer.
    fn visible_instances(&self, boxes: &[Aabb]) -> u64 {
        let frustum = self.camera.as_ref().expect("a query or box test outside a frame").frustum();
        (0..self.bounds.len())
            .filter(|&i| self.visible[i] && frustum.intersects(&self.bounds[i]))
            .filter(|&i| boxes.iter().any(|b| b.overlaps(&self.bounds[i])))
            .count() as u64
    }

    /// GPU-resident culling's resources (only offered when on).
    fn resources(&mut self) -> &mut HostResources {
        self.culling.as_mut().expect("GPU culling is offered only when on")
    }

    /// A box test of the boxes of `boxes` named by `ids` into `flags`.
    fn test(&mut self, boxes: BoxSet, ids: IdList, flags: Flags, pyramid: bool) {
        let camera = self.camera.expect("a box test outside a frame");
        let frustum = camera.frustum();
        let res = self.culling.as_ref().expect("GPU culling is offered only when on");
        let tested = res.lists[ids.0 as usize].ids.clone();
        let set: Vec<u32> = tested
            .iter()
            .copied()
            .filter(|&id| {
                res.boxes[boxes.0 as usize][id as usize].is_some_and(|b| {
                    camera.box_touches_near_region(&b) || (frustum.intersects(&b) && self.visible_instances(&[b]) > 0)
                })
            })
            .collect();
        self.count.stats.query_boxes += tested.len() as u64;
        self.resources().put(set, ExpandInto::Flags(flags));
        self.commands += 1;
        self.push(Call::TestBoxes { ids: tested, pyramid });
    }

    fn is_ready(&self, query: QueryHandle) -> bool {
        self.queries[query.0 as usize].ready_at <= self.commands
    }
}

impl Backend for MockBackend {
    fn begin_frame(&mut self, camera: &Camera) {
        self.camera = Some(*camera);
        self.count.begin_frame();
        self.queries.clear();
        self.push(Call::BeginFrame);
    }

    fn update_instances(&mut self, scene: &Scene, changed: &[u32]) {
        for &i in changed {
            let inst = &scene.instances[i as usize];
            self.bounds[i as usize] = inst.culling_bounds();
            self.triangles[i as usize] = scene.instance_triangles(i as usize);
        }
        self.push(Call::UpdateInstances(changed.to_vec()));
    }

    fn draw(&mut self, instances: &[u32]) {
        for &i in instances {
            self.count.set_state(RenderState::Material(self.materials[i as usize]));
            self.count.draw(i, self.triangles[i as usize]);
        }
        self.commands += 1;
        self.push(Call::Draw(instances.to_vec()));
    }

    fn issue_query(&mut self, boxes: &[Aabb]) -> QueryHandle {
        let value = self.visible_instances(boxes);
        self.count.query(boxes.len());
        self.commands += 1;
        let query = QueryHandle(self.queries.len() as u32);
        self.queries.push(MockQuery { value, ready_at: self.commands + self.latency });
        self.push(Call::IssueQuery { query, boxes: boxes.to_vec() });
        query
    }

    fn is_available(&mut self, query: QueryHandle) -> bool {
        let available = self.is_ready(query);
        self.push(Call::IsAvailable { query, available });
        available
    }

    fn result(&mut self, query: QueryHandle) -> u64 {
        let waited = !self.is_ready(query);
        let value = self.queries[query.0 as usize].value;
        self.push(Call::Result { query, value, waited });
        value
    }

    fn traverse(&mut self, nodes: u64) {
        self.count.traverse(nodes);
        self.push(Call::Traverse(nodes));
    }

    fn resolution(&self) -> (u32, u32) {
        self.push(Call::Resolution);
        self.resolution
    }

    fn cpu_culling(&mut self, work: CpuCullingWork) {
        self.push(Call::CpuCulling(work));
    }

    fn end_frame(&mut self) -> FrameStats {
        self.camera = None;
        self.push(Call::EndFrame);
        self.count.stats
    }

    fn failure(&self) -> Option<String> {
        self.push(Call::Failure);
        None
    }

    fn gpu_culling(&mut self) -> Result<&mut dyn GpuCulling, GpuCullingUnsupported> {
        self.push(Call::GpuCulling);
        if self.culling.is_none() {
            return Err(GpuCullingUnsupported(NO_GPU_CULLING.into()));
        }
        Ok(self)
    }

    fn instruments(&mut self) -> Option<&mut dyn Instruments> {
        self.push(Call::Instruments);
        None
    }

    fn cost_model(&self) -> Option<CostModel> {
        self.push(Call::CostModel);
        self.cost_model
    }
}

impl GpuCulling for MockBackend {
    fn create_boxes(&mut self, boxes: &[Aabb]) -> BoxSet {
        self.resources().create_boxes(boxes)
    }

    fn update_boxes(&mut self, boxes: BoxSet, changed: &[(u32, Aabb)]) {
        self.resources().update_boxes(boxes, changed);
    }

    fn release_all(&mut self) {
        self.resources().release_all();
    }

    fn create_flags(&mut self, len: u32) -> Flags {
        self.resources().create_flags(len)
    }

    fn create_list(&mut self, capacity: u32, ids: &[u32]) -> IdList {
        self.resources().create_list(capacity, ids)
    }

    fn create_table(&mut self, ranges: &[ItemRange], items: &[u32]) -> RangeTable {
        self.resources().create_table(ranges, items)
    }

    fn clear_flags(&mut self, flags: Flags) {
        self.resources().flags[flags.0 as usize].fill(false);
    }

    fn write_flags(&mut self, flags: Flags, set: &[bool]) {
        self.resources().write_flags(flags, set);
    }

    fn copy_flags(&mut self, src: Flags, dst: Flags) {
        self.resources().copy_flags(src, dst);
    }

    fn test_boxes(&mut self, boxes: BoxSet, ids: IdList, flags: Flags) {
        self.test(boxes, ids, flags, false);
    }

    fn pyramid_support(&mut self) -> Result<(), GpuCullingUnsupported> {
        Ok(())
    }

    fn create_pyramid(&mut self) -> Pyramid {
        let (width, height) = self.resolution;
        self.resources().create_pyramid(width, height)
    }

    fn build_pyramid(&mut self, _pyramid: Pyramid) {
        self.push(Call::BuildPyramid);
    }

    /// The script has no depth: a pyramid test answers as a test against
    /// the depth buffer does (a pyramid may only add visibility).
    fn test_boxes_pyramid(&mut self, boxes: BoxSet, ids: IdList, _pyramid: Pyramid, _reach: u32, flags: Flags) {
        self.test(boxes, ids, flags, true);
    }

    fn expand(&mut self, src: IdList, filter: Flags, table: RangeTable, into: ExpandInto) {
        let items = self.resources().gather(src, filter, table);
        self.resources().put(items, into);
    }

    fn drop_outside_frustum(&mut self, boxes: BoxSet, flags: Flags) {
        let frustum = self.camera.expect("drop_outside_frustum outside a frame").frustum();
        self.resources().drop_outside_frustum(boxes, flags, &frustum);
    }

    fn compact(&mut self, flags: Flags, unless: Option<Flags>, dst: IdList) {
        let ids = self.resources().compacted(flags, unless);
        self.resources().lists[dst.0 as usize].set(ids);
    }

    fn draw_list(&mut self, list: IdList) {
        let ids = self.resources().lists[list.0 as usize].ids.clone();
        self.count.indirect_draw(RenderState::Indirect);
        for &i in &ids {
            self.count.stats.indirect_draw_calls += 1;
            self.count.draw(i, self.triangles[i as usize]);
        }
        self.commands += 1;
        self.push(Call::DrawList(ids));
    }

    fn read_count(&mut self, list: IdList) -> u32 {
        self.count.stats.readbacks += 1;
        self.push(Call::ReadBack);
        self.resources().lists[list.0 as usize].ids.len() as u32
    }

    fn read_list(&mut self, list: IdList) -> Vec<u32> {
        self.count.stats.readbacks += 1;
        self.push(Call::ReadBack);
        self.resources().lists[list.0 as usize].ids.clone()
    }

    fn read_flags(&mut self, flags: Flags) -> Vec<bool> {
        self.count.stats.readbacks += 1;
        self.push(Call::ReadBack);
        self.resources().flags[flags.0 as usize].clone()
    }
}

/// Wraps a [`MockBackend`] (of a one-box scene) with `wrap`, calls every
/// [`Backend`] method once on the result, and panics naming each method the
/// mock did not receive: a decorator that forgets to forward a defaulted
/// method silently drops work, and this finds it.
pub fn assert_forwards_every_call<D: Backend>(wrap: impl FnOnce(MockBackend) -> D) {
    let mut scene = Scene::new("one box");
    let unit = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
    let mesh = scene.add_mesh(Mesh::new(unit.corners().to_vec(), vec![0, 1, 3]));
    scene.add_instance(mesh, Mat4::IDENTITY, 0);
    let mock = MockBackend::new(&scene, 8, 8);
    let log = mock.log();
    let mut decorator = wrap(mock);
    let view = Mat4::look_at_rh(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO, Vec3::Y);
    let camera = Camera::from_matrices(view, Mat4::perspective_rh(1.0, 1.0, 0.1, 100.0), false).expect("a camera");
    decorator.update_instances(&scene, &[0]);
    decorator.begin_frame(&camera);
    decorator.draw(&[0]);
    let query = decorator.issue_query(&[unit]);
    decorator.is_available(query);
    decorator.result(query);
    decorator.traverse(1);
    decorator.resolution();
    decorator.cpu_culling(CpuCullingWork { triangles: 1, tiles: 1, boxes: 1, subtiles_read: 1 });
    decorator.end_frame();
    decorator.failure();
    if let Err(e) = decorator.gpu_culling() {
        assert_eq!(e.0, NO_GPU_CULLING, "gpu_culling answered by the decorator, not forwarded");
    }
    decorator.instruments();
    decorator.cost_model();
    let received: Vec<&str> = log.borrow().iter().map(Call::name).collect();
    let missing: Vec<&str> = BACKEND_CALLS.iter().copied().filter(|c| !received.contains(c)).collect();
    assert!(missing.is_empty(), "the decorator did not forward {missing:?}");
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_cubes() -> Scene {
        let mut scene = Scene::new("two cubes");
        let cube =
            scene.add_mesh(Mesh::new(Aabb::new(Vec3::splat(-0.5), Vec3::splat(0.5)).corners().to_vec(), vec![0, 1, 2]));
        scene.add_instance(cube, Mat4::IDENTITY, 0);
        scene.add_instance(cube, Mat4::from_translation(Vec3::new(0.0, 0.0, -5.0)), 1);
        scene
    }

    /// The mock itself receives every call (so that the check holds for
    /// decorators of it), and a decorator that forwards nothing but the
    /// required calls is caught.
    #[test]
    fn every_call_is_logged_and_a_forgetful_decorator_is_caught() {
        assert_forwards_every_call(|mock| mock);

        struct Forgetful(MockBackend);
        impl Backend for Forgetful {
            fn begin_frame(&mut self, camera: &Camera) {
                self.0.begin_frame(camera);
            }
            fn draw(&mut self, instances: &[u32]) {
                self.0.draw(instances);
            }
            fn issue_query(&mut self, boxes: &[Aabb]) -> QueryHandle {
                self.0.issue_query(boxes)
            }
            fn is_available(&mut self, query: QueryHandle) -> bool {
                self.0.is_available(query)
            }
            fn result(&mut self, query: QueryHandle) -> u64 {
                self.0.result(query)
            }
            fn resolution(&self) -> (u32, u32) {
                self.0.resolution()
            }
            fn end_frame(&mut self) -> FrameStats {
                self.0.end_frame()
            }
        }
        let caught = std::panic::catch_unwind(|| assert_forwards_every_call(Forgetful));
        assert!(caught.is_err(), "a decorator forwarding only the required calls passed");
    }

    /// Queries see the scripted visibility, in the frustum only, and their
    /// results wait for the latency.
    #[test]
    fn queries_answer_the_script_after_the_latency() {
        let scene = two_cubes();
        let mut mock = MockBackend::new(&scene, 8, 8).with_latency(2);
        let camera = Camera::from_matrices(
            Mat4::look_at_rh(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO, Vec3::Y),
            Mat4::perspective_rh(1.0, 1.0, 0.1, 100.0),
            false,
        )
        .unwrap();
        mock.begin_frame(&camera);
        let both = Aabb::new(Vec3::new(-1.0, -1.0, -6.0), Vec3::splat(1.0));
        let first = mock.issue_query(&[both]);
        assert!(!mock.is_available(first));
        mock.set_visible(0, false);
        let second = mock.issue_query(&[both]);
        mock.draw(&[1]);
        assert!(mock.is_available(first), "two commands later");
        assert_eq!(mock.result(first), 2);
        assert_eq!(mock.result(second), 1);
        let behind = Aabb::new(Vec3::splat(20.0), Vec3::splat(21.0));
        let outside = mock.issue_query(&[behind]);
        assert_eq!(mock.result(outside), 0);
        let stats = mock.end_frame();
        assert_eq!((stats.queries, stats.draw_calls, stats.triangles), (3, 1, 1));
        let waits: Vec<bool> = mock
            .take_log()
            .iter()
            .filter_map(|c| if let Call::Result { waited, .. } = c { Some(*waited) } else { None })
            .collect();
        assert_eq!(waits, [false, true, true]);
    }
}
