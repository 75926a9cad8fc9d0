//! Mesh builders shared by the scenes: boxes, cylinders, cones, spheres, tori,
//! stairs and pipes along polylines, plus a builder that merges parts.
//!
//! Every closed shape is watertight (each directed edge has exactly one
//! opposite edge), wound counter-clockwise seen from outside, and has no
//! degenerate (zero-area) triangle, so renderers may cull back faces and
//! tests may check volumes by the divergence theorem.

use glam::{Mat4, Quat, Vec2, Vec3};
use occlude_core::Mesh;

/// Accumulates parts (each placed with a transform) into one mesh, so that a
/// detailed object such as a building or a pump is one instance (one draw call)
/// that many instances can share.
#[derive(Clone, Debug, Default)]
pub struct MeshBuilder {
    positions: Vec<Vec3>,
    indices: Vec<u32>,
}

impl MeshBuilder {
    /// An empty builder.
    pub fn new() -> Self {
        Self::default()
    }

    /// Appends `part` transformed by `transform`; a mirroring transform flips
    /// the winding so that the part stays outward-facing.
    pub fn add(&mut self, part: &Mesh, transform: Mat4) -> &mut Self {
        let base = self.positions.len() as u32;
        self.positions.extend(part.positions.iter().map(|&p| transform.transform_point3(p)));
        let mirrored = transform.determinant() < 0.0;
        for t in part.indices.chunks_exact(3) {
            let (a, b, c) = (t[0] + base, t[1] + base, t[2] + base);
            if mirrored {
                self.indices.extend([a, c, b]);
            } else {
                self.indices.extend([a, b, c]);
            }
        }
        self
    }

    /// Appends `part` translated by `offset`.
    pub fn add_at(&mut self, part: &Mesh, offset: Vec3) -> &mut Self {
        self.add(part, Mat4::from_translation(offset))
    }

    /// The merged mesh.
    pub fn build(self) -> Mesh {
        Mesh::new(self.positions, self.indices)
    }
}

/// An axis-aligned box from `min` to `max` (12 triangles).
pub fn cuboid(min: Vec3, max: Vec3) -> Mesh {
    let p = |x: bool, y: bool, z: bool| {
        Vec3::new(if x { max.x } else { min.x }, if y { max.y } else { min.y }, if z { max.z } else { min.z })
    };
    let positions = vec![
        p(false, false, false),
        p(true, false, false),
        p(true, true, false),
        p(false, true, false),
        p(false, false, true),
        p(true, false, true),
        p(true, true, true),
        p(false, true, true),
    ];
    #[rustfmt::skip]
    let indices = vec![
        0, 3, 2, 0, 2, 1, // -z
        4, 5, 6, 4, 6, 7, // +z
        0, 4, 7, 0, 7, 3, // -x
        1, 2, 6, 1, 6, 5, // +x
        0, 1, 5, 0, 5, 4, // -y
        3, 7, 6, 3, 6, 2, // +y
    ];
    Mesh::new(positions, indices)
}

/// A box of size `size` whose base is centred on the origin (`y` from 0 up).
pub fn block(size: Vec3) -> Mesh {
    cuboid(Vec3::new(-0.5 * size.x, 0.0, -0.5 * size.z), Vec3::new(0.5 * size.x, size.y, 0.5 * size.z))
}

/// A ring of `sides` points of radius `radius` around the `y` axis at height
/// `y`, counter-clockwise seen from `+y`.
fn ring_y(radius: f32, y: f32, sides: u32) -> Vec<Vec3> {
    (0..sides)
        .map(|k| {
            let a = std::f32::consts::TAU * k as f32 / sides as f32;
            Vec3::new(radius * a.cos(), y, -radius * a.sin())
        })
        .collect()
}

