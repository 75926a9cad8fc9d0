//! Masked software occlusion culling (`moc`), after Hasselgren, Andersson and
//! Akenine-Möller, "Masked Software Occlusion Culling" (HPG 2016): occluders
//! are rasterized on the CPU into a coarse masked depth buffer
//! ([`occlude_moc::MaskedBuffer`]; the buffer is the paper's section 3, its
//! layer merge section 3.1), then the hierarchy is walked front to back and
//! each node's box is tested against that buffer on the CPU (section 4,
//! "occlusion queries": the box's screen rectangle at its nearest depth).
//! Survivors are drawn with no occlusion query, so no result ever comes back
//! from the GPU.
//!
//! # Occluders (`moc.occluders`)
//!
//! - `drawn` (the default): each object is rendered into the buffer right
//!   after it is drawn. The walk is front to back, so everything drawn in
//!   front of a node is in the buffer before the node is tested: the coarse
//!   analogue of stop-and-wait's exact depth buffer, with no state between
//!   frames. It is the default because it culls nearly what `sw` culls, at
//!   the price of rasterizing every drawn triangle on the CPU.
//! - `last`: the objects drawn in the previous frame, rendered before the walk
//!   (the paper's usage with last frame's visible set); nothing is added
//!   during the walk. Fewer CPU triangles where much is drawn but little
//!   occludes; the first frame and disocclusions cull less.
//! - `largest`: the `moc.count` objects in the frustum whose boxes look
//!   largest from the eye (size over distance), rendered before the walk:
//!   designated occluders without temporal state.
//!
//! With `moc.proxies=on` (default off), an occluder whose mesh has [inner
//! boxes](crate::inner_box) is rendered as those boxes (12 triangles each)
//! where `occluder_proxies.rs` shows that this stays conservative for its
//! instance this frame, and in full otherwise. It changes how an occluder is
//! rendered, not which objects occlude. The counters `proxy_occluders` and
//! `meshes_with_proxy` report its use.
//!
//! # Why it never culls a visible object
//!
//! A node is culled only when the buffer answers
//! [`Occluded`](occlude_moc::Visibility::Occluded) for its box (or the box is
//! wholly outside a frustum plane). Let an object inside the node own pixel
//! `p` of view-frustum culling's image. Then `p` lies in the object's screen
//! footprint and its depth there is below every occluder's depth at `p` (or no
//! occluder covers `p`). The test cannot answer occluded:
//!
//! - The box tested is the occlusion queries' proxy
//!   ([`query_box::padded`]) pulled towards the eye by
//!   [`QUERY_DEPTH_BIAS`], so geometry on its faces never rounds in front of
//!   it, exactly as for the query methods. The buffer rounds the box's screen
//!   rectangle outward by a pixel and lowers its nearest depth by a relative
//!   1e-6, more than the rounding of either backend's interpolated depth.
//! - Depth precision: the buffer's bound at `p` is at least the depth plane
//!   through the occluder's snapped vertices anywhere in `p`'s 8x4-pixel
//!   subtile (its maximum over the subtile's corners, computed in `f64`,
//!   rounded up to `f32`), raised by the plane's change over one grid step so
//!   that it also bounds a rasterizer that placed a vertex a step away; the
//!   test compares strictly (`nearest < bound` is visible), so ties are
//!   visible.
//! - Near-plane clipping: occluders are clipped to the near plane in clip space
//!   before the divide; a box reaching the camera's near region
//!   ([`Camera::box_touches_near_region`], which includes a camera inside the
//!   box) or with a corner behind the near plane is visible untested.
//! - Coverage: the buffer covers with each occluder triangle exactly the
//!   pixels a rasterizer with 8 sub-pixel bits and the top-left rule covers
//!   with it (`occlude_moc`'s crate doc): it snaps the vertices to the same
//!   1/256-pixel grid, after the same `f64` projection of the same `f32`
//!   clip coordinates, and evaluates the same edge functions, exactly in
//!   `f64`. So a pixel counts as covered only where the backend's image has
//!   that occluder, on every frame of any scene; no step rests on the
//!   scenes. Triangles crossing the near plane or reaching 8000 pixels beyond
//!   the screen are drawn with their edges 1/32 pixel inward instead, more
//!   than clipping and snapping move a rasterizer's edges. The soft backend
//!   computes the clip coordinates with the same code (`view_projection *
//!   transform` applied by glam), so for it the argument is complete. The
//!   wgpu backend computes them on the GPU in its own `f32` arithmetic;
//!   where that moves a vertex across a rounding tie of the grid (it moves
//!   vertices by about `1e-4` pixel), the GPU snaps it one grid step away and
//!   a pixel centre within 1/256 pixel of that vertex's outer edges can
//!   differ: the one assumption left, for GPUs only (the depth bounds allow
//!   for that step).
//!
//! [`Camera::box_touches_near_region`]: crate::Camera::box_touches_near_region
//! [`QUERY_DEPTH_BIAS`]: crate::query_box::QUERY_DEPTH_BIAS
//! [`query_box::padded`]: crate::query_box::padded

