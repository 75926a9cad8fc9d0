//! Camera paths read from JSON files (`--camera-path`) and the walkthrough
//! frames made from any path, checked so that every frame is a camera that
//! can render: bounded times, finite positions within the coordinates
//! imported models may use, a target apart from the position and a field of
//! view that is neither a sliver nor a half-space.

use crate::error::{invalid, Error, Result};
use crate::limits::MAX_FRAMES;
use occlude_core::{Camera, CameraPath, Keyframe, Sampling};
use occlude_scenes::import::MAX_COORDINATE;
use std::path::Path;

/// The largest camera-path file read, bytes (some 300,000 keyframes).
pub const MAX_FILE_BYTES: u64 = 64 << 20;

/// The latest keyframe time, seconds either side of 0 (27.8 hours): times
/// are 32-bit floats, which still tell frames of 1000 fps apart there.
pub const MAX_TIME: f32 = 1e5;

/// The smallest distance from a camera to its target, metres: below it the
/// view direction is lost to rounding.
pub const MIN_TARGET_DISTANCE: f32 = 1e-3;

/// The narrowest and widest vertical field of view, degrees.
pub const FOV_RANGE: (f32, f32) = (0.01, 179.0);

/// A walkthrough that cannot be run as asked: more frames than a run takes,
/// or a frame whose camera cannot render. The user's input (the camera path,
/// `--frames`, `--fps`), so the command line exits with code 2.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct UnusableWalkthrough(String);

/// Reads a walkthrough from a JSON file of camera keyframes (see [`parse`]);
/// only a regular file of at most [`MAX_FILE_BYTES`] is read.
pub fn load(path: &Path) -> Result<CameraPath> {
    let text = occlude_core::input_file::read_text(path, MAX_FILE_BYTES)
        .map_err(|source| Error::Io { context: format!("cannot read camera path {}", path.display()), source })?;
    parse(&text, &path.display().to_string())
}

/// Parses a walkthrough,
/// `{"keyframes":[{"time":0,"position":[x,y,z],"target":[x,y,z],"fov_y_deg":60}, ...]}`
/// (the serde form of [`CameraPath`]; a leading byte-order mark is
/// ignored), and checks that it can be replayed: at least one keyframe,
/// each as [`check_keyframe`] asks, times strictly increasing. `name` names
/// the file in errors.
pub fn parse(text: &str, name: &str) -> Result<CameraPath> {
    let camera_path: CameraPath =
        serde_json::from_str(occlude_core::input_file::strip_bom(text)).map_err(|source| Error::Json {
            context: format!("{name} is not a camera path (JSON of keyframes)"),
            source,
        })?;
    if camera_path.keyframes.is_empty() {
        invalid!("camera path {name} has no keyframes");
    }
    for (i, k) in camera_path.keyframes.iter().enumerate() {
        check_keyframe(k).map_err(|e| Error::Invalid(format!("camera path {name}: keyframe {i}: {e}")))?;
        if i > 0 && k.time <= camera_path.keyframes[i - 1].time {
            invalid!(
                "camera path {name}: keyframe {i} (time {}) is not later than the one before (times are read as \
                 32-bit floats, about 7 significant digits)",
                k.time
            );
        }
    }
    Ok(camera_path)
}

/// Checks one keyframe: a time within ±[`MAX_TIME`] s, a position and a
/// target within ±[`MAX_COORDINATE`] m, at least [`MIN_TARGET_DISTANCE`]
/// apart, and a field of view within [`FOV_RANGE`].
pub fn check_keyframe(k: &Keyframe) -> Result<(), String> {
    if !(-MAX_TIME..=MAX_TIME).contains(&k.time) {
        return Err(format!("time {} is out of range: expected -{MAX_TIME:e} to {MAX_TIME:e} s", k.time));
    }
    for (what, p) in [("position", k.position), ("target", k.target)] {
        if !p.is_finite() || p.abs().max_element() > MAX_COORDINATE {
            return Err(format!(
                "{what} {p} is out of range: each coordinate must be finite, within ±{MAX_COORDINATE:e} m"
            ));
        }
    }
    check_view(k.position.distance(k.target), k.fov_y_deg)
}

/// Checks a camera's distance to its target and its field of view.
fn check_view(distance: f32, fov_y_deg: f32) -> Result<(), String> {
    if distance.is_nan() || distance < MIN_TARGET_DISTANCE {
        return Err(format!(
            "the target is {} m from the position: it must be at least {MIN_TARGET_DISTANCE} m away",
            if distance == 0.0 { "0".to_string() } else { format!("{distance:e}") }
        ));
    }
    let (low, high) = FOV_RANGE;
    if !(low..=high).contains(&fov_y_deg) {
        return Err(format!("fov_y_deg {fov_y_deg} is out of range: expected {low} to {high} degrees"));
    }
    Ok(())
}

