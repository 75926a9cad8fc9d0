//! Inner boxes: axis-aligned boxes strictly inside a mesh's closed parts,
//! each with a stated clearance from the part's surface. `moc` renders such
//! boxes (12 triangles each) into its occlusion buffer in place of the full
//! mesh (the argument why that is conservative is in `methods::moc`'s
//! module doc).
//!
//! # How a box is found, and why it is inside
//! 1. Parts: vertices with equal positions are welded, triangles with two
//!    equal welded corners (no area) are left out, and the rest fall into
//!    connected parts (triangles sharing a welded vertex). A part is closed
//!    when each of its edges belongs to an even number of its triangles
//!    (two, or four where two solids touch along an edge). A closed part
//!    splits space by parity: a point off its surface is inside when a ray
//!    from it crosses the part an odd number of times, the same count for
//!    every ray. Open parts (a hole for a spout, a missing face) get no box.
//!    Parts are taken one by one because scenes build objects from solids
//!    that overlap (a ledge through a wall): the overlap is even, outside by
//!    parity, and would cut a box of the whole mesh down to one cell.
//! 2. A centre `c` is inside a part when six rays from it (three skewed
//!    directions and their opposites, in `f64`) all cross the part an odd
//!    number of times. A ray that passes within a relative `1e-9` of a
//!    triangle's edge, or runs nearly parallel to its plane, makes the count
//!    inconclusive and the candidate is rejected, so `f64` rounding cannot
//!    flip a crossing. The candidates are the centre of the part's bounding
//!    box, then six points a quarter of the box's half-size from it along
//!    each axis.
//! 3. A box about `c` grows while no triangle of the part overlaps it
//!    (separating-axis test in `f64`, touching counts as overlap): first
//!    uniformly, a fraction of the bounding box's half-size, then face by
//!    face, those across the longest axis first; each by bisection, keeping
//!    the largest size found free. A box that contains an inside point and
//!    meets no triangle never crosses the surface, so all of it is inside.
//! 4. The free box is shrunk by a margin of 1/32 of its smallest size on
//!    every side and its corners rounded inwards to `f32`. Every triangle of
//!    the part lies outside the free box, so at least that margin (the
//!    [`InnerBox::clearance`]) from every point of the inner box.
//! 5. A mesh keeps the [`MAX_BOXES`] boxes of largest surface area.
//!
//! # Limits
//! Open parts and parts whose centre candidates lie outside or on the surface
//! get no box. A box grows from its candidate one face at a time, so it is
//! small for parts whose inside is far from every candidate (a ring) or
//! narrow around it (an L's corner), and for thin parts tilted off the axes.

use crate::geometry::Aabb;
use crate::scene::Mesh;
use glam::{DVec3, Vec3};
use std::collections::HashMap;

/// A box inside a closed part of a mesh, in mesh space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InnerBox {
    /// The box.
    pub bounds: Aabb,
    /// A distance (mesh space) from every point of the box to every triangle
    /// of its part is at least this, and it is positive.
    pub clearance: f32,
}

/// Most boxes kept per mesh: each costs 12 occluder triangles.
pub const MAX_BOXES: usize = 4;

/// Bisection steps of each growth.
const STEPS: u32 = 20;

/// The inner boxes of `mesh`'s closed parts, largest surface first, at most
/// [`MAX_BOXES`]; empty when no part is closed with an inside centre found
/// (module doc).
pub fn inner_boxes(mesh: &Mesh) -> Vec<InnerBox> {
    let mut boxes: Vec<InnerBox> = closed_parts(mesh).iter().filter_map(|part| part_box(part)).collect();
    boxes.sort_by(|a, b| b.bounds.surface_area().total_cmp(&a.bounds.surface_area()));
    boxes.truncate(MAX_BOXES);
    boxes
}

