//! The proxies that occlusion queries rasterize, shared by every backend so
//! that all of them test the same surfaces with the same conservative margins
//! (CHC paper, section 3: a query renders a node's bounding box with depth
//! writes off and counts the pixels that pass the depth test).
//!
//! A query whose box reaches the camera's near region counts as visible
//! without rasterizing: near-plane clipping may remove the box's faces
//! towards the eye. Boxes are grown by [`QUERY_BOX_PAD`] and drawn with
//! [`QUERY_DEPTH_BIAS`], so geometry on a box face never rounds in front of
//! it. The price is weaker culling far away: with the near plane at 0.25 m,
//! the bias is about 0.6 m of depth at 200 m.

use crate::camera::Camera;
use crate::geometry::Aabb;

/// Relative growth of query boxes, so geometry lying on a box face or edge
/// can never round to outside the box's pixels.
pub const QUERY_BOX_PAD: f32 = 1e-5;

/// Depth bias of query boxes in normalized device depth (about 64 float
/// steps near 1.0), subtracted as `z - bias * w` in clip space: the box's
/// depth always rounds in front of geometry that lies on its faces, so a
/// visible object's box is never reported hidden.
pub const QUERY_DEPTH_BIAS: f32 = 4e-6;

/// The 12 triangles of a box's surface as indices into [`Aabb::corners`],
/// counter-clockwise seen from outside, so that culling back faces leaves the
/// faces towards the eye.
pub const BOX_TRIANGLES: [[u8; 3]; 12] = {
    const FACES: [[u8; 4]; 6] = [[0, 4, 6, 2], [1, 3, 7, 5], [0, 1, 5, 4], [2, 6, 7, 3], [0, 2, 3, 1], [4, 5, 7, 6]];
    let mut out = [[0u8; 3]; 12];
    let mut f = 0;
    while f < 6 {
        let [a, b, c, d] = FACES[f];
        out[2 * f] = [a, b, c];
        out[2 * f + 1] = [a, c, d];
        f += 1;
    }
    out
};

/// `b` grown by [`QUERY_BOX_PAD`] of its size plus the same fraction of its
/// coordinates' magnitude, so that a box far from the origin grows by more
/// than a float step: the proxy every occlusion test rasterizes.
pub fn padded(b: &Aabb) -> Aabb {
    b.expanded(QUERY_BOX_PAD, QUERY_BOX_PAD * b.min.abs().max(b.max.abs()).max_element())
}

/// The boxes a query over `boxes` rasterizes, each [`padded`], or `None`
/// when one of them touches the camera's near region
/// ([`Camera::box_touches_near_region`]): such a query cannot be rasterized
/// soundly and counts as visible.
pub fn query_boxes(camera: &Camera, boxes: &[Aabb]) -> Option<Vec<Aabb>> {
    let padded: Vec<Aabb> = boxes.iter().map(padded).collect();
    (!padded.iter().any(|b| camera.box_touches_near_region(b))).then_some(padded)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn box_triangles_face_outwards() {
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let c = b.corners();
        for t in BOX_TRIANGLES {
            let [p0, p1, p2] = t.map(|i| c[i as usize]);
            let normal = (p1 - p0).cross(p2 - p0);
            let centre_to_face = (p0 + p1 + p2) / 3.0 - b.center();
            assert!(normal.dot(centre_to_face) > 0.0, "triangle {t:?} faces inwards");
        }
    }

    #[test]
    fn near_boxes_are_not_rasterized() {
        let camera = Camera {
            position: Vec3::ZERO,
            target: Vec3::NEG_Z,
            up: Vec3::Y,
            fov_y_deg: 60.0,
            aspect: 1.0,
            near: 0.25,
            far: 100.0,
            matrices: None,
        };
        let far = Aabb::new(Vec3::new(-1.0, -1.0, -11.0), Vec3::new(1.0, 1.0, -10.0));
        let around_eye = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        let padded = query_boxes(&camera, &[far]).expect("a far box is rasterized");
        assert!(padded[0].min.x < far.min.x && padded[0].max.z > far.max.z);
        assert!(query_boxes(&camera, &[far, around_eye]).is_none());
    }
}
