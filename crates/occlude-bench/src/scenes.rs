//! `occlude scenes`: the procedural scenes with their sizes, and whether
//! they move by themselves.

use occlude_core::hierarchy::BuildOptions;
use occlude_core::{Hierarchy, HierarchyKind};
use occlude_scenes::{generate_moving, Size, SCENE_NAMES};
use std::fmt::Write;
use std::time::Instant;

/// One line of the scene list.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneRow {
    /// Scene name.
    pub name: &'static str,
    /// Size.
    pub size: Size,
    /// Triangles over all instances.
    pub triangles: usize,
    /// Triangles stored once per mesh.
    pub unique_triangles: usize,
    /// Instances.
    pub instances: usize,
    /// BVH nodes with the default leaf size.
    pub bvh_nodes: usize,
    /// kD-tree nodes with the default leaf size.
    pub kdtree_nodes: usize,
    /// Real time to generate the scene (and its motion).
    pub generate_ms: f64,
    /// Whether the scene moves by itself (vehicles, people, doors).
    pub moves: bool,
}

/// Generates every scene at `size` (with `seed`) and measures it.
pub fn rows(size: Size, seed: u64) -> Vec<SceneRow> {
    SCENE_NAMES
        .iter()
        .map(|&name| {
            let start = Instant::now();
            let (scene, motion) = generate_moving(name, size, seed).expect("built-in scene names are valid");
            let generate_ms = start.elapsed().as_secs_f64() * 1e3;
            let nodes = |kind| Hierarchy::build(&scene, kind, BuildOptions::default()).node_count();
            SceneRow {
                name,
                size,
                triangles: scene.triangle_count(),
                unique_triangles: scene.unique_triangle_count(),
                instances: scene.instances.len(),
                bvh_nodes: nodes(HierarchyKind::Bvh),
                kdtree_nodes: nodes(HierarchyKind::KdTree),
                generate_ms,
                moves: motion.is_some(),
            }
        })
        .collect()
}

/// The rows as an aligned table.
pub fn render(rows: &[SceneRow]) -> String {
    let mut out = format!(
        "{:<8} {:<6} {:>11} {:>11} {:>9} {:>9} {:>9} {:>9} {:<5}\n",
        "scene", "size", "triangles", "unique tri", "instances", "bvh nodes", "kd nodes", "gen ms", "moves"
    );
    for r in rows {
        let _ = writeln!(
            out,
            "{:<8} {:<6} {:>11} {:>11} {:>9} {:>9} {:>9} {:>9.0} {:<5}",
            r.name,
            r.size.to_string(),
            r.triangles,
            r.unique_triangles,
            r.instances,
            r.bvh_nodes,
            r.kdtree_nodes,
            r.generate_ms,
            if r.moves { "yes" } else { "no" }
        );
    }
    out
}
