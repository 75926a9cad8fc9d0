//! The camera and its view frustum.
//!
//! A camera is either look-at with a perspective projection (its fields) or
//! any view and projection matrix ([`Camera::from_matrices`]: reverse-Z,
//! infinite far, orthographic), whose frustum planes and near region are
//! derived from the matrices. Either way the backends rasterize
//! [`Camera::view_projection`], in the wgpu convention: clip-space depth in
//! `[0, 1]`, 0 nearest, so the soft and wgpu backends agree.

use crate::geometry::Aabb;
use glam::{Mat4, Vec3, Vec4, Vec4Swizzles};
use serde::{Deserialize, Serialize};

/// A camera looking from `position` towards `target`: perspective from its
/// fields, or the matrices it was made from ([`Camera::from_matrices`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    /// Eye position in world space.
    pub position: Vec3,
    /// Point the camera looks at.
    pub target: Vec3,
    /// World up direction (not necessarily orthogonal to the view direction).
    pub up: Vec3,
    /// Vertical field of view in degrees (0 for an orthographic camera).
    pub fov_y_deg: f32,
    /// Width / height of the image.
    pub aspect: f32,
    /// Near clipping distance along the view direction (> 0, except for an
    /// orthographic camera, whose near plane may lie behind `position`).
    pub near: f32,
    /// Far clipping distance (> near).
    pub far: f32,
    /// The view and projection of a camera made by [`Camera::from_matrices`]
    /// (the fields above are then derived from them); `None` for a look-at
    /// camera, whose matrices come from the fields.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub matrices: Option<CameraMatrices>,
}

/// A view and a projection matrix as a renderer gives them.
///
/// View space is right-handed, looking along -Z (as `Mat4::look_at_rh`
/// makes it); clip-space depth is in `[0, 1]` (wgpu's convention), either
/// 0 nearest or, for a reverse-Z projection, 1 nearest. The projection may be
/// perspective with a finite or infinite far plane, or orthographic.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct CameraMatrices {
    /// World-to-view transform.
    pub view: Mat4,
    /// View-to-clip transform.
    pub projection: Mat4,
    /// True when clip depth 1 is nearest (reverse-Z).
    pub reverse_z: bool,
}

/// Why [`Camera::from_matrices`] refused a pair of matrices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum CameraError {
    /// A matrix holds a NaN or an infinity.
    #[error("the {0} matrix is not finite")]
    NotFinite(&'static str),
    /// A matrix cannot be inverted (it flattens space).
    #[error("the {0} matrix is singular")]
    Singular(&'static str),
    /// The projection's near plane is not ahead of the eye (along -Z in view
    /// space) and before its far plane: a forward-Z projection said to be
    /// reverse-Z, or the other way round, or one looking along +Z.
    #[error("the projection's near plane is not ahead of the eye and before its far plane (view space looks along -Z; is reverse_z right?)")]
    NearPlane,
}

/// A sphere holding the near plane's rectangle (and, centred on the eye of a
/// perspective camera, everything between the eye and it). A box reaching
/// into it may lose the faces that face the camera to near-plane clipping,
/// so a query cannot test it: it is visible without a test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NearRegion {
    /// The sphere's centre: the eye of a perspective camera, the centre of the
    /// near rectangle of an orthographic one.
    pub center: Vec3,
    /// The sphere's radius, with the 1% margin of
    /// [`Camera::box_touches_near_region`].
    pub radius: f32,
}

/// The margin on the near region's radius: a box that does not touch the
/// region lies clearly beyond the near plane, where a small depth bias cannot
/// push it behind the eye.
const NEAR_REGION_MARGIN: f32 = 1.01;

/// Maps reverse-Z clip depth to forward (`z' = w - z`): the depth order the
/// backends' `Less` test and clear to 1 expect.
const FLIP_DEPTH: Mat4 =
    Mat4::from_cols(Vec4::X, Vec4::Y, Vec4::new(0.0, 0.0, -1.0, 0.0), Vec4::new(0.0, 0.0, 1.0, 1.0));

