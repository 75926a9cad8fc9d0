//! `rooms`: furnished rooms walked through from inside, the IOC poster's
//! simple scene (section 3, Figure 3: 2,753 objects in 5k BVH nodes; at
//! `paper` size this one has about as many).
//!
//! The rooms are those of [`building`](crate::building): storeys of square
//! rooms with a door in every inner wall and furniture of a few hundred to a
//! thousand triangles a piece. The walkthrough snakes through every room of
//! the ground floor, row by row, passing each door square to its wall; the
//! furniture in its way is left out, as the city leaves out lamps and trees
//! on its path. From inside a room the walls hide nearly everything else, so
//! every culling method culls most of the scene and none has much to gain
//! over another: the poster finds IOC slower than ROC here.

use crate::building::{self, Doors, DOOR_HEIGHT, ROOM_SIDE};
use crate::walk::{PathBuilder, PathClearance, EYE};
use crate::Size;
use glam::Vec3;
use occlude_core::{CameraPath, Scene};

/// Storeys and rooms along each side of a size.
pub(crate) fn layout(size: Size) -> (u32, u32) {
    size.pick((1, 5), (2, 8), (2, 10))
}

/// Length of the walkthrough, seconds, whatever the number of rooms.
const DURATION: f32 = 30.0;

/// How far before and after a door the walk is square to its wall, metres.
const DOOR_RUN: f32 = 0.9;

/// Builds the rooms.
pub(crate) fn generate(size: Size, seed: u64) -> Scene {
    with_doors(size, seed).0
}

/// Builds the rooms, and where the ground floor's doors are.
pub(crate) fn with_doors(size: Size, seed: u64) -> (Scene, Doors) {
    let (floors, rooms) = layout(size);
    let (mut scene, doors) = building::with_doors(floors, rooms, seed);
    scene.name = "rooms".into();
    scene.path = walkthrough(&doors, rooms);
    let clearance = PathClearance::new(&scene.path);
    scene.instances.retain(|i| !building::is_furniture(i.material) || clearance.is_clear(&i.bounds));
    (scene, doors)
}

/// The snake through the ground floor's `rooms` x `rooms` rooms: from the
/// middle of the first room, through each door (a key before it, in it and
/// after it, so that the walk crosses the wall square to it), to the middle
/// of the last room, at a constant speed.
fn walkthrough(doors: &Doors, rooms: u32) -> CameraPath {
    // Below the lintels by more than the walkthrough's clearance.
    let eye = (DOOR_HEIGHT - 0.6).min(EYE);
    let centre = |i: u32, j: u32| Vec3::new((i as f32 + 0.5) * ROOM_SIDE, eye, (j as f32 + 0.5) * ROOM_SIDE);
    let order: Vec<(u32, u32)> =
        (0..rooms).flat_map(|j| (0..rooms).map(move |k| (if j % 2 == 0 { k } else { rooms - 1 - k }, j))).collect();
    let mut points = vec![centre(order[0].0, order[0].1)];
    for pair in order.windows(2) {
        let ((i, j), (ni, nj)) = (pair[0], pair[1]);
        let (door, normal) = if nj > j {
            (doors.towards_z(i, j), Vec3::Z)
        } else if ni > i {
            (doors.towards_x(i, j), Vec3::X)
        } else {
            (doors.towards_x(ni, j), Vec3::NEG_X)
        };
        let door = door + Vec3::Y * eye;
        points.extend([door - normal * DOOR_RUN, door, door + normal * DOOR_RUN]);
    }
    let last = order[order.len() - 1];
    points.push(centre(last.0, last.1));
    let length: f32 = points.windows(2).map(|p| p[0].distance(p[1])).sum();
    let speed = length / DURATION;
    let mut path = PathBuilder::new();
    for (k, &p) in points.iter().enumerate() {
        let ahead = if k + 1 < points.len() { points[k + 1] - p } else { p - points[k - 1] };
        let seconds = if k == 0 { 0.0 } else { p.distance(points[k - 1]) / speed };
        path.key(seconds, p, p + ahead.normalize() * 3.0);
    }
    path.build()
}
