//! Axis-aligned bounding boxes, the bounding volume every method queries.

use glam::{Mat4, Vec3};
use serde::{Deserialize, Serialize};

/// An axis-aligned box `[min, max]`. An empty box has `min > max` on some axis.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Aabb {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    /// The empty box: the identity of [`Aabb::union`].
    pub const EMPTY: Aabb = Aabb { min: Vec3::splat(f32::INFINITY), max: Vec3::splat(f32::NEG_INFINITY) };

    /// A box from two corners (`min <= max` on every axis).
    pub fn new(min: Vec3, max: Vec3) -> Self {
        Self { min, max }
    }

    /// The smallest box holding every point.
    pub fn from_points<'a>(points: impl IntoIterator<Item = &'a Vec3>) -> Self {
        points.into_iter().fold(Self::EMPTY, |b, p| b.union_point(*p))
    }

    /// True when the box holds no point.
    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    /// True when both corners are finite numbers.
    pub fn is_finite(&self) -> bool {
        self.min.is_finite() && self.max.is_finite()
    }

    /// The smallest box holding both boxes.
    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb::new(self.min.min(other.min), self.max.max(other.max))
    }

    /// The smallest box holding this box and a point.
    pub fn union_point(&self, p: Vec3) -> Aabb {
        Aabb::new(self.min.min(p), self.max.max(p))
    }

    /// The common part of two boxes (possibly empty).
    pub fn intersection(&self, other: &Aabb) -> Aabb {
        Aabb::new(self.min.max(other.min), self.max.min(other.max))
    }

    /// Centre point.
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Edge lengths (zero for an empty box).
    pub fn extent(&self) -> Vec3 {
        (self.max - self.min).max(Vec3::ZERO)
    }

    /// Surface area, the cost measure of the surface-area heuristic.
    pub fn surface_area(&self) -> f32 {
        let e = self.extent();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    /// True when `p` lies inside or on the boundary.
    pub fn contains_point(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// True when the boxes share at least one point.
    pub fn overlaps(&self, other: &Aabb) -> bool {
        self.min.cmple(other.max).all() && other.min.cmple(self.max).all()
    }

    /// The eight corners, bit `i` of the index choosing `max` on axis `i`.
    pub fn corners(&self) -> [Vec3; 8] {
        std::array::from_fn(|i| {
            Vec3::new(
                if i & 1 == 0 { self.min.x } else { self.max.x },
                if i & 2 == 0 { self.min.y } else { self.max.y },
                if i & 4 == 0 { self.min.z } else { self.max.z },
            )
        })
    }

    /// The box of this box's corners under an affine transform.
    pub fn transformed(&self, m: &Mat4) -> Aabb {
        if self.is_empty() {
            return *self;
        }
        Aabb::from_points(&self.corners().map(|c| m.transform_point3(c)))
    }

    /// This box grown on every side by `relative` times its largest edge plus
    /// `absolute`. Query boxes are grown so that geometry lying on a box face
    /// can never be in front of the box's rasterized depth by rounding.
    pub fn expanded(&self, relative: f32, absolute: f32) -> Aabb {
        let pad = self.extent().max_element() * relative + absolute;
        Aabb::new(self.min - Vec3::splat(pad), self.max + Vec3::splat(pad))
    }

    /// Squared distance from `p` to the box (zero inside).
    pub fn distance_squared(&self, p: Vec3) -> f32 {
        let d = (self.min - p).max(p - self.max).max(Vec3::ZERO);
        d.length_squared()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn vec3() -> impl Strategy<Value = Vec3> {
        (-100.0f32..100.0, -100.0f32..100.0, -100.0f32..100.0).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    proptest! {
        #[test]
        fn union_contains_both(a in vec3(), b in vec3(), c in vec3(), d in vec3()) {
            let x = Aabb::from_points(&[a, b]);
            let y = Aabb::from_points(&[c, d]);
            let u = x.union(&y);
            for p in [a, b, c, d] {
                prop_assert!(u.contains_point(p));
            }
            prop_assert!(u.surface_area() >= x.surface_area().max(y.surface_area()));
        }

        #[test]
        fn transformed_box_contains_transformed_points(a in vec3(), b in vec3(), t in vec3(), angle in 0.0f32..6.3) {
            let m = Mat4::from_rotation_translation(glam::Quat::from_rotation_y(angle) * glam::Quat::from_rotation_x(angle * 0.5), t);
            let bx = Aabb::from_points(&[a, b]).expanded(0.0, 1e-3);
            let tb = bx.transformed(&m);
            for c in bx.corners() {
                prop_assert!(tb.expanded(1e-5, 1e-3).contains_point(m.transform_point3(c)));
            }
        }

        #[test]
        fn overlap_is_symmetric_and_matches_intersection(a in vec3(), b in vec3(), c in vec3(), d in vec3()) {
            let x = Aabb::from_points(&[a, b]);
            let y = Aabb::from_points(&[c, d]);
            prop_assert_eq!(x.overlaps(&y), y.overlaps(&x));
            prop_assert_eq!(x.overlaps(&y), !x.intersection(&y).is_empty());
        }
    }

    #[test]
    fn empty_box_is_union_identity() {
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
        assert!(Aabb::EMPTY.is_empty());
        assert_eq!(Aabb::EMPTY.union(&b), b);
        assert_eq!(Aabb::EMPTY.extent(), Vec3::ZERO);
    }
}
