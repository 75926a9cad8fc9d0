//! Inner boxes: an axis-aligned box strictly inside a closed mesh's solid,
//! with a stated clearance from its surface. `moc` renders such a box (12
//! triangles) into its occlusion buffer in place of the full mesh (the
//! argument why that is conservative is in `methods::moc`'s module doc).
//!
//! # How a box is found, and why it is inside
//! 1. The mesh must be closed: after welding vertices with equal positions,
//!    every edge of a non-degenerate triangle belongs to exactly two
//!    triangles (a triangle with two equal welded corners has no area and is
//!    left out). The surface then splits space into an inside and an outside
//!    by parity: a point off the surface is inside when a ray from it crosses
//!    the surface an odd number of times, the same for every ray.
//! 2. A centre `c` is inside when six rays from it (three skewed directions
//!    and their opposites, in `f64`) all cross the surface an odd number of
//!    times. A ray that passes within a relative `1e-9` of a triangle's edge,
//!    or runs nearly parallel to its plane, makes the count inconclusive and
//!    the candidate is rejected, so `f64` rounding cannot flip a crossing.
//!    The candidates are the centre of the mesh's bounding box, then six
//!    points a quarter of the box's half-size from it along each axis.
//! 3. The box about `c` grows while no triangle overlaps it (exact
//!    separating-axis test in `f64`, touching counts as overlap): first
//!    uniformly, a fraction of the bounding box's half-size, then along each
//!    axis in turn, longest first; each by bisection, keeping the largest
//!    size found free. A box that contains an inside point and meets no
//!    triangle is connected and never crosses the surface, so all of it is
//!    inside.
//! 4. The free box is shrunk by a margin of 1/16 of its smallest half-size on
//!    every side and its corners rounded inwards to `f32`. Every triangle lies
//!    outside the free box, so it is at least that margin (the
//!    [`InnerBox::clearance`]) from every point of the inner box.
//!
//! # Limits
//! Open meshes (a missing face, a hole for a spout) and meshes whose centre
//! candidates lie outside or on the surface get no box. The box is centred on
//! its candidate, so it is small for shapes whose inside is far from every
//! candidate (an L or a ring) and for thin shapes tilted off the axes.

use crate::geometry::Aabb;
use crate::scene::Mesh;
use glam::{DVec3, Vec3};
use std::collections::HashMap;

/// A box inside a closed mesh's solid, in mesh space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InnerBox {
    /// The box.
    pub bounds: Aabb,
    /// A distance (mesh space) from every point of the box to every triangle
    /// of the mesh is at least this, and it is positive.
    pub clearance: f32,
}

/// Bisection steps of each growth.
const STEPS: u32 = 20;

/// The inner box of `mesh`, or `None` when the mesh is not closed or no
/// candidate centre is found inside it (module doc).
pub fn inner_box(mesh: &Mesh) -> Option<InnerBox> {
    let triangles = surface_triangles(mesh)?;
    let bounds = &mesh.bounds;
    let (lo, hi) = (bounds.min.as_dvec3(), bounds.max.as_dvec3());
    let half = (hi - lo) * 0.5;
    if half.min_element() <= 0.0 || !half.is_finite() {
        return None;
    }
    let mid = (lo + hi) * 0.5;
    let offsets = [DVec3::ZERO, DVec3::X, -DVec3::X, DVec3::Y, -DVec3::Y, DVec3::Z, -DVec3::Z];
    let centre = offsets.iter().map(|o| mid + *o * half * 0.25).find(|&c| is_inside(c, &triangles))?;
    let free = FreeBoxes { centre, triangles: &triangles };

    // Uniform growth, then each axis, longest first.
    let uniform = bisect(0.0, 1.0, |t| free.is_free(half * t));
    let mut size = half * uniform;
    if size.min_element() <= 0.0 {
        return None;
    }
    let mut axes = [0usize, 1, 2];
    axes.sort_by(|&a, &b| half[b].total_cmp(&half[a]));
    for axis in axes {
        // Beyond the far face of the bounding box the box leaves the solid.
        let limit = half[axis] + (centre[axis] - mid[axis]).abs();
        let grown = bisect(size[axis], limit, |s| {
            let mut e = size;
            e[axis] = s;
            free.is_free(e)
        });
        size[axis] = grown;
    }

    let margin = size.min_element() / 16.0;
    let inner = size - DVec3::splat(margin);
    let min = round_towards(centre - inner, centre);
    let max = round_towards(centre + inner, centre);
    Some(InnerBox { bounds: Aabb::new(min, max), clearance: margin as f32 })
}