/// The inner box of one closed part's triangles, if a centre is found inside.
fn part_box(triangles: &[[DVec3; 3]]) -> Option<InnerBox> {
    let (lo, hi) =
        triangles.iter().flatten().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    let half = (hi - lo) * 0.5;
    if half.min_element() <= 0.0 || !half.is_finite() {
        return None;
    }
    let mid = (lo + hi) * 0.5;
    let offsets = [DVec3::ZERO, DVec3::X, -DVec3::X, DVec3::Y, -DVec3::Y, DVec3::Z, -DVec3::Z];
    let centre = offsets.iter().map(|o| mid + *o * half * 0.25).find(|&c| is_inside(c, triangles))?;
    let free = FreeBoxes { triangles };

    // Uniform growth about the centre, then each face in turn, those across
    // the longest axis first.
    let uniform = bisect(0.0, 1.0, |t| free.is_free(centre - half * t, centre + half * t));
    if uniform <= 0.0 {
        return None;
    }
    let (mut min, mut max) = (centre - half * uniform, centre + half * uniform);
    let mut axes = [0usize, 1, 2];
    axes.sort_by(|&a, &b| half[b].total_cmp(&half[a]));
    for axis in axes {
        // Beyond the bounding box the box leaves the solid.
        let reach = bisect(0.0, min[axis] - lo[axis], |d| {
            let mut m = min;
            m[axis] -= d;
            free.is_free(m, max)
        });
        min[axis] -= reach;
        let reach = bisect(0.0, hi[axis] - max[axis], |d| {
            let mut m = max;
            m[axis] += d;
            free.is_free(min, m)
        });
        max[axis] += reach;
    }

    let margin = (max - min).min_element() / 32.0;
    let inner = (min + DVec3::splat(margin), max - DVec3::splat(margin));
    let centre = (min + max) * 0.5;
    let bounds = Aabb::new(round_towards(inner.0, centre), round_towards(inner.1, centre));
    Some(InnerBox { bounds, clearance: margin as f32 })
}

/// A part's triangles and how many of them use each welded edge.
type Part = (Vec<[DVec3; 3]>, HashMap<(u32, u32), u32>);

/// The triangles (in `f64`) of each closed part of `mesh` (module doc, step
/// 1). A mesh with an index out of range has none.
fn closed_parts(mesh: &Mesh) -> Vec<Vec<[DVec3; 3]>> {
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
    let mut triangles: Vec<([u32; 3], [u32; 3])> = Vec::with_capacity(mesh.indices.len() / 3);
    for t in mesh.indices.chunks_exact(3) {
        let Some(v) = [t[0], t[1], t[2]].map(|i| ids.get(i as usize).copied()).into_iter().collect::<Option<Vec<_>>>()
        else {
            return Vec::new();
        };
        let (a, b, c) = (v[0], v[1], v[2]);
        if a != b && b != c && c != a {
            triangles.push(([a, b, c], [t[0], t[1], t[2]]));
        }
    }
    // Parts: union-find over welded vertices.
    let mut parent: Vec<u32> = (0..welded.len() as u32).collect();
    fn root(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            parent[x as usize] = parent[parent[x as usize] as usize];
            x = parent[x as usize];
        }
        x
    }
    for (w, _) in &triangles {
        for k in 1..3 {
            let (a, b) = (root(&mut parent, w[0]), root(&mut parent, w[k]));
            parent[a as usize] = b;
        }
    }
    // Parts in the order of their first triangle, so the result is the
    // same on every run.
    let mut part_of_root: HashMap<u32, usize> = HashMap::new();
    let mut parts: Vec<Part> = Vec::new();
    for (w, t) in &triangles {
        let r = root(&mut parent, w[0]);
        let next = parts.len();
        let index = *part_of_root.entry(r).or_insert(next);
        if index == next {
            parts.push(Default::default());
        }
        let (tris, edges) = &mut parts[index];
        for (x, y) in [(w[0], w[1]), (w[1], w[2]), (w[2], w[0])] {
            *edges.entry((x.min(y), x.max(y))).or_insert(0) += 1;
        }
        tris.push(t.map(|i| mesh.positions[i as usize].as_dvec3()));
    }
    parts.into_iter().filter(|(_, edges)| edges.values().all(|&n| n % 2 == 0)).map(|(t, _)| t).collect()
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

/// Boxes tested against a part's triangles.
struct FreeBoxes<'a> {
    triangles: &'a [[DVec3; 3]],
}