/// Connects rings into a surface. Each ring is one point (a pole) or `n`
/// points ordered counter-clockwise about the direction from ring to ring;
/// open ends get flat caps, and `closed_loop` joins the last ring to the first
/// (a torus). Triangles that would collapse at a pole are not emitted.
fn loft(rings: &[Vec<Vec3>], closed_loop: bool) -> Mesh {
    let mut positions = Vec::new();
    let mut starts = Vec::new();
    for r in rings {
        starts.push(positions.len() as u32);
        positions.extend_from_slice(r);
    }
    let mut indices = Vec::new();
    let count = rings.len();
    let pairs = if closed_loop { count } else { count - 1 };
    for i in 0..pairs {
        let j = (i + 1) % count;
        let (na, nb) = (rings[i].len() as u32, rings[j].len() as u32);
        let n = na.max(nb);
        for k in 0..n {
            let k1 = (k + 1) % n;
            let a = |k: u32| starts[i] + if na == 1 { 0 } else { k };
            let b = |k: u32| starts[j] + if nb == 1 { 0 } else { k };
            if na > 1 {
                indices.extend([a(k), a(k1), b(k1)]);
            }
            if nb > 1 {
                indices.extend([a(k), b(k1), b(k)]);
            }
        }
    }
    if !closed_loop {
        let cap = |ring: usize, reverse: bool, indices: &mut Vec<u32>| {
            let n = rings[ring].len() as u32;
            let s = starts[ring];
            for k in 1..n.saturating_sub(1) {
                if reverse {
                    indices.extend([s, s + k + 1, s + k]);
                } else {
                    indices.extend([s, s + k, s + k + 1]);
                }
            }
        };
        cap(0, true, &mut indices);
        cap(count - 1, false, &mut indices);
    }
    Mesh::new(positions, indices)
}

/// A closed truncated cone along `+y` from radius `bottom` at `y = 0` to radius
/// `top` at `y = height`; a radius of zero gives an apex (a cone).
pub fn frustum(bottom: f32, top: f32, height: f32, sides: u32) -> Mesh {
    let ring = |r: f32, y: f32| if r > 0.0 { ring_y(r, y, sides) } else { vec![Vec3::new(0.0, y, 0.0)] };
    loft(&[ring(bottom, 0.0), ring(top, height)], false)
}

/// A closed cylinder of `radius` along `+y` from 0 to `height`
/// (`4 * sides - 4` triangles).
pub fn cylinder(radius: f32, height: f32, sides: u32) -> Mesh {
    frustum(radius, radius, height, sides)
}

/// A closed cone with its base (radius `radius`) at `y = 0` and apex at
/// `y = height` (`2 * sides - 2` triangles).
pub fn cone(radius: f32, height: f32, sides: u32) -> Mesh {
    frustum(radius, 0.0, height, sides)
}

/// A UV sphere centred on the origin with single-vertex poles
/// (`2 * slices * (stacks - 1)` triangles).
pub fn sphere(radius: f32, stacks: u32, slices: u32) -> Mesh {
    let rings: Vec<Vec<Vec3>> = (0..=stacks)
        .map(|i| {
            let phi = std::f32::consts::PI * i as f32 / stacks as f32;
            let y = -radius * phi.cos();
            if i == 0 || i == stacks {
                vec![Vec3::new(0.0, y, 0.0)]
            } else {
                ring_y(radius * phi.sin(), y, slices)
            }
        })
        .collect();
    loft(&rings, false)
}

/// A torus around the `y` axis: tube radius `minor` swept along a circle of
/// radius `major` (`2 * major_segments * minor_segments` triangles).
pub fn torus(major: f32, minor: f32, major_segments: u32, minor_segments: u32) -> Mesh {
    let rings: Vec<Vec<Vec3>> = (0..major_segments)
        .map(|i| {
            let a = std::f32::consts::TAU * i as f32 / major_segments as f32;
            // Sweep counter-clockwise about +y; the tube ring must turn
            // counter-clockwise about that sweep direction.
            let radial = Vec3::new(a.cos(), 0.0, -a.sin());
            let tangent = Vec3::new(-a.sin(), 0.0, -a.cos());
            let binormal = tangent.cross(radial);
            (0..minor_segments)
                .map(|k| {
                    let b = std::f32::consts::TAU * k as f32 / minor_segments as f32;
                    radial * (major + minor * b.cos()) + binormal * (minor * b.sin())
                })
                .collect()
        })
        .collect();
    loft(&rings, true)
}

