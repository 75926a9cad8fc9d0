//! Camera paths: keyframes with smooth (Catmull-Rom) interpolation, sampled
//! into frames ([`Sampling`]) so every method sees the same walkthrough.

use crate::camera::Camera;
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// One keyframe of a walkthrough.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Keyframe {
    /// Time in seconds (strictly increasing along a path).
    pub time: f32,
    /// Eye position.
    pub position: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Vertical field of view in degrees.
    pub fov_y_deg: f32,
}

impl Keyframe {
    /// The look-at camera of this keyframe (y up), with the given image
    /// aspect and clipping distances.
    pub fn camera(&self, aspect: f32, near: f32, far: f32) -> Camera {
        Camera {
            position: self.position,
            target: self.target,
            up: Vec3::Y,
            fov_y_deg: self.fov_y_deg,
            aspect,
            near,
            far,
            matrices: None,
        }
    }
}

/// A walkthrough: keyframes in time order.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CameraPath {
    /// The keyframes, sorted by time.
    pub keyframes: Vec<Keyframe>,
}

/// Catmull-Rom spline through `p1..p2` with neighbours `p0`, `p3`, at `t` in `[0, 1]`.
fn catmull_rom(p0: Vec3, p1: Vec3, p2: Vec3, p3: Vec3, t: f32) -> Vec3 {
    let t2 = t * t;
    let t3 = t2 * t;
    0.5 * ((2.0 * p1)
        + (p2 - p0) * t
        + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * t2
        + (3.0 * p1 - p0 - 3.0 * p2 + p3) * t3)
}

/// How a walkthrough is cut into frames.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Sampling {
    /// This many frames spread evenly over the whole path, its first and last
    /// keyframes included, however long the path.
    Spread(usize),
    /// One frame every `1 / fps` seconds of walkthrough time from the path's
    /// start to its end (as the papers render their walkthroughs, at a frame
    /// rate, so consecutive frames are as coherent as the motion allows),
    /// at most `limit` of them: the first ones.
    Rate {
        /// Frames per second of walkthrough time.
        fps: f32,
        /// The most frames taken from the start (`None`: the whole path).
        limit: Option<usize>,
    },
}

impl CameraPath {
    /// A path through the given keyframes, evenly spaced one second apart.
    pub fn through(points: impl IntoIterator<Item = (Vec3, Vec3)>, fov_y_deg: f32) -> Self {
        let keyframes = points
            .into_iter()
            .enumerate()
            .map(|(i, (position, target))| Keyframe { time: i as f32, position, target, fov_y_deg })
            .collect();
        Self { keyframes }
    }

    /// Duration from the first to the last keyframe.
    pub fn duration(&self) -> f32 {
        match (self.keyframes.first(), self.keyframes.last()) {
            (Some(a), Some(b)) => b.time - a.time,
            _ => 0.0,
        }
    }

    /// The interpolated keyframe at time `t` (clamped to the path).
    pub fn at(&self, t: f32) -> Option<Keyframe> {
        let k = &self.keyframes;
        let first = k.first()?;
        if k.len() == 1 || t <= first.time {
            return Some(*first);
        }
        let last = k.last()?;
        if t >= last.time {
            return Some(*last);
        }
        let i = k.partition_point(|f| f.time <= t).clamp(1, k.len() - 1) - 1;
        let (a, b) = (k[i], k[i + 1]);
        let p0 = k[i.saturating_sub(1)];
        let p3 = k[(i + 2).min(k.len() - 1)];
        let s = ((t - a.time) / (b.time - a.time).max(f32::EPSILON)).clamp(0.0, 1.0);
        Some(Keyframe {
            time: t,
            position: catmull_rom(p0.position, a.position, b.position, p3.position, s),
            target: catmull_rom(p0.target, a.target, b.target, p3.target, s),
            fov_y_deg: a.fov_y_deg + (b.fov_y_deg - a.fov_y_deg) * s,
        })
    }

    /// How many frames `sampling` takes of this path (0 without keyframes),
    /// computed without allocating them, so that a caller can bound a run
    /// before [`Self::frame_times`] makes them; a path too long to count
    /// gives `usize::MAX`.
    pub fn frame_count(&self, sampling: Sampling) -> usize {
        if self.keyframes.is_empty() {
            return 0;
        }
        match sampling {
            Sampling::Spread(frames) => frames,
            Sampling::Rate { fps, limit } => {
                // Every frame whose time lies on the path; the small margin
                // keeps a path of whole frames from losing its last one to
                // rounding. The float-to-integer cast saturates, the `+ 1`
                // must too.
                let whole = ((f64::from(self.duration()) * f64::from(fps) + 1e-6).floor() as usize).saturating_add(1);
                limit.map_or(whole, |l| l.min(whole))
            }
        }
    }