impl FreeBoxes<'_> {
    /// Whether the closed box from `min` to `max` meets no triangle.
    fn is_free(&self, min: DVec3, max: DVec3) -> bool {
        let (centre, half) = ((min + max) * 0.5, (max - min) * 0.5);
        !self.triangles.iter().any(|t| triangle_meets_box(&t.map(|v| v - centre), half))
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
        let mut indices: Vec<u32> = vec![0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5];
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
        let boxes = inner_boxes(&mesh);
        assert_eq!(boxes.len(), 1);
        let inner = boxes[0];
        assert!(inner.clearance > 0.0);
        assert!(b.contains_point(inner.bounds.min) && b.contains_point(inner.bounds.max), "{inner:?}");
        assert!(clear_of_surface(&mesh, &inner.bounds, f64::from(inner.clearance) * 0.999), "{inner:?}");
        // Free growth nearly reaches the faces; the margin takes 1/32 of the
        // smallest size (1) off every side.
        let (got, want) = (inner.bounds.extent(), b.extent() - Vec3::splat(2.0 / 32.0));
        assert!((got - want).abs().max_element() < 1e-4, "{got} against {want}");
    }

    #[test]
    fn faces_with_their_own_corners_are_welded() {
        // The box's 12 triangles with three vertices each, none shared.
        let boxed = box_mesh(Aabb::new(Vec3::ZERO, Vec3::ONE));
        let positions: Vec<Vec3> = boxed.indices.iter().map(|&i| boxed.positions[i as usize]).collect();
        let mesh = Mesh::new(positions, (0..36).collect());
        assert_eq!(inner_boxes(&mesh).len(), 1);
    }

    #[test]
    fn an_open_mesh_gets_none() {
        let mut mesh = box_mesh(Aabb::new(Vec3::ZERO, Vec3::ONE));
        mesh.indices.truncate(30); // one face missing
        assert_eq!(inner_boxes(&mesh), vec![]);
        // A triangle of the face repeated: three of its edges are used three times.
        let mut odd = box_mesh(Aabb::new(Vec3::ZERO, Vec3::ONE));
        odd.indices.extend_from_within(..3);
        assert_eq!(inner_boxes(&odd), vec![]);
    }

    #[test]
    fn overlapping_and_touching_solids_are_parts_of_their_own() {
        // A slab through a tower (overlapping, no shared vertex), and a
        // column touching the tower along an edge (welded: one part with
        // that edge used 4 times).
        let tower = Aabb::new(Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 10.0, 1.0));
        let slab = Aabb::new(Vec3::new(-1.5, 4.9, -1.5), Vec3::new(1.5, 5.1, 1.5));
        let touching = Aabb::new(Vec3::new(1.0, 0.0, 1.0), Vec3::new(2.0, 10.0, 2.0));
        let (mut positions, mut indices) = (Vec::new(), Vec::new());
        for b in [tower, slab, touching] {
            let m = box_mesh(b);
            indices.extend(m.indices.iter().map(|i| i + positions.len() as u32));
            positions.extend_from_slice(&m.positions);
        }
        let mesh = Mesh::new(positions, indices);
        let boxes = inner_boxes(&mesh);
        assert_eq!(boxes.len(), 2, "{boxes:?}");
        // The largest is the tower's, nearly all of it, through the slab
        // (another part), clear of its own part.
        let inner = boxes[0];
        assert!(tower.contains_point(inner.bounds.min) && tower.contains_point(inner.bounds.max), "{boxes:?}");
        assert!(inner.bounds.extent().cmpgt(Vec3::new(1.8, 9.8, 1.8)).all(), "{boxes:?}");
        let own =
            Mesh::new(mesh.positions.clone(), mesh.indices[..36].iter().chain(&mesh.indices[72..]).copied().collect());
        assert!(clear_of_surface(&own, &inner.bounds, f64::from(inner.clearance) * 0.999), "{inner:?}");
        assert!(!clear_of_surface(&mesh, &inner.bounds, 0.0), "the slab crosses the tower's box");
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]

        /// On random closed star-shaped meshes the box, grown by its
        /// clearance, still meets no triangle, and its centre is inside.
        #[test]
        fn random_closed_meshes_keep_their_clearance(seed in any::<u64>(), levels in 0u32..3) {
            let mut rng = crate::rng::Rng::new(seed, 7);
            let mesh = lumpy_sphere(levels, |_| rng.range(0.3, 1.0));
            for inner in inner_boxes(&mesh) {
                prop_assert!(inner.clearance > 0.0);
                prop_assert!(inner.bounds.min.cmplt(inner.bounds.max).all(), "{:?}", inner);
                prop_assert!(clear_of_surface(&mesh, &inner.bounds, f64::from(inner.clearance) * 0.999), "{:?}", inner);
                let parts = closed_parts(&mesh);
                prop_assert_eq!(parts.len(), 1);
                prop_assert!(is_inside(inner.bounds.center().as_dvec3(), &parts[0]));
            }
        }
    }

    #[test]
    fn a_lumpy_sphere_gets_a_box() {
        let mut rng = crate::rng::Rng::new(3, 7);
        let mesh = lumpy_sphere(2, |_| rng.range(0.8, 1.0));
        let inner = inner_boxes(&mesh)[0];
        assert!(inner.bounds.extent().min_element() > 0.5, "{inner:?}");
    }
}
