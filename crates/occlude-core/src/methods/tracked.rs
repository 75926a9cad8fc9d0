//! Keeping a method's state true while the scene moves ([`crate::motion`]).
//!
//! A method remembers the hierarchy [`Version`] its state was made for.
//! Each frame it asks what changed since ([`Hierarchy::since`]): after a
//! refit, node ids keep their meaning, so per-node state (CHC's
//! classification, CHC++'s queues) carries over and only cached boxes are
//! redone; after a rebuild, per-node state starts afresh.

use crate::backend::Backend;
use crate::gpu_culling::{BoxSet, GpuCulling};
use crate::hierarchy::{Changes, Hierarchy, NodeId, Since, Version};
use crate::scene::Scene;

/// The hierarchy version a method's state was last brought up to.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Tracked(Option<Version>);

impl Tracked {
    /// What changed in `h` since the last call (everything, the first
    /// time); remembers `h`'s version.
    pub(crate) fn since<'h>(&mut self, h: &'h Hierarchy) -> Since<'h> {
        let since = h.since(self.0);
        self.0 = Some(h.version());
        since
    }

    /// Brings device resources made for `h` up to date: after a rebuild
    /// (or before the first frame), releases them all and leaves
    /// `resources` `None` for the method to make anew; after a refit,
    /// calls `refit` with what changed (`None`: anything may have).
    pub(crate) fn keep_up<R>(
        &mut self,
        h: &Hierarchy,
        resources: &mut Option<R>,
        backend: &mut dyn Backend,
        refit: impl FnOnce(&R, &mut dyn GpuCulling, Option<&Changes>),
    ) {
        let since = self.since(h);
        let (Some(r), Ok(gpu)) = (resources.as_ref(), backend.gpu_culling()) else { return };
        match since {
            Since::Unchanged => {}
            Since::Refit(changes) => refit(r, gpu, changes),
            Since::New => {
                gpu.release_all();
                *resources = None;
            }
        }
    }
}

/// Rewrites the boxes of `set` (instance `k` in slot `k`) of the instances
/// of `scene` that changed (all of them when `changes` is `None`).
pub(crate) fn update_instance_boxes(gpu: &mut dyn GpuCulling, set: BoxSet, scene: &Scene, changes: Option<&Changes>) {
    let boxes: Vec<_> = match changes {
        Some(c) => c.instances.iter().map(|&i| (i, scene.instances[i as usize].culling_bounds())).collect(),
        None => scene.instances.iter().zip(0..).map(|(inst, i)| (i, inst.culling_bounds())).collect(),
    };
    if !boxes.is_empty() {
        gpu.update_boxes(set, &boxes);
    }
}

/// Rewrites the boxes of `set` (node `n` in slot `n`) of the nodes of `h`
/// whose box changed (all of them when `changes` is `None`).
pub(crate) fn update_node_boxes(gpu: &mut dyn GpuCulling, set: BoxSet, h: &Hierarchy, changes: Option<&Changes>) {
    let boxes: Vec<_> = match changes {
        Some(c) => c.nodes.iter().map(|&n| (n, *h.bounds(n))).collect(),
        None => (0..h.node_count() as NodeId).map(|n| (n, *h.bounds(n))).collect(),
    };
    if !boxes.is_empty() {
        gpu.update_boxes(set, &boxes);
    }
}
