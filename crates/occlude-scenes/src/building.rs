//! A generated building to be written as a model file ([`crate::export`])
//! and imported: the imported model with real occlusion that the import tests
//! and benchmarks walk through, exercising the import path (glTF nodes,
//! instancing, the automatic walk). The procedural scene `rooms` is built
//! from it, with a walkthrough through the doors of its ground floor.
//!
//! Every floor is a square grid of rooms. Walls between rooms have a door
//! (1.2 m x 2.1 m) at a random place; outer walls are closed. Each room has
//! its own floor and ceiling slab and a random set of furniture (a table with
//! chairs, a sofa, a bookshelf, a floor lamp, a potted plant), each piece an
//! instance of a shared mesh of a few hundred to a thousand triangles, as in
//! architectural models. Tall pieces stand in corners, clear of the doors, so
//! the automatic walk finds its way from room to room on the ground floor;
//! the floors above are hidden behind the ceiling.

use crate::rng::Rng;
use crate::shapes::{cuboid, cylinder, frustum, sphere, MeshBuilder};
use glam::{Mat4, Quat, Vec3};
use occlude_core::{Mesh, Scene};

/// Room side, wall centre to wall centre, metres.
const ROOM: f32 = 5.0;
/// Floor to floor height.
const STOREY: f32 = 3.2;
/// Thickness of floor slabs and walls.
const SLAB: f32 = 0.2;
/// Door opening width and height.
const DOOR: (f32, f32) = (1.2, 2.1);

// Materials.
const WALLS: u32 = 0;
const FLOORS: u32 = 1;
pub(crate) const WOOD: u32 = 2;
pub(crate) const FABRIC: u32 = 3;
const METAL: u32 = 4;
const LEAVES: u32 = 5;
const BOOKS: u32 = 6;
const MATERIALS: u32 = 7;

/// Whether instances of `material` are furniture (not walls or slabs).
pub(crate) fn is_furniture(material: u32) -> bool {
    !matches!(material, WALLS | FLOORS)
}

/// The shared meshes of a building.
struct Meshes {
    /// The unit cube `[0, 1]³`, scaled into walls and slabs.
    cube: u32,
    table: u32,
    chair: u32,
    sofa: u32,
    shelf: u32,
    books: u32,
    lamp: u32,
    plant: u32,
}

/// A table 1.6 x 0.9 m, 0.75 m high, base centred on the origin.
fn table() -> Mesh {
    let mut b = MeshBuilder::new();
    b.add(&cuboid(Vec3::new(-0.8, 0.71, -0.45), Vec3::new(0.8, 0.75, 0.45)), Mat4::IDENTITY);
    for (x, z) in [(-0.7, -0.35), (0.7, -0.35), (-0.7, 0.35), (0.7, 0.35)] {
        b.add_at(&cylinder(0.03, 0.71, 12), Vec3::new(x, 0.0, z));
    }
    b.build()
}

/// A chair facing `+z`, seat 0.45 m high.
fn chair() -> Mesh {
    let mut b = MeshBuilder::new();
    b.add(&cuboid(Vec3::new(-0.22, 0.42, -0.22), Vec3::new(0.22, 0.46, 0.22)), Mat4::IDENTITY);
    b.add(&cuboid(Vec3::new(-0.22, 0.46, -0.22), Vec3::new(0.22, 0.9, -0.19)), Mat4::IDENTITY);
    for (x, z) in [(-0.19, -0.19), (0.19, -0.19), (-0.19, 0.19), (0.19, 0.19)] {
        b.add_at(&cylinder(0.02, 0.42, 10), Vec3::new(x, 0.0, z));
    }
    b.build()
}

