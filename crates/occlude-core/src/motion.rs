//! Scenes in motion: what a renderer tells occlude once per frame.
//!
//! Online occlusion culling needs no preprocessing, so it "allows for fully
//! dynamic scenes" (CHC++ paper, section 2); the occupancy-map paper
//! (section 1) asks only that "the bounding box hierarchy of the scene graph
//! has to be up to date in each frame". A frame of a moving scene is:
//!
//! 1. [`Scene::apply`] the frame's [`InstanceChange`]s (rigid motion of
//!    whole instances, hiding and showing them): every change is checked
//!    before any is applied, and the changed instances are returned;
//! 2. [`Hierarchy::update`](crate::Hierarchy::update) with them: a refit
//!    that keeps node ids, or a rebuild when refits have degraded the tree;
//! 3. [`Backend::update_instances`](crate::Backend::update_instances) on
//!    each backend with them: the backend copies what changed into its own
//!    copy of the instances (on a GPU, an upload of the changed transforms);
//! 4. the frame as ever ([`crate::render_frame`]). Methods see the changes
//!    through [`Hierarchy::since`](crate::Hierarchy::since).
//!
//! Meshes never change: an animated mesh is a new mesh. Spawning is showing
//! an instance that was hidden: the instance count is fixed once a
//! hierarchy is built over the scene.

use crate::geometry::Aabb;
use crate::scene::Scene;
use glam::Mat4;
use thiserror::Error;

/// One change to an instance of a scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum InstanceChange {
    /// The instance's object-to-world transform becomes `transform`.
    Move {
        /// Instance index.
        instance: u32,
        /// Its new transform; must be finite.
        transform: Mat4,
    },
    /// The instance is drawn again after [`InstanceChange::Hide`].
    Show(u32),
    /// The instance leaves the scene until shown again: no backend draws
    /// it, no node box holds it.
    Hide(u32),
}

impl InstanceChange {
    /// Moves instance `instance` of a scene of boxes
    /// ([`Scene::from_bounds`]) to the box `bounds`.
    pub fn to_box(instance: u32, bounds: &Aabb) -> Self {
        InstanceChange::Move { instance, transform: Scene::box_transform(bounds) }
    }

    /// The instance the change applies to.
    pub fn instance(&self) -> u32 {
        match *self {
            InstanceChange::Move { instance, .. } | InstanceChange::Show(instance) | InstanceChange::Hide(instance) => {
                instance
            }
        }
    }
}

/// Why [`Scene::apply`] refused a frame's changes (none of them applied).
#[derive(Clone, Debug, Error, PartialEq)]
pub enum MotionError {
    /// A change names an instance the scene does not have.
    #[error("change {change} names instance {instance}, but the scene has {instances} instances")]
    UnknownInstance {
        /// Index of the change in the list.
        change: usize,
        /// The instance it names.
        instance: u32,
        /// Instances the scene has.
        instances: usize,
    },
    /// A move's transform has a NaN or infinite entry, or moves the
    /// instance's box out of finite range.
    #[error("change {change} moves instance {instance} by a transform that is not finite")]
    NonFiniteTransform {
        /// Index of the change in the list.
        change: usize,
        /// The instance it moves.
        instance: u32,
    },
}

impl Scene {
    /// Applies one frame's `changes` in order (a later change of an
    /// instance wins) and returns the changed instances, sorted, each once.
    /// Checks every change first: on an error nothing has changed.
    pub fn apply(&mut self, changes: &[InstanceChange]) -> Result<Vec<u32>, MotionError> {
        let instances = self.instances.len();
        for (k, change) in changes.iter().enumerate() {
            let instance = change.instance();
            let Some(inst) = self.instances.get(instance as usize) else {
                return Err(MotionError::UnknownInstance { change: k, instance, instances });
            };
            if let InstanceChange::Move { transform, .. } = change {
                let bounds = self.meshes[inst.mesh as usize].bounds.transformed(transform);
                if !transform.is_finite() || !bounds.is_finite() {
                    return Err(MotionError::NonFiniteTransform { change: k, instance });
                }
            }
        }
        let mut changed: Vec<u32> = changes.iter().map(InstanceChange::instance).collect();
        for change in changes {
            let inst = &mut self.instances[change.instance() as usize];
            match *change {
                InstanceChange::Move { transform, .. } => {
                    inst.transform = transform;
                    inst.bounds = self.meshes[inst.mesh as usize].bounds.transformed(&transform);
                }
                InstanceChange::Show(_) => inst.enabled = true,
                InstanceChange::Hide(_) => inst.enabled = false,
            }
        }
        changed.sort_unstable();
        changed.dedup();
        if !changed.is_empty() {
            self.bump_revision();
        }
        Ok(changed)
    }