use super::occluder_proxies::OccluderProxies;
use super::{CullingMethod, FrameContext, FrontToBack, MethodParams, OptionError, ParamVisitor};
use crate::backend::{Backend, CpuCullingWork};
use crate::geometry::Aabb;
use crate::query_box::{padded, QUERY_DEPTH_BIAS};
use glam::Mat4;
use occlude_moc::{CullMode, MaskedBuffer, MergeMode, Visibility};
use std::fmt;
use std::str::FromStr;

/// Which objects are rendered into the masked buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Occluders {
    /// Every object drawn, right after it is drawn (front to back).
    Drawn,
    /// The objects drawn in the previous frame, before the walk.
    Last,
    /// The `moc.count` objects in view with the largest boxes over distance.
    Largest,
}

impl fmt::Display for Occluders {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Occluders::Drawn => "drawn",
            Occluders::Last => "last",
            Occluders::Largest => "largest",
        })
    }
}

impl FromStr for Occluders {
    type Err = ();
    fn from_str(s: &str) -> Result<Self, ()> {
        match s {
            "drawn" => Ok(Occluders::Drawn),
            "last" => Ok(Occluders::Last),
            "largest" => Ok(Occluders::Largest),
            _ => Err(()),
        }
    }
}

/// Parameters of `moc`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MocParams {
    /// `moc.occluders`: `drawn` (default), `last` or `largest`.
    pub occluders: Occluders,
    /// `moc.count` (default 64): how many objects `largest` renders.
    pub count: u32,
    /// `moc.merge`: `layer` (the paper's heuristic, default) or `quick`.
    pub merge: MergeMode,
    /// `moc.proxies` (default off): render each occluder as its mesh's
    /// inner box where the conditions hold (module doc), else in full.
    pub proxies: bool,
}

impl Default for MocParams {
    fn default() -> Self {
        Self { occluders: Occluders::Drawn, count: 64, merge: MergeMode::LayerMerge, proxies: false }
    }
}

impl MethodParams for MocParams {
    const METHOD: &'static str = "moc";
    fn visit(&mut self, v: &mut ParamVisitor) -> Result<(), OptionError> {
        v.value("occluders", &mut self.occluders, "drawn, last or largest", |_| true)?;
        v.value("count", &mut self.count, "an integer from 1 to 65536", |c| (1..=65536).contains(c))?;
        v.value("merge", &mut self.merge, "layer or quick", |_| true)?;
        v.flag("proxies", &mut self.proxies)
    }
}

/// `moc`: hierarchical culling against a masked occlusion buffer on the CPU.
#[derive(Debug)]
pub struct MaskedOcclusion {
    params: MocParams,
    buffer: Option<MaskedBuffer>,
    /// Instances drawn this frame (the next frame's `last` occluders).
    drawn: Vec<u32>,
    /// This frame's work, reported by [`CullingMethod::counters`].
    work: CpuCullingWork,
    /// The meshes' inner boxes (`moc.proxies`).
    proxies: OccluderProxies,
    /// Occluders rendered as inner boxes this frame.
    proxied: u64,
}

impl MaskedOcclusion {
    /// A method with no state from earlier frames.
    pub fn new(params: MocParams) -> Self {
        Self {
            params,
            buffer: None,
            drawn: Vec::new(),
            work: CpuCullingWork::default(),
            proxies: OccluderProxies::default(),
            proxied: 0,
        }
    }

    /// The masked buffer as it stood at the end of the last frame, if any.
    pub fn buffer(&self) -> Option<&MaskedBuffer> {
        self.buffer.as_ref()
    }

