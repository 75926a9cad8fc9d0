//! The visibility-backend interface that hierarchical methods are written
//! against: [`Backend`], with the benchmark's [`Instruments`] beside it.
//!
//! A backend owns the scene's geometry, a depth buffer and a clock. Methods
//! issue draws and occlusion queries in order; the backend answers queries as a
//! GPU would: exactly (pixel counts), but only after the query has passed
//! through the GPU queue plus a read-back latency.

use crate::camera::Camera;
use crate::cost_model::CostModel;
use crate::geometry::Aabb;
use crate::gpu_culling::{GpuCulling, GpuCullingUnsupported};
use crate::scene::Scene;
use crate::stats::FrameStats;

/// Handle of an issued occlusion query, valid until the frame ends.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct QueryHandle(pub u32);

/// A renderer that can draw instances and answer occlusion queries: all a
/// culling method needs.
///
/// A renderer of one's own implements the required calls (frames, draws,
/// queries, its resolution); every other call has a default that is right
/// for a backend that measures its own time and offers nothing more:
/// [`Backend::traverse`] and [`Backend::cpu_culling`] charge nothing (a
/// measured clock has already seen that work pass), [`Backend::failure`] is
/// `None`, and [`Backend::gpu_culling`] and [`Backend::instruments`] say the
/// backend has none, so that a method needing them is refused
/// ([`check_support`](crate::methods::check_support)) rather than run on a
/// fallback. The benchmark's instruments (the depth image, the oracle) are
/// the separate trait [`Instruments`].
///
/// A backend that wraps another (a decorator) must forward every call,
/// the defaulted ones too: a default it forgets silently drops work.
/// With feature `mock`, `mock::assert_forwards_every_call` checks a
/// decorator, and `mock::MockBackend` logs every call of this trait: a
/// method added here is added there too.
pub trait Backend {
    /// Starts a frame seen by `camera`: clears depth and statistics.
    fn begin_frame(&mut self, camera: &Camera);

    /// Takes the `changed` instances of `scene` (the scene the backend
    /// was made for, after [`Scene::apply`](crate::Scene::apply)) into the
    /// backend's own copy, for the frames that follow: their transforms,
    /// boxes and whether they are shown ([`crate::motion`]). A backend that
    /// keeps a copy of the instances (both of `occlude`'s: a GPU keeps its
    /// own copy of the transforms) implements it; one that reads the
    /// renderer's data in place need not (the default does nothing).
    fn update_instances(&mut self, _scene: &Scene, _changed: &[u32]) {}

    /// Draws the given instances in order, one draw call each. Counts draw
    /// calls, triangles and state changes (material switches).
    fn draw(&mut self, instances: &[u32]);

    /// Issues one occlusion query over the union of the boxes' surfaces (a
    /// multi-query when there are several): the result is the number of pixels
    /// of the boxes that pass the depth test, with depth writes off. A box that
    /// touches the camera's near region ([`Camera::box_touches_near_region`])
    /// cannot be rasterized soundly and makes the query count as visible.
    fn issue_query(&mut self, boxes: &[Aabb]) -> QueryHandle;

    /// Whether the query's result can be read without waiting. Never blocks.
    fn is_available(&mut self, query: QueryHandle) -> bool;

    /// The query's visible-pixel count, waiting for it if needed; the time
    /// spent waiting is the frame's wait time.
    fn result(&mut self, query: QueryHandle) -> u64;

    /// Charges the CPU cost of visiting `nodes` hierarchy nodes. A backend
    /// whose CPU time is measured has seen that time pass and need not
    /// implement it (the default does nothing).
    fn traverse(&mut self, _nodes: u64) {}

    /// Width and height of the images the backend renders, in pixels: the
    /// resolution a method's own screen-space buffers must have.
    fn resolution(&self) -> (u32, u32);

    /// Charges CPU work a method did itself on a software occlusion buffer
    /// (`moc`). A backend whose CPU time is measured (wgpu) has already seen
    /// it pass and does nothing (the default); the soft backend's simulated
    /// clock charges it from its cost model.
    fn cpu_culling(&mut self, _work: CpuCullingWork) {}

    /// Ends the frame and returns its statistics. Methods never read them;
    /// a backend that measures nothing returns what its [`FrameCounter`]
    /// counted, or `FrameStats::default()`.
    fn end_frame(&mut self) -> FrameStats;

    /// A fatal error the backend met (a lost GPU device, say), after which
    /// its answers mean nothing: whoever runs frames stops and reports it.
    /// The interface's calls stay infallible so that methods need not thread
    /// errors through every draw; a failed backend answers queries as
    /// visible and draws nothing. `None` while all is well.
    fn failure(&self) -> Option<String> {
        None
    }