impl Camera {
    /// A camera of any view and projection matrix (see [`CameraMatrices`]
    /// for the conventions). Its fields are derived from the matrices: the
    /// eye and the directions from the view, the aspect from the projection's
    /// scales, the field of view (0 for an orthographic projection), and
    /// `near` and `far` as distances along the view direction (`far` infinite
    /// for an infinite far plane). Matrices that are not finite or not
    /// invertible, or whose near plane is not ahead of the eye, are refused.
    ///
    /// ```
    /// use glam::{Mat4, Vec3};
    /// use occlude_core::{Aabb, Camera, CameraError, Visibility};
    ///
    /// // A renderer's reverse-Z camera with an infinite far plane.
    /// let view = Mat4::look_at_rh(Vec3::new(0.0, 2.0, 10.0), Vec3::ZERO, Vec3::Y);
    /// let projection = Mat4::perspective_infinite_reverse_rh(1.0, 16.0 / 9.0, 0.1);
    /// let camera = Camera::from_matrices(view, projection, true)?;
    /// assert_eq!(camera.near, 0.1);
    /// assert!(camera.far.is_infinite());
    ///
    /// // Its frustum: a box ahead is in view however far, one behind is not.
    /// let ahead = Aabb::new(Vec3::new(-1.0, -1.0, -1e6), Vec3::new(1.0, 1.0, -1e6 + 1.0));
    /// let behind = Aabb::new(Vec3::new(-1.0, -1.0, 20.0), Vec3::new(1.0, 1.0, 21.0));
    /// assert_ne!(camera.frustum().classify(&ahead), Visibility::Outside);
    /// assert_eq!(camera.frustum().classify(&behind), Visibility::Outside);
    ///
    /// // The same projection said to be forward-Z is refused.
    /// assert_eq!(Camera::from_matrices(view, projection, false), Err(CameraError::NearPlane));
    /// # Ok::<(), CameraError>(())
    /// ```
    pub fn from_matrices(view: Mat4, projection: Mat4, reverse_z: bool) -> Result<Self, CameraError> {
        for (name, m) in [("view", &view), ("projection", &projection)] {
            if !m.is_finite() {
                return Err(CameraError::NotFinite(name));
            }
            let det = m.determinant();
            if det == 0.0 || !det.is_finite() {
                return Err(CameraError::Singular(name));
            }
        }
        let to_world = view.inverse();
        let position = to_world.transform_point3(Vec3::ZERO);
        let forward = to_world.transform_vector3(Vec3::NEG_Z).normalize();
        let up = to_world.transform_vector3(Vec3::Y).normalize();
        let matrices = CameraMatrices { view, projection, reverse_z };
        let (near_z, far_z) = if reverse_z { (1.0, 0.0) } else { (0.0, 1.0) };
        // The distance d along -Z in view space at which the view axis
        // reaches clip depth t: z(d) / w(d) = t solved for d (infinite where
        // the depth is reached only at infinity).
        let p = &projection;
        let depth_at = |t: f32| (p.w_axis.z - t * p.w_axis.w) / (p.z_axis.z - t * p.z_axis.w);
        let near = depth_at(near_z);
        let far = match depth_at(far_z) {
            f if f.is_infinite() => f32::INFINITY,
            f => f,
        };
        if near.is_nan() || near >= far || (is_perspective(p) && near <= 0.0) {
            return Err(CameraError::NearPlane);
        }
        let fov_y_deg = if is_perspective(&projection) {
            (2.0 * (1.0 / projection.y_axis.y).atan()).to_degrees().abs()
        } else {
            0.0
        };
        Ok(Camera {
            position,
            target: position + forward,
            up,
            fov_y_deg,
            aspect: (projection.y_axis.y / projection.x_axis.x).abs(),
            near,
            far,
            matrices: Some(matrices),
        })
    }

    /// World-to-view transform.
    pub fn view(&self) -> Mat4 {
        if let Some(m) = &self.matrices {
            return m.view;
        }
        let up = if (self.target - self.position).cross(self.up).length_squared() < 1e-12 {
            // Looking straight along `up`: pick any other up so the basis exists.
            Vec3::Z
        } else {
            self.up
        };
        Mat4::look_at_rh(self.position, self.target, up)
    }

