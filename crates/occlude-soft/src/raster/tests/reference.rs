//! The reference rasterizer: the rasterizer's rules in their plainest form. Commands
//! run one after the other; each triangle's fragments come from [`Fragments`] (its
//! edge functions evaluated directly at every pixel of its bounding box), and each
//! covered pixel's depth is tested one at a time: no tiles, bins, spans, SIMD or
//! hierarchical depth. The optimized paths must agree with it bit for bit.

use glam::Vec4;

use super::super::fragments::Fragments;
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
    let mut fragments = Fragments::new(width, height);
    let mut results = Vec::with_capacity(commands.len());
    for c in commands {
        let mut r = CommandResult::default();
        for tri in &triangles[c.triangles.start as usize..c.triangles.end as usize] {
            fragments.each(tri, c.cull_back, |x, y, z| {
                let d = &mut depth[y as usize * width as usize + x as usize];
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
            });
        }
        if let CommandKind::QueryAny(_) = c.kind {
            r = CommandResult { fragments: 0, passed: r.passed.min(1) };
        }
        results.push(r);
    }
    results
}
