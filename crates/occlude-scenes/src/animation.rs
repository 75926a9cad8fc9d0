//! A model's own node animations, played along the walkthrough's time.
//!
//! A glTF file's animations (read by the importer) move nodes; a moved node
//! carries every instance of its own mesh and of its descendants' meshes.
//! [`SceneAnimation`] keeps, for the nodes on the way from an animated node
//! down to a mesh, their rest transforms and their channels, so that the
//! world transform of every moved instance can be computed at any time.
//! Instances outside animated subtrees never move and are not kept.
//!
//! All animations of a file play together, from time 0, and loop over the
//! longest one's duration. Where several channels animate the same property
//! of a node, the last one in the file wins. Only rigid node motion plays:
//! skins and morph targets stay in their rest pose (the importer warns).

use glam::{Mat4, Quat, Vec3, Vec4};
use occlude_core::InstanceChange;

/// How a channel interpolates between its keys (glTF 2.0, section 3.11).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Interpolation {
    /// The value of the key before.
    Step,
    /// Linear; spherical linear for rotations.
    Linear,
    /// Cubic Hermite spline: every key has an in-tangent, a value and an
    /// out-tangent.
    CubicSpline,
}

/// The node property a channel animates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Property {
    /// Translation, a vector.
    Translation,
    /// Rotation, a unit quaternion (x, y, z, w).
    Rotation,
    /// Scale, a vector.
    Scale,
}

/// One animated property of one node: its keys and how to interpolate them.
#[derive(Clone, Debug)]
pub(crate) struct Channel {
    /// Which property.
    pub property: Property,
    /// How values between keys are found.
    pub interpolation: Interpolation,
    /// Key times, seconds, finite and strictly increasing, at least one.
    pub times: Vec<f32>,
    /// Per key its value (vectors with w = 0); for
    /// [`Interpolation::CubicSpline`] three per key: in-tangent, value,
    /// out-tangent. Rotations of the other interpolations are unit length.
    pub values: Vec<Vec4>,
}

impl Channel {
    /// The value at `t`, clamped to the first and last keys.
    fn sample(&self, t: f32) -> Vec4 {
        let cubic = self.interpolation == Interpolation::CubicSpline;
        let value = |k: usize| if cubic { self.values[3 * k + 1] } else { self.values[k] };
        let last = self.times.len() - 1;
        if t <= self.times[0] {
            return value(0);
        }
        if t >= self.times[last] {
            return value(last);
        }
        // times[k] <= t < times[k + 1], k < last.
        let k = self.times.partition_point(|&key| key <= t) - 1;
        let interval = self.times[k + 1] - self.times[k];
        let s = (t - self.times[k]) / interval;
        let rotation = self.property == Property::Rotation;
        match self.interpolation {
            Interpolation::Step => value(k),
            Interpolation::Linear if rotation => {
                Vec4::from(Quat::from_vec4(value(k)).slerp(Quat::from_vec4(value(k + 1)), s))
            }
            Interpolation::Linear => value(k).lerp(value(k + 1), s),
            Interpolation::CubicSpline => {
                // glTF 2.0, appendix C: tangents scaled by the interval.
                let (s2, s3) = (s * s, s * s * s);
                let out_tangent = self.values[3 * k + 2] * interval;
                let in_tangent = self.values[3 * (k + 1)] * interval;
                let v = value(k) * (2.0 * s3 - 3.0 * s2 + 1.0)
                    + out_tangent * (s3 - 2.0 * s2 + s)
                    + value(k + 1) * (-2.0 * s3 + 3.0 * s2)
                    + in_tangent * (s3 - s2);
                if rotation {
                    v.try_normalize().unwrap_or(Vec4::W)
                } else {
                    v
                }
            }
        }
    }

    /// The last key's time.
    pub fn end(&self) -> f32 {
        self.times[self.times.len() - 1]
    }
}

/// Where a node of the animated subtrees hangs.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Parent {
    /// Below a node that never moves, whose world transform this is.
    Fixed(Mat4),
    /// Below the node kept at this index (which comes before it).
    Moving(usize),
}

/// A node on the way from an animated node to a mesh.
#[derive(Clone, Debug)]
pub(crate) struct Node {
    /// Where it hangs.
    pub parent: Parent,
    /// How it stands relative to its parent.
    pub pose: Pose,
}

/// A node's transform relative to its parent.
#[derive(Clone, Debug)]
pub(crate) enum Pose {
    /// Fixed: the node only moves with its parent.
    Still(Mat4),
    /// Animated: its rest translation, rotation and scale, and its channels
    /// in file order (a later one wins).
    Animated {
        /// Translation, rotation and scale where no channel animates them.
        rest: (Vec3, Quat, Vec3),
        /// Its channels.
        channels: Vec<Channel>,
    },
}

impl Pose {
    /// The transform at `t`.
    fn at(&self, t: f32) -> Mat4 {
        let (rest, channels) = match self {
            Pose::Still(local) => return *local,
            Pose::Animated { rest, channels } => (rest, channels),
        };
        let (mut translation, mut rotation, mut scale) = *rest;
        for channel in channels {
            let v = channel.sample(t);
            match channel.property {
                Property::Translation => translation = v.truncate(),
                Property::Rotation => rotation = Quat::from_vec4(v),
                Property::Scale => scale = v.truncate(),
            }
        }
        Mat4::from_scale_rotation_translation(scale, rotation, translation)
    }
}

/// A model's node animations (module documentation): which instances they
/// move, and where to at any time.
#[derive(Clone, Debug, Default)]
pub struct SceneAnimation {
    /// The nodes of the animated subtrees, each after its parent.
    nodes: Vec<Node>,
    /// Per moved instance, the index of its node in `nodes`; sorted by
    /// instance.
    instances: Vec<(u32, usize)>,
    /// The longest channel's last key time, seconds.
    duration: f32,
}