    /// The backend's GPU-resident culling pipeline ([`GpuCulling`]), or why
    /// it has none (a device lacking a feature it needs, named). Methods
    /// that need it say so ([`CullingMethod::needs_gpu_culling`]), and the
    /// runner asks before the first frame.
    ///
    /// [`CullingMethod::needs_gpu_culling`]: crate::CullingMethod::needs_gpu_culling
    fn gpu_culling(&mut self) -> Result<&mut dyn GpuCulling, GpuCullingUnsupported> {
        Err(GpuCullingUnsupported("this backend has no GPU-resident culling".into()))
    }

    /// The backend's benchmark instruments ([`Instruments`]: its depth image
    /// and the oracle pass), or `None` for a backend that renders into
    /// images it does not read back (the default). `opt` needs them
    /// ([`CullingMethod::needs_oracle`]), and so does the correctness rule.
    ///
    /// [`CullingMethod::needs_oracle`]: crate::CullingMethod::needs_oracle
    fn instruments(&mut self) -> Option<&mut dyn Instruments> {
        None
    }

    /// The backend's estimate of what draws, queries and GPU-driven passes
    /// cost, for methods that decide by cost whether a query pays (`nohc`)
    /// or which method may win (`auto`), or `None` for a backend that
    /// measures its time rather than modelling it (the default): `nohc`
    /// then uses [`CostModel::default`], and `auto` bounds nothing.
    fn cost_model(&self) -> Option<CostModel> {
        None
    }
}

/// What a benchmark reads from a backend beyond culling: the depth image
/// (the correctness rule compares it with view-frustum culling's,
/// [`crate::frame::differing_pixels`]) and the oracle pass behind `opt`.
/// Reached through [`Backend::instruments`]; both backends of `occlude`
/// implement it, a renderer of one's own need not.
pub trait Instruments {
    /// Writes the depth image of the last finished frame, row by row, into
    /// `out` (replacing what it held), for the correctness rule (`docs/design.md`).
    /// Costs nothing on the frame's clock; `out`'s memory is reused, so that a
    /// run comparing every frame's image allocates none.
    fn depth_image(&mut self, out: &mut Vec<f32>);

    /// Oracle pass, outside any frame's clock: draws all `candidates` from
    /// `camera` and reports which of them have at least one pixel in the
    /// final depth image (ties included), with that image. Used by `opt`.
    fn oracle(&mut self, camera: &Camera, candidates: &[u32]) -> OracleView;
}

/// CPU work on a masked software occlusion buffer, the measure its cost is
/// simulated from ([`Backend::cpu_culling`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CpuCullingWork {
    /// Occluder triangles set up (after near-plane clipping).
    pub triangles: u64,
    /// 32x8-pixel tiles the occluder triangles' bounding boxes overlap.
    pub tiles: u64,
    /// Boxes tested against the buffer.
    pub boxes: u64,
    /// Subtiles (8x4 pixels) those box tests read: a test's time beyond its
    /// fixed part follows them (`occlude_moc::MaskedBuffer::test_aabb_counted`).
    pub subtiles_read: u64,
}

impl std::ops::AddAssign for CpuCullingWork {
    fn add_assign(&mut self, other: Self) {
        self.triangles += other.triangles;
        self.tiles += other.tiles;
        self.boxes += other.boxes;
        self.subtiles_read += other.subtiles_read;
    }
}

/// The render state a command needs: a material for draws, the query state
/// (depth writes off) for occlusion queries. Switching between a drawing
/// state and [`RenderState::Query`] is a state change as the CHC++ paper
/// counts them (section 4); switching between two drawing states is a
/// material switch ([`FrameCounter::set_state`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RenderState {
    /// Drawing with this material.
    Material(u32),
    /// Rasterizing query proxies (occlusion queries or batched box tests).
    Query,
    /// Drawing an id list with one indirect multi-draw, materials read per
    /// instance ([`GpuCulling::draw_list`]).
    Indirect,
}

/// Follows the render state across a frame's commands, so that every backend
/// counts state changes by the same rule.
#[derive(Clone, Copy, Debug, Default)]
pub struct StateTracker(Option<RenderState>);

impl StateTracker {
    /// Moves to `state`; true when that is a change (setting the frame's
    /// first state is not).
    pub fn switch(&mut self, state: RenderState) -> bool {
        self.switch_from(state).is_some()
    }

    /// Moves to `state`; the state it left when that is a change, `None`
    /// otherwise (setting the frame's first state is no change).
    pub fn switch_from(&mut self, state: RenderState) -> Option<RenderState> {
        let left = self.0.filter(|&s| s != state);
        self.0 = Some(state);
        left
    }
}

/// The counts every backend keeps by the same rules while it records a
/// frame: draw calls, triangles, distinct instances drawn, render-state
/// changes (split into state changes and material switches), queries and their boxes, indirect draws and traversal steps. A
/// backend adds its own figures (times, fragments, dispatches) to
/// [`FrameCounter::stats`].
#[derive(Clone, Debug, Default)]
pub struct FrameCounter {
    /// The frame's statistics so far.
    pub stats: FrameStats,
    state: StateTracker,
    drawn: Vec<bool>,
}