    /// View-to-clip transform: the matrix given to
    /// [`Camera::from_matrices`], else perspective with depth in `[0, 1]`,
    /// 0 at the near plane.
    pub fn projection(&self) -> Mat4 {
        match &self.matrices {
            Some(m) => m.projection,
            None => Mat4::perspective_rh(self.fov_y_deg.to_radians(), self.aspect, self.near, self.far),
        }
    }

    /// World-to-clip transform as the backends rasterize it: depth in
    /// `[0, 1]`, 0 nearest (a reverse-Z projection's depth flipped, so that
    /// every backend keeps one depth test).
    pub fn view_projection(&self) -> Mat4 {
        match &self.matrices {
            Some(m) if m.reverse_z => FLIP_DEPTH * m.projection * m.view,
            _ => self.projection() * self.view(),
        }
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

    /// The sphere of [`Camera::box_touches_near_region`]. For a look-at
    /// camera: around the eye, [`Camera::near_region_radius`] with the
    /// margin. From matrices: around the eye of a perspective projection
    /// (the centre of projection), or the near rectangle's centre of an
    /// orthographic one, out to the farthest corner of the near rectangle
    /// (unprojected from clip space) with the margin.
    pub fn near_region(&self) -> NearRegion {
        let Some(m) = &self.matrices else {
            return NearRegion { center: self.position, radius: self.near_region_radius() * NEAR_REGION_MARGIN };
        };
        let to_world = self.view_projection().inverse();
        let corners = [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)]
            .map(|(x, y)| to_world.project_point3(Vec3::new(x, y, 0.0)));
        let center = if is_perspective(&m.projection) {
            // The centre of projection: the point clip space sends to w = 0
            // with x = y = 0.
            let eye = to_world * Vec4::Z;
            eye.xyz() / eye.w
        } else {
            corners.iter().sum::<Vec3>() * 0.25
        };
        let radius = corners.iter().map(|c| c.distance(center)).fold(0.0, f32::max);
        NearRegion { center, radius: radius * NEAR_REGION_MARGIN }
    }

    /// True when the box comes so close to the eye that the near plane may cut
    /// it inside the view. Such a box cannot be tested by rasterizing it (the
    /// camera may be inside), so every query treats it as visible. The radius
    /// has a margin ([`NearRegion`]).
    pub fn box_touches_near_region(&self, b: &Aabb) -> bool {
        let region = self.near_region();
        b.distance_squared(region.center) <= region.radius * region.radius
    }
}

/// True for a perspective projection (clip w depends on view depth), false
/// for an orthographic one.
fn is_perspective(projection: &Mat4) -> bool {
    projection.z_axis.w != 0.0
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
    /// Left, right, bottom, top, near, far; each normalised. The far plane of
    /// an infinite projection, which every point passes, is `(0, 0, 0, 1)`.
    pub planes: [Vec4; 6],
}