/// A prism: the convex polygon `profile` (in the `xy` plane, counter-clockwise
/// seen from `+z`) extruded along `+z` from 0 to `depth`; a gabled roof is a
/// triangular prism.
pub fn prism(profile: &[Vec2], depth: f32) -> Mesh {
    let ring = |z: f32| profile.iter().map(|p| p.extend(z)).collect::<Vec<_>>();
    loft(&[ring(0.0), ring(depth)], false)
}

/// A solid staircase of `steps` steps, `width` wide along `x`, climbing `rise`
/// per step over `run` per step along `+z` from the origin (12 triangles per
/// step: one box per step, from the floor to its tread).
pub fn stairs(width: f32, steps: u32, rise: f32, run: f32) -> Mesh {
    let mut b = MeshBuilder::new();
    for i in 0..steps {
        let z = i as f32 * run;
        b.add(&cuboid(Vec3::new(0.0, 0.0, z), Vec3::new(width, (i + 1) as f32 * rise, z + run)), Mat4::IDENTITY);
    }
    b.build()
}

/// Replaces every inner corner of `points` by a bend of `segments` straight
/// pieces (a quadratic Bezier from `bend` before the corner to `bend` after),
/// as pipe fitters' elbows look when tessellated.
pub fn round_corners(points: &[Vec3], bend: f32, segments: u32) -> Vec<Vec3> {
    let mut out = vec![points[0]];
    for w in points.windows(3) {
        let (p0, p, p1) = (w[0], w[1], w[2]);
        let d0 = (p - p0).normalize();
        let d1 = (p1 - p).normalize();
        if d0.dot(d1) > 0.9999 {
            out.push(p);
            continue;
        }
        let t = bend.min(0.45 * (p - p0).length()).min(0.45 * (p1 - p).length());
        let (a, b) = (p - d0 * t, p + d1 * t);
        for s in 0..=segments {
            let s = s as f32 / segments as f32;
            out.push(a * (1.0 - s) * (1.0 - s) + p * (2.0 * s * (1.0 - s)) + b * (s * s));
        }
    }
    out.push(points[points.len() - 1]);
    out
}

