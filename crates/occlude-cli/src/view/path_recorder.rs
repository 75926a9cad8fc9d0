//! Recording a fly-through as a camera path (key R): the fly camera's pose is
//! kept a few times a second and written as the JSON that
//! `occlude bench --camera-path` replays (the serde form of
//! [`CameraPath`]; its Catmull-Rom interpolation smooths between the poses).

use super::camera_control::FlyCamera;
use anyhow::{Context, Result};
use occlude_core::CameraPath;
use std::path::Path;

/// Seconds between two recorded poses.
pub const KEYFRAME_INTERVAL: f32 = 0.25;

/// A recording in progress.
#[derive(Clone, Debug, Default)]
pub struct PathRecorder {
    path: CameraPath,
    elapsed: f32,
}

impl PathRecorder {
    /// A recording that starts with `camera`'s pose at time 0.
    pub fn start(camera: &FlyCamera) -> Self {
        Self { path: CameraPath { keyframes: vec![camera.keyframe(0.0)] }, elapsed: 0.0 }
    }

    /// Lets `dt` seconds pass with the camera at `camera`; keeps its pose
    /// when [`KEYFRAME_INTERVAL`] has passed since the last kept one.
    pub fn sample(&mut self, camera: &FlyCamera, dt: f32) {
        self.elapsed += dt.max(0.0);
        let last = self.path.keyframes.last().map_or(f32::NEG_INFINITY, |k| k.time);
        if self.elapsed - last >= KEYFRAME_INTERVAL {
            self.path.keyframes.push(camera.keyframe(self.elapsed));
        }
    }

    /// Poses kept so far.
    pub fn keyframes(&self) -> usize {
        self.path.keyframes.len()
    }

    /// Ends the recording with `camera`'s final pose (when time passed since
    /// the last kept one): keyframe times strictly increase, as replaying
    /// requires.
    pub fn finish(mut self, camera: &FlyCamera) -> CameraPath {
        if self.path.keyframes.last().is_none_or(|k| self.elapsed > k.time) {
            self.path.keyframes.push(camera.keyframe(self.elapsed));
        }
        self.path
    }
}

/// Writes `path` as pretty JSON to `file`.
pub fn write(path: &CameraPath, file: &Path) -> Result<()> {
    let json = serde_json::to_string_pretty(path).context("encoding the camera path")?;
    std::fs::write(file, json + "\n").with_context(|| format!("cannot write camera path {}", file.display()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use occlude_bench::camera_path::load as load_camera_path;
    use occlude_core::Keyframe;

    #[test]
    fn a_recorded_flight_loads_as_a_bench_camera_path() {
        let start = Keyframe { time: 0.0, position: Vec3::new(0.0, 2.0, 0.0), target: Vec3::X, fov_y_deg: 60.0 };
        let mut fly = FlyCamera::from_keyframe(&start);
        let mut recorder = PathRecorder::start(&fly);
        for _ in 0..40 {
            fly.position.x += 0.1;
            fly.turn(3.0, 0.0);
            recorder.sample(&fly, 1.0 / 30.0);
        }
        assert!(recorder.keyframes() >= 5, "{} keyframes in 1.3 s", recorder.keyframes());
        let path = recorder.finish(&fly);
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("flight.json");
        write(&path, &file).unwrap();
        let loaded = load_camera_path(&file).unwrap();
        assert_eq!(loaded, path);
        assert_eq!(loaded.keyframes.first().unwrap().position, start.position);
        let last = loaded.keyframes.last().unwrap();
        assert!((last.position - fly.position).length() < 1e-6);
        assert!((last.time - 40.0 / 30.0).abs() < 1e-4, "{}", last.time);
    }

    #[test]
    fn a_recording_without_time_is_one_keyframe() {
        let fly = FlyCamera::from_keyframe(&Keyframe {
            time: 0.0,
            position: Vec3::ZERO,
            target: Vec3::NEG_Z,
            fov_y_deg: 60.0,
        });
        assert_eq!(PathRecorder::start(&fly).finish(&fly).keyframes.len(), 1);
    }
}
