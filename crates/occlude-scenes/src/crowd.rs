//! `crowd`: the `rooms` building (the same rooms and walkthrough at the same
//! size and seed) with people walking back and forth through its ground
//! floor and doors that open and close.
//!
//! A doorway the walkthrough keeps clear of may get a door: a thin slab that
//! is shown (closed, an occluder) for part of each period and hidden (open)
//! for the rest. People (box-ish figures 1.75 m tall) walk through the other
//! doorways, square to the wall, and back and forth across the rooms (one
//! to three a room), at 1 to 1.5 m/s. A person who would come near the
//! walkthrough's camera is left out, so the camera never walks into one.

use crate::building::{DOOR_HEIGHT, DOOR_WIDTH, FABRIC, ROOM_SIDE, WOOD};
use crate::motion::{SceneMotion, Stroke, Track};
use crate::rng::Rng;
use crate::rooms;
use crate::shapes::{cuboid, MeshBuilder};
use crate::walk::{EyeTimeline, PathClearance};
use crate::Size;
use glam::{Mat4, Vec3};
use occlude_core::{Mesh, Scene};

/// How far before and after a doorway a person walking through it turns.
const THROUGH: f32 = 1.6;
/// How far from the walls a person walking across a room turns.
const WALL_GAP: f32 = 0.7;
/// Thickness of a door leaf.
const LEAF: f32 = 0.06;

/// A person 1.75 m tall facing `+x`: legs, a torso and a head, feet
/// centred on the origin.
fn person() -> Mesh {
    let mut b = MeshBuilder::new();
    b.add(&cuboid(Vec3::new(-0.12, 0.0, -0.18), Vec3::new(0.12, 0.85, 0.18)), Mat4::IDENTITY);
    b.add(&cuboid(Vec3::new(-0.14, 0.85, -0.24), Vec3::new(0.14, 1.5, 0.24)), Mat4::IDENTITY);
    b.add(&cuboid(Vec3::new(-0.11, 1.52, -0.1), Vec3::new(0.11, 1.75, 0.1)), Mat4::IDENTITY);
    b.build()
}

/// A door leaf filling a doorway in a wall along `x`, centred on the
/// origin's vertical, from the floor up.
fn door() -> Mesh {
    let h = 0.5 * DOOR_WIDTH - 0.01;
    cuboid(Vec3::new(-h, 0.0, -0.5 * LEAF), Vec3::new(h, DOOR_HEIGHT - 0.01, 0.5 * LEAF))
}

/// The turn that makes a mesh facing `+x` face `heading` (horizontal).
fn facing(heading: Vec3) -> Mat4 {
    Mat4::from_rotation_y((-heading.z).atan2(heading.x))
}

/// Builds the rooms with their people and doors, at time 0, and their
/// motion.
pub(crate) fn generate(size: Size, seed: u64) -> (Scene, SceneMotion) {
    let (_, rooms) = rooms::layout(size);
    let (mut scene, doors) = rooms::with_doors(size, seed);
    scene.name = "crowd".into();
    let clearance = PathClearance::new(&scene.path);
    let eyes = EyeTimeline::new(&scene.path);
    let mut rng = Rng::new(seed, 0x0063_726f_7764);
    let person = scene.add_mesh(person());
    let door = scene.add_mesh(door());
    let mut tracks = Vec::new();
    // Adds the instance of `mesh` that `track` moves if it keeps clear of
    // the camera.
    let mut add = |scene: &mut Scene, mesh: u32, track: Track, material: u32| {
        let bounds = scene.meshes[mesh as usize].bounds.transformed(&track.base);
        if eyes.keeps_clear(&track, &bounds) {
            scene.add_instance(mesh, track.transform_at(0.0), material);
            scene.instances[track.instance as usize].enabled = !track.is_hidden(0.0);
            tracks.push(track);
        }
    };
    let walker = |rng: &mut Rng, instance: u32, from: Vec3, to: Vec3| Track {
        instance,
        base: Mat4::from_translation(from) * facing(to - from),
        stroke: Stroke::Shuttle,
        offset: to - from,
        period: 2.0 * from.distance(to) / rng.range(1.0, 1.5),
        phase: rng.unit(),
        hidden: 0.0..0.0,
    };
    for (centre, normal) in doors.all().collect::<Vec<_>>() {
        let instance = scene.instances.len() as u32;
        let base = Mat4::from_translation(centre) * facing(normal.cross(Vec3::Y));
        if rng.chance(0.5) && clearance.is_clear(&scene.meshes[door as usize].bounds.transformed(&base)) {
            let track = Track {
                instance,
                base,
                stroke: Stroke::Shuttle,
                offset: Vec3::ZERO,
                period: rng.range(6.0, 12.0),
                phase: rng.unit(),
                hidden: 0.0..rng.range(0.3, 0.6),
            };
            add(&mut scene, door, track, WOOD);
        } else {
            let track = walker(&mut rng, instance, centre - normal * THROUGH, centre + normal * THROUGH);
            add(&mut scene, person, track, FABRIC);
        }
    }
    for i in 0..rooms {
        for j in 0..rooms {
            let corner = Vec3::new(i as f32, 0.0, j as f32) * ROOM_SIDE;
            for _ in 0..1 + rng.below(3) {
                let across = rng.range(WALL_GAP, ROOM_SIDE - WALL_GAP);
                let (from, to) = if rng.chance(0.5) {
                    (Vec3::new(WALL_GAP, 0.0, across), Vec3::new(ROOM_SIDE - WALL_GAP, 0.0, across))
                } else {
                    (Vec3::new(across, 0.0, WALL_GAP), Vec3::new(across, 0.0, ROOM_SIDE - WALL_GAP))
                };
                let track = walker(&mut rng, scene.instances.len() as u32, corner + from, corner + to);
                add(&mut scene, person, track, FABRIC);
            }
        }
    }
    (scene, SceneMotion::scripted(tracks))
}
