//! Helpers shared by the scene generators: building walkthroughs and keeping
//! scattered objects clear of them.

use crate::motion::Track;
use glam::Vec3;
use occlude_core::{Aabb, CameraPath, Keyframe};

/// Vertical field of view of every default walkthrough, in degrees.
pub(crate) const FOV_Y_DEG: f32 = 60.0;

/// Eye height above a floor, in metres.
pub(crate) const EYE: f32 = 1.7;

/// Distance every walkthrough keeps from every object (the tests check 0.5 m;
/// generation keeps a little more so that sampling never decides it).
pub(crate) const CLEARANCE: f32 = 0.6;

/// Builds a walkthrough key by key, each key a given number of seconds after
/// the previous one, so that a path can walk slowly in a street and fly fast
/// over the roofs.
pub(crate) struct PathBuilder {
    keyframes: Vec<Keyframe>,
}

impl PathBuilder {
    /// An empty path.
    pub(crate) fn new() -> Self {
        Self { keyframes: Vec::new() }
    }

    /// Adds a key `seconds` after the previous one (the first key is at 0).
    pub(crate) fn key(&mut self, seconds: f32, position: Vec3, target: Vec3) -> &mut Self {
        let time = self.keyframes.last().map_or(0.0, |k| k.time + seconds);
        self.keyframes.push(Keyframe { time, position, target, fov_y_deg: FOV_Y_DEG });
        self
    }

    /// The finished path.
    pub(crate) fn build(&mut self) -> CameraPath {
        CameraPath { keyframes: std::mem::take(&mut self.keyframes) }
    }
}

/// Eye positions along `path`, `per_second` of them per second of walkthrough.
pub(crate) fn eye_positions(path: &CameraPath, per_second: f32) -> Vec<Vec3> {
    let count = (path.duration() * per_second).ceil() as usize + 1;
    path.sample(count, 1.0, 0.1, 1.0).into_iter().map(|c| c.position).collect()
}

/// Eye positions under boxes of 64 consecutive ones, each grown by
/// [`CLEARANCE`], so that the eyes near a box are found without testing
/// every one.
struct EyeGroups {
    eyes: Vec<Vec3>,
    boxes: Vec<Aabb>,
}

/// Eyes a group holds.
const GROUP: usize = 64;

impl EyeGroups {
    fn new(eyes: Vec<Vec3>) -> Self {
        let boxes = eyes.chunks(GROUP).map(|c| Aabb::from_points(c).expanded(0.0, CLEARANCE)).collect();
        Self { eyes, boxes }
    }

    /// Every eye that may come within [`CLEARANCE`] of `b`, with its index.
    fn near(&self, b: Aabb) -> impl Iterator<Item = (usize, Vec3)> + '_ {
        let groups = self.boxes.iter().enumerate().filter(move |(_, g)| g.overlaps(&b));
        groups.flat_map(move |(g, _)| {
            let first = g * GROUP;
            self.eyes[first..(first + GROUP).min(self.eyes.len())]
                .iter()
                .copied()
                .enumerate()
                .map(move |(i, e)| (first + i, e))
        })
    }
}

/// Answers "does this box keep [`CLEARANCE`] from the walkthrough?" quickly,
/// by grouping dense samples of the path under boxes.
pub(crate) struct PathClearance(EyeGroups);

impl PathClearance {
    /// Samples `path` densely (a few centimetres apart at walking and flying
    /// speeds).
    pub(crate) fn new(path: &CameraPath) -> Self {
        Self(EyeGroups::new(eye_positions(path, 400.0)))
    }

    /// True when every sampled eye position is at least [`CLEARANCE`] from `b`.
    pub(crate) fn is_clear(&self, b: &Aabb) -> bool {
        let limit = CLEARANCE * CLEARANCE;
        self.0.near(*b).all(|(_, p)| b.distance_squared(p) >= limit)
    }
}

/// Eye positions per second that [`EyeTimeline`] checks: four per frame at
/// `occlude bench`'s default 30 frames per second, whose frames are among
/// them.
const TIMELINE_RATE: f64 = 120.0;

/// The walkthrough's eye at evenly spaced times, grouped under boxes, to
/// keep moving instances clear of where the camera is when they are there.
pub(crate) struct EyeTimeline {
    /// The path's first key time.
    start: f32,
    /// Eye positions, one per `1 / TIMELINE_RATE` seconds from `start`.
    eyes: EyeGroups,
}

impl EyeTimeline {
    /// Samples `path` at [`TIMELINE_RATE`] from its first key to its last.
    pub(crate) fn new(path: &CameraPath) -> Self {
        let start = path.keyframes.first().map_or(0.0, |k| k.time);
        let count = (f64::from(path.duration()) * TIMELINE_RATE).floor() as usize + 1;
        let eyes = (0..count).filter_map(|k| path.at(Self::time(start, k))).map(|key| key.position).collect();
        Self { start, eyes: EyeGroups::new(eyes) }
    }

    /// The time of the `k`th eye, as the path's frame times are computed.
    fn time(start: f32, k: usize) -> f32 {
        start + (k as f64 / TIMELINE_RATE) as f32
    }

    /// True when the instance `track` moves, whose box is `bounds` at its
    /// base, keeps [`CLEARANCE`] from the eye at every sampled time at which
    /// it is shown.
    pub(crate) fn keeps_clear(&self, track: &Track, bounds: &Aabb) -> bool {
        let swept = track.swept(bounds);
        let limit = CLEARANCE * CLEARANCE;
        self.eyes.near(swept).all(|(k, eye)| {
            let t = Self::time(self.start, k);
            let d = track.displacement(t);
            track.is_hidden(t) || Aabb::new(bounds.min + d, bounds.max + d).distance_squared(eye) >= limit
        })
    }
}
