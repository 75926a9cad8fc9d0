//! Clipping of clip-space triangles against the near plane and a guard band.
//!
//! Clipping runs in `f64` on homogeneous coordinates. A clipped vertex is always
//! computed from the inside endpoint of an edge towards the outside endpoint, so two
//! triangles sharing an edge produce bit-identical clipped vertices on it, which keeps
//! shared edges watertight after snapping.

use glam::{DVec4, Vec4};

/// Most vertices a clipped triangle can have: 3, plus one per clipping plane (5).
pub(super) const MAX_POLY: usize = 8;

/// Pixels the guard band extends beyond each side of the viewport. Geometry beyond
/// it is clipped away, which bounds the fixed-point coordinates (see `setup`).
pub(super) const GUARD_PIXELS: f64 = 8192.0;

/// A convex polygon in clip space, the result of clipping one triangle.
pub(super) struct Polygon {
    /// Vertices in order; only the first `len` are valid.
    pub verts: [DVec4; MAX_POLY],
    /// Number of valid vertices.
    pub len: usize,
}

impl Polygon {
    /// An empty polygon, used as scratch space.
    pub fn new() -> Self {
        Self { verts: [DVec4::ZERO; MAX_POLY], len: 0 }
    }

    /// The valid vertices.
    pub fn as_slice(&self) -> &[DVec4] {
        &self.verts[..self.len]
    }
}

/// Guard-band extents in NDC units: geometry is kept where `|x| <= gx * w` and
/// `|y| <= gy * w`.
#[derive(Clone, Copy, Debug)]
pub(super) struct GuardBand {
    /// Horizontal extent, in multiples of `w`.
    pub gx: f64,
    /// Vertical extent, in multiples of `w`.
    pub gy: f64,
}

impl GuardBand {
    /// The guard band of a `width` x `height` viewport: `GUARD_PIXELS` beyond each side.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            gx: 1.0 + 2.0 * GUARD_PIXELS / f64::from(width.max(1)),
            gy: 1.0 + 2.0 * GUARD_PIXELS / f64::from(height.max(1)),
        }
    }

    /// Signed distances of `v` to the five clipping planes (inside where `>= 0`):
    /// near (`z >= 0`), then the four guard-band planes.
    fn distances(self, v: DVec4) -> [f64; 5] {
        [v.z, self.gx * v.w - v.x, self.gx * v.w + v.x, self.gy * v.w - v.y, self.gy * v.w + v.y]
    }
}

/// What clipping a triangle left of it.
pub(super) enum Clipped {
    /// Nothing that can cover a pixel centre: a non-finite coordinate, or a
    /// triangle crossing a clipping plane that lies entirely behind the near plane
    /// or outside one side of the viewport.
    Outside,
    /// The whole triangle (in `f64`), inside every clipping plane; it may still lie
    /// off the viewport, which its set-up finds.
    Inside([DVec4; 3]),
    /// The polygon left in the `out` argument of [`clip_triangle`].
    Polygon,
}

/// Clips `tri` to the near plane and the guard band; a clipped polygon is written to
/// `out`.
pub(super) fn clip_triangle(tri: &[Vec4; 3], guard: GuardBand, out: &mut Polygon) -> Clipped {
    if !tri.iter().all(|v| v.is_finite()) {
        return Clipped::Outside;
    }
    let verts = tri.map(|v| v.as_dvec4());

    let mask =
        |v: DVec4| guard.distances(v).iter().enumerate().fold(0u8, |m, (plane, &d)| m | u8::from(d < 0.0) << plane);
    let crossed = mask(verts[0]) | mask(verts[1]) | mask(verts[2]);
    if crossed == 0 {
        // Inside the guard band, the usual case: one that is off the viewport
        // covers no pixel, which its set-up finds.
        return Clipped::Inside(verts);
    }

    // Trivial rejection against the near plane and the viewport sides: if all three
    // vertices are outside one of these planes, so is every point of the triangle.
    let outside = |v: DVec4| {
        u8::from(v.z < 0.0)
            | u8::from(v.w - v.x < 0.0) << 1
            | u8::from(v.w + v.x < 0.0) << 2
            | u8::from(v.w - v.y < 0.0) << 3
            | u8::from(v.w + v.y < 0.0) << 4
    };
    if outside(verts[0]) & outside(verts[1]) & outside(verts[2]) != 0 {
        return Clipped::Outside;
    }
    out.verts[..3].copy_from_slice(&verts);
    out.len = 3;
    let mut scratch = Polygon::new();
    for plane in 0..5 {
        if crossed & (1 << plane) != 0 {
            clip_plane(out, &mut scratch, |v| guard.distances(v)[plane]);
            std::mem::swap(out, &mut scratch);
            if out.len < 3 {
                return Clipped::Outside;
            }
        }
    }
    Clipped::Polygon
}

/// One Sutherland-Hodgman step: clips `input` against the half-space `dist >= 0`.
fn clip_plane(input: &Polygon, output: &mut Polygon, dist: impl Fn(DVec4) -> f64) {
    output.len = 0;
    let n = input.len;
    for i in 0..n {
        let cur = input.verts[i];
        let next = input.verts[(i + 1) % n];
        let (dc, dn) = (dist(cur), dist(next));
        if dc >= 0.0 {
            output.verts[output.len] = cur;
            output.len += 1;
        }
        if (dc >= 0.0) != (dn >= 0.0) {
            // Always interpolate from the inside vertex, so that the same edge gives
            // the same point whichever triangle (and direction) it is clipped in.
            let (vin, din, vout, dout) = if dc >= 0.0 { (cur, dc, next, dn) } else { (next, dn, cur, dc) };
            let t = din / (din - dout);
            output.verts[output.len] = vin + (vout - vin) * t;
            output.len += 1;
        }
    }
}
