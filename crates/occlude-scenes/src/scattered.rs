//! `scattered`: `N` randomly placed and rotated objects of 606 triangles
//! each in a cube, seen from outside by a camera circling it: the setting of
//! the granular-visibility-queries paper's section 4.1 (Tables 1 and 2: 100
//! to 500 "randomly placed objects", "each object consists of 606
//! triangles"). The paper does not say what the objects are; here each is
//! a torus of 101 segments around a triangular tube (`2 x 101 x 3` = 606
//! triangles), about 2.2 m across, and the cube's side is fixed (not
//! scaled with `N`), so that more objects overlap more on the screen, as in
//! the paper. Not one of the sizes of `generate`: the count is the
//! experiment's variable.

use crate::rng::Rng;
use crate::shapes::torus;
use crate::walk::PathBuilder;
use glam::{Mat4, Vec3};
use occlude_core::{CameraPath, Scene};

/// Triangles of each object (the paper's).
pub const OBJECT_TRIANGLES: usize = 606;

/// Side of the cube the objects' centres are drawn from, metres.
const CUBE: f32 = 24.0;

/// Distance of the circling camera from the cube's centre, metres.
const ORBIT: f32 = 36.0;

/// Materials the objects are spread over.
const MATERIALS: u32 = 4;

/// A camera circling the cube once in 8 s (four quarter turns), looking at
/// its centre from a little above.
fn orbit() -> CameraPath {
    let centre = Vec3::splat(0.5 * CUBE);
    let mut b = PathBuilder::new();
    for k in 0..=4 {
        let a = std::f32::consts::FRAC_PI_2 * k as f32;
        let eye = centre + Vec3::new(ORBIT * a.cos(), 0.3 * ORBIT, ORBIT * a.sin());
        b.key(if k == 0 { 0.0 } else { 2.0 }, eye, centre);
    }
    b.build()
}

/// `objects` objects placed from `seed` (module documentation).
pub fn scattered(objects: u32, seed: u64) -> Scene {
    let mut scene = Scene::new(format!("scattered-{objects}"));
    scene.path = orbit();
    let mesh = scene.add_mesh(torus(0.8, 0.3, 101, 3));
    let mut rng = Rng::new(seed, 0x5CA7_7E4D);
    for _ in 0..objects {
        let at = rng.point_in(Vec3::ZERO, Vec3::splat(CUBE));
        let transform = Mat4::from_translation(at) * Mat4::from_quat(rng.rotation());
        scene.add_instance(mesh, transform, rng.below(MATERIALS));
    }
    scene
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_object_has_the_papers_triangles_and_the_scene_is_valid() {
        let scene = scattered(120, 1);
        scene.validate().unwrap();
        assert_eq!(scene.instances.len(), 120);
        assert_eq!(scene.meshes[0].triangle_count(), OBJECT_TRIANGLES);
        assert_eq!(scene.triangle_count(), 120 * OBJECT_TRIANGLES);
        let transforms = |s: &Scene| s.instances.iter().map(|i| i.transform).collect::<Vec<_>>();
        assert_eq!(transforms(&scattered(120, 1)), transforms(&scene), "deterministic");
        assert_ne!(transforms(&scattered(120, 2)), transforms(&scene));
    }
}
