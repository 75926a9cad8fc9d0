//! Conservativeness against a simple exact reference written here (vertices
//! snapped to 1/256 pixel as a rasterizer snaps them, per pixel centre edge
//! test in f64, depth by interpolating NDC z), and coverage checks.

use glam::{Mat4, Vec2, Vec3, Vec4};
use occlude_moc::{CullMode, MaskedBuffer, MergeMode, Visibility};

struct Lcg(u64);
impl Lcg {
    fn unit(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// Exact depth buffer of a rasterizer with 8 sub-pixel bits: vertices snapped
/// to 1/256 pixel, pixel centres inside (edges inclusive, more coverage than
/// the masked buffer takes), near-clipped triangles, nearest NDC z kept.
fn reference(w: u32, h: u32, tris: &[[Vec3; 3]]) -> Vec<f64> {
    let mut depth = vec![1.0f64; (w * h) as usize];
    for t in tris {
        let c = t.map(|p| p.extend(1.0));
        // Clip against z >= 0 (here w = 1 - z' style: use the identity transform, w = 1).
        let poly: Vec<Vec4> = {
            let mut out = Vec::new();
            for i in 0..3 {
                let (a, b) = (c[i], c[(i + 1) % 3]);
                if a.z >= 0.0 {
                    out.push(a);
                }
                if (a.z >= 0.0) != (b.z >= 0.0) {
                    out.push(a + (b - a) * (a.z / (a.z - b.z)));
                }
            }
            out
        };
        let s: Vec<[f64; 3]> = poly
            .iter()
            .map(|v| {
                let snap = |p: f64| (p * 256.0).round() / 256.0;
                [snap((v.x as f64 + 1.0) * 0.5 * w as f64), snap((1.0 - v.y as f64) * 0.5 * h as f64), v.z as f64]
            })
            .collect();
        for k in 1..s.len().saturating_sub(1) {
            let (a, b, cc) = (s[0], s[k], s[k + 1]);
            let area = (b[0] - a[0]) * (cc[1] - a[1]) - (cc[0] - a[0]) * (b[1] - a[1]);
            if area == 0.0 {
                continue;
            }
            for y in 0..h {
                for x in 0..w {
                    let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                    let e = |p: [f64; 3], q: [f64; 3]| (q[0] - p[0]) * (py - p[1]) - (q[1] - p[1]) * (px - p[0]);
                    let (l0, l1, l2) = (e(b, cc) / area, e(cc, a) / area, e(a, b) / area);
                    if l0 >= 0.0 && l1 >= 0.0 && l2 >= 0.0 {
                        let z = l0 * a[2] + l1 * b[2] + l2 * cc[2];
                        let d = &mut depth[(y * w + x) as usize];
                        *d = d.min(z);
                    }
                }
            }
        }
    }
    depth
}

#[test]
fn never_occluded_when_exact_depth_shows_a_pixel() {
    let mut rng = Lcg(7);
    let (mut drawn, mut occluded) = (0usize, 0usize);
    for &(w, h) in &[(1u32, 1u32), (37, 23), (97, 61)] {
        for mode in [MergeMode::LayerMerge, MergeMode::QuickMask] {
            for round in 0..20 {
                let tris: Vec<[Vec3; 3]> = (0..1 + round % 12)
                    .map(|_| {
                        let c = Vec2::new(rng.unit() * 2.4 - 1.2, rng.unit() * 2.4 - 1.2);
                        let r = 0.2 + rng.unit() * 1.5;
                        [0, 1, 2].map(|_| {
                            let z = rng.unit() * 1.1 - 0.1; // some cross the near plane
                            (c + Vec2::new(rng.unit() - 0.5, rng.unit() - 0.5) * r).extend(z)
                        })
                    })
                    .collect();
                let mut buffer = MaskedBuffer::new(w, h).unwrap();
                buffer.merge = mode;
                let positions: Vec<Vec3> = tris.iter().flatten().copied().collect();
                let indices: Vec<u32> = (0..positions.len() as u32).collect();
                buffer.render_triangles(&positions, &indices, Mat4::IDENTITY, CullMode::None);
                let exact = reference(w, h, &tris);
                let mut image = Vec::new();
                buffer.depth_image(&mut image);
                drawn += image.iter().filter(|&&b| b < 1.0).count();
                for (i, (&b, &e)) in image.iter().zip(&exact).enumerate() {
                    assert!(b as f64 >= e - 1e-6, "{w}x{h} pixel {i}: bound {b} nearer than exact {e}");
                }
                for _ in 0..50 {
                    let a = Vec2::new(rng.unit() * w as f32, rng.unit() * h as f32);
                    let b = a + Vec2::new(rng.unit() * 20.0, rng.unit() * 10.0);
                    let z = rng.unit();
                    let shown = (0..h).any(|y| {
                        (0..w).any(|x| {
                            let inside = x as f32 >= a.x.floor()
                                && x as f32 <= b.x.floor()
                                && y as f32 >= a.y.floor()
                                && y as f32 <= b.y.floor();
                            inside && (z as f64) < exact[(y * w + x) as usize]
                        })
                    });
                    let v = buffer.test_rect(a, b, z);
                    occluded += usize::from(v == Visibility::Occluded);
                    if shown {
                        assert_eq!(v, Visibility::Visible, "{w}x{h} {a} {b} {z}");
                    }
                }
            }
        }
    }
    assert!(drawn > 1000 && occluded > 20, "drawn {drawn}, occluded {occluded}");
}

fn quad(z: f32) -> ([Vec3; 4], [u32; 6]) {
    (
        [Vec3::new(-1.0, -1.0, z), Vec3::new(1.0, -1.0, z), Vec3::new(1.0, 1.0, z), Vec3::new(-1.0, 1.0, z)],
        [0, 1, 2, 0, 2, 3],
    )
}

#[test]
fn screen_quad_occludes_boxes_behind_and_not_in_front() {
    for mode in [MergeMode::LayerMerge, MergeMode::QuickMask] {
        for &(w, h) in &[(1u32, 1u32), (37, 23), (641, 479)] {
            let mut buffer = MaskedBuffer::new(w, h).unwrap();
            buffer.merge = mode;
            let (p, i) = quad(0.5);
            buffer.render_triangles(&p, &i, Mat4::IDENTITY, CullMode::Back);
            let behind = buffer.test_aabb(Vec3::new(-0.9, -0.9, 0.6), Vec3::new(0.9, 0.9, 0.9), Mat4::IDENTITY);
            assert_eq!(behind, Visibility::Occluded, "{mode:?} {w}x{h}");
            let front = buffer.test_aabb(Vec3::new(-0.3, -0.3, 0.1), Vec3::new(0.3, 0.3, 0.4), Mat4::IDENTITY);
            assert_eq!(front, Visibility::Visible);
            let away = buffer.test_aabb(Vec3::new(2.0, 2.0, 0.6), Vec3::new(3.0, 3.0, 0.9), Mat4::IDENTITY);
            assert_eq!(away, Visibility::ViewCulled);
        }
    }
}

#[test]
fn back_faces_culled_and_bad_input_skipped() {
    let mut buffer = MaskedBuffer::new(64, 32).unwrap();
    let (p, _) = quad(0.5);
    buffer.render_triangles(&p, &[0, 2, 1, 0, 3, 2], Mat4::IDENTITY, CullMode::Back);
    buffer.render_triangles(&p, &[0, 1, 9, 0, 0, 0], Mat4::IDENTITY, CullMode::None);
    buffer.render_triangles(&[Vec3::NAN; 3], &[0, 1, 2], Mat4::IDENTITY, CullMode::None);
    let mut image = Vec::new();
    buffer.depth_image(&mut image);
    assert!(image.iter().all(|&d| d == 1.0));
    assert!(MaskedBuffer::new(0, 5).is_err());
}
