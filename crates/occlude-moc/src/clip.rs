//! Near-plane clipping in clip space (wgpu: visible `0 <= z <= w`).
//!
//! Triangles are clipped to `z >= 0` in clip space before the divide, so no
//! vertex behind the eye is projected; a clipped polygon with a vertex at
//! `w <= 0` or beyond `10^9` pixels is not drawn (an occluder left out only
//! makes the buffer cull less).

use glam::Vec4;

/// Clips the triangle `t` to `z >= 0`, writing a convex polygon of up to 4
/// vertices into `out`; returns how many (0 when entirely in front of the near
/// plane's wrong side). Vertices with a NaN coordinate make the polygon empty.
pub(crate) fn clip_near(t: [Vec4; 3], out: &mut [Vec4; 4]) -> usize {
    if t.iter().any(|v| !v.is_finite()) {
        return 0;
    }
    let mut n = 0;
    for i in 0..3 {
        let (a, b) = (t[i], t[(i + 1) % 3]);
        if a.z >= 0.0 {
            out[n] = a;
            n += 1;
        }
        if (a.z >= 0.0) != (b.z >= 0.0) {
            let s = a.z / (a.z - b.z);
            let mut p = a + (b - a) * s;
            p.z = p.z.max(0.0);
            out[n] = p;
            n += 1;
        }
    }
    n
}
