//! `swarm`: a million small objects between large blocks, the scale of
//! GPU-driven culling (a scene of 1,000,000 instances).
//!
//! Square blocks of a regular grid (20 m across, 8 to 40 m tall, 10 m
//! streets between them) stand on a ground plate; the small objects (boxes,
//! pyramids, spheres and cylinders of 6 to 24 triangles, 0.3 to 1.2 m
//! across) fill the streets up to 8 m above the ground. Seen from a street,
//! the blocks hide every other street, so most objects are occluded by
//! larger ones; seen from above, the blocks hide nothing but each other's
//! feet. The object count is the size's: 4,000 at `small`, 100,000 at
//! `medium` and 1,000,000 at `paper`; the grid grows with it so that a
//! street holds about as many objects per metre at every size but `small`.
//!
//! The walkthrough starts high above a corner with the whole swarm in
//! view, descends into a middle street, flies along it at 3 m, turns into
//! the crossing street, climbs over the blocks and ends beyond the border
//! looking outward (nothing in view).
//!
//! Generation keeps one [`Instance`](occlude_core::Instance) per object and
//! nothing else per object: the instances are reserved once, and the block
//! an object falls on is found by arithmetic on the grid.

use crate::rng::Rng;
use crate::shapes::{cone, cuboid, cylinder, sphere};
use crate::walk::{PathBuilder, PathClearance};
use crate::Size;
use glam::{Mat4, Vec3};
use occlude_core::{CameraPath, Mesh, Scene};

/// Side of a grid cell: a block and a street, metres.
const CELL: f32 = 30.0;
/// Side of a block's square footprint, metres (the street is the rest).
const BLOCK: f32 = 20.0;
/// Height the objects reach above the ground, metres.
const LAYER: f32 = 8.0;
/// Height of the walkthrough inside the streets, metres.
const STREET_EYE: f32 = 3.0;
/// Materials of the objects (0 is the ground, the next one the blocks).
const OBJECT_MATERIALS: u32 = 10;

/// Objects and grid cells per side of a size.
fn layout(size: Size) -> (u32, u32) {
    size.pick((4_000, 6), (100_000, 8), (1_000_000, 24))
}

/// The unit objects (about 1 m across, centred on the origin): 12, 6, 24
/// and 20 triangles.
fn object_meshes() -> Vec<Mesh> {
    let half = Vec3::splat(0.5);
    vec![cuboid(-half, half), cone(0.5, 1.0, 4), sphere(0.5, 3, 6), cylinder(0.4, 1.0, 6)]
}

/// Centre line of street `k` (between block `k` and block `k + 1`).
fn street(k: u32) -> f32 {
    k as f32 * CELL + 0.5 * (BLOCK + CELL)
}

/// The walkthrough over a grid of `cells` x `cells` blocks (module
/// documentation). Its keys out of the streets stay low (12 m), so that
/// the spline through them dips little below the street keys' 3 m.
fn walkthrough(cells: u32) -> CameraPath {
    let side = cells as f32 * CELL;
    let centre = Vec3::new(0.5 * side, 0.0, 0.5 * side);
    let s = street(cells / 2 - 1);
    let mut b = PathBuilder::new();
    b.key(0.0, Vec3::new(-0.3 * side, 0.6 * side, -0.3 * side), centre)
        .key(5.0, Vec3::new(s, 12.0, -15.0), Vec3::new(s, STREET_EYE, 0.3 * side))
        .key(4.0, Vec3::new(s, STREET_EYE, 0.15 * side), Vec3::new(s, STREET_EYE, 0.6 * side))
        .key(5.0, Vec3::new(s, STREET_EYE, s - 8.0), Vec3::new(s + 40.0, STREET_EYE, s))
        .key(5.0, Vec3::new(s + 0.25 * side, STREET_EYE, s), Vec3::new(side, STREET_EYE, s))
        .key(5.0, Vec3::new(0.85 * side, 12.0, s), Vec3::new(0.9 * side, 0.0, 0.8 * side))
        .key(6.0, Vec3::new(1.1 * side, 0.3 * side, 1.1 * side), Vec3::new(1.5 * side, 0.2 * side, 1.5 * side));
    b.build()
}

