//! The flying camera: a position, a heading and a pitch, started at a
//! keyframe of the scene's walkthrough, steered by keys and the mouse.

use glam::{Mat4, Vec3};
use occlude::{Aabb, Keyframe};

/// Steepest pitch up or down, short of vertical (where heading is lost).
const MAX_PITCH: f32 = 1.55;
/// Nearest depth drawn, metres.
pub const NEAR: f32 = 0.1;

/// A camera a person flies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fly {
    /// Eye position.
    pub position: Vec3,
    /// Heading in radians: 0 looks along -z, positive turns towards +x.
    pub yaw: f32,
    /// Radians above the horizon.
    pub pitch: f32,
    /// Vertical field of view, degrees.
    pub fov_y_deg: f32,
}

impl Fly {
    /// At `k`'s position, looking at its target.
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

    /// Turns `right` and `up` radians.
    pub fn turn(&mut self, right: f32, up: f32) {
        self.yaw = (self.yaw + right).rem_euclid(std::f32::consts::TAU);
        self.pitch = (self.pitch + up).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Moves `forward`, `right` and `up` metres in the camera's frame (up
    /// along world up).
    pub fn step(&mut self, forward: f32, right: f32, up: f32) {
        let (sy, cy) = self.yaw.sin_cos();
        self.position += self.forward() * forward + Vec3::new(cy, 0.0, sy) * right + Vec3::Y * up;
    }

    /// World-to-view transform.
    pub fn view(&self) -> Mat4 {
        Mat4::look_to_rh(self.position, self.forward(), Vec3::Y)
    }

    /// View-to-clip transform for an image of `aspect` (width / height)
    /// showing all of `bounds`: depth 0 at [`NEAR`], 1 beyond the scene's
    /// far side.
    pub fn projection(&self, aspect: f32, bounds: &Aabb) -> Mat4 {
        let far = self.position.distance(bounds.center()) + bounds.extent().length() + NEAR;
        Mat4::perspective_rh(self.fov_y_deg.to_radians(), aspect, NEAR, far)
    }
}