/// A sofa 2 m wide facing `+z`, with round arm rests and cushions.
fn sofa() -> Mesh {
    let mut b = MeshBuilder::new();
    b.add(&cuboid(Vec3::new(-0.9, 0.1, -0.45), Vec3::new(0.9, 0.4, 0.45)), Mat4::IDENTITY);
    b.add(&cuboid(Vec3::new(-0.9, 0.4, -0.45), Vec3::new(0.9, 0.85, -0.25)), Mat4::IDENTITY);
    for x in [-0.45, 0.45] {
        b.add(&cuboid(Vec3::new(x - 0.43, 0.4, -0.25), Vec3::new(x + 0.43, 0.52, 0.43)), Mat4::IDENTITY);
    }
    let lying = Quat::from_rotation_x(std::f32::consts::FRAC_PI_2);
    for x in [-1.0, 1.0] {
        b.add(&cylinder(0.12, 0.9, 20), Mat4::from_rotation_translation(lying, Vec3::new(x, 0.5, -0.45)));
        b.add(&cuboid(Vec3::new(x - 0.1, 0.0, -0.45), Vec3::new(x + 0.1, 0.5, 0.45)), Mat4::IDENTITY);
    }
    b.build()
}

/// An open bookshelf 0.9 m wide, 0.35 m deep, 2 m high, against `-z`.
fn shelf() -> Mesh {
    let mut b = MeshBuilder::new();
    b.add(&cuboid(Vec3::new(-0.45, 0.0, -0.175), Vec3::new(-0.43, 2.0, 0.175)), Mat4::IDENTITY);
    b.add(&cuboid(Vec3::new(0.43, 0.0, -0.175), Vec3::new(0.45, 2.0, 0.175)), Mat4::IDENTITY);
    b.add(&cuboid(Vec3::new(-0.43, 0.0, -0.175), Vec3::new(0.43, 2.0, -0.16)), Mat4::IDENTITY);
    for k in 0..6 {
        let y = k as f32 * 0.39;
        b.add(&cuboid(Vec3::new(-0.43, y, -0.16), Vec3::new(0.43, y + 0.02, 0.175)), Mat4::IDENTITY);
    }
    b.build()
}

/// The books of a [`shelf`]: rows of volumes of varied height and width.
fn books(rng: &mut Rng) -> Mesh {
    let mut b = MeshBuilder::new();
    for k in 0..5 {
        let y = k as f32 * 0.39 + 0.02;
        let mut x = -0.42;
        while x < 0.38 {
            let width = rng.range(0.02, 0.05);
            let height = rng.range(0.2, 0.33);
            b.add(&cuboid(Vec3::new(x, y, -0.15), Vec3::new(x + width, y + height, 0.1)), Mat4::IDENTITY);
            x += width + 0.003;
        }
    }
    b.build()
}

/// A floor lamp 1.8 m high: base, pole, shade and bulb.
fn lamp() -> Mesh {
    let mut b = MeshBuilder::new();
    b.add_at(&cylinder(0.18, 0.03, 32), Vec3::ZERO);
    b.add_at(&cylinder(0.015, 1.5, 12), Vec3::new(0.0, 0.03, 0.0));
    b.add_at(&frustum(0.25, 0.12, 0.3, 48), Vec3::new(0.0, 1.5, 0.0));
    b.add_at(&sphere(0.06, 12, 24), Vec3::new(0.0, 1.55, 0.0));
    b.build()
}

/// A potted plant 1.6 m high: a pot, a stem and a round crown of leaves.
fn plant() -> Mesh {
    let mut b = MeshBuilder::new();
    b.add_at(&frustum(0.15, 0.2, 0.35, 32), Vec3::ZERO);
    b.add_at(&cylinder(0.02, 1.0, 8), Vec3::new(0.0, 0.35, 0.0));
    b.add(
        &sphere(0.35, 16, 32),
        Mat4::from_scale_rotation_translation(Vec3::new(1.0, 0.8, 1.0), Quat::IDENTITY, Vec3::new(0.0, 1.3, 0.0)),
    );
    b.build()
}

/// A building of `floors` storeys of `rooms` x `rooms` rooms, deterministic
/// from `seed` (see the module documentation), with no walkthrough: importing
/// it makes one. A room has about 4 thousand triangles on average: 3 floors
/// of 6 x 6 rooms have 449,792 in 1,580 instances of 8 meshes.
pub fn generate(floors: u32, rooms: u32, seed: u64) -> Scene {
    with_doors(floors, rooms, seed).0
}

/// Where the doors of the ground floor are, for a walkthrough through them.
pub(crate) struct Doors {
    rooms: u32,
    /// Per wall along x (`line * rooms + k`: the wall at `z = line * ROOM`
    /// beside room `k`), the `x` of its door's centre; NaN without a door.
    along_x: Vec<f32>,
    /// The same for walls along z (at `x = line * ROOM`): the `z` of the
    /// door's centre.
    along_z: Vec<f32>,
}