impl FrameCounter {
    /// A counter for a scene of `instances` instances.
    pub fn new(instances: usize) -> Self {
        Self { drawn: vec![false; instances], ..Self::default() }
    }

    /// Starts a frame: every count zero, no render state, nothing drawn.
    pub fn begin_frame(&mut self) {
        self.stats = FrameStats::default();
        self.state = StateTracker::default();
        self.drawn.fill(false);
    }

    /// Moves to render state `state`; true (and counted) when that is a
    /// change. A switch into or out of [`RenderState::Query`] counts in
    /// `state_changes` (the CHC++ paper's state change: color and depth
    /// writes disabled for queries, enabled again for drawing); a switch
    /// between two drawing states (materials, indirect multi-draws) counts
    /// in `material_switches`. Each change is one pipeline switch, so a
    /// draw right after a query counts once, as a state change, whatever
    /// material was drawn before the query.
    pub fn set_state(&mut self, state: RenderState) -> bool {
        let Some(left) = self.state.switch_from(state) else { return false };
        if left == RenderState::Query || state == RenderState::Query {
            self.stats.state_changes += 1;
        } else {
            self.stats.material_switches += 1;
        }
        true
    }

    /// Counts one draw call of instance `instance`, of `triangles`
    /// triangles (a visible object the first time in the frame).
    pub fn draw(&mut self, instance: u32, triangles: u64) {
        self.stats.draw_calls += 1;
        self.stats.triangles += triangles;
        if !std::mem::replace(&mut self.drawn[instance as usize], true) {
            self.stats.visible_objects += 1;
        }
    }

    /// True when instance `instance` has been drawn this frame.
    pub fn was_drawn(&self, instance: usize) -> bool {
        self.drawn[instance]
    }

    /// Counts an occlusion query over `boxes` boxes, in render state
    /// [`RenderState::Query`]; true when that state is a change.
    pub fn query(&mut self, boxes: usize) -> bool {
        let changed = self.set_state(RenderState::Query);
        self.stats.queries += 1;
        self.stats.query_boxes += boxes as u64;
        changed
    }

    /// Counts an indirect multi-draw in render state `state`; true when that
    /// state is a change.
    pub fn indirect_draw(&mut self, state: RenderState) -> bool {
        let changed = self.set_state(state);
        self.stats.indirect_draws += 1;
        changed
    }

    /// Counts `nodes` hierarchy nodes visited.
    pub fn traverse(&mut self, nodes: u64) {
        self.stats.traversal_steps += nodes;
    }
}

/// What an oracle pass saw.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct OracleView {
    /// Candidates with at least one pixel in the image.
    pub visible: Vec<u32>,
    /// Each candidate's pixel count in the image, in candidate order (exact
    /// on the soft backend; on a GPU whose occlusion queries are not precise
    /// only zero or not zero is promised).
    pub pixels: Vec<u64>,
    /// The depth image (normalized device depth, 1.0 where nothing was
    /// drawn), row 0 at the top.
    pub depth: Vec<f32>,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl OracleView {
    /// The view of `candidates` whose image holds `pixels[i]` pixels of
    /// candidate `i`.
    pub fn new(candidates: &[u32], pixels: Vec<u64>, depth: Vec<f32>, width: u32, height: u32) -> Self {
        let visible = candidates.iter().zip(&pixels).filter(|(_, &p)| p > 0).map(|(&i, _)| i).collect();
        Self { visible, pixels, depth, width, height }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Switches to and from queries are state changes, switches between
    /// drawing states material switches; staying in a state, and the
    /// frame's first state, neither.
    #[test]
    fn frame_counter_tells_state_changes_from_material_switches() {
        let mut c = FrameCounter::new(4);
        c.begin_frame();
        let (a, b) = (RenderState::Material(0), RenderState::Material(1));
        let changed: Vec<bool> = [a, a, b, RenderState::Query, RenderState::Query, a, RenderState::Indirect, b]
            .into_iter()
            .map(|s| c.set_state(s))
            .collect();
        assert_eq!(changed, [false, false, true, true, false, true, true, true]);
        // Material 0 to 1, indirect and back to material 1: three material
        // switches; into queries and out again: two state changes.
        assert_eq!((c.stats.state_changes, c.stats.material_switches), (2, 3));
        assert!(c.query(2), "a query after a draw is a state change");
        assert_eq!((c.stats.state_changes, c.stats.material_switches, c.stats.queries), (3, 3, 1));
        c.begin_frame();
        assert!(!c.query(1), "the frame's first state is no change");
        assert_eq!((c.stats.state_changes, c.stats.material_switches), (0, 0));
    }
}