/// The mesh's triangles in `f64` when the mesh is closed (module doc, step
/// 1), else `None`. Triangles with two equal welded corners are left out.
fn surface_triangles(mesh: &Mesh) -> Option<Vec<[DVec3; 3]>> {
    let mut welded: HashMap<[u32; 3], u32> = HashMap::new();
    // -0.0 and 0.0 are the same position.
    let key = |p: Vec3| (p + Vec3::ZERO).to_array().map(f32::to_bits);
    let ids: Vec<u32> = mesh
        .positions
        .iter()
        .map(|&p| {
            let next = welded.len() as u32;
            *welded.entry(key(p)).or_insert(next)
        })
        .collect();
    let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
    let mut triangles = Vec::with_capacity(mesh.indices.len() / 3);
    for t in mesh.indices.chunks_exact(3) {
        let v = [t[0], t[1], t[2]].map(|i| ids.get(i as usize).copied());
        let [Some(a), Some(b), Some(c)] = v else { return None };
        if a == b || b == c || c == a {
            continue;
        }
        for (x, y) in [(a, b), (b, c), (c, a)] {
            *edges.entry((x.min(y), x.max(y))).or_insert(0) += 1;
        }
        triangles.push([t[0], t[1], t[2]].map(|i| mesh.positions[i as usize].as_dvec3()));
    }
    (!triangles.is_empty() && edges.values().all(|&n| n == 2)).then_some(triangles)
}

/// Whether `p` is inside by parity along six rays that all agree (module
/// doc, step 2).
fn is_inside(p: DVec3, triangles: &[[DVec3; 3]]) -> bool {
    let skewed = [DVec3::new(1.0, 0.31, 0.17), DVec3::new(0.23, 1.0, 0.41), DVec3::new(0.37, 0.13, 1.0)];
    skewed.iter().flat_map(|&d| [d, -d]).all(|d| {
        let mut odd = false;
        for t in triangles {
            match ray_crosses(p, d, t) {
                Some(hit) => odd ^= hit,
                None => return false,
            }
        }
        odd
    })
}

/// Whether the ray from `p` along `d` crosses triangle `t`; `None` when it
/// passes too close to an edge, to its start or along the plane to decide.
fn ray_crosses(p: DVec3, d: DVec3, t: &[DVec3; 3]) -> Option<bool> {
    const TOO_CLOSE: f64 = 1e-9;
    let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
    let q = d.cross(e2);
    let det = e1.dot(q);
    let scale = e1.length() * e2.length() * d.length();
    if det.abs() <= TOO_CLOSE * scale {
        // Parallel to the plane: a miss unless the ray lies in it.
        let normal = e1.cross(e2);
        let off = (p - t[0]).dot(normal).abs();
        return (off > TOO_CLOSE * normal.length() * (p - t[0]).length().max(e1.length())).then_some(false);
    }
    let s = p - t[0];
    let u = s.dot(q) / det;
    let r = s.cross(e1);
    let v = d.dot(r) / det;
    let along = e2.dot(r) / det;
    let w = 1.0 - u - v;
    if [u, v, w].iter().any(|x| x.abs() <= TOO_CLOSE) || along.abs() <= TOO_CLOSE * e1.length().max(e2.length()) {
        return None;
    }
    Some(u > 0.0 && v > 0.0 && w > 0.0 && along > 0.0)
}

/// Boxes about a fixed centre tested against a mesh's triangles.
struct FreeBoxes<'a> {
    centre: DVec3,
    triangles: &'a [[DVec3; 3]],
}

impl FreeBoxes<'_> {
    /// Whether the closed box of half-size `half` about the centre meets no
    /// triangle.
    fn is_free(&self, half: DVec3) -> bool {
        !self.triangles.iter().any(|t| triangle_meets_box(&t.map(|v| v - self.centre), half))
    }
}

