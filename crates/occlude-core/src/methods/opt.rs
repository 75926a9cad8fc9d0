//! The ideal visible set (`docs/design.md`): a lower bound, not a method
//! one could run. With the default `opt.granularity=instance` it draws
//! exactly the instances that own at least one pixel of the final image, in
//! one batch sorted by material, with no query. The set comes from an
//! oracle pass run before the frame's clock starts. Every such instance
//! must be drawn by any method whose image is view-frustum culling's, so no
//! conservative method draws fewer triangles (tested on every frame of the
//! small scenes, on the soft and the wgpu backend).
//!
//! `opt.granularity=node` draws instead the whole hierarchy leaves that
//! have at least one visible pixel (the best a method deciding per leaf can
//! do; methods culling single instances beat it). A leaf has a visible
//! pixel when it holds an instance the oracle sees and, where instances are
//! shared by several leaves (kD-tree), when a visible pixel's surface point
//! lies in the leaf's box: otherwise a large object referenced by every
//! leaf it crosses would make all those leaves "visible".
//!
//! Neither is a paper's ideal: the CHC paper's `ideal` and the CHC++
//! paper's OPT (`ideal-sorted`) draw what stop-and-wait's queries find
//! visible, in the benchmark runner (`occlude::bench::ideal`).

use super::hiz::Granularity;
use super::options::{MethodParams, OptionError, ParamVisitor};
use super::{CullingMethod, FrameContext};
use crate::backend::{Backend, OracleView};
use crate::camera::Camera;
use crate::geometry::Aabb;
use crate::hierarchy::{Hierarchy, NodeId};
use glam::{DVec3, DVec4, Vec3};

/// Parameters of `opt`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OptParams {
    /// `opt.granularity`: `instance` (default, the instances owning a
    /// pixel) or `node` (the leaves holding a visible pixel).
    pub granularity: Granularity,
}

impl Default for OptParams {
    fn default() -> Self {
        Self { granularity: Granularity::Instance }
    }
}

impl MethodParams for OptParams {
    const METHOD: &'static str = "opt";
    fn visit(&mut self, v: &mut ParamVisitor) -> Result<(), OptionError> {
        v.value("granularity", &mut self.granularity, "instance or node", |_| true)
    }
}

/// `opt`: render the oracle's visible instances (or leaves) only.
#[derive(Clone, Debug, Default)]
pub struct Optimal {
    params: OptParams,
    /// The leaves to draw (node granularity, or every leaf in view without
    /// an oracle).
    leaves: Vec<NodeId>,
    /// The instances to draw, sorted by material (instance granularity).
    instances: Vec<u32>,
}

impl Optimal {
    /// `opt` with `params`.
    pub fn new(params: OptParams) -> Self {
        Self { params, ..Self::default() }
    }
}

impl CullingMethod for Optimal {
    fn name(&self) -> &'static str {
        "opt"
    }

    fn needs_oracle(&self) -> bool {
        true
    }

    fn prepare(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend) {
        let in_view = leaves_in_view(ctx);
        self.instances.clear();
        let Some((view, visible)) = oracle_visible(ctx, backend, &in_view) else {
            // Without an oracle (refused up front by `check_support`), every
            // leaf in view: a conservative image, not the ideal set.
            self.leaves = in_view;
            return;
        };
        if self.params.granularity == Granularity::Instance {
            self.leaves.clear();
            self.instances = view.visible;
            let instances = &ctx.scene.instances;
            self.instances.sort_by_key(|&i| (instances[i as usize].material, i));
            return;
        }
        let h = ctx.hierarchy;
        let shared_instances = h.items.len() > ctx.scene.instances.len();
        let seen_leaves = shared_instances.then(|| leaves_with_visible_pixels(h, &ctx.camera, &view));
        self.leaves = in_view
            .into_iter()
            .filter(|&n| h.instances(n).iter().any(|&i| visible[i as usize]))
            .filter(|&n| seen_leaves.as_ref().is_none_or(|seen| seen[n as usize]))
            .collect();
    }

    /// One batch sorted by material: the fewest material switches any
    /// method could reach for this set, and no state change.
    fn render(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend) {
        ctx.draw_leaves(backend, &self.leaves, true);
        ctx.draw_instances(backend, &self.instances);
    }
}

/// The hierarchy's leaves in the frame's view.
pub(crate) fn leaves_in_view(ctx: &FrameContext<'_>) -> Vec<NodeId> {
    let h = ctx.hierarchy;
    (0..h.node_count() as NodeId).filter(|&n| h.is_leaf(n) && ctx.in_frustum(n)).collect()
}