impl SceneAnimation {
    /// An animation of `nodes` (each after its parent) moving `instances`
    /// (instance, node index) lasting `duration` seconds.
    pub(crate) fn new(nodes: Vec<Node>, mut instances: Vec<(u32, usize)>, duration: f32) -> Self {
        instances.sort_unstable();
        Self { nodes, instances, duration }
    }

    /// The duration of one loop: the longest animation's, seconds (0 when
    /// every key is at time 0).
    pub fn duration(&self) -> f32 {
        self.duration
    }

    /// The instances it moves, sorted.
    pub fn moved(&self) -> impl Iterator<Item = u32> + '_ {
        self.instances.iter().map(|&(i, _)| i)
    }

    /// The moves that put every animated instance where it is at time `t`
    /// (seconds of the walkthrough, looped over [`SceneAnimation::duration`]).
    pub fn changes_at(&self, t: f32) -> Vec<InstanceChange> {
        let t = if self.duration > 0.0 { t.rem_euclid(self.duration) } else { 0.0 };
        let mut world: Vec<Mat4> = Vec::with_capacity(self.nodes.len());
        for node in &self.nodes {
            let parent = match node.parent {
                Parent::Fixed(above) => above,
                Parent::Moving(p) => world[p],
            };
            world.push(parent * node.pose.at(t));
        }
        self.instances
            .iter()
            .map(|&(instance, node)| InstanceChange::Move { instance, transform: world[node] })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn channel(interpolation: Interpolation, property: Property, times: &[f32], values: &[Vec4]) -> Channel {
        Channel { property, interpolation, times: times.to_vec(), values: values.to_vec() }
    }

    #[test]
    fn linear_step_and_cubic_spline_between_keys_and_clamped_outside() {
        let keys = [Vec4::ZERO, Vec4::new(2.0, 4.0, 0.0, 0.0)];
        let linear = channel(Interpolation::Linear, Property::Translation, &[1.0, 3.0], &keys);
        assert_eq!(linear.sample(2.0), Vec4::new(1.0, 2.0, 0.0, 0.0));
        assert_eq!(linear.sample(2.5), Vec4::new(1.5, 3.0, 0.0, 0.0));
        assert_eq!(linear.sample(-5.0), keys[0]);
        assert_eq!(linear.sample(9.0), keys[1]);
        let step = channel(Interpolation::Step, Property::Scale, &[1.0, 3.0], &keys);
        assert_eq!(step.sample(2.9), keys[0]);
        assert_eq!(step.sample(3.0), keys[1]);
        // Zero tangents: the smoothstep 3s² - 2s³, 0.5 halfway.
        let flat = [Vec4::ZERO, keys[0], Vec4::ZERO, Vec4::ZERO, keys[1], Vec4::ZERO];
        let cubic = channel(Interpolation::CubicSpline, Property::Translation, &[1.0, 3.0], &flat);
        assert_eq!(cubic.sample(2.0), keys[1] * 0.5);
        assert_eq!(cubic.sample(0.0), keys[0]);
        assert_eq!(cubic.sample(4.0), keys[1]);
        // Tangents scaled by the 2 s interval: a unit out-tangent at key 0
        // adds 2 (s³ - 2s² + s) = 0.25 halfway.
        let sloped = [Vec4::ZERO, Vec4::ZERO, Vec4::X, Vec4::ZERO, Vec4::ZERO, Vec4::ZERO];
        let cubic = channel(Interpolation::CubicSpline, Property::Translation, &[1.0, 3.0], &sloped);
        assert!((cubic.sample(2.0).x - 0.25).abs() < 1e-6);
    }

    #[test]
    fn rotations_slerp_and_cubic_rotations_are_unit() {
        let quarter = Vec4::from(Quat::from_rotation_y(std::f32::consts::FRAC_PI_2));
        let linear = channel(Interpolation::Linear, Property::Rotation, &[0.0, 1.0], &[Vec4::W, quarter]);
        let eighth = Quat::from_vec4(linear.sample(0.5));
        assert!(eighth.angle_between(Quat::from_rotation_y(std::f32::consts::FRAC_PI_4)) < 1e-5);
        let keys = [Vec4::ZERO, Vec4::W, Vec4::ZERO, Vec4::ZERO, quarter, Vec4::ZERO];
        let cubic = channel(Interpolation::CubicSpline, Property::Rotation, &[0.0, 1.0], &keys);
        assert!((cubic.sample(0.5).length() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn a_child_moves_with_its_animated_parent_and_time_loops() {
        let slide = channel(Interpolation::Linear, Property::Translation, &[0.0, 2.0], &[Vec4::ZERO, Vec4::X * 4.0]);
        let rest = (Vec3::ZERO, Quat::IDENTITY, Vec3::ONE);
        let above = Mat4::from_translation(Vec3::Y);
        let nodes = vec![
            Node { parent: Parent::Fixed(above), pose: Pose::Animated { rest, channels: vec![slide] } },
            Node { parent: Parent::Moving(0), pose: Pose::Still(Mat4::from_translation(Vec3::Z)) },
        ];
        let animation = SceneAnimation::new(nodes, vec![(7, 1), (3, 0)], 2.0);
        assert_eq!(animation.moved().collect::<Vec<_>>(), [3, 7]);
        let at = |t: f32| match animation.changes_at(t)[1] {
            InstanceChange::Move { instance: 7, transform } => transform.w_axis.truncate(),
            other => panic!("{other:?}"),
        };
        assert_eq!(at(1.0), Vec3::new(2.0, 1.0, 1.0));
        assert_eq!(at(3.0), at(1.0));
    }
}