    /// The walkthrough times (seconds, from the first keyframe's) of the
    /// frames `sampling` asks for; empty for a path without keyframes.
    pub fn frame_times(&self, sampling: Sampling) -> Vec<f32> {
        let Some(start) = self.keyframes.first().map(|k| k.time) else { return Vec::new() };
        let span = self.duration();
        let count = self.frame_count(sampling);
        match sampling {
            Sampling::Spread(frames) => (0..count)
                .map(|f| if frames > 1 { start + span * f as f32 / (frames - 1) as f32 } else { start })
                .collect(),
            Sampling::Rate { fps, .. } => (0..count).map(|f| start + (f as f64 / f64::from(fps)) as f32).collect(),
        }
    }

    /// `frames` cameras evenly spaced in time over the whole path
    /// ([`Sampling::Spread`]).
    pub fn sample(&self, frames: usize, aspect: f32, near: f32, far: f32) -> Vec<Camera> {
        self.sample_with(Sampling::Spread(frames), aspect, near, far)
    }

    /// The cameras of the frames `sampling` asks for.
    pub fn sample_with(&self, sampling: Sampling, aspect: f32, near: f32, far: f32) -> Vec<Camera> {
        self.frame_times(sampling).into_iter().filter_map(|t| self.at(t)).map(|k| k.camera(aspect, near, far)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampling_hits_keyframes_at_ends_and_interpolates_between() {
        let path = CameraPath::through(
            [
                (Vec3::ZERO, Vec3::X),
                (Vec3::new(10.0, 0.0, 0.0), Vec3::X * 20.0),
                (Vec3::new(20.0, 0.0, 0.0), Vec3::X * 30.0),
            ],
            60.0,
        );
        let cams = path.sample(5, 1.0, 0.1, 100.0);
        assert_eq!(cams.len(), 5);
        assert_eq!(cams[0].position, Vec3::ZERO);
        assert_eq!(cams[4].position, Vec3::new(20.0, 0.0, 0.0));
        assert!((cams[2].position - Vec3::new(10.0, 0.0, 0.0)).length() < 1e-4);
        assert!(cams[1].position.x > 0.0 && cams[1].position.x < 10.0);
    }

    #[test]
    fn empty_path_samples_nothing() {
        assert!(CameraPath::default().sample(10, 1.0, 0.1, 1.0).is_empty());
        assert!(CameraPath::default().frame_times(Sampling::Rate { fps: 30.0, limit: None }).is_empty());
    }

    #[test]
    fn a_frame_rate_covers_the_whole_path_or_its_first_frames() {
        let mut path = CameraPath::through([(Vec3::ZERO, Vec3::X), (Vec3::X, Vec3::X * 2.0)], 60.0);
        path.keyframes[1].time = 2.0;
        let all = path.frame_times(Sampling::Rate { fps: 30.0, limit: None });
        // 2 s at 30 fps: frames at 0, 1/30, ..., 60/30 s.
        assert_eq!(all.len(), 61);
        assert_eq!(all[0], 0.0);
        assert!((all[1] - 1.0 / 30.0).abs() < 1e-7);
        assert_eq!(*all.last().unwrap(), 2.0);
        let first = path.frame_times(Sampling::Rate { fps: 30.0, limit: Some(10) });
        assert_eq!(first, all[..10]);
        // A limit past the path's end takes the whole path, no more.
        assert_eq!(path.frame_times(Sampling::Rate { fps: 30.0, limit: Some(1000) }), all);
        // A rate that does not divide the path stops at the last whole frame.
        let sparse = path.frame_times(Sampling::Rate { fps: 0.75, limit: None });
        assert_eq!(sparse, vec![0.0, 4.0 / 3.0]);
        let cams = path.sample_with(Sampling::Rate { fps: 30.0, limit: None }, 1.0, 0.1, 10.0);
        assert_eq!(cams.len(), 61);
        assert_eq!(cams[60].position, Vec3::X);
    }

    #[test]
    fn a_path_too_long_to_count_saturates_instead_of_wrapping() {
        let mut path = CameraPath::through([(Vec3::ZERO, Vec3::X), (Vec3::X, Vec3::X * 2.0)], 60.0);
        path.keyframes[1].time = 1e30;
        assert_eq!(path.frame_count(Sampling::Rate { fps: 30.0, limit: None }), usize::MAX);
        assert_eq!(path.frame_count(Sampling::Rate { fps: 30.0, limit: Some(5) }), 5);
        assert_eq!(path.frame_times(Sampling::Rate { fps: 30.0, limit: Some(5) }).len(), 5);
        assert_eq!(CameraPath::default().frame_count(Sampling::Spread(3)), 0);
    }
}