/// The cameras of `path`'s frames as `sampling` takes them (see
/// `CameraPath::sample_with`), refused when there are more than
/// [`MAX_FRAMES`] (counted before any is made) or when a frame's camera
/// cannot render: the interpolated path passes through its target, or so
/// close that the view direction is lost.
pub fn cameras(
    path: &CameraPath,
    sampling: Sampling,
    aspect: f32,
    near: f32,
    far: f32,
) -> Result<Vec<Camera>, UnusableWalkthrough> {
    let count = path.frame_count(sampling);
    if count > MAX_FRAMES {
        let count = if count == usize::MAX { "too many".to_string() } else { count.to_string() };
        return Err(UnusableWalkthrough(format!(
            "the walkthrough ({} s) has {count} frames at this frame rate, more than the {MAX_FRAMES} a run takes: \
             pass --frames N (at most {MAX_FRAMES}) or a lower --fps",
            path.duration()
        )));
    }
    let cameras = path.sample_with(sampling, aspect, near, far);
    for (k, camera) in cameras.iter().enumerate() {
        check_view(camera.position.distance(camera.target), camera.fov_y_deg).map_err(|e| {
            UnusableWalkthrough(format!(
                "frame {k} of the walkthrough: {e} (the camera path passes through its target there)"
            ))
        })?;
    }
    Ok(cameras)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn keyframes(json: &str) -> String {
        format!("{{\"keyframes\":[{json}]}}")
    }

    const GOOD: &str = r#"{"time":0,"position":[0,0,0],"target":[0,0,-1],"fov_y_deg":60}"#;

    /// Every value of a keyframe out of its range is refused, naming it and
    /// the range; a byte-order mark is not.
    #[test]
    fn a_keyframe_out_of_range_is_refused_naming_the_value() {
        parse(&keyframes(GOOD), "p.json").unwrap();
        parse(&format!("\u{feff}{}", keyframes(GOOD)), "p.json").unwrap();
        let cases = [
            (GOOD.replace("\"time\":0", "\"time\":1e8"), "time 100000000"),
            (GOOD.replace("[0,0,0]", "[1e30,0,0]"), "position"),
            (GOOD.replace("[0,0,-1]", "[0,0,1e-30]"), "at least 0.001 m"),
            (GOOD.replace("60}", "1e-40}"), "fov_y_deg"),
            (GOOD.replace("60}", "180}"), "0.01 to 179"),
        ];
        for (keyframe, names) in cases {
            let e = parse(&keyframes(&keyframe), "p.json").unwrap_err().to_string();
            assert!(e.contains("p.json: keyframe 0") && e.contains(names), "{e}");
        }
        let same = GOOD.replace("\"time\":0", "\"time\":1e4");
        let next = GOOD.replace("\"time\":0", "\"time\":10000.0001");
        let e = parse(&keyframes(&format!("{same},{next}")), "p.json").unwrap_err().to_string();
        assert!(e.contains("keyframe 1") && e.contains("not later") && e.contains("32-bit"), "{e}");
    }

    /// A walkthrough is refused before it is sampled when it has more frames
    /// than a run takes, and when a frame's camera sits on its target.
    #[test]
    fn frames_are_bounded_and_each_can_render() {
        let mut path = CameraPath::through([(Vec3::ZERO, Vec3::X), (Vec3::X * 2.0, Vec3::X * 3.0)], 60.0);
        path.keyframes[1].time = MAX_TIME;
        let all = Sampling::Rate { fps: 1000.0, limit: None };
        let e = cameras(&path, all, 1.0, 0.1, 10.0).unwrap_err().to_string();
        assert!(e.contains("100000001 frames") && e.contains("--frames"), "{e}");
        path.keyframes[1].time = 1e30;
        assert!(cameras(&path, all, 1.0, 0.1, 10.0).unwrap_err().to_string().contains("too many frames"));
        let first = Sampling::Rate { fps: 1000.0, limit: Some(3) };
        assert_eq!(cameras(&path, first, 1.0, 0.1, 10.0).unwrap().len(), 3);
        // Position and target swap places: halfway, the camera is on its target.
        let through = CameraPath::through([(Vec3::ZERO, Vec3::X), (Vec3::X, Vec3::ZERO)], 60.0);
        let e = cameras(&through, Sampling::Spread(3), 1.0, 0.1, 10.0).unwrap_err().to_string();
        assert!(e.contains("frame 1") && e.contains("passes through its target"), "{e}");
    }
}