impl Doors {
    /// The centre of the door between rooms `(i, j)` and `(i + 1, j)` (rooms
    /// counted along x and z), at floor height.
    pub(crate) fn towards_x(&self, i: u32, j: u32) -> Vec3 {
        let line = i + 1;
        Vec3::new(line as f32 * ROOM, 0.0, self.along_z[(line * self.rooms + j) as usize])
    }

    /// Every door of the ground floor: its centre at floor height, and the
    /// normal of its wall (`+x` or `+z`).
    pub(crate) fn all(&self) -> impl Iterator<Item = (Vec3, Vec3)> + '_ {
        let line = |k: usize| (k as u32 / self.rooms) as f32 * ROOM;
        let along_x = self.along_x.iter().enumerate().map(move |(k, &x)| (Vec3::new(x, 0.0, line(k)), Vec3::Z));
        let along_z = self.along_z.iter().enumerate().map(move |(k, &z)| (Vec3::new(line(k), 0.0, z), Vec3::X));
        along_x.chain(along_z).filter(|(centre, _)| !centre.is_nan())
    }

    /// The centre of the door between rooms `(i, j)` and `(i, j + 1)`.
    pub(crate) fn towards_z(&self, i: u32, j: u32) -> Vec3 {
        let line = j + 1;
        Vec3::new(self.along_x[(line * self.rooms + i) as usize], 0.0, line as f32 * ROOM)
    }
}

/// The room side, for walkthroughs: room `(i, j)` spans `[i, i + 1] * ROOM`
/// along x and `[j, j + 1] * ROOM` along z.
pub(crate) const ROOM_SIDE: f32 = ROOM;

/// The lowest height above a floor at which a door's lintel starts.
pub(crate) const DOOR_HEIGHT: f32 = DOOR.1;

/// The width of a door's opening.
pub(crate) const DOOR_WIDTH: f32 = DOOR.0;

/// [`generate`], and where the ground floor's doors are.
pub(crate) fn with_doors(floors: u32, rooms: u32, seed: u64) -> (Scene, Doors) {
    let walls = ((rooms + 1) * rooms) as usize;
    let mut doors = Doors { rooms, along_x: vec![f32::NAN; walls], along_z: vec![f32::NAN; walls] };
    let mut scene = Scene::new("building");
    scene.material_count = MATERIALS;
    let mut rng = Rng::new(seed, 0x0062_7569_6c64);
    let meshes = Meshes {
        cube: scene.add_mesh(cuboid(Vec3::ZERO, Vec3::ONE)),
        table: scene.add_mesh(table()),
        chair: scene.add_mesh(chair()),
        sofa: scene.add_mesh(sofa()),
        shelf: scene.add_mesh(shelf()),
        books: scene.add_mesh(books(&mut rng)),
        lamp: scene.add_mesh(lamp()),
        plant: scene.add_mesh(plant()),
    };
    let boxed = |scene: &mut Scene, min: Vec3, max: Vec3, material: u32| {
        scene.add_instance(
            meshes.cube,
            Mat4::from_scale_rotation_translation(max - min, Quat::IDENTITY, min),
            material,
        );
    };
    for floor in 0..=floors {
        let y = floor as f32 * STOREY;
        // Slabs: the floor of this storey, the ceiling of the one below.
        for i in 0..rooms {
            for j in 0..rooms {
                let (x, z) = (i as f32 * ROOM, j as f32 * ROOM);
                boxed(&mut scene, Vec3::new(x, y - SLAB, z), Vec3::new(x + ROOM, y, z + ROOM), FLOORS);
            }
        }
        if floor == floors {
            break;
        }
        let top = y + STOREY - SLAB;
        // Walls along x (on z = line) and along z (on x = line), one per room
        // side; inner ones have a door. Walls along x reach over the corners.
        for line in 0..=rooms {
            let (c, inner) = (line as f32 * ROOM, line > 0 && line < rooms);
            for k in 0..rooms {
                let (start, end) = (k as f32 * ROOM, (k + 1) as f32 * ROOM);
                for along_x in [true, false] {
                    // A wall piece from `a` to `b` along the wall, from `lo` up.
                    let piece = |a: f32, b: f32, lo: f32| {
                        let at = |along: f32, y: f32, across: f32| {
                            if along_x {
                                Vec3::new(along, y, across)
                            } else {
                                Vec3::new(across, y, along)
                            }
                        };
                        (at(a, lo, c - SLAB / 2.0), at(b, top, c + SLAB / 2.0))
                    };
                    let reach = if along_x { SLAB / 2.0 } else { -SLAB / 2.0 };
                    let (a, b) = (start - reach, end + reach);
                    let parts = if inner {
                        let door = start + rng.range(1.6, ROOM - 1.6);
                        if floor == 0 {
                            let list = if along_x { &mut doors.along_x } else { &mut doors.along_z };
                            list[(line * rooms + k) as usize] = door;
                        }
                        let (l, r) = (door - DOOR.0 / 2.0, door + DOOR.0 / 2.0);
                        vec![piece(a, l, y), piece(r, b, y), piece(l, r, y + DOOR.1)]
                    } else {
                        vec![piece(a, b, y)]
                    };
                    for (min, max) in parts {
                        boxed(&mut scene, min, max, WALLS);
                    }
                }
            }
        }
        for i in 0..rooms {
            for j in 0..rooms {
                let inside = Vec3::new(i as f32 * ROOM + SLAB / 2.0, y, j as f32 * ROOM + SLAB / 2.0);
                furnish(&mut scene, &meshes, &mut rng, inside, ROOM - SLAB);
            }
        }
    }
    (scene, doors)
}

