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
//! The generated scenes that move by themselves (`traffic`, `crowd`) script
//! their vehicles, people and doors with the same [`SceneMotion`]: every
//! moving instance follows a periodic track (a sine, a walk back and forth,
//! a drive that wraps around) and may hide for part of each period.
//!
//! [`Motion`] plays a scene's own motion ([`OwnMotion`]: a model's
//! animation or a generated scene's script) together with the scripted
//! motion of a share of the instances it does not move.

use crate::SceneAnimation;
use glam::{Mat4, Vec3};
use occlude_core::rng::Rng;
use occlude_core::{Aabb, InstanceChange, Scene};
use std::f32::consts::TAU;
use std::ops::Range;

/// How an instance moves over one period of its [`Track`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Stroke {
    /// Back and forth by a sine, between `-offset` and `offset`.
    Sway,
    /// Back and forth at a constant speed, between no offset and `offset`.
    Shuttle,
    /// From no offset to `offset` at a constant speed, then from the start
    /// again (a vehicle wrapping around at the city's edge).
    Loop,
}

/// One moving instance: where it goes over a period, and when it is hidden.
#[derive(Clone, Debug)]
pub(crate) struct Track {
    /// The instance it moves.
    pub instance: u32,
    /// Its transform with no offset.
    pub base: Mat4,
    /// How it moves.
    pub stroke: Stroke,
    /// The displacement at the stroke's far end; zero for an instance that
    /// stays put.
    pub offset: Vec3,
    /// Seconds.
    pub period: f32,
    /// The share of a period done at time 0, 0 to 1.
    pub phase: f32,
    /// The part of each period (shares, 0 to 1) during which it is hidden;
    /// empty for one that never hides.
    pub hidden: Range<f32>,
}

impl Track {
    /// The share of the current period done at time `t`.
    fn cycle(&self, t: f32) -> f32 {
        (t / self.period + self.phase).rem_euclid(1.0)
    }

    /// Its displacement from [`Track::base`] at time `t`.
    pub(crate) fn displacement(&self, t: f32) -> Vec3 {
        let u = self.cycle(t);
        let s = match self.stroke {
            Stroke::Sway => (TAU * u).sin(),
            Stroke::Shuttle => 1.0 - (2.0 * u - 1.0).abs(),
            Stroke::Loop => u,
        };
        self.offset * s
    }

    /// Its transform at time `t`.
    pub(crate) fn transform_at(&self, t: f32) -> Mat4 {
        Mat4::from_translation(self.displacement(t)) * self.base
    }

    /// Whether it is hidden at time `t`.
    pub(crate) fn is_hidden(&self, t: f32) -> bool {
        self.hidden.contains(&self.cycle(t))
    }

    /// The box that `bounds` (its box at [`Track::base`]) sweeps over a
    /// period.
    pub(crate) fn swept(&self, bounds: &Aabb) -> Aabb {
        let back = if self.stroke == Stroke::Sway { -self.offset } else { Vec3::ZERO };
        let shifted = |d: Vec3| Aabb::new(bounds.min + d, bounds.max + d);
        shifted(back).union(&shifted(self.offset))
    }
}

/// The motion of a scene's moving instances over time: `--motion`'s slide
/// of a chosen share of them (module documentation), or a generated scene's
/// own script.
#[derive(Clone, Debug, Default)]
pub struct SceneMotion {
    /// Sorted by instance, one per instance.
    tracks: Vec<Track>,
}

/// The part of each period during which a blinking slider is hidden: where
/// its sine is above 0.5, a third of the period.
const BLINK: Range<f32> = 1.0 / 12.0..5.0 / 12.0;