/// The backend's oracle pass over the instances of `in_view` (leaves): what
/// it saw, and per scene instance whether it has a visible pixel; `None`
/// for a backend without an oracle.
pub(crate) fn oracle_visible(
    ctx: &FrameContext<'_>,
    backend: &mut dyn Backend,
    in_view: &[NodeId],
) -> Option<(OracleView, Vec<bool>)> {
    let h = ctx.hierarchy;
    let shown = |&i: &u32| ctx.scene.instances[i as usize].enabled;
    let mut candidates: Vec<u32> = in_view.iter().flat_map(|&n| h.instances(n).iter().copied()).filter(shown).collect();
    candidates.sort_unstable();
    candidates.dedup();
    let view = backend.instruments()?.oracle(&ctx.camera, &candidates);
    let mut visible = vec![false; ctx.scene.instances.len()];
    for &i in &view.visible {
        visible[i as usize] = true;
    }
    Some((view, visible))
}

/// Relative depth uncertainty of a stored pixel depth (a few float steps
/// near 1.0): the surface point is searched on the segment this spans.
const DEPTH_TOLERANCE: f64 = 5e-7;

/// Growth of a pixel's segment box, relative to its largest coordinate: far
/// above `f32`'s rounding (about 6e-8), so that neither the segment's
/// rounding to `f32` nor that of the leaves' boxes can separate the box that
/// holds the surface point from the segment.
const SEGMENT_PAD_RELATIVE: f64 = 1e-5;

/// Growth of a pixel's segment box in world units, for segments near the
/// origin, where a relative growth vanishes.
const SEGMENT_PAD_ABSOLUTE: f64 = 1e-4;

/// Pixels per side of the blocks whose segments [`leaves_with_visible_pixels`]
/// takes down the tree together.
const BLOCK: usize = 8;

/// Marks, per node, the leaves whose box holds the surface point of some
/// drawn pixel. Each pixel is unprojected (in f64) to a short segment along
/// its ray covering the depth's rounding, and every leaf whose box, slightly
/// grown, meets that segment's box is marked, so the leaf that really holds
/// the point is never missed.
///
/// The segments of an 8x8 block of pixels go down the tree together, by the
/// box holding them all; a leaf reached is marked when one of the block's
/// segments meets its box. Since a node's box holds its children's, a
/// leaf's box meeting a segment has every ancestor's box meet it too, and
/// the box of all the block's segments: the marks are exactly those of
/// taking each pixel down the tree alone (tested), for one descent per
/// block instead of one per pixel.
fn leaves_with_visible_pixels(h: &Hierarchy, camera: &Camera, view: &OracleView) -> Vec<bool> {
    let (w, ht) = (view.width as usize, view.height as usize);
    let segment = pixel_segments(camera, w, ht);
    let mut seen = vec![false; h.node_count()];
    let (mut stack, mut segments) = (Vec::new(), Vec::new());
    for by in (0..ht).step_by(BLOCK) {
        for bx in (0..w).step_by(BLOCK) {
            segments.clear();
            for py in by..(by + BLOCK).min(ht) {
                for px in bx..(bx + BLOCK).min(w) {
                    let depth = view.depth[py * w + px];
                    if depth < 1.0 {
                        segments.push(segment(px, py, depth));
                    }
                }
            }
            let Some(all) = segments.iter().copied().reduce(|a, b| a.union(&b)) else {
                continue;
            };
            stack.push(h.root());
            while let Some(n) = stack.pop() {
                if !h.bounds(n).overlaps(&all) {
                    continue;
                }
                if h.is_leaf(n) {
                    let seen = &mut seen[n as usize];
                    *seen = *seen || segments.iter().any(|s| h.bounds(n).overlaps(s));
                } else {
                    stack.extend_from_slice(h.children(n));
                }
            }
        }
    }
    seen
}

/// The box of pixel `(px, py)`'s segment (of a `width` x `height` image seen
/// by `camera`) at stored depth `depth`: the points along its ray whose depth
/// rounds to it, grown as [`SEGMENT_PAD_RELATIVE`] and
/// [`SEGMENT_PAD_ABSOLUTE`] say.
fn pixel_segments(camera: &Camera, width: usize, height: usize) -> impl Fn(usize, usize, f32) -> Aabb {
    let inverse = camera.view_projection().as_dmat4().inverse();
    let unproject = move |x: f64, y: f64, z: f64| {
        let p = inverse * DVec4::new(x, y, z, 1.0);
        p.truncate() / p.w
    };
    move |px, py, depth| {
        let x = (px as f64 + 0.5) / width as f64 * 2.0 - 1.0;
        let y = 1.0 - (py as f64 + 0.5) / height as f64 * 2.0;
        let z = f64::from(depth);
        let a = unproject(x, y, (z - DEPTH_TOLERANCE).max(0.0));
        let b = unproject(x, y, (z + DEPTH_TOLERANCE).min(1.0));
        let pad = SEGMENT_PAD_RELATIVE * a.abs().max(b.abs()).max_element() + SEGMENT_PAD_ABSOLUTE;
        Aabb::new(to_vec3(a.min(b) - DVec3::splat(pad)), to_vec3(a.max(b) + DVec3::splat(pad)))
    }
}

