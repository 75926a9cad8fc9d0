//! The viewer's two ways of moving the camera: a fly camera a person steers
//! (position, heading and pitch), and playback of the scene's walkthrough in
//! real time.

use glam::Vec3;
use occlude_core::{Camera, CameraPath, Keyframe};

/// Radians the view turns per pixel the mouse moves.
const TURN_PER_PIXEL: f32 = 0.003;

/// Steepest pitch up or down (just short of vertical, where heading is lost).
const MAX_PITCH: f32 = 1.55;

/// Speed factor while Shift is held.
const FAST: f32 = 4.0;

/// Field of view when neither the path nor the person chose one.
pub const DEFAULT_FOV_Y_DEG: f32 = 60.0;

/// A camera a person flies: where it is and where it looks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlyCamera {
    /// Eye position.
    pub position: Vec3,
    /// Heading in radians: 0 looks along -z, positive turns towards +x.
    pub yaw: f32,
    /// Radians above the horizon.
    pub pitch: f32,
    /// Vertical field of view in degrees.
    pub fov_y_deg: f32,
}

/// Which way the held keys push the camera this frame: each axis -1, 0 or 1
/// (or in between), in the camera's own frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Movement {
    /// Forward (W) minus backward (S).
    pub forward: f32,
    /// Right (D) minus left (A).
    pub right: f32,
    /// Up (E, Space) minus down (Q, Ctrl), along world up.
    pub up: f32,
    /// Shift held: move [`FAST`] times quicker.
    pub fast: bool,
}

impl FlyCamera {
    /// A camera at a keyframe's position looking at its target.
    pub fn from_keyframe(k: &Keyframe) -> Self {
        let d = (k.target - k.position).normalize_or(Vec3::NEG_Z);
        Self {
            position: k.position,
            yaw: d.x.atan2(-d.z),
            pitch: d.y.clamp(-1.0, 1.0).asin().clamp(-MAX_PITCH, MAX_PITCH),
            fov_y_deg: k.fov_y_deg,
        }
    }

    /// Unit view direction.
    pub fn forward(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        Vec3::new(sy * cp, sp, -cy * cp)
    }

    /// Unit direction to the right of the view, horizontal.
    pub fn right(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        Vec3::new(cy, 0.0, sy)
    }

    /// Turns the view by a mouse motion of `dx`, `dy` pixels (right and down
    /// positive): right turns right, down looks down.
    pub fn turn(&mut self, dx: f32, dy: f32) {
        self.yaw = (self.yaw + dx * TURN_PER_PIXEL).rem_euclid(std::f32::consts::TAU);
        self.pitch = (self.pitch - dy * TURN_PER_PIXEL).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Moves for `dt` seconds at `speed` metres per second as `movement`
    /// says (forward follows the view, pitch included: flying, not walking).
    pub fn step(&mut self, movement: &Movement, speed: f32, dt: f32) {
        let dir = self.forward() * movement.forward + self.right() * movement.right + Vec3::Y * movement.up;
        let factor = if movement.fast { FAST } else { 1.0 };
        self.position += dir.normalize_or_zero() * speed * factor * dt;
    }

    /// The camera's pose as a keyframe at `time` (target one metre ahead).
    pub fn keyframe(&self, time: f32) -> Keyframe {
        Keyframe { time, position: self.position, target: self.position + self.forward(), fov_y_deg: self.fov_y_deg }
    }

    /// The camera for an image of aspect ratio `aspect`.
    pub fn camera(&self, aspect: f32, near: f32, far: f32) -> Camera {
        self.keyframe(0.0).camera(aspect, near, far)
    }
}

/// Playing a walkthrough: seconds since the path's first keyframe.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Playback {
    /// Seconds played.
    pub elapsed: f32,
}

impl Playback {
    /// Advances by `dt` seconds of real time, starting over at the path's end.
    pub fn advance(&mut self, path: &CameraPath, dt: f32) {
        let duration = path.duration();
        self.elapsed = if duration > 0.0 { (self.elapsed + dt) % duration } else { 0.0 };
    }

    /// Frame `k` of `frames` sampled evenly over the whole path, first and
    /// last keyframes included (as `CameraPath::sample` spreads them).
    pub fn sampled(path: &CameraPath, k: usize, frames: usize) -> Self {
        let elapsed = if frames > 1 { path.duration() * k as f32 / (frames - 1) as f32 } else { 0.0 };
        Self { elapsed }
    }

    /// The path's pose now, or `None` for a path without keyframes.
    pub fn keyframe(&self, path: &CameraPath) -> Option<Keyframe> {
        let start = path.keyframes.first()?.time;
        path.at(start + self.elapsed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn keyframe(position: Vec3, target: Vec3) -> Keyframe {
        Keyframe { time: 0.0, position, target, fov_y_deg: 50.0 }
    }

    #[test]
    fn a_keyframe_round_trips_through_the_fly_camera() {
        let k = keyframe(Vec3::new(1.0, 2.0, 3.0), Vec3::new(4.0, 1.0, -2.0));
        let fly = FlyCamera::from_keyframe(&k);
        let back = fly.keyframe(0.0);
        let want = (k.target - k.position).normalize();
        assert!((back.target - back.position - want).length() < 1e-5, "{back:?}");
        assert_eq!(back.fov_y_deg, 50.0);
    }

    #[test]
    fn keys_move_in_the_camera_frame() {
        let mut fly = FlyCamera::from_keyframe(&keyframe(Vec3::ZERO, Vec3::X));
        assert!((fly.right() - Vec3::Z).length() < 1e-6, "looking along +x, right is +z");
        fly.step(&Movement { forward: 1.0, ..Movement::default() }, 2.0, 0.5);
        assert!((fly.position - Vec3::X).length() < 1e-5, "{:?}", fly.position);
        fly.step(&Movement { up: 1.0, fast: true, ..Movement::default() }, 1.0, 0.5);
        assert!((fly.position - Vec3::new(1.0, 2.0, 0.0)).length() < 1e-5, "{:?}", fly.position);
    }

    #[test]
    fn turning_right_and_down_and_pitch_is_clamped() {
        let mut fly = FlyCamera::from_keyframe(&keyframe(Vec3::ZERO, Vec3::NEG_Z));
        fly.turn(100.0, 0.0);
        assert!(fly.forward().x > 0.0, "mouse right turns right");
        fly.turn(0.0, 100.0);
        assert!(fly.forward().y < 0.0, "mouse down looks down");
        fly.turn(0.0, 1e6);
        assert_eq!(fly.pitch, -MAX_PITCH);
    }

    #[test]
    fn playback_loops_and_samples_like_bench() {
        let path = CameraPath::through([(Vec3::ZERO, Vec3::X), (Vec3::X * 10.0, Vec3::X * 20.0)], 60.0);
        let mut p = Playback::default();
        p.advance(&path, 0.25);
        assert!((p.keyframe(&path).unwrap().position.x - 2.5).abs() < 0.5);
        p.advance(&path, 1.0);
        assert!((p.elapsed - 0.25).abs() < 1e-6, "loops at the end: {}", p.elapsed);
        let cams = path.sample(5, 1.0, 0.1, 100.0);
        for (k, cam) in cams.iter().enumerate() {
            let sampled = Playback::sampled(&path, k, 5).keyframe(&path).unwrap();
            assert_eq!(sampled.position, cam.position);
        }
        assert!(Playback::default().keyframe(&CameraPath::default()).is_none());
    }
}