/// Whether a point of the ground plan lies on a block's footprint.
fn on_block(x: f32, z: f32) -> bool {
    x.rem_euclid(CELL) < BLOCK && z.rem_euclid(CELL) < BLOCK
}

/// Builds the swarm (module documentation).
pub(crate) fn generate(size: Size, seed: u64) -> Scene {
    let (count, cells) = layout(size);
    let side = cells as f32 * CELL;
    let mut scene = Scene::new("swarm");
    scene.path = walkthrough(cells);
    let clearance = PathClearance::new(&scene.path);
    scene.instances.reserve_exact(count as usize + (cells * cells) as usize + 1);

    let ground = scene.add_mesh(cuboid(Vec3::new(-20.0, -0.5, -20.0), Vec3::new(side + 20.0, 0.0, side + 20.0)));
    scene.add_instance(ground, Mat4::IDENTITY, 0);
    let mut rng = Rng::new(seed, 0x5_3A73);
    let block = scene.add_mesh(cuboid(Vec3::ZERO, Vec3::ONE));
    for (i, j) in (0..cells).flat_map(|i| (0..cells).map(move |j| (i, j))) {
        let height = rng.range(8.0, 40.0);
        let at = Vec3::new(i as f32 * CELL, 0.0, j as f32 * CELL);
        let transform = Mat4::from_translation(at) * Mat4::from_scale(Vec3::new(BLOCK, height, BLOCK));
        // A block the walkthrough would pass through is left out (a square).
        if clearance.is_clear(&scene.meshes[block as usize].bounds.transformed(&transform)) {
            scene.add_instance(block, transform, 1);
        }
    }

    let meshes: Vec<u32> = object_meshes().into_iter().map(|m| scene.add_mesh(m)).collect();
    let mut placed = 0;
    while placed < count {
        let mesh = meshes[rng.below(meshes.len() as u32) as usize];
        let s = rng.range(0.3, 1.2);
        let at = rng.point_in(Vec3::new(0.0, 0.6, 0.0), Vec3::new(side, LAYER, side));
        if on_block(at.x, at.z) {
            continue;
        }
        let transform = Mat4::from_scale_rotation_translation(Vec3::splat(s), rng.rotation(), at);
        let material = 2 + rng.below(OBJECT_MATERIALS);
        let bounds = scene.meshes[mesh as usize].bounds.transformed(&transform);
        let clear_of_blocks = [bounds.min, bounds.max, Vec3::new(bounds.min.x, 0.0, bounds.max.z)]
            .into_iter()
            .chain([Vec3::new(bounds.max.x, 0.0, bounds.min.z)])
            .all(|p| !on_block(p.x, p.z));
        if bounds.min.y > 0.0 && clear_of_blocks && clearance.is_clear(&bounds) {
            scene.add_instance(mesh, transform, material);
            placed += 1;
        }
    }
    scene
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn objects_keep_to_the_streets_and_most_are_small() {
        let scene = generate(Size::Small, 1);
        let (count, cells) = layout(Size::Small);
        let blocks = scene.instances.iter().filter(|i| i.material == 1).count();
        assert!(blocks > (cells * cells) as usize / 2, "only {blocks} blocks");
        assert_eq!(scene.instances.len(), 1 + blocks + count as usize);
        for inst in scene.instances.iter().filter(|i| i.material >= 2) {
            let b = inst.bounds;
            // A unit object reaches 1.12 m from its origin, scaled 1.2 at most.
            assert!(b.min.y > 0.0 && b.max.y < LAYER + 1.35, "{b:?} leaves the layer");
            assert!(b.extent().max_element() < 2.7, "{b:?} is no small object");
            for p in [b.min, b.max] {
                assert!(!on_block(p.x, p.z), "{b:?} reaches into a block");
            }
        }
    }

    #[test]
    fn the_paper_size_plans_a_million_objects() {
        assert_eq!(layout(Size::Paper).0, 1_000_000);
        // Street length per object about the same at medium and paper.
        let per_metre = |size| {
            let (count, cells) = layout(size);
            count as f32 / (2.0 * cells as f32 * cells as f32 * CELL)
        };
        let (medium, paper) = (per_metre(Size::Medium), per_metre(Size::Paper));
        assert!(paper / medium < 2.0 && medium / paper < 2.0, "{medium} vs {paper} objects per metre");
    }
}