fn to_vec3(v: DVec3) -> Vec3 {
    v.as_vec3()
}

#[cfg(test)]
mod tests {
    use super::super::test_rig::{assert_draws_exactly, method, Rig};
    use super::super::{check_support, Unsupported};
    use super::*;
    use crate::hierarchy::BuildOptions;
    use crate::rng::Rng;
    use crate::{HierarchyKind, Keyframe, Scene};

    /// [`leaves_with_visible_pixels`] by its definition: each drawn pixel's
    /// segment taken down the tree alone.
    fn leaves_pixel_by_pixel(h: &Hierarchy, camera: &Camera, view: &OracleView) -> Vec<bool> {
        let (w, ht) = (view.width as usize, view.height as usize);
        let segment = pixel_segments(camera, w, ht);
        let mut seen = vec![false; h.node_count()];
        for (index, &depth) in view.depth.iter().enumerate().filter(|(_, &d)| d < 1.0) {
            let s = segment(index % w, index / w, depth);
            let mut stack = vec![h.root()];
            while let Some(n) = stack.pop() {
                if h.bounds(n).overlaps(&s) {
                    if h.is_leaf(n) {
                        seen[n as usize] = true;
                    } else {
                        stack.extend_from_slice(h.children(n));
                    }
                }
            }
        }
        seen
    }

    /// On a kD-tree of random overlapping boxes (instances shared by
    /// leaves), seen from several places, with depth images of near,
    /// far and empty pixels at odd sizes, the leaves marked block by block
    /// are exactly those marked pixel by pixel.
    #[test]
    fn blocks_of_pixels_mark_the_leaves_pixels_alone_mark() {
        let mut rng = Rng::new(7, 0);
        let boxes: Vec<Aabb> = (0..300)
            .map(|_| {
                let c = Vec3::new(rng.range(-20.0, 20.0), rng.range(-3.0, 3.0), rng.range(-20.0, 20.0));
                let e = Vec3::new(rng.range(0.1, 4.0), rng.range(0.1, 2.0), rng.range(0.1, 4.0));
                Aabb::new(c - e, c + e)
            })
            .collect();
        let scene = Scene::from_bounds("boxes", &boxes).unwrap();
        let h = Hierarchy::build(&scene, HierarchyKind::KdTree, BuildOptions::default());
        assert!(h.items.len() > scene.instances.len(), "instances shared by leaves");
        // The premise: a node's box holds its children's, bound by bound.
        for n in 0..h.node_count() as NodeId {
            for &c in h.children(n) {
                let (p, c) = (h.bounds(n), h.bounds(c));
                assert!(p.min.cmple(c.min).all() && c.max.cmple(p.max).all(), "node {n}");
            }
        }
        let (mut some, mut not_all) = (false, false);
        for (k, (w, ht)) in [(61u32, 47u32), (80, 64), (33, 90)].into_iter().enumerate() {
            let at = Vec3::new(rng.range(-25.0, 25.0), rng.range(-2.0, 8.0), rng.range(-25.0, 25.0));
            let key = Keyframe { time: 0.0, position: at, target: Vec3::ZERO, fov_y_deg: 60.0 };
            let camera = key.camera(w as f32 / ht as f32, 0.1, 200.0);
            let depth: Vec<f32> = (0..w * ht)
                .map(|_| match rng.range(0.0, 1.0) {
                    p if p < 0.3 => 1.0,
                    p if p < 0.5 => rng.range(0.0, 0.99),
                    _ => rng.range(0.99, 0.99999),
                })
                .collect();
            let view = OracleView::new(&[], Vec::new(), depth, w, ht);
            let blocks = leaves_with_visible_pixels(&h, &camera, &view);
            assert_eq!(blocks, leaves_pixel_by_pixel(&h, &camera, &view), "view {k}");
            some |= blocks.iter().any(|&b| b);
            not_all |= (0..h.node_count()).any(|n| h.is_leaf(n as NodeId) && !blocks[n]);
        }
        assert!(some && not_all, "some leaves marked, not all");
    }

    /// `opt` needs the oracle: refused on a backend without instruments,
    /// and, run anyway, it draws every leaf in view (a conservative image)
    /// rather than nothing.
    #[test]
    fn is_refused_without_an_oracle_and_falls_back_to_every_leaf_in_view() {
        let rig = Rig::row(4);
        let mut mock = rig.mock();
        let mut opt = method("opt", &[]);
        let refused = check_support(opt.method.as_ref(), &mut mock).unwrap_err();
        assert_eq!(refused, Unsupported::NoOracle);
        mock.set_visible(2, false);
        let calls = &rig.run(&mut opt, &mut mock, 1)[0];
        assert_draws_exactly(calls, &rig.in_view());
    }
}
