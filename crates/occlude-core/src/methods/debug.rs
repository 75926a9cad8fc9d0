//! What a method decided in one frame, recorded on request for a visual check
//! (`occlude bench --dump-frame`): plain data, drawn by the benchmark tool.

use glam::Vec2;

/// A screen rectangle in normalized device coordinates (`x`, `y` in `[-1, 1]`
/// on screen, `y` up); it may reach past the screen's edges.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NdcRect {
    /// Lower-left corner.
    pub min: Vec2,
    /// Upper-right corner.
    pub max: Vec2,
}

/// What became of a node a method looked at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NodeClass {
    /// Drawn without asking the GPU (`om`'s stage 1).
    DrawnWithoutQuery,
    /// Drawn because an occlusion query found it visible.
    DrawnAfterQuery,
    /// An occlusion query found no visible pixel, so it was culled.
    FoundHidden,
}

impl NodeClass {
    /// Every class, in the order a view is drawn and its legend listed.
    pub const ALL: [NodeClass; 3] = [NodeClass::DrawnWithoutQuery, NodeClass::DrawnAfterQuery, NodeClass::FoundHidden];
}

/// One frame's decisions of a method (see [`super::CullingMethod::debug_view`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DebugView {
    /// Columns of the occupancy map.
    pub map_width: u32,
    /// Rows of the occupancy map.
    pub map_height: u32,
    /// The occupancy map as the method used it (for `om`, at the end of stage
    /// 1): `true` for a covered cell, row by row, row 0 at the top of the
    /// screen; `map_width * map_height` cells.
    pub occupancy: Vec<bool>,
    /// The screen rectangle of every node with what became of it, in the
    /// order the method decided.
    pub nodes: Vec<(NodeClass, NdcRect)>,
}