impl SceneMotion {
    /// Motion of `fraction` (0 to 1) of `scene`'s instances, as built,
    /// chosen and shaped from `seed`.
    pub fn new(scene: &Scene, fraction: f64, seed: u64) -> Self {
        let extent = scene.bounds().extent();
        let width = extent.x.max(extent.z);
        let tracks = scene
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
                Some(Track {
                    instance: i,
                    base: inst.transform,
                    stroke: Stroke::Sway,
                    offset: axis * amplitude,
                    period: rng.range(4.0, 10.0),
                    phase: rng.unit(),
                    hidden: if rng.below(8) == 0 { BLINK } else { 0.0..0.0 },
                })
            })
            .collect();
        Self { tracks }
    }

    /// A generated scene's script: `tracks`, one per instance.
    pub(crate) fn scripted(mut tracks: Vec<Track>) -> Self {
        tracks.sort_unstable_by_key(|t| t.instance);
        Self { tracks }
    }

    /// Instances that move.
    pub fn moving(&self) -> usize {
        self.tracks.len()
    }

    /// The instances it moves, sorted.
    pub fn moved(&self) -> impl Iterator<Item = u32> + '_ {
        self.tracks.iter().map(|t| t.instance)
    }

    /// The changes that put every moving instance where it is at time `t`
    /// (seconds of the walkthrough), shown or hidden.
    pub fn changes_at(&self, t: f32) -> Vec<InstanceChange> {
        let mut changes = Vec::with_capacity(self.tracks.len() * 2);
        for track in &self.tracks {
            if track.offset != Vec3::ZERO {
                changes.push(InstanceChange::Move { instance: track.instance, transform: track.transform_at(t) });
            }
            if !track.hidden.is_empty() {
                changes.push(if track.is_hidden(t) {
                    InstanceChange::Hide(track.instance)
                } else {
                    InstanceChange::Show(track.instance)
                });
            }
        }
        changes
    }
}

/// A scene's own motion, which plays along its walkthrough: an imported
/// model's node animation or a generated scene's script.
#[derive(Clone, Debug)]
pub enum OwnMotion {
    /// A glTF model's animations.
    Animation(SceneAnimation),
    /// A generated scene's vehicles, people and doors.
    Scripted(SceneMotion),
}

impl OwnMotion {
    /// The instances it moves or hides, sorted.
    pub fn moved(&self) -> Vec<u32> {
        match self {
            OwnMotion::Animation(a) => a.moved().collect(),
            OwnMotion::Scripted(s) => s.moved().collect(),
        }
    }

    /// The changes that put every instance it moves where it is at time
    /// `t` (seconds of the walkthrough), shown or hidden.
    pub fn changes_at(&self, t: f32) -> Vec<InstanceChange> {
        match self {
            OwnMotion::Animation(a) => a.changes_at(t),
            OwnMotion::Scripted(s) => s.changes_at(t),
        }
    }
}

impl From<SceneAnimation> for OwnMotion {
    fn from(animation: SceneAnimation) -> Self {
        OwnMotion::Animation(animation)
    }
}

/// Everything that moves a scene along its walkthrough: its own motion
/// ([`OwnMotion`]), which moves the instances it moves, and [`SceneMotion`]
/// of a share of the instances it does not.
#[derive(Clone, Debug)]
pub struct Motion {
    own: Option<OwnMotion>,
    scripted: SceneMotion,
}

impl Motion {
    /// `scene`'s own motion (if any) with scripted motion of `fraction` of
    /// its instances (from `seed`; the instances of its own motion are left
    /// to it). None when nothing moves.
    pub fn new(scene: &Scene, own: Option<OwnMotion>, fraction: f64, seed: u64) -> Option<Self> {
        let mut scripted = SceneMotion::new(scene, fraction, seed);
        if let Some(own) = &own {
            let moved = own.moved();
            scripted.tracks.retain(|t| moved.binary_search(&t.instance).is_err());
        }
        (own.is_some() || scripted.moving() > 0).then_some(Self { own, scripted })
    }

    /// The changes that put every moving instance where it is at time `t`
    /// (seconds of the walkthrough).
    pub fn changes_at(&self, t: f32) -> Vec<InstanceChange> {
        let mut changes = self.own.as_ref().map(|o| o.changes_at(t)).unwrap_or_default();
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