    /// The occluders rendered before the walk.
    fn occluders_before_walk(&self, ctx: &FrameContext<'_>, backend: &mut dyn Backend) -> Vec<u32> {
        match self.params.occluders {
            Occluders::Drawn => Vec::new(),
            Occluders::Last => self.drawn.clone(),
            Occluders::Largest => {
                let instances = &ctx.scene.instances;
                backend.traverse(instances.len() as u64);
                let eye = ctx.camera.position;
                let mut scored: Vec<(f32, u32)> = (0..instances.len() as u32)
                    .filter(|&i| ctx.frustum.intersects(&instances[i as usize].culling_bounds()))
                    .map(|i| {
                        let b = &instances[i as usize].bounds;
                        (b.extent().length_squared() / b.distance_squared(eye).max(1e-12), i)
                    })
                    .collect();
                let count = (self.params.count as usize).min(scored.len());
                if count > 0 && count < scored.len() {
                    scored.select_nth_unstable_by(count - 1, |a, b| b.0.total_cmp(&a.0));
                }
                scored[..count].iter().map(|&(_, i)| i).collect()
            }
        }
    }
}

/// Renders `instances` into `buffer` seen through `view_projection`, each as
/// its inner box where `proxies` gives one for it this frame, else in full;
/// returns the work done and how many were rendered as boxes.
fn render_occluders(
    buffer: &mut MaskedBuffer,
    ctx: &FrameContext<'_>,
    view_projection: Mat4,
    instances: &[u32],
    mut proxies: Option<&mut OccluderProxies>,
) -> (CpuCullingWork, u64) {
    let mut work = CpuCullingWork::default();
    let mut proxied = 0;
    let size = (buffer.width(), buffer.height());
    for &i in instances {
        let inst = &ctx.scene.instances[i as usize];
        if !inst.enabled {
            continue;
        }
        let to_clip = view_projection * inst.transform;
        let done = match proxies.as_mut().and_then(|p| p.proxy(ctx.scene, &ctx.camera, inst, size)) {
            Some((corners, indices)) => {
                proxied += 1;
                buffer.render_triangles(corners, indices, to_clip, CullMode::Back)
            }
            None => {
                let mesh = &ctx.scene.meshes[inst.mesh as usize];
                buffer.render_triangles(&mesh.positions, &mesh.indices, to_clip, CullMode::Back)
            }
        };
        work += CpuCullingWork { triangles: done.triangles, tiles: done.tiles, ..CpuCullingWork::default() };
    }
    (work, proxied)
}

/// Charges `work` on the backend's clock and adds it to the frame's
/// counters.
fn charge(total: &mut CpuCullingWork, backend: &mut dyn Backend, work: CpuCullingWork) {
    backend.cpu_culling(work);
    *total += work;
}

/// `view_projection` with clip-space depth pulled towards the eye by
/// [`QUERY_DEPTH_BIAS`] (`z - bias * w`), as query boxes are drawn.
fn biased(view_projection: Mat4) -> Mat4 {
    let mut m = view_projection;
    for c in [&mut m.x_axis, &mut m.y_axis, &mut m.z_axis, &mut m.w_axis] {
        c.z -= QUERY_DEPTH_BIAS * c.w;
    }
    m
}

impl CullingMethod for MaskedOcclusion {
    fn name(&self) -> &'static str {
        "moc"
    }

    fn render(&mut self, ctx: &mut FrameContext<'_>, backend: &mut dyn Backend) {
        let before = self.occluders_before_walk(ctx, backend);
        let (width, height) = backend.resolution();
        let buffer = match &mut self.buffer {
            Some(b) if (b.width(), b.height()) == (width, height) => b,
            slot => slot.insert(match MaskedBuffer::new(width, height) {
                Ok(b) => b,
                // No pixels: nothing can be seen, nothing to cull against.
                Err(_) => return,
            }),
        };
        buffer.merge = self.params.merge;
        buffer.clear();
        let view_projection = ctx.camera.view_projection();
        let box_projection = biased(view_projection);

        self.work = CpuCullingWork::default();
        let mut proxies = if self.params.proxies {
            self.proxies.prepare(ctx.scene);
            Some(&mut self.proxies)
        } else {
            None
        };
        let (work, mut proxied) = render_occluders(buffer, ctx, view_projection, &before, proxies.as_deref_mut());
        charge(&mut self.work, backend, work);
        self.drawn.clear();

        let h = ctx.hierarchy;
        let mut queue = FrontToBack::new();
        ctx.push_in_frustum(&[h.root()], &mut queue);
        let mut candidates = Vec::new();
        while let Some(node) = queue.pop() {
            backend.traverse(1);
            let (visible, work) = test_box(buffer, ctx, box_projection, h.bounds(node));
            charge(&mut self.work, backend, work);
            if !visible {
                continue;
            }
            if h.is_leaf(node) {
                // A leaf of several objects tests each object's own box.
                candidates.clear();
                let alone = h.instances(node).len() == 1;
                for &i in h.instances(node) {
                    if ctx.was_drawn(i) {
                        continue;
                    }
                    let visible = alone || {
                        let (visible, work) =
                            test_box(buffer, ctx, box_projection, &ctx.scene.instances[i as usize].bounds);
                        charge(&mut self.work, backend, work);
                        visible
                    };
                    if visible {
                        candidates.push(i);
                    }
                }
                let drawn = ctx.draw_instances(backend, &candidates);
                self.drawn.extend_from_slice(drawn);
                if self.params.occluders == Occluders::Drawn {
                    let (work, boxes) =
                        render_occluders(buffer, ctx, view_projection, &candidates, proxies.as_deref_mut());
                    charge(&mut self.work, backend, work);
                    proxied += boxes;
                }
            } else {
                ctx.push_in_frustum(h.children(node), &mut queue);
            }
        }
        self.proxied = proxied;
    }

    fn counters(&self) -> Vec<(&'static str, f64)> {
        vec![
            ("occluder_triangles", self.work.triangles as f64),
            ("occluder_tiles", self.work.tiles as f64),
            ("tested_boxes", self.work.boxes as f64),
            ("box_subtiles_read", self.work.subtiles_read as f64),
            ("proxy_occluders", self.proxied as f64),
            ("meshes_with_proxy", self.proxies.meshes_with_box() as f64),
        ]
    }
}

