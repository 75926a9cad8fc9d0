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
    /// Time the CPU was busy issuing commands and traversing (wait excluded).
    pub cpu_ms: f64,
    /// Time the GPU was busy.
    pub gpu_ms: f64,
    /// Time the CPU was blocked on query results.
    pub wait_ms: f64,
    /// Occlusion queries issued (a multi-query counts once).
    pub queries: u64,
    /// Boxes rasterized by those queries.
    pub query_boxes: u64,
    /// Draw calls (one per instance drawn).
    pub draw_calls: u64,
    /// Render-state changes: material switches and switches between
    /// drawing and querying (CHC++ paper, section 4).
    pub state_changes: u64,
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
}