/// A closed pipe of `radius` along the polyline `points` (at least two points,
/// no reversal between consecutive segments), with mitred joints and flat end
/// caps. Use [`round_corners`] first for smooth bends.
pub fn tube(points: &[Vec3], radius: f32, sides: u32) -> Mesh {
    let dirs: Vec<Vec3> = points.windows(2).map(|w| (w[1] - w[0]).normalize()).collect();
    let first = dirs[0];
    let helper = if first.y.abs() < 0.9 { Vec3::Y } else { Vec3::X };
    let mut normal = helper.cross(first).normalize();
    let mut rings = Vec::with_capacity(points.len());
    for (i, &p) in points.iter().enumerate() {
        let d_in = dirs[i.saturating_sub(1)];
        let d_out = dirs[i.min(dirs.len() - 1)];
        let binormal = d_in.cross(normal);
        let mitre = (d_in + d_out).normalize();
        let ring = (0..sides)
            .map(|k| {
                let a = std::f32::consts::TAU * k as f32 / sides as f32;
                let q = normal * (radius * a.cos()) + binormal * (radius * a.sin());
                // Slide along the incoming direction onto the mitre plane.
                q - d_in * (q.dot(mitre) / d_in.dot(mitre))
            })
            .map(|q| p + q)
            .collect();
        rings.push(ring);
        // Parallel transport of the frame onto the next segment.
        normal = Quat::from_rotation_arc(d_in, d_out) * normal;
    }
    loft(&rings, false)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use std::collections::HashMap;
    use std::f32::consts::PI;

    /// Volume enclosed by a closed mesh (divergence theorem); positive when
    /// the winding is outward.
    pub(crate) fn signed_volume(m: &Mesh) -> f64 {
        m.indices
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| m.positions[i as usize].as_dvec3());
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    /// The smallest triangle area of a mesh.
    pub(crate) fn min_area(m: &Mesh) -> f32 {
        m.indices
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| m.positions[i as usize]);
                0.5 * (b - a).cross(c - a).length()
            })
            .fold(f32::INFINITY, f32::min)
    }

    /// Every directed edge appears once and its reverse once: closed and
    /// consistently oriented.
    fn is_closed(m: &Mesh) -> bool {
        let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
        for t in m.indices.chunks_exact(3) {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                *edges.entry((a, b)).or_default() += 1;
            }
        }
        edges.iter().all(|(&(a, b), &n)| n == 1 && edges.get(&(b, a)) == Some(&1))
    }

    fn check(name: &str, m: &Mesh, volume: f64, tolerance: f64) {
        assert!(is_closed(m), "{name} is not closed");
        assert!(min_area(m) > 1e-6, "{name} has a degenerate triangle");
        let v = signed_volume(m);
        assert!(v > 0.0, "{name} is wound inward: volume {v}");
        assert!((v - volume).abs() <= tolerance * volume, "{name}: volume {v}, expected about {volume}");
    }

    #[test]
    fn closed_shapes_are_outward_and_have_their_volume() {
        check("cuboid", &cuboid(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(1.0, 3.0, 2.5)), 3.0, 1e-5);
        check("block", &block(Vec3::new(2.0, 3.0, 4.0)), 24.0, 1e-5);
        check("cylinder", &cylinder(1.0, 2.0, 64), 2.0 * PI as f64, 0.01);
        check("cone", &cone(1.0, 3.0, 64), PI as f64, 0.01);
        check("frustum", &frustum(2.0, 1.0, 3.0, 64), PI as f64 * 7.0, 0.01);
        check("sphere", &sphere(2.0, 48, 96), 4.0 / 3.0 * PI as f64 * 8.0, 0.01);
        check("torus", &torus(3.0, 1.0, 96, 48), 2.0 * (PI as f64).powi(2) * 3.0, 0.01);
        let gable = [Vec2::new(-2.0, 0.0), Vec2::new(2.0, 0.0), Vec2::new(0.0, 1.5)];
        check("prism", &prism(&gable, 3.0), 3.0 * 3.0, 1e-5);
        check("stairs", &stairs(1.0, 4, 0.2, 0.3), 0.2 * 0.3 * 10.0, 1e-5);
        let straight = tube(&[Vec3::ZERO, Vec3::new(0.0, 0.0, 5.0)], 0.5, 64);
        check("tube", &straight, PI as f64 * 0.25 * 5.0, 0.01);
        // A bent pipe: the volume is about the cross-section times the length
        // of its centre line.
        let bent = round_corners(
            &[Vec3::ZERO, Vec3::new(4.0, 0.0, 0.0), Vec3::new(4.0, 3.0, 0.0), Vec3::new(4.0, 3.0, 2.0)],
            0.8,
            6,
        );
        let length: f32 = bent.windows(2).map(|w| (w[1] - w[0]).length()).sum();
        check("bent tube", &tube(&bent, 0.2, 32), PI as f64 * 0.04 * length as f64, 0.02);
    }

    #[test]
    fn builder_keeps_parts_outward_even_when_mirrored() {
        let mut b = MeshBuilder::new();
        b.add_at(&cylinder(1.0, 1.0, 16), Vec3::X * 5.0);
        b.add(&cuboid(Vec3::ZERO, Vec3::ONE), Mat4::from_scale(Vec3::new(-2.0, 1.0, 1.0)));
        let m = b.build();
        check("merged", &m, signed_volume(&cylinder(1.0, 1.0, 16)) + 2.0, 1e-4);
        assert_eq!(m.triangle_count(), 60 + 12);
    }

    #[test]
    fn triangle_counts_match_their_formulas() {
        assert_eq!(cylinder(1.0, 1.0, 10).triangle_count(), 36);
        assert_eq!(cone(1.0, 1.0, 10).triangle_count(), 18);
        assert_eq!(sphere(1.0, 6, 10).triangle_count(), 100);
        assert_eq!(torus(2.0, 0.5, 12, 6).triangle_count(), 144);
        assert_eq!(stairs(1.0, 5, 0.2, 0.3).triangle_count(), 60);
    }
}