/// The largest value in `[lo, hi]` found by bisection for which `free`
/// holds, assuming it holds at `lo` and that it stays false once false.
fn bisect(mut lo: f64, mut hi: f64, free: impl Fn(f64) -> bool) -> f64 {
    for _ in 0..STEPS {
        let mid = 0.5 * (lo + hi);
        if free(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// Separating-axis test of a triangle against the closed box `[-half, half]`
/// (Akenine-Möller, "Fast 3D triangle-box overlap testing"): true when they
/// meet, touching included.
pub(crate) fn triangle_meets_box(t: &[DVec3; 3], half: DVec3) -> bool {
    // The box's axes.
    for a in 0..3 {
        let (lo, hi) = (t[0][a].min(t[1][a]).min(t[2][a]), t[0][a].max(t[1][a]).max(t[2][a]));
        if lo > half[a] || hi < -half[a] {
            return false;
        }
    }
    // The triangle's plane.
    let normal = (t[1] - t[0]).cross(t[2] - t[0]);
    if separates(normal, t, half) {
        return false;
    }
    // Edge by box axis.
    let edges = [t[1] - t[0], t[2] - t[1], t[0] - t[2]];
    !edges.iter().any(|e| [DVec3::X, DVec3::Y, DVec3::Z].iter().any(|a| separates(e.cross(*a), t, half)))
}

/// Whether `axis` separates the triangle from the box `[-half, half]`.
fn separates(axis: DVec3, t: &[DVec3; 3], half: DVec3) -> bool {
    let p = t.map(|v| v.dot(axis));
    let r = half.dot(axis.abs());
    p[0].min(p[1]).min(p[2]) > r || p[0].max(p[1]).max(p[2]) < -r
}

/// `p` rounded to `f32` towards `centre`, coordinate by coordinate.
fn round_towards(p: DVec3, centre: DVec3) -> Vec3 {
    let round = |x: f64, c: f64| {
        let f = x as f32;
        if f64::from(f) > x && x > c {
            step(f, false)
        } else if f64::from(f) < x && x < c {
            step(f, true)
        } else {
            f
        }
    };
    Vec3::new(round(p.x, centre.x), round(p.y, centre.y), round(p.z, centre.z))
}

/// The `f32` next to a finite `f`, upwards or downwards.
fn step(f: f32, up: bool) -> f32 {
    let tiny = f32::from_bits(1);
    if f == 0.0 {
        return if up { tiny } else { -tiny };
    }
    let bits = f.to_bits();
    f32::from_bits(if (f > 0.0) == up { bits + 1 } else { bits - 1 })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::query_box::BOX_TRIANGLES;
    use proptest::prelude::*;

    /// A closed box mesh over `b`: its 8 corners, 12 triangles.
    fn box_mesh(b: Aabb) -> Mesh {
        let indices = BOX_TRIANGLES.iter().flatten().map(|&i| u32::from(i)).collect();
        Mesh::new(b.corners().to_vec(), indices)
    }

    /// Whether no triangle of `mesh` comes within `distance` of `inner`: the
    /// box grown by it on every side meets none.
    fn clear_of_surface(mesh: &Mesh, inner: &Aabb, distance: f64) -> bool {
        let centre = (inner.min.as_dvec3() + inner.max.as_dvec3()) * 0.5;
        let half = (inner.max.as_dvec3() - inner.min.as_dvec3()) * 0.5 + DVec3::splat(distance);
        mesh.indices
            .chunks_exact(3)
            .all(|t| !triangle_meets_box(&[0, 1, 2].map(|k| mesh.positions[t[k] as usize].as_dvec3() - centre), half))
    }

    /// A closed mesh shaped like a sphere (an octahedron subdivided
    /// `levels` times) with each vertex at its own distance `radius(v)` from
    /// the origin: star-shaped about the origin, so the origin is inside.
    fn lumpy_sphere(levels: u32, mut radius: impl FnMut(Vec3) -> f32) -> Mesh {
        let mut positions = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        let mut indices: Vec<u32> =
            vec![0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5];
        for _ in 0..levels {
            let mut mids: HashMap<(u32, u32), u32> = HashMap::new();
            let mut mid = |a: u32, b: u32, positions: &mut Vec<Vec3>| {
                *mids.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    positions.push((positions[a as usize] + positions[b as usize]).normalize());
                    positions.len() as u32 - 1
                })
            };
            let mut next = Vec::new();
            for t in indices.chunks_exact(3) {
                let (a, b, c) = (t[0], t[1], t[2]);
                let (ab, bc, ca) = (mid(a, b, &mut positions), mid(b, c, &mut positions), mid(c, a, &mut positions));
                next.extend_from_slice(&[a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca]);
            }
            indices = next;
        }
        let positions = positions.into_iter().map(|p| p * radius(p)).collect();
        Mesh::new(positions, indices)
    }

    #[test]
    fn a_closed_box_gets_most_of_itself_clear_of_its_faces() {
        let b = Aabb::new(Vec3::new(-1.0, 2.0, 3.0), Vec3::new(4.0, 3.0, 9.0));
        let mesh = box_mesh(b);
        let inner = inner_box(&mesh).expect("a closed box has an inner box");
        assert!(inner.clearance > 0.0);
        assert!(b.contains_point(inner.bounds.min) && b.contains_point(inner.bounds.max), "{inner:?}");
        assert!(clear_of_surface(&mesh, &inner.bounds, f64::from(inner.clearance) * 0.999), "{inner:?}");
        // Free growth nearly reaches the faces; the margin takes 1/16 of the
        // thinnest half-size (0.5) off every side.
        let (got, want) = (inner.bounds.extent(), b.extent() - Vec3::splat(2.0 * 0.5 / 16.0));
        assert!((got - want).abs().max_element() < 1e-4, "{got} against {want}");
    }

    #[test]
    fn faces_with_their_own_corners_are_welded() {
        // The box's 12 triangles with three vertices each, none shared.
        let boxed = box_mesh(Aabb::new(Vec3::ZERO, Vec3::ONE));
        let positions: Vec<Vec3> = boxed.indices.iter().map(|&i| boxed.positions[i as usize]).collect();
        let mesh = Mesh::new(positions, (0..36).collect());
        assert!(inner_box(&mesh).is_some());
    }

    #[test]
    fn an_open_mesh_gets_none() {
        let mut mesh = box_mesh(Aabb::new(Vec3::ZERO, Vec3::ONE));
        mesh.indices.truncate(30); // one face missing
        assert_eq!(inner_box(&mesh), None);
        // A face twice: four triangles on each of its edges.
        let mut doubled = box_mesh(Aabb::new(Vec3::ZERO, Vec3::ONE));
        doubled.indices.extend_from_slice(&doubled.indices[..6].to_vec());
        assert_eq!(inner_box(&doubled), None);
    }

    #[test]
    fn two_boxes_apart_get_none_when_the_centre_is_between_them() {
        // Closed, but every candidate centre lies in the gap (outside).
        let left = box_mesh(Aabb::new(Vec3::new(-10.0, 0.0, 0.0), Vec3::new(-9.0, 1.0, 1.0)));
        let right = box_mesh(Aabb::new(Vec3::new(9.0, 0.0, 0.0), Vec3::new(10.0, 1.0, 1.0)));
        let mut positions = left.positions.clone();
        positions.extend_from_slice(&right.positions);
        let indices = left.indices.iter().copied().chain(right.indices.iter().map(|i| i + 8)).collect();
        assert_eq!(inner_box(&Mesh::new(positions, indices)), None);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]

        /// On random closed star-shaped meshes the box, grown by its
        /// clearance, still meets no triangle, and its centre is inside.
        #[test]
        fn random_closed_meshes_keep_their_clearance(seed in any::<u64>(), levels in 0u32..3) {
            let mut rng = crate::rng::Rng::new(seed, 7);
            let mesh = lumpy_sphere(levels, |_| rng.range(0.3, 1.0));
            if let Some(inner) = inner_box(&mesh) {
                prop_assert!(inner.clearance > 0.0);
                prop_assert!(inner.bounds.min.cmplt(inner.bounds.max).all(), "{:?}", inner);
                prop_assert!(clear_of_surface(&mesh, &inner.bounds, f64::from(inner.clearance) * 0.999), "{:?}", inner);
                let triangles = surface_triangles(&mesh).unwrap();
                prop_assert!(is_inside(inner.bounds.center().as_dvec3(), &triangles));
            }
        }
    }

    #[test]
    fn a_lumpy_sphere_gets_a_box() {
        let mut rng = crate::rng::Rng::new(3, 7);
        let mesh = lumpy_sphere(2, |_| rng.range(0.8, 1.0));
        let inner = inner_box(&mesh).expect("the origin is inside");
        assert!(inner.bounds.extent().min_element() > 0.5, "{inner:?}");
    }
}