/// Places random furniture in the room whose free floor starts at `corner`
/// (its lowest x and z, at floor height) and is `size` metres square: low
/// pieces anywhere away from the walls, tall ones in corners.
fn furnish(scene: &mut Scene, meshes: &Meshes, rng: &mut Rng, corner: Vec3, size: f32) {
    let place = |scene: &mut Scene, mesh: u32, at: Vec3, quarter_turns: u32, material: u32| {
        let turn = Quat::from_rotation_y(quarter_turns as f32 * std::f32::consts::FRAC_PI_2);
        scene.add_instance(mesh, Mat4::from_rotation_translation(turn, corner + at), material);
    };
    let centre = Vec3::new(size / 2.0 + rng.range(-0.4, 0.4), 0.0, size / 2.0 + rng.range(-0.4, 0.4));
    if rng.chance(0.8) {
        let turns = rng.below(2);
        place(scene, meshes.table, centre, turns, WOOD);
        let (along, across) = if turns == 0 { (Vec3::X, Vec3::Z) } else { (Vec3::Z, Vec3::X) };
        for (offset, side) in [(-0.4, -1.0), (0.4, -1.0), (-0.4, 1.0), (0.4, 1.0)] {
            if rng.chance(0.8) {
                let at = centre + along * offset + across * side * 0.7;
                let facing = if side < 0.0 { 0 } else { 2 } + turns;
                place(scene, meshes.chair, at, facing, WOOD);
            }
        }
    }
    if rng.chance(0.6) {
        let turns = rng.below(4);
        let towards = Quat::from_rotation_y(turns as f32 * std::f32::consts::FRAC_PI_2) * Vec3::Z;
        let at = Vec3::new(size / 2.0, 0.0, size / 2.0) - towards * (size / 2.0 - 0.6);
        place(scene, meshes.sofa, at, turns, FABRIC);
    }
    // Tall pieces in the corners, 0.5 m from the walls.
    let corners = [(0.5, 0.5, 0), (size - 0.5, 0.5, 3), (size - 0.5, size - 0.5, 2), (0.5, size - 0.5, 1)];
    for (x, z, turns) in corners {
        let at = Vec3::new(x, 0.0, z);
        match rng.below(4) {
            0 => {
                place(scene, meshes.shelf, at, turns, WOOD);
                place(scene, meshes.books, at, turns, BOOKS);
            }
            1 => place(scene, meshes.lamp, at, 0, METAL),
            2 => place(scene, meshes.plant, at, 0, LEAVES),
            _ => {}
        }
    }
}