    /// Copies the `changed` instances of `source` (this scene's original,
    /// after [`Scene::apply`]) into this copy, and its revision: what a
    /// backend keeping its own copy does in
    /// [`Backend::update_instances`](crate::Backend::update_instances).
    ///
    /// # Panics
    /// If `source` has other instances than this copy (another scene).
    pub fn copy_instances(&mut self, source: &Scene, changed: &[u32]) {
        assert_eq!(self.instances.len(), source.instances.len(), "instances copied from another scene");
        for &i in changed {
            self.instances[i as usize] = source.instances[i as usize].clone();
        }
        self.set_revision(source.revision());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Mesh;
    use glam::Vec3;

    fn two_cubes() -> Scene {
        let mut s = Scene::new("two");
        let corners = Aabb::new(Vec3::ZERO, Vec3::ONE).corners().to_vec();
        let m = s.add_mesh(Mesh::new(corners, vec![0, 1, 2]));
        s.add_instance(m, Mat4::IDENTITY, 0);
        s.add_instance(m, Mat4::from_translation(Vec3::X * 3.0), 0);
        s
    }

    #[test]
    fn moves_update_transform_and_box_and_the_revision() {
        let mut s = two_cubes();
        let to = Mat4::from_translation(Vec3::new(0.0, 5.0, 0.0));
        let changed = s.apply(&[InstanceChange::Move { instance: 1, transform: to }, InstanceChange::Hide(0)]);
        assert_eq!(changed, Ok(vec![0, 1]));
        assert_eq!(s.instances[1].bounds, Aabb::new(Vec3::new(0.0, 5.0, 0.0), Vec3::new(1.0, 6.0, 1.0)));
        assert!(!s.instances[0].enabled && s.instances[0].culling_bounds().is_empty());
        assert_eq!(s.instance_triangles(0), 0);
        assert_eq!(s.revision(), 1);
        assert_eq!(s.apply(&[]), Ok(vec![]));
        assert_eq!(s.revision(), 1, "no change, same revision");
        assert_eq!(s.apply(&[InstanceChange::Show(0)]), Ok(vec![0]));
        assert!(s.instances[0].enabled);
    }

    #[test]
    fn bad_changes_are_refused_and_change_nothing() {
        let mut s = two_cubes();
        let before = s.instances.clone();
        let good = InstanceChange::Move { instance: 0, transform: Mat4::from_translation(Vec3::Y) };
        let nan = InstanceChange::Move { instance: 1, transform: Mat4::from_scale(Vec3::splat(f32::NAN)) };
        assert_eq!(s.apply(&[good, nan]), Err(MotionError::NonFiniteTransform { change: 1, instance: 1 }));
        let far =
            Mat4::from_scale_rotation_translation(Vec3::splat(f32::MAX), glam::Quat::IDENTITY, Vec3::splat(f32::MAX));
        let huge = InstanceChange::Move { instance: 1, transform: far };
        assert_eq!(s.apply(&[huge]), Err(MotionError::NonFiniteTransform { change: 0, instance: 1 }));
        let unknown = InstanceChange::Hide(2);
        assert_eq!(
            s.apply(&[good, unknown]),
            Err(MotionError::UnknownInstance { change: 1, instance: 2, instances: 2 })
        );
        assert_eq!(s.revision(), 0);
        for (a, b) in s.instances.iter().zip(&before) {
            assert_eq!((a.transform, a.bounds, a.enabled), (b.transform, b.bounds, b.enabled));
        }
    }
}
