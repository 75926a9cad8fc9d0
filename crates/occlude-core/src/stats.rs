//! Per-frame statistics: what every table, plot and JSON file is made of.

use serde::{Deserialize, Serialize};

/// What one method cost on one frame.
///
/// Times under `frame_ms`, `cpu_ms`, `gpu_ms` and `wait_ms` come from the
/// backend's clock: simulated (deterministic) on the soft backend. `wall_ms` is
/// the real time the frame took on this machine and varies between runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FrameStats {
    /// Frame time: max(CPU end, GPU end).
    pub frame_ms: f64,
    /// Time the CPU was busy issuing commands and traversing (waits for
    /// results and blocked submissions excluded).
    pub cpu_ms: f64,
    /// Time the GPU was busy.
    pub gpu_ms: f64,
    /// Time the CPU was blocked on query results.
    pub wait_ms: f64,
    /// Time the CPU was blocked in submitting calls because the driver's
    /// command queue was full (the soft backend's bounded queue,
    /// `GpuModel::driver_queue_us`; 0 on wgpu, where such time is in
    /// `cpu_ms`). Neither `cpu_ms` nor `wait_ms` includes it.
    #[serde(default)]
    pub submit_wait_ms: f64,
    /// Occlusion queries issued (a multi-query counts once).
    pub queries: u64,
    /// Boxes rasterized by those queries.
    pub query_boxes: u64,
    /// Draw calls (one per instance drawn).
    pub draw_calls: u64,
    /// State changes as the CHC++ paper counts them (section 4): switches
    /// between drawing and querying (occlusion queries or batched box
    /// tests), each of which disables or re-enables color and depth writes.
    /// View-frustum culling makes none.
    pub state_changes: u64,
    /// Switches from one drawing state to another (one material to
    /// another, or to or from an indirect multi-draw) with no query
    /// between them; not counted in `state_changes`.
    #[serde(default)]
    pub material_switches: u64,
    /// Triangles submitted for drawing.
    pub triangles: u64,
    /// Pixels covered by drawn triangles (before the depth test).
    pub fragments: u64,
    /// Distinct instances drawn.
    pub visible_objects: u64,
    /// Hierarchy nodes the method visited.
    pub traversal_steps: u64,
    /// Pixels whose final depth differs from view-frustum culling's.
    pub missing_pixels: u64,
    /// Real time the frame took on this machine (not deterministic).
    pub wall_ms: f64,
    /// GPU time of the occlusion tests: query boxes, batched box tests and
    /// the compute passes that compact their results (simulated on the soft
    /// backend; on wgpu from pass timestamps where the adapter has them, 0
    /// otherwise, and a pass that mixes tests and draws counts in `gpu_ms`
    /// only).
    #[serde(default)]
    pub cull_ms: f64,
    /// GPU time of drawing the scene's instances (as `cull_ms`).
    #[serde(default)]
    pub render_ms: f64,
    /// GPU time of building depth pyramids (part of `gpu_ms` and
    /// `cull_ms`; as `cull_ms`, simulated or from timestamps). With
    /// `late_ms` it splits a two-phase frame (`hiz`) into its passes: early
    /// (`gpu_ms - pyramid_ms - late_ms`), pyramid and late.
    #[serde(default)]
    pub pyramid_ms: f64,
    /// GPU time of everything after the frame's first depth-pyramid build:
    /// `hiz`'s late pass (box tests against the pyramid, compaction, the
    /// draw of the newly visible); 0 in a frame that builds no pyramid.
    #[serde(default)]
    pub late_ms: f64,
    /// Compute dispatches.
    #[serde(default)]
    pub dispatches: u64,
    /// Indirect multi-draw commands; the draws they contain are counted in
    /// `draw_calls` too.
    #[serde(default)]
    pub indirect_draws: u64,
    /// Draws contained in indirect multi-draws (part of `draw_calls`).
    #[serde(default)]
    pub indirect_draw_calls: u64,
    /// Buffers read back from the GPU during the frame (query results are
    /// counted in `queries`, not here).
    #[serde(default)]
    pub readbacks: u64,
    /// Real time spent before the frame keeping the scene up to date
    /// (`crate::motion`): the hierarchy's refit or rebuild and the
    /// backend's update of the instances that changed; 0 in a still scene.
    #[serde(default)]
    pub update_ms: f64,
    /// The upkeep as `frame_ms` and `cpu_ms` include it, CPU work before
    /// the frame: `update_ms` on wgpu, a modelled time on the soft
    /// backend's simulated clock (the benchmark runner's
    /// `modelled_upkeep_ms`).
    #[serde(default)]
    pub update_charged_ms: f64,
    /// Instances that moved, hid or showed before the frame.
    #[serde(default)]
    pub instances_moved: u64,
    /// Whether the hierarchy was rebuilt before the frame (1) or not (0).
    #[serde(default)]
    pub rebuilds: u64,
}
