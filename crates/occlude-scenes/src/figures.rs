//! `figures`: tens of thousands of geometric figures (spheres, boxes, cones,
//! tori, cylinders of varied sizes and materials) scattered through a volume,
//! like the IOC poster's scene (72k objects at paper size).
//!
//! The walkthrough starts above a corner with the whole volume in view, dives
//! into it and weaves through the figures (each layer hides the next), climbs
//! out above it, and ends at its border looking outward (almost nothing in
//! view).

use crate::rng::Rng;
use crate::shapes::{cone, cuboid, cylinder, sphere, torus, MeshBuilder};
use crate::walk::{PathBuilder, PathClearance};
use crate::Size;
use glam::{Mat4, Vec3};
use occlude_core::{CameraPath, Mesh, Scene};

/// Figures per cubic metre: the mean free path of a sight line is a few tens
/// of metres, so views inside are mostly occluded.
const DENSITY: f32 = 0.02;
/// Number of figure materials (material 0 is the floor).
const FIGURE_MATERIALS: u32 = 15;

/// Figure count, volume height and tessellation (`t`, about the number of
/// sides of a round figure) of a size.
fn layout(size: Size) -> (u32, f32, u32) {
    size.pick((2_000, 24.0, 12), (12_000, 30.0, 20), (72_000, 40.0, 20))
}

/// The unit figures (each about 1 m across, centred on the origin),
/// tessellated with `t` sides.
fn figure_meshes(t: u32) -> Vec<Mesh> {
    let half = Vec3::splat(0.5);
    let centred = |m: Mesh| {
        let mut b = MeshBuilder::new();
        b.add_at(&m, -0.5 * Vec3::Y);
        b.build()
    };
    vec![
        sphere(0.5, (t / 2).max(3), t),
        cuboid(-half, half),
        centred(cone(0.5, 1.0, t)),
        torus(0.4, 0.12, t, (t / 2).max(3)),
        centred(cylinder(0.4, 1.0, t)),
        cuboid(Vec3::new(-0.5, -0.1, -0.5), Vec3::new(0.5, 0.1, 0.5)),
    ]
}

/// The walkthrough for a volume of `side` x `height` x `side` metres.
fn walkthrough(side: f32, height: f32) -> CameraPath {
    let p = |x: f32, y: f32, z: f32| Vec3::new(x * side, y * height, z * side);
    let centre = p(0.5, 0.4, 0.5);
    let mut b = PathBuilder::new();
    b.key(0.0, p(-0.25, 1.5, -0.25), centre)
        .key(3.0, p(-0.05, 0.9, 0.0), centre)
        .key(3.0, p(0.12, 0.5, 0.15), p(0.35, 0.45, 0.3))
        .key(2.5, p(0.3, 0.45, 0.25), p(0.5, 0.55, 0.35))
        .key(2.5, p(0.5, 0.6, 0.35), p(0.65, 0.35, 0.55))
        .key(2.5, p(0.62, 0.35, 0.55), p(0.9, 0.3, 0.5))
        .key(2.5, p(0.58, 0.5, 0.75), p(0.3, 0.5, 0.75))
        .key(2.5, p(0.38, 0.4, 0.7), p(0.2, 0.5, 0.4))
        .key(2.5, p(0.25, 0.6, 0.5), p(0.5, 0.7, 0.5))
        .key(3.0, p(0.45, 1.3, 0.5), p(0.7, 0.2, 0.6))
        .key(3.0, p(0.6, 1.4, 0.8), p(0.5, 0.0, 0.4))
        .key(3.0, p(0.55, 0.5, 1.05), p(0.55, 0.45, 1.6))
        .key(3.0, p(0.4, 0.4, 1.08), p(0.2, 0.4, 1.6));
    b.build()
}

/// Builds the volume of figures.
pub(crate) fn generate(size: Size, seed: u64) -> Scene {
    let (count, height, t) = layout(size);
    let side = (count as f32 / DENSITY / height).sqrt();
    let mut scene = Scene::new("figures");
    scene.path = walkthrough(side, height);
    let clearance = PathClearance::new(&scene.path);

    let floor = scene.add_mesh(cuboid(Vec3::new(-20.0, -0.5, -20.0), Vec3::new(side + 20.0, 0.0, side + 20.0)));
    scene.add_instance(floor, Mat4::IDENTITY, 0);
    let meshes: Vec<u32> = figure_meshes(t).into_iter().map(|m| scene.add_mesh(m)).collect();

    let mut rng = Rng::new(seed, 0xF16_0BE5);
    let lo = Vec3::new(0.0, 1.5, 0.0);
    let hi = Vec3::new(side, height, side);
    let mut placed = 0;
    while placed < count {
        let mesh = meshes[rng.below(meshes.len() as u32) as usize];
        // Sizes from about 0.5 m to 4 m, most of them small.
        let s = 0.5 + 3.5 * rng.unit().powi(3);
        let stretch = Vec3::new(rng.range(0.7, 1.4), rng.range(0.7, 1.4), rng.range(0.7, 1.4));
        let transform = Mat4::from_scale_rotation_translation(stretch * s, rng.rotation(), rng.point_in(lo, hi));
        let material = 1 + rng.below(FIGURE_MATERIALS);
        let bounds = scene.meshes[mesh as usize].bounds.transformed(&transform);
        if bounds.min.y > 0.0 && clearance.is_clear(&bounds) {
            scene.add_instance(mesh, transform, material);
            placed += 1;
        }
    }
    scene
}

/// Figure instances and an estimate of triangles of a size (the mean over the
/// figure kinds), without building the scene.
#[cfg(test)]
pub(crate) fn planned_counts(size: Size) -> (usize, usize) {
    let (count, _, t) = layout(size);
    let meshes = figure_meshes(t);
    let mean = meshes.iter().map(Mesh::triangle_count).sum::<usize>() / meshes.len();
    (count as usize + 1, count as usize * mean + 12)
}