impl Frustum {
    /// Planes of the clip volume of `m`.
    pub fn from_view_projection(m: &Mat4) -> Self {
        let r = [m.row(0), m.row(1), m.row(2), m.row(3)];
        let planes = [r[3] + r[0], r[3] - r[0], r[3] + r[1], r[3] - r[1], r[2], r[3] - r[2]].map(|p| {
            let n = p.xyz().length();
            // A plane without a normal holds everywhere or nowhere; only an
            // infinite far plane (every point inside) comes out that way.
            if n > 0.0 {
                p / n
            } else {
                Vec4::W
            }
        });
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
            matrices: None,
        }
    }

    fn in_clip(m: &Mat4, p: Vec3) -> bool {
        in_clip_within(m, p, 0.0)
    }

    /// Whether `p` lies in the clip volume grown by `eps` of its `w` on
    /// every side: a point on a plane rounds to either side of it.
    fn in_clip_within(m: &Mat4, p: Vec3, eps: f32) -> bool {
        let c = *m * p.extend(1.0);
        let e = eps * c.w.abs();
        c.x.abs() <= c.w + e && c.y.abs() <= c.w + e && c.z >= -e && c.z <= c.w + e
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
            // Inside only spares the plane tests below a node (drawing more
            // stays conservative): a corner on a plane may round out.
            if class == Visibility::Inside {
                prop_assert!(b.corners().iter().all(|&c| in_clip_within(&vp, c, 1e-4)));
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

    /// The projection kinds a renderer may give, as (name, projection,
    /// reverse-Z), for a 4:3 image.
    fn projections() -> Vec<(&'static str, Mat4, bool)> {
        let (fov, aspect) = (1.0, 4.0 / 3.0);
        vec![
            ("perspective", Mat4::perspective_rh(fov, aspect, 0.1, 100.0), false),
            ("perspective reverse-Z", Mat4::perspective_rh(fov, aspect, 100.0, 0.1), true),
            ("infinite far", Mat4::perspective_infinite_rh(fov, aspect, 0.1), false),
            ("infinite far reverse-Z", Mat4::perspective_infinite_reverse_rh(fov, aspect, 0.1), true),
            ("orthographic", Mat4::orthographic_rh(-8.0, 8.0, -6.0, 6.0, 0.5, 60.0), false),
            ("orthographic reverse-Z", Mat4::orthographic_rh(-8.0, 8.0, -6.0, 6.0, 60.0, 0.5), true),
            ("orthographic, near behind the eye", Mat4::orthographic_rh(-8.0, 8.0, -6.0, 6.0, -20.0, 60.0), false),
        ]
    }

    /// A camera of each projection kind, looking from `eye` at `target`.
    fn cameras_from_matrices(eye: Vec3, target: Vec3) -> Vec<(&'static str, Camera, Mat4)> {
        let view = Mat4::look_at_rh(eye, target, Vec3::Y);
        projections()
            .into_iter()
            .map(|(name, p, reverse)| {
                let cam = Camera::from_matrices(view, p, reverse).unwrap_or_else(|e| panic!("{name}: {e}"));
                (name, cam, p * view)
            })
            .collect()
    }

    /// How far `p` lies inside (positive) or outside (negative) the clip
    /// volume of `m`, relative to `w`: `|x|, |y| <= w` and `0 <= z <= w`.
    fn clip_margin(m: &Mat4, p: Vec3) -> f32 {
        let c = *m * p.extend(1.0);
        let w = c.w.abs().max(1e-6);
        [c.w - c.x.abs(), c.w - c.y.abs(), c.z, c.w - c.z].into_iter().fold(f32::INFINITY, f32::min) / w
    }

    proptest! {
        /// For every projection kind, a point is in the camera's frustum
        /// exactly when the given matrices' clip-space test says so (points
        /// within rounding of a plane excepted).
        #[test]
        fn frustum_from_matrices_agrees_with_clip_space(
            ex in -10.0f32..10.0, ey in -10.0f32..10.0, ez in -10.0f32..10.0,
            tx in -10.0f32..10.0, ty in -10.0f32..10.0, tz in -10.0f32..10.0,
            px in -80.0f32..80.0, py in -80.0f32..80.0, pz in -80.0f32..80.0,
        ) {
            let (eye, target, p) = (Vec3::new(ex, ey, ez), Vec3::new(tx, ty, tz), Vec3::new(px, py, pz));
            prop_assume!(eye.distance(target) > 0.5 && (target - eye).normalize().dot(Vec3::Y).abs() < 0.99);
            for (name, cam, vp) in cameras_from_matrices(eye, target) {
                let margin = clip_margin(&vp, p);
                prop_assume!(margin.abs() > 1e-4);
                let inside = cam.frustum().classify(&Aabb::new(p, p)) != Visibility::Outside;
                prop_assert_eq!(inside, margin > 0.0, "{}: {:?}, clip margin {}", name, p, margin);
                // What the backends rasterize puts the point in the same place.
                prop_assert_eq!(clip_margin(&cam.view_projection(), p) > 0.0, margin > 0.0, "{}", name);
            }
        }

        /// For every projection kind, every point that the near plane clips
        /// inside the view, up to the eye of a perspective camera, lies in the
        /// near region.
        #[test]
        fn near_region_from_matrices_holds_clipped_points(
            u in -1.0f32..1.0, v in -1.0f32..1.0, d in 0.0f32..1.0,
            ex in -10.0f32..10.0, ez in -10.0f32..10.0,
        ) {
            let eye = Vec3::new(ex, 2.0, ez);
            // Not looking straight down (the look-at up would be degenerate).
            prop_assume!((ex - 0.3).hypot(ez + 0.2) > 1.0);
            for (name, cam, vp) in cameras_from_matrices(eye, Vec3::new(0.3, 1.0, -0.2)) {
                let region = cam.near_region();
                let to_world = vp.inverse();
                let near_z = if cam.matrices.unwrap().reverse_z { 1.0 } else { 0.0 };
                let on_near = to_world.project_point3(Vec3::new(u, v, near_z));
                let p = if is_perspective(&cam.projection()) { eye + (on_near - eye) * d } else { on_near };
                prop_assert!(p.distance(region.center) <= region.radius, "{}: {:?} outside {:?}", name, p, region);
                // Boxes through the point are forced visible.
                prop_assert!(cam.box_touches_near_region(&Aabb::new(p, p + Vec3::splat(0.01))), "{}", name);
            }
        }
    }

    #[test]
    fn look_at_camera_from_its_matrices_matches_the_look_at_one() {
        let look_at = camera();
        let cam = Camera::from_matrices(look_at.view(), look_at.projection(), false).unwrap();
        assert!(cam.position.distance(look_at.position) < 1e-5, "{:?}", cam.position);
        let dir = (look_at.target - look_at.position).normalize();
        assert!((cam.target - cam.position).distance(dir) < 1e-5);
        for (got, want) in [(cam.fov_y_deg, 60.0), (cam.aspect, 4.0 / 3.0), (cam.near, 0.1), (cam.far, 100.0)] {
            assert!((got - want).abs() < want * 1e-4, "{got} != {want}");
        }
        assert_eq!(cam.view_projection(), look_at.view_projection());
        for (a, b) in cam.frustum().planes.iter().zip(&look_at.frustum().planes) {
            assert!(a.distance(*b) < 1e-6, "{a} != {b}");
        }
        let (a, b) = (cam.near_region(), look_at.near_region());
        assert!(a.center.distance(b.center) < 1e-5 && (a.radius - b.radius).abs() < b.radius * 1e-4, "{a:?} {b:?}");
    }

    #[test]
    fn reverse_z_is_rasterized_in_forward_depth_order() {
        let view = Mat4::look_at_rh(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y);
        let forward = Camera::from_matrices(view, Mat4::perspective_rh(1.0, 1.0, 0.1, 100.0), false).unwrap();
        let reverse = Camera::from_matrices(view, Mat4::perspective_rh(1.0, 1.0, 100.0, 0.1), true).unwrap();
        let infinite = Camera::from_matrices(view, Mat4::perspective_infinite_reverse_rh(1.0, 1.0, 0.1), true).unwrap();
        assert_eq!(infinite.far, f32::INFINITY);
        for cam in [forward, reverse, infinite] {
            let depth = |d: f32| cam.view_projection().project_point3(Vec3::new(0.0, 0.0, -d)).z;
            assert!(depth(0.1).abs() < 1e-5, "near depth {}", depth(0.1));
            assert!(
                depth(1.0) < depth(10.0) && depth(10.0) < depth(99.0),
                "{} {} {}",
                depth(1.0),
                depth(10.0),
                depth(99.0)
            );
            assert!(depth(99.0) <= 1.0);
        }
    }

    #[test]
    fn bad_matrices_are_refused() {
        let view = Mat4::look_at_rh(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y);
        let p = Mat4::perspective_rh(1.0, 1.0, 0.1, 100.0);
        let nan = Mat4::from_cols_array(&[f32::NAN; 16]);
        assert_eq!(Camera::from_matrices(nan, p, false), Err(CameraError::NotFinite("view")));
        assert_eq!(Camera::from_matrices(view, Mat4::ZERO, false), Err(CameraError::Singular("projection")));
        // The depth convention said wrong either way.
        assert_eq!(Camera::from_matrices(view, p, true), Err(CameraError::NearPlane));
        let reverse = Mat4::perspective_infinite_reverse_rh(1.0, 1.0, 0.1);
        assert_eq!(Camera::from_matrices(view, reverse, false), Err(CameraError::NearPlane));
        // A left-handed projection looks along +Z.
        assert_eq!(
            Camera::from_matrices(view, Mat4::perspective_lh(1.0, 1.0, 0.1, 100.0), false),
            Err(CameraError::NearPlane)
        );
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
