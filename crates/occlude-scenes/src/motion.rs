//! Deterministic motion for any scene (`occlude bench --motion FRACTION`):
//! a chosen share of its instances slide back and forth, and some of them
//! leave the scene and come back, all decided by the seed.
//!
//! Every instance is chosen with probability `fraction` (from the seed and
//! its index, so that the chosen ones do not depend on the order of the
//! others). A chosen instance slides along a horizontal axis (x or z) by a
//! sine of the walkthrough's time, with a period of 4 to 10 seconds and an
//! amplitude of twice its own size or 5 % of the scene's width, whichever is
//! larger: small objects cross streets, large ones (buildings, blocks) are
//! moving occluders that reveal what they hid. One in eight chosen
//! instances also hides for a third of each period (doors, spawns).
//!
//! [`Motion`] plays it together with a model's own animation: the
//! animation moves its instances, the scripted motion a share of the others.

use crate::SceneAnimation;
use glam::{Mat4, Vec3};
use occlude_core::rng::Rng;
use occlude_core::{InstanceChange, Scene};
use std::f32::consts::TAU;

/// One moving instance.
#[derive(Clone, Debug)]
struct Mover {
    instance: u32,
    /// Its transform in the scene as built.
    base: Mat4,
    /// Displacement at the sine's peak.
    offset: Vec3,
    period: f32,
    phase: f32,
    /// Whether it hides for part of each period.
    blinks: bool,
}

/// The motion of a scene's chosen instances over time (module
/// documentation).
#[derive(Clone, Debug, Default)]
pub struct SceneMotion {
    movers: Vec<Mover>,
}

/// Sine phases above this are hidden for blinking movers: a third of the
/// period.
const HIDDEN_ABOVE: f32 = 0.5;

impl SceneMotion {
    /// Motion of `fraction` (0 to 1) of `scene`'s instances, as built,
    /// chosen and shaped from `seed`.
    pub fn new(scene: &Scene, fraction: f64, seed: u64) -> Self {
        let extent = scene.bounds().extent();
        let width = extent.x.max(extent.z);
        let movers = scene
            .instances
            .iter()
            .zip(0u32..)
            .filter_map(|(inst, i)| {
                let mut rng = Rng::new(seed, 0x6d6f_7665 ^ u64::from(i) << 8);
                if f64::from(rng.unit()) >= fraction {
                    return None;
                }
                let axis = if rng.chance(0.5) { Vec3::X } else { Vec3::Z };
                let amplitude = (2.0 * inst.bounds.extent().max_element()).max(0.05 * width);
                Some(Mover {
                    instance: i,
                    base: inst.transform,
                    offset: axis * amplitude,
                    period: rng.range(4.0, 10.0),
                    phase: rng.unit(),
                    blinks: rng.below(8) == 0,
                })
            })
            .collect();
        Self { movers }
    }

    /// Instances that move.
    pub fn moving(&self) -> usize {
        self.movers.len()
    }

    /// The changes that put every moving instance where it is at time `t`
    /// (seconds of the walkthrough), shown or hidden.
    pub fn changes_at(&self, t: f32) -> Vec<InstanceChange> {
        let mut changes = Vec::with_capacity(self.movers.len() * 2);
        for m in &self.movers {
            let s = (TAU * (t / m.period + m.phase)).sin();
            let transform = Mat4::from_translation(m.offset * s) * m.base;
            changes.push(InstanceChange::Move { instance: m.instance, transform });
            if m.blinks {
                changes.push(if s > HIDDEN_ABOVE {
                    InstanceChange::Hide(m.instance)
                } else {
                    InstanceChange::Show(m.instance)
                });
            }
        }
        changes
    }
}

/// Everything that moves a scene along its walkthrough: a model's own
/// animation, which moves the instances it animates, and [`SceneMotion`]
/// of a share of the instances it does not.
#[derive(Clone, Debug)]
pub struct Motion {
    animation: Option<SceneAnimation>,
    scripted: SceneMotion,
}

impl Motion {
    /// `scene`'s `animation` (if any) with scripted motion of `fraction` of
    /// its instances (from `seed`; the animated instances are left to the
    /// animation). None when nothing moves.
    pub fn new(scene: &Scene, animation: Option<SceneAnimation>, fraction: f64, seed: u64) -> Option<Self> {
        let mut scripted = SceneMotion::new(scene, fraction, seed);
        if let Some(animation) = &animation {
            let animated: Vec<u32> = animation.moved().collect();
            scripted.movers.retain(|m| animated.binary_search(&m.instance).is_err());
        }
        (animation.is_some() || scripted.moving() > 0).then_some(Self { animation, scripted })
    }

    /// The changes that put every moving instance where it is at time `t`
    /// (seconds of the walkthrough).
    pub fn changes_at(&self, t: f32) -> Vec<InstanceChange> {
        let mut changes = self.animation.as_ref().map(|a| a.changes_at(t)).unwrap_or_default();
        changes.extend(self.scripted.changes_at(t));
        changes
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{generate, Size};

    #[test]
    fn motion_is_deterministic_and_moves_the_chosen_share() {
        let scene = generate("city", Size::Small, 1).unwrap();
        let a = SceneMotion::new(&scene, 0.1, 7);
        let b = SceneMotion::new(&scene, 0.1, 7);
        assert_eq!(a.changes_at(1.5), b.changes_at(1.5));
        let share = a.moving() as f64 / scene.instances.len() as f64;
        assert!((0.05..0.15).contains(&share), "{share}");
        assert_eq!(SceneMotion::new(&scene, 0.0, 7).moving(), 0);
        assert_eq!(SceneMotion::new(&scene, 1.0, 7).moving(), scene.instances.len());
        let mut moved = scene.clone();
        let changed = moved.apply(&a.changes_at(2.0)).unwrap();
        assert_eq!(changed.len(), a.moving());
        assert!(changed.iter().any(|&i| moved.instances[i as usize].bounds != scene.instances[i as usize].bounds));
        // Over a whole period some blinking instance is hidden at some time.
        let hidden =
            (0..40).any(|k| a.changes_at(k as f32 * 0.25).iter().any(|c| matches!(c, InstanceChange::Hide(_))));
        assert!(hidden);
        // Without an animation, Motion plays the scripted motion alone.
        assert!(Motion::new(&scene, None, 0.0, 7).is_none());
        assert_eq!(Motion::new(&scene, None, 0.1, 7).unwrap().changes_at(1.5), a.changes_at(1.5));
    }
}
