//! `traffic`: the city (the same blocks and walkthrough as `city` at the
//! same size and seed) with vehicles driving its streets.
//!
//! Every street has two lanes each way. The inner lanes carry cars (small
//! moving occludees) at 8 to 14 m/s; the outer lanes carry buses and trucks
//! (long, tall boxes: moving occluders that hide cars and the street behind
//! them) among slower cars at 6 to 10 m/s. All vehicles of a lane drive at
//! the lane's speed, so they never run into one another; they wrap around
//! at the city's edge and cross the crossings without stopping. A vehicle
//! that would come near the walkthrough's camera is left out, so the camera
//! never drives into one.

use crate::city::{self, FACADES, FACADE_FIRST, LAMP, PITCH, STREET};
use crate::motion::{SceneMotion, Stroke, Track};
use crate::rng::Rng;
use crate::shapes::{cuboid, MeshBuilder};
use crate::walk::EyeTimeline;
use crate::Size;
use glam::{Mat4, Vec3};
use occlude_core::{Mesh, Scene};

/// Distance of the inner (car) lanes' centres from the street's centre
/// line, metres.
const INNER_LANE: f32 = 0.125 * STREET;
/// Distance of the outer (bus) lanes' centres.
const OUTER_LANE: f32 = 0.375 * STREET;
/// The shortest gap between two vehicles of a lane, metres.
const MIN_GAP: f32 = 8.0;
/// The longest.
const MAX_GAP: f32 = 70.0;

/// A car 4.4 m long, 1.8 m wide and 1.45 m high facing `+x`: a body and a
/// cabin, base centred on the origin.
fn car() -> Mesh {
    let mut b = MeshBuilder::new();
    b.add(&cuboid(Vec3::new(-2.2, 0.3, -0.9), Vec3::new(2.2, 0.95, 0.9)), Mat4::IDENTITY);
    b.add(&cuboid(Vec3::new(-1.2, 0.95, -0.8), Vec3::new(1.0, 1.45, 0.8)), Mat4::IDENTITY);
    b.build()
}

/// A bus 12 m long, 2.5 m wide and 3.2 m high facing `+x`.
fn bus() -> Mesh {
    cuboid(Vec3::new(-6.0, 0.3, -1.25), Vec3::new(6.0, 3.2, 1.25))
}

/// A truck 8 m long, 2.5 m wide and 3.6 m high facing `+x`: a cab and a
/// box.
fn truck() -> Mesh {
    let mut b = MeshBuilder::new();
    b.add(&cuboid(Vec3::new(2.2, 0.3, -1.2), Vec3::new(4.0, 2.8, 1.2)), Mat4::IDENTITY);
    b.add(&cuboid(Vec3::new(-4.0, 0.5, -1.25), Vec3::new(2.0, 3.6, 1.25)), Mat4::IDENTITY);
    b.build()
}

/// Builds the city with its traffic, at time 0, and the traffic's motion.
pub(crate) fn generate(size: Size, seed: u64) -> (Scene, SceneMotion) {
    let (blocks, _) = city::layout(size);
    let mut scene = city::generate(size, seed, crate::Inputs::Own);
    scene.name = "traffic".into();
    let span = blocks as f32 * PITCH;
    let eyes = EyeTimeline::new(&scene.path);
    let mut rng = Rng::new(seed, 0x0074_7261_6666);
    let meshes = [scene.add_mesh(car()), scene.add_mesh(bus()), scene.add_mesh(truck())];
    let mut tracks = Vec::new();
    for line in 0..=blocks {
        let across = line as f32 * PITCH;
        for heading in [Vec3::X, Vec3::NEG_X, Vec3::Z, Vec3::NEG_Z] {
            // Drive on the right; a lane runs from the city's edge where its
            // vehicles come in to the edge where they leave.
            let right = heading.cross(Vec3::Y);
            let entry = if heading.x + heading.z > 0.0 { 0.0 } else { span };
            let on_line = |along: f32| {
                if heading.x != 0.0 {
                    Vec3::new(along, 0.0, across)
                } else {
                    Vec3::new(across, 0.0, along)
                }
            };
            let turn = Mat4::from_rotation_y((-heading.z).atan2(heading.x));
            for outer in [false, true] {
                let start = on_line(entry) + right * if outer { OUTER_LANE } else { INNER_LANE };
                let speed = if outer { rng.range(6.0, 10.0) } else { rng.range(8.0, 14.0) };
                let first = rng.range(0.0, MAX_GAP);
                let mut at = first;
                loop {
                    let kind = if outer && rng.chance(0.5) { 1 + rng.below(2) as usize } else { 0 };
                    let mesh = meshes[kind];
                    let length = scene.meshes[mesh as usize].bounds.extent().x;
                    if at + length + MIN_GAP > first + span {
                        break;
                    }
                    let centre = at + 0.5 * length;
                    let track = Track {
                        instance: scene.instances.len() as u32,
                        base: Mat4::from_translation(start) * turn,
                        stroke: Stroke::Loop,
                        offset: heading * span,
                        period: span / speed,
                        phase: (centre / span).fract(),
                        hidden: 0.0..0.0,
                    };
                    let material = if kind == 0 { FACADE_FIRST + rng.below(FACADES) } else { LAMP };
                    at += length + rng.range(MIN_GAP, MAX_GAP);
                    let bounds = scene.meshes[mesh as usize].bounds.transformed(&track.base);
                    if eyes.keeps_clear(&track, &bounds) {
                        scene.add_instance(mesh, track.transform_at(0.0), material);
                        tracks.push(track);
                    }
                }
            }
        }
    }
    (scene, SceneMotion::scripted(tracks))
}
