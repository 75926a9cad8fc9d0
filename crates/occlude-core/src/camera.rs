//! Perspective camera and its view frustum.
//!
//! Projection follows the wgpu convention: right-handed view space, clip-space
//! depth in `[0, 1]` (0 at the near plane), so the soft and wgpu backends agree.

use crate::geometry::Aabb;
use glam::{Mat4, Vec3, Vec4, Vec4Swizzles};
use serde::{Deserialize, Serialize};

/// A perspective camera looking from `position` towards `target`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    /// Eye position in world space.
    pub position: Vec3,
    /// Point the camera looks at.
    pub target: Vec3,
    /// World up direction (not necessarily orthogonal to the view direction).
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub fov_y_deg: f32,
    /// Width / height of the image.
    pub aspect: f32,
    /// Near clipping distance (> 0).
    pub near: f32,
    /// Far clipping distance (> near).
    pub far: f32,
}

impl Camera {
    /// World-to-view transform.
    pub fn view(&self) -> Mat4 {
        let up = if (self.target - self.position).cross(self.up).length_squared() < 1e-12 {
            // Looking straight along `up`: pick any other up so the basis exists.
            Vec3::Z
        } else {
            self.up
        };
        Mat4::look_at_rh(self.position, self.target, up)
    }

    /// View-to-clip transform (depth in `[0, 1]`).
    pub fn projection(&self) -> Mat4 {
        Mat4::perspective_rh(self.fov_y_deg.to_radians(), self.aspect, self.near, self.far)
    }

    /// World-to-clip transform.
    pub fn view_projection(&self) -> Mat4 {
        self.projection() * self.view()
    }

    /// The six clipping planes in world space.
    pub fn frustum(&self) -> Frustum {
        Frustum::from_view_projection(&self.view_projection())
    }

    /// Distance from the eye to a corner of the near-plane rectangle: every
    /// point that the near plane clips away inside the view lies within it.
    pub fn near_region_radius(&self) -> f32 {
        let half_h = self.near * (self.fov_y_deg.to_radians() * 0.5).tan();
        let half_w = half_h * self.aspect;
        (self.near * self.near + half_h * half_h + half_w * half_w).sqrt()
    }

    /// True when the box comes so close to the eye that the near plane may cut
    /// it inside the view. Such a box cannot be tested by rasterizing it (the
    /// camera may be inside), so every query treats it as visible. The radius
    /// has a 1% margin so that a box that does not touch lies clearly beyond
    /// the near plane, where a small depth bias cannot push it behind the eye.
    pub fn box_touches_near_region(&self, b: &Aabb) -> bool {
        let r = self.near_region_radius() * 1.01;
        b.distance_squared(self.position) <= r * r
    }
}

/// Result of classifying a box against the frustum.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Visibility {
    /// Entirely outside one plane.
    Outside,
    /// Crosses at least one plane.
    Intersecting,
    /// Inside all six planes.
    Inside,
}

/// Six planes `n·p + d >= 0` inside, extracted from a view-projection matrix
/// (Gribb and Hartmann's method for `[0, 1]` clip depth).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frustum {
    /// Left, right, bottom, top, near, far; each normalised.
    pub planes: [Vec4; 6],
}

impl Frustum {
    /// Planes of the clip volume of `m`.
    pub fn from_view_projection(m: &Mat4) -> Self {
        let r = [m.row(0), m.row(1), m.row(2), m.row(3)];
        let planes =
            [r[3] + r[0], r[3] - r[0], r[3] + r[1], r[3] - r[1], r[2], r[3] - r[2]].map(|p| p / p.xyz().length());
        Self { planes }
    }

    /// Classifies a box with the positive/negative vertex test.
    pub fn classify(&self, b: &Aabb) -> Visibility {
        let mut inside = true;
        for p in &self.planes {
            let n = p.xyz();
            let positive = Vec3::select(n.cmpge(Vec3::ZERO), b.max, b.min);
            if n.dot(positive) + p.w < 0.0 {
                return Visibility::Outside;
            }
            let negative = Vec3::select(n.cmpge(Vec3::ZERO), b.min, b.max);
            if n.dot(negative) + p.w < 0.0 {
                inside = false;
            }
        }
        if inside {
            Visibility::Inside
        } else {
            Visibility::Intersecting
        }
    }

    /// True unless the box is entirely outside a plane.
    pub fn intersects(&self, b: &Aabb) -> bool {
        self.classify(b) != Visibility::Outside
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn camera() -> Camera {
        Camera {
            position: Vec3::new(0.0, 1.0, 5.0),
            target: Vec3::new(0.3, 0.8, 0.0),
            up: Vec3::Y,
            fov_y_deg: 60.0,
            aspect: 4.0 / 3.0,
            near: 0.1,
            far: 100.0,
        }
    }

    fn in_clip(m: &Mat4, p: Vec3) -> bool {
        let c = *m * p.extend(1.0);
        c.x.abs() <= c.w && c.y.abs() <= c.w && c.z >= 0.0 && c.z <= c.w
    }

    proptest! {
        /// A box holding a point inside the clip volume is never culled, and a
        /// box culled as outside holds no point of the clip volume.
        #[test]
        fn frustum_is_conservative(
            x in -20.0f32..20.0, y in -20.0f32..20.0, z in -120.0f32..20.0,
            sx in 0.01f32..10.0, sy in 0.01f32..10.0, sz in 0.01f32..10.0,
        ) {
            let cam = camera();
            let vp = cam.view_projection();
            let b = Aabb::new(Vec3::new(x, y, z), Vec3::new(x + sx, y + sy, z + sz));
            let class = cam.frustum().classify(&b);
            let inside_corners = b.corners().iter().filter(|&&c| in_clip(&vp, c)).count();
            if inside_corners > 0 {
                prop_assert_ne!(class, Visibility::Outside);
            }
            if class == Visibility::Inside {
                prop_assert_eq!(inside_corners, 8);
            }
            // Sample points inside the box: none may be in the clip volume if culled.
            if class == Visibility::Outside {
                for i in 0..27 {
                    let t = Vec3::new((i % 3) as f32, ((i / 3) % 3) as f32, (i / 9) as f32) * 0.5;
                    let p = b.min + (b.max - b.min) * t;
                    let c = vp * p.extend(1.0);
                    // Points exactly on a plane may round either way.
                    let on_plane = (c.x.abs() - c.w).abs() < 1e-3 || (c.y.abs() - c.w).abs() < 1e-3;
                    prop_assert!(!in_clip(&vp, p) || on_plane);
                }
            }
        }

        /// Every point the near plane clips inside the view is within the near radius.
        #[test]
        fn near_region_holds_clipped_points(u in -1.0f32..1.0, v in -1.0f32..1.0, d in 0.0f32..1.0) {
            let cam = camera();
            let inv = cam.view_projection().inverse();
            let on_near = inv.project_point3(Vec3::new(u, v, 0.0));
            let p = cam.position + (on_near - cam.position) * d;
            prop_assert!(p.distance(cam.position) <= cam.near_region_radius() * 1.0001);
        }
    }

    #[test]
    fn box_around_eye_touches_near_region() {
        let cam = camera();
        let b = Aabb::new(cam.position - Vec3::ONE, cam.position + Vec3::ONE);
        assert!(cam.box_touches_near_region(&b));
        let far = Aabb::new(Vec3::new(-1.0, -1.0, -50.0), Vec3::new(1.0, 1.0, -48.0));
        assert!(!cam.box_touches_near_region(&far));
    }
}
