//! The reference rasterizer: the rasterizer's rules in their plainest form. Commands
//! run one after the other; each set-up triangle's three edge functions are evaluated
//! directly at every pixel of its bounding box, and each covered pixel's depth is
//! tested one at a time: no tiles, bins, spans, SIMD or hierarchical depth. The
//! optimized paths must agree with it bit for bit.

use glam::Vec4;

use super::super::clip::Polygon;
use super::super::setup::{setup_triangle, Viewport};
use super::super::{Command, CommandKind, CommandResult, DepthTest};

/// Runs `commands` on the `width` x `height` row-major depth image `depth`.
pub fn execute(
    depth: &mut [f32],
    width: u32,
    height: u32,
    triangles: &[[Vec4; 3]],
    commands: &[Command],
) -> Vec<CommandResult> {
    assert_eq!(depth.len(), width as usize * height as usize);
    if width == 0 || height == 0 {
        return vec![CommandResult::default(); commands.len()];
    }
    let viewport = Viewport::new(width, height);
    let mut poly = Polygon::new();
    let mut setups = Vec::new();
    let mut results = Vec::with_capacity(commands.len());
    for (ci, c) in commands.iter().enumerate() {
        let mut r = CommandResult::default();
        for tri in &triangles[c.triangles.start as usize..c.triangles.end as usize] {
            setups.clear();
            setup_triangle(tri, c.cull_back, ci as u32, viewport, &mut poly, |t| setups.push(t));
            for s in &setups {
                let edges = s.edges();
                for dy in 0..=s.y1 - s.y0 {
                    let plane = s.row_plane(dy);
                    for dx in 0..=s.x1 - s.x0 {
                        let covered =
                            edges.iter().all(|e| e.origin + e.step_x * i64::from(dx) + e.step_y * i64::from(dy) >= 0);
                        if !covered {
                            continue;
                        }
                        let z = plane.depth(dx);
                        let d = &mut depth[(s.y0 + dy) as usize * width as usize + (s.x0 + dx) as usize];
                        r.fragments += 1;
                        let pass = match c.kind {
                            CommandKind::Draw
                            | CommandKind::Query(DepthTest::Less)
                            | CommandKind::QueryAny(DepthTest::Less) => z < *d,
                            CommandKind::Query(DepthTest::Equal) | CommandKind::QueryAny(DepthTest::Equal) => z == *d,
                        };
                        if pass {
                            r.passed += 1;
                            if c.kind == CommandKind::Draw {
                                *d = z;
                            }
                        }
                    }
                }
            }
        }
        if let CommandKind::QueryAny(_) = c.kind {
            r = CommandResult { fragments: 0, passed: r.passed.min(1) };
        }
        results.push(r);
    }
    results
}