/// Whether something inside `bounds` may have a visible pixel: its padded box
/// touches the near region or the buffer does not answer occluded for it (a
/// box wholly outside a frustum plane counts as hidden); and the work of that
/// test (one box, and the subtiles the buffer read for it).
fn test_box(
    buffer: &MaskedBuffer,
    ctx: &FrameContext<'_>,
    box_projection: Mat4,
    bounds: &Aabb,
) -> (bool, CpuCullingWork) {
    let b = padded(bounds);
    let (visible, subtiles_read) = if ctx.camera.box_touches_near_region(&b) {
        (true, 0)
    } else {
        let (v, reads) = buffer.test_aabb_counted(b.min, b.max, box_projection);
        (v == Visibility::Visible, reads)
    };
    (visible, CpuCullingWork { boxes: 1, subtiles_read, ..CpuCullingWork::default() })
}

#[cfg(test)]
mod tests {
    use super::super::test_rig::{assert_draws_exactly, method, queries, Rig, BEHIND, SIDE, WALL};
    use crate::mock::Call;

    /// Behind a drawn wall, a cube is culled on the CPU although the mock
    /// would answer any query about it "visible": no query is issued, and
    /// the buffer's work is reported to the backend, the subtiles the box
    /// tests read included (the cube's hidden box reads its whole rectangle).
    /// Without occluders (`last` on the first frame) nothing is culled.
    #[test]
    fn culls_what_the_drawn_wall_hides_without_a_query() {
        let rig = Rig::wall();
        for options in [&[][..], &["moc.merge=quick"]] {
            let mut moc = method("moc", options);
            let calls = &rig.run(&mut moc, &mut rig.mock(), 1)[0];
            assert_draws_exactly(calls, &[WALL, SIDE]);
            assert!(queries(calls).is_empty(), "{options:?}");
            let mut work = crate::backend::CpuCullingWork::default();
            for c in calls {
                if let Call::CpuCulling(w) = c {
                    work += *w;
                }
            }
            assert!(work.triangles >= 12, "{options:?}: the wall's triangles were not reported ({work:?})");
            assert!(work.subtiles_read >= 1, "{options:?}: no subtile read was reported ({work:?})");
            let counter = moc.method.counters().iter().find(|c| c.0 == "box_subtiles_read").map(|c| c.1);
            assert_eq!(counter, Some(work.subtiles_read as f64), "{options:?}");
        }
        let first = &rig.run(&mut method("moc", &["moc.occluders=last"]), &mut rig.mock(), 1)[0];
        assert_draws_exactly(first, &[WALL, BEHIND, SIDE]);
    }

    /// With `moc.proxies=on` the wall, a closed box, goes into the buffer as
    /// its inner box and still hides the cube behind it.
    #[test]
    fn the_walls_inner_box_hides_the_cube_behind_it() {
        let rig = Rig::wall();
        let mut moc = method("moc", &["moc.proxies=on"]);
        let calls = &rig.run(&mut moc, &mut rig.mock(), 1)[0];
        assert_draws_exactly(calls, &[WALL, SIDE]);
        let counter = |name| moc.method.counters().iter().find(|c| c.0 == name).map(|c| c.1);
        assert!(counter("proxy_occluders") >= Some(1.0), "{:?}", moc.method.counters());
        assert!(counter("meshes_with_proxy") >= Some(1.0), "{:?}", moc.method.counters());
    }
}
