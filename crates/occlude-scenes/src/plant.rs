//! `plant`: a dense industrial hall standing in for the UNC Power Plant (the
//! CHC 2004 scene, 12.7M triangles): outer walls, several floor levels of
//! slabs and see-through gratings on steel columns and girders, tanks, pumps,
//! stairs and platforms, riser pipes, pipe racks over the aisles and pipes
//! dropping from them with segmented bends.
//!
//! The hall is a grid of bays; each bay has a cross of aisles through its
//! centre and four equipment quadrants around it. One bay is an open shaft
//! through every level. The walkthrough (see `walkthrough`) has the CHC
//! paper's kinds of sections: views of a large part of the hall along whole
//! aisles and from the shaft, short views outwards at its border (low depth
//! complexity) and, at its end, views across the equipment of the ground
//! floor (high depth complexity, strong occlusion).

use crate::rng::Rng;
use crate::shapes::{block, cuboid, cylinder, round_corners, sphere, stairs, torus, tube, MeshBuilder};
use crate::walk::{PathBuilder, EYE};
use crate::{Inputs, Size};
use glam::{Mat4, Vec3};
use occlude_core::{CameraPath, Mesh, Scene};

/// Side of a bay, in metres.
const BAY: f32 = 10.0;
/// Height of a level, floor to floor.
const LEVEL: f32 = 6.0;
/// Thickness of floor slabs, gratings and the roof.
const SLAB: f32 = 0.3;
/// Thickness of the outer walls.
const WALL_THICKNESS: f32 = 0.3;
/// Centre of a quadrant from its bay's corner (along x and z).
const QUADRANT: f32 = 2.0;
/// Half the side of the square an equipment item fits in.
const ROOM: f32 = 1.5;

// Materials.
pub(crate) const WALL: u32 = 0;
const FLOOR: u32 = 1;
const GRATING: u32 = 2;
const STEEL: u32 = 3;
const PIPE_FIRST: u32 = 4;
const PIPES: u32 = 4;
const TANK_FIRST: u32 = 8;
const TANKS: u32 = 3;
const MACHINE: u32 = 11;
const GROUND: u32 = 12;

/// Bays along x and z, levels, and sides of round parts for one size.
struct Layout {
    bays: [u32; 2],
    levels: u32,
    sides: u32,
}

fn layout(size: Size) -> Layout {
    size.pick(
        Layout { bays: [6, 4], levels: 2, sides: 8 },
        Layout { bays: [12, 7], levels: 3, sides: 16 },
        Layout { bays: [16, 12], levels: 5, sides: 32 },
    )
}

/// An I-beam along `+y` of `length` (profile `width` x `depth`): two flanges
/// and a web.
fn i_beam(width: f32, depth: f32, length: f32) -> Mesh {
    let (w, d, t) = (0.5 * width, 0.5 * depth, 0.08 * depth.min(width));
    let mut b = MeshBuilder::new();
    b.add(&cuboid(Vec3::new(-w, 0.0, -d), Vec3::new(w, length, -d + t)), Mat4::IDENTITY);
    b.add(&cuboid(Vec3::new(-w, 0.0, d - t), Vec3::new(w, length, d)), Mat4::IDENTITY);
    b.add(&cuboid(Vec3::new(-0.5 * t, 0.0, -d + t), Vec3::new(0.5 * t, length, d - t)), Mat4::IDENTITY);
    b.build()
}

/// A floor grating over one bay: a frame and bars one metre apart, top at
/// `y = 0`, so the levels below show through.
fn grating() -> Mesh {
    let mut b = MeshBuilder::new();
    let bar = 0.08;
    for k in 0..=10 {
        let x = (k as f32 * (BAY - bar) / 10.0).min(BAY - bar);
        b.add(&cuboid(Vec3::new(x, -SLAB, 0.0), Vec3::new(x + bar, 0.0, BAY)), Mat4::IDENTITY);
    }
    for k in 0..=10 {
        let z = k as f32 * (BAY - bar) / 10.0;
        for i in 0..10 {
            let x0 = i as f32 * (BAY - bar) / 10.0 + bar;
            let x1 = (i + 1) as f32 * (BAY - bar) / 10.0;
            b.add(&cuboid(Vec3::new(x0, -0.6 * SLAB, z), Vec3::new(x1, 0.0, z + bar)), Mat4::IDENTITY);
        }
    }
    b.build()
}

/// A pipe between two points with flanges (short wider cylinders) at both
/// ends.
fn flanged_pipe(b: &mut MeshBuilder, from: Vec3, to: Vec3, radius: f32, sides: u32) {
    b.add(&tube(&[from, to], radius, sides), Mat4::IDENTITY);
    let dir = (to - from).normalize();
    let flange = tube(&[Vec3::ZERO, dir * 0.12], radius + 0.06, sides);
    b.add_at(&flange, from);
    b.add_at(&flange, to - dir * 0.12);
}

/// A rack of parallel pipes over an aisle along `+x` for one bay, at `height`
/// above the floor, centred on `z = 0`, with two cross supports.
fn rack(rng: &mut Rng, height: f32, sides: u32) -> Mesh {
    let mut b = MeshBuilder::new();
    let pipes = 3 + rng.below(4);
    let spacing = 2.6 / pipes as f32;
    for i in 0..pipes {
        let z = -1.3 + (i as f32 + 0.5) * spacing;
        let r = rng.range(0.08, 0.45 * spacing);
        let y = height + 0.5;
        flanged_pipe(&mut b, Vec3::new(0.0, y, z), Vec3::new(BAY, y, z), r, sides);
    }
    for x in [0.8, BAY - 1.0] {
        b.add(&cuboid(Vec3::new(x, height, -1.45), Vec3::new(x + 0.2, height + 0.15, 1.45)), Mat4::IDENTITY);
    }
    b.build()
}

/// A pipe dropping from a rack over the aisle (`+z` side, 3 m from the
/// quadrant's centre) into the quadrant, with segmented bends.
fn drop_pipe(rng: &mut Rng, sides: u32) -> Mesh {
    let x = rng.range(-0.8, 0.8);
    let low = rng.range(2.6, 3.4);
    let points = [
        Vec3::new(x, 4.9, 2.6),
        Vec3::new(x, 4.9, 0.4),
        Vec3::new(x, 3.9, 0.4),
        Vec3::new(-x, 3.9, -0.4),
        Vec3::new(-x, low, -0.4),
    ];
    let r = rng.range(0.07, 0.14);
    tube(&round_corners(&points, 0.35, (sides / 4).max(2)), r, sides)
}

/// A vertical tank with a domed top, flanged rings and a nozzle.
fn vertical_tank(rng: &mut Rng, sides: u32) -> Mesh {
    let r = rng.range(0.8, 1.3);
    let h = rng.range(1.8, 2.9);
    let mut b = MeshBuilder::new();
    b.add(&cylinder(r, h, sides), Mat4::IDENTITY);
    b.add_at(&sphere(r, sides / 2, sides), Vec3::Y * h);
    for k in 1..=2 {
        b.add_at(&cylinder(r + 0.06, 0.1, sides), Vec3::Y * (h * k as f32 / 3.0));
    }
    let y = 0.6 * h;
    flanged_pipe(&mut b, Vec3::new(r - 0.1, y, 0.0), Vec3::new((r + 0.3).min(ROOM), y, 0.0), 0.12, sides / 2);
    b.build()
}

/// A horizontal tank on two saddles.
fn horizontal_tank(rng: &mut Rng, sides: u32) -> Mesh {
    let r = rng.range(0.5, 0.85);
    let half = ROOM - r;
    let y = r + 0.4;
    let mut b = MeshBuilder::new();
    b.add(&tube(&[Vec3::new(-half, y, 0.0), Vec3::new(half, y, 0.0)], r, sides), Mat4::IDENTITY);
    for x in [-half, half] {
        b.add_at(&sphere(r, sides / 2, sides), Vec3::new(x, y, 0.0));
    }
    for x in [-0.6 * half, 0.6 * half] {
        b.add_at(&block(Vec3::new(0.3, y, 1.2 * r)), Vec3::X * x);
    }
    b.build()
}

/// A pump: a base, a motor, a casing and a discharge pipe with bends.
fn pump(rng: &mut Rng, sides: u32) -> Mesh {
    let mut b = MeshBuilder::new();
    b.add(&block(Vec3::new(2.6, 0.35, 1.2)), Mat4::IDENTITY);
    let motor = rng.range(0.3, 0.45);
    b.add(
        &tube(&[Vec3::new(-1.2, 0.35 + motor, 0.0), Vec3::new(0.1, 0.35 + motor, 0.0)], motor, sides),
        Mat4::IDENTITY,
    );
    b.add_at(&sphere(0.5, sides / 2, sides), Vec3::new(0.7, 0.85, 0.0));
    let pipe = [Vec3::new(0.7, 1.2, 0.0), Vec3::new(0.7, 2.2, 0.0), Vec3::new(1.3, 2.2, 0.0), Vec3::new(1.3, 3.4, 0.8)];
    b.add(&tube(&round_corners(&pipe, 0.3, (sides / 4).max(2)), 0.12, sides / 2), Mat4::IDENTITY);
    b.build()
}

/// A cluster of riser pipes through the whole level with ring flanges.
fn risers(rng: &mut Rng, sides: u32) -> Mesh {
    let mut b = MeshBuilder::new();
    let height = LEVEL - SLAB;
    for _ in 0..3 + rng.below(3) {
        let r = rng.range(0.08, 0.22);
        let at = Vec3::new(rng.range(-1.1, 1.1), 0.0, rng.range(-1.1, 1.1));
        b.add_at(&cylinder(r, height, sides / 2), at);
        let ring = torus(r + 0.03, 0.05, sides / 2, 4);
        for k in 1..4 {
            b.add_at(&ring, at + Vec3::Y * (height * k as f32 / 4.0));
        }
    }
    b.build()
}

/// Stairs up to a platform with railing posts.
fn stair_platform() -> Mesh {
    let mut b = MeshBuilder::new();
    let (rise, run, steps) = (0.3, 0.3, 8);
    let top = rise * steps as f32;
    b.add_at(&stairs(0.9, steps, rise, run), Vec3::new(-ROOM, 0.0, -ROOM));
    let landing = -ROOM + run * steps as f32;
    b.add(&cuboid(Vec3::new(-ROOM, top - 0.15, landing), Vec3::new(ROOM, top, ROOM)), Mat4::IDENTITY);
    for x in [-0.4, 0.4, 1.4] {
        b.add(&cuboid(Vec3::new(x, top, ROOM - 0.1), Vec3::new(x + 0.05, top + 1.0, ROOM - 0.05)), Mat4::IDENTITY);
    }
    b.add(&cuboid(Vec3::new(-0.4, top + 1.0, ROOM - 0.1), Vec3::new(1.45, top + 1.05, ROOM - 0.05)), Mat4::IDENTITY);
    for k in 0..4 {
        let x = -0.5 + k as f32 * 0.6;
        b.add(&cuboid(Vec3::new(x, 0.0, landing), Vec3::new(x + 0.15, top - 0.15, landing + 0.15)), Mat4::IDENTITY);
    }
    b.build()
}

/// A large outdoor spherical tank on legs (seen from the hall's border).
fn outdoor_tank(sides: u32) -> Mesh {
    let mut b = MeshBuilder::new();
    b.add_at(&sphere(6.0, sides, 2 * sides), Vec3::Y * 9.0);
    for (x, z) in [(-4.0, -4.0), (4.0, -4.0), (-4.0, 4.0), (4.0, 4.0)] {
        b.add_at(&cylinder(0.3, 9.0, sides / 2), Vec3::new(x, 0.0, z));
    }
    b.build()
}

/// The longest straight move between two keys of the plant's walkthrough:
/// near a corner, the spline through the keys strays from the aisle's centre
/// line by up to about 7 % of the neighbouring keys' distance (0.74 m at one
/// bay), and an aisle leaves 1.5 m on each side of it, 1 m with the clearance.
const STEP: f32 = BAY;

/// Builds the plant's walkthrough move by move along the aisles and through
/// the shaft, each move cut into steps of at most [`STEP`], so that the path
/// stays in the aisles however far a move goes at any size.
struct AisleWalk {
    path: PathBuilder,
    at: Vec3,
}

impl AisleWalk {
    /// Starts at `position`, looking at `target`.
    fn new(position: Vec3, target: Vec3) -> Self {
        let mut path = PathBuilder::new();
        path.key(0.0, position, target);
        Self { path, at: position }
    }

    /// Stands still for `seconds`, turning to look at `target`.
    fn look(&mut self, seconds: f32, target: Vec3) -> &mut Self {
        self.path.key(seconds, self.at, target);
        self
    }

    /// Moves straight to `to` at an even speed over `seconds`, turning to
    /// look at `target` on the first step and holding it.
    fn go(&mut self, seconds: f32, to: Vec3, target: Vec3) -> &mut Self {
        let steps = ((to - self.at).length() / STEP).ceil().max(1.0);
        let from = self.at;
        for k in 1..=steps as u32 {
            self.path.key(seconds / steps, from.lerp(to, k as f32 / steps), target);
        }
        self.at = to;
        self
    }

    /// The finished path.
    fn build(&mut self) -> CameraPath {
        self.path.build()
    }
}

/// The walkthrough through a hall of `nx` x `nz` bays and `levels` levels,
/// with the main aisle in bay row `row` and the shaft at bay `shaft` of it:
/// 130 s, 3,901 frames at 30 fps.
///
/// The path is an input of the experiment, laid out from the CHC paper's
/// description of its power plant walkthrough (section 6.2, Figure 7) before
/// any method ran on it: the paper's runs past frame 3800 and has "several
/// viewpoints from which a large part of the model is visible" (spikes
/// where all methods are slow), "viewpoints along the border of the model
/// directed outwards with low depth complexity" (short holes where all are
/// fast), a stretch with "not much occlusion" near frame 2200 and
/// "viewpoints inside the power plant with high depth complexity" near
/// frames 3700-3800. In our hall the views of a large part are those along
/// a whole aisle or a whole cross aisle and those from the shaft across the
/// levels; the views outwards are through the end wall's openings and at
/// the outer walls from the aisles' ends; depth is deepest on the ground
/// floor looking across the equipment. Frames at 30 fps:
///
/// - 0-360: the ground-floor main aisle from the far end to the shaft,
///   glancing into the equipment on both sides;
/// - 360-690: up the shaft to the top level, looking across the levels;
/// - 690-990: along the top level's main aisle to the end wall's opening;
///   990-1050 looking outwards through it (a hole), then along the whole
///   top-level aisle (1125-1185);
/// - 1215-1455: along the last cross aisle across the bay rows; 1485-1530
///   at the outer wall, facing it (a hole);
/// - 1560-1905: along the border aisle (1710-1755 facing the outer wall),
///   then along the shaft's cross aisle across the rows to the shaft
///   (1935-2145);
/// - 2145-2550 (the paper's 2200): down the shaft, looking down it and
///   along the middle level's aisle both ways;
/// - 2550-2865: along the ground floor's main aisle to the door; 2865-2955
///   out of it, looking outwards (a hole; the eye is outside the walls for
///   3.3 s), then back in, looking along the whole aisle (2985-3045);
/// - 3090-3900 (the paper's 3700-3800): down the last cross aisle to an
///   inner aisle (3270 on) and along it over the whole hall, looking across
///   the equipment on either side.
///
/// Under the methods, the views along a whole aisle are where occlusion
/// pays most, and no view has every method slow as the paper's spikes.
fn walkthrough(nx: u32, nz: u32, levels: u32, row: u32, shaft: u32) -> CameraPath {
    // `p(x, level, z)` is at eye height on `level` at `x`, `z` in bays; the
    // aisles run along the bays' centre lines (`x` or `z` a whole number and
    // a half) and cross at the bays' centres.
    let p = |x: f32, level: u32, z: f32| Vec3::new(x * BAY, level as f32 * LEVEL + EYE, z * BAY);
    let r = row as f32 + 0.5;
    let inner = (row / 2) as f32 + 0.5;
    let s = shaft as f32 + 0.5;
    let end = nx as f32;
    let last = end - 0.5;
    let border = nz as f32 - 0.5;
    let (top, mid) = (levels - 1, (levels - 1) / 2);
    let halfway = Vec3::Y * (0.5 * top as f32 * LEVEL);
    let mut w = AisleWalk::new(p(0.3, 0, r), p(3.0, 0, r));
    // The ground-floor main aisle, glancing into the equipment on both sides.
    w.go(2.5, p(1.0, 0, r), p(1.4, 0, r + 0.4) - Vec3::Y * 0.5)
        .go(2.5, p(1.8, 0, r), p(4.0, 0, r))
        .go(3.5, p(0.5 * (1.8 + s), 0, r), p(s, 0, r - 0.4))
        .go(3.5, p(s, 0, r), p(s + 3.0, 0, r))
        // Turn in the shaft, then rise through it looking across the levels
        // (a short first step: a key far above its neighbours would make
        // the spline dip towards the floor first).
        .look(2.0, p(s, 0, r + 2.0))
        .go(1.5, p(s, 0, r) + Vec3::Y * 1.5, p(s, 0, r + 2.0))
        .go(3.0, p(s, 0, r) + halfway, p(s + 0.3, top, r - 2.0))
        .go(2.5, p(s, top, r), p(s - 0.3, top, r) - Vec3::Y * 3.0)
        .look(2.0, p(s + 3.0, top, r))
        // Along the top level to the opening in the end wall, looking out
        // through it and down to the ground, then back along the whole aisle
        // (turning through a side view, never looking at the eye itself).
        .go(9.0, p(last, top, r), p(end + 3.0, top, r))
        .go(1.0, p(end - 0.2, top, r), p(end + 4.0, top, r) - Vec3::Y * 4.0)
        .look(2.0, p(end + 3.0, top, r + 1.5) - Vec3::Y * 5.0)
        .look(1.0, p(end - 0.2, top, r + 2.0))
        .go(1.5, p(last, top, r), p(0.0, top, r))
        .look(2.0, p(0.0, top, r))
        // Along the last cross aisle to the outer wall, facing it, and back
        // along the border aisle, glancing at the wall once more.
        .look(1.0, p(last, top, border))
        .go(8.0, p(last, top, border), p(last, top, border + 3.0))
        .go(1.0, p(last, top, border + 0.2), p(last, top, border + 3.0))
        .look(1.5, p(last - 0.3, top, border + 3.0) - Vec3::Y * 1.0)
        .go(1.0, p(last, top, border), p(s, top, border))
        .go(5.0, p(0.5 * (last + s), top, border), p(s, top, border))
        .look(1.5, p(0.5 * (last + s) - 0.3, top, border + 3.0) - Vec3::Y * 1.0)
        .go(5.0, p(s, top, border), p(0.0, top, border))
        // Along the shaft's cross aisle across the rows to the shaft.
        .look(1.0, p(s, top, r))
        .go(7.0, p(s, top, r), p(s, top, 0.0))
        // Down the shaft: looking down it, along the middle level's aisle
        // both ways, and along the ground floor's cross aisle.
        .look(2.0, p(s + 1.5, 0, r + 1.0))
        .go(4.0, p(s, mid, r), p(0.0, mid, r))
        .look(2.5, p(end, mid, r))
        .go(3.0, p(s, 0, r), p(s, 0, 0.0))
        .look(2.0, p(end, 0, r))
        // Along the ground floor's main aisle, out of the door, looking
        // outwards, then back in along the whole aisle.
        .go(10.5, p(last, 0, r), p(end + 3.0, 0, r))
        .go(1.0, p(end + 0.6, 0, r), p(end + 5.0, 0, r) + Vec3::Y * 3.0)
        .look(1.5, p(end + 5.0, 0, r + 2.0))
        .look(0.5, p(end + 0.6, 0, r + 3.0))
        .go(1.0, p(end - 0.2, 0, r), p(0.0, 0, r))
        .look(2.0, p(0.0, 0, r))
        .go(1.5, p(last, 0, r), p(0.0, 0, r))
        // Down the last cross aisle to an inner aisle and along it over the
        // whole hall, looking across the equipment ahead on either side.
        .look(1.0, p(last, 0, inner))
        .go(4.0, p(last, 0, inner), p(last, 0, 0.0))
        .look(1.0, p(0.0, 0, inner));
    for k in 1..=6 {
        let x = last + (1.5 - last) * k as f32 / 6.0;
        let side = if k % 2 == 0 { 0.4 } else { -0.4 };
        w.go(3.5, p(x, 0, inner), p(x - 0.5, 0, inner + side) - Vec3::Y * 0.8);
    }
    w.build()
}

/// Vertical field of view of the CHC Table 1 plant's walkthrough, in
/// degrees.
const TABLE1_FOV_Y_DEG: f32 = 50.0;
/// How far the CHC Table 1 plant's cameras see, in metres (8 bays).
const TABLE1_VIEW: f32 = 80.0;

/// Builds the plant; with [`Inputs::ChcTable1`], its cameras see
/// [`TABLE1_VIEW`] far in a [`TABLE1_FOV_Y_DEG`] field of view.
pub(crate) fn generate(size: Size, seed: u64, inputs: Inputs) -> Scene {
    let Layout { bays: [nx, nz], levels, sides } = layout(size);
    let (row, shaft) = (nz / 2, nx / 2);
    let (wx, wz, height) = (nx as f32 * BAY, nz as f32 * BAY, levels as f32 * LEVEL);
    let mut scene = Scene::new("plant");
    scene.path = walkthrough(nx, nz, levels, row, shaft);
    let mut rng = Rng::new(seed, 0x9A27);

    let ground = scene.add_mesh(cuboid(Vec3::new(-60.0, -0.5, -60.0), Vec3::new(wx + 120.0, 0.0, wz + 60.0)));
    scene.add_instance(ground, Mat4::IDENTITY, GROUND);
    let wall = scene.add_mesh(cuboid(Vec3::ZERO, Vec3::new(BAY, LEVEL, WALL_THICKNESS)));
    let slab = scene.add_mesh(cuboid(Vec3::new(0.0, -SLAB, 0.0), Vec3::new(BAY, 0.0, BAY)));
    let grating = scene.add_mesh(grating());
    let column = scene.add_mesh(i_beam(0.4, 0.4, LEVEL - SLAB));
    let girder = scene.add_mesh(i_beam(0.3, 0.5, BAY - 0.4));
    let outdoor = scene.add_mesh(outdoor_tank(sides));

    // Shared equipment meshes, each with its material family.
    let mut equipment: Vec<(u32, u32, u32)> = Vec::new();
    for _ in 0..4 {
        let m = vertical_tank(&mut rng, sides);
        equipment.push((scene.add_mesh(m), TANK_FIRST, TANKS));
        let m = horizontal_tank(&mut rng, sides);
        equipment.push((scene.add_mesh(m), TANK_FIRST, TANKS));
        let m = pump(&mut rng, sides);
        equipment.push((scene.add_mesh(m), MACHINE, 1));
        let m = risers(&mut rng, sides);
        equipment.push((scene.add_mesh(m), PIPE_FIRST, PIPES));
    }
    equipment.push((scene.add_mesh(stair_platform()), STEEL, 1));
    // Racks along x run lower than those along z, which cross over them.
    let racks: Vec<u32> = [3.8, 4.0, 4.4, 4.5].map(|h| scene.add_mesh(rack(&mut rng, h, sides))).to_vec();
    let drops: Vec<u32> = (0..4).map(|_| scene.add_mesh(drop_pipe(&mut rng, sides))).collect();

    let quarter = |k: u32| Mat4::from_rotation_y(std::f32::consts::FRAC_PI_2 * k as f32);
    for level in 0..levels {
        let y = level as f32 * LEVEL;
        let top = level + 1 == levels;
        // Columns on the bay grid and girders along its lines, under the
        // next floor.
        for ix in 0..=nx {
            for iz in 0..=nz {
                let p = Vec3::new(ix as f32 * BAY, y, iz as f32 * BAY);
                scene.add_instance(column, Mat4::from_translation(p), STEEL);
                // Girders lie with their web upright: the beam's length (y)
                // along x or z, its depth (z) vertical.
                let under = p + Vec3::Y * (LEVEL - SLAB - 0.25);
                if ix < nx {
                    let t = Mat4::from_cols(
                        Vec3::Z.extend(0.0),
                        Vec3::X.extend(0.0),
                        Vec3::Y.extend(0.0),
                        (under + Vec3::X * 0.2).extend(1.0),
                    );
                    scene.add_instance(girder, t, STEEL);
                }
                if iz < nz {
                    let t = Mat4::from_cols(
                        Vec3::NEG_X.extend(0.0),
                        Vec3::Z.extend(0.0),
                        Vec3::Y.extend(0.0),
                        (under + Vec3::Z * 0.2).extend(1.0),
                    );
                    scene.add_instance(girder, t, STEEL);
                }
            }
        }
        // Outer walls, with openings at both ends of the main aisle's row on
        // the +x side (ground floor and top level).
        for ix in 0..nx {
            let x = ix as f32 * BAY;
            scene.add_instance(wall, Mat4::from_translation(Vec3::new(x, y, -WALL_THICKNESS)), WALL);
            scene.add_instance(wall, Mat4::from_translation(Vec3::new(x, y, wz)), WALL);
        }
        for iz in 0..nz {
            let z = iz as f32 * BAY;
            let opening = iz == row && (level == 0 || top);
            let side = quarter(3);
            scene.add_instance(wall, Mat4::from_translation(Vec3::new(-WALL_THICKNESS, y, z)) * side, WALL);
            if !opening {
                scene.add_instance(wall, Mat4::from_translation(Vec3::new(wx, y, z)) * side, WALL);
            }
        }
        for ix in 0..nx {
            for iz in 0..nz {
                let corner = Vec3::new(ix as f32 * BAY, y, iz as f32 * BAY);
                let in_shaft = ix == shaft && iz == row;
                // The floor of this level (the ground is level 0's floor).
                if level > 0 && !in_shaft {
                    let (mesh, material) = if rng.chance(0.5) { (grating, GRATING) } else { (slab, FLOOR) };
                    scene.add_instance(mesh, Mat4::from_translation(corner), material);
                }
                if top {
                    scene.add_instance(slab, Mat4::from_translation(corner + Vec3::Y * (LEVEL + SLAB)), FLOOR);
                }
                // Equipment in the four quadrants, pipes dropping into them.
                for (qx, qz, turn) in [(0, 0, 0), (1, 0, 3), (1, 1, 2), (0, 1, 1)] {
                    let centre = corner + Vec3::new(QUADRANT + qx as f32 * 6.0, 0.0, QUADRANT + qz as f32 * 6.0);
                    if in_shaft && level > 0 {
                        continue;
                    }
                    if rng.chance(0.9) {
                        let (mesh, first, count) = equipment[rng.below(equipment.len() as u32) as usize];
                        let t = Mat4::from_translation(centre) * quarter(rng.below(4));
                        scene.add_instance(mesh, t, first + rng.below(count));
                    }
                    if !in_shaft && rng.chance(0.5) {
                        // The drop starts over the aisle on the quadrant's
                        // +z side (after turning towards the bay's centre).
                        let t = Mat4::from_translation(centre) * quarter(turn);
                        let mesh = drops[rng.below(drops.len() as u32) as usize];
                        scene.add_instance(mesh, t, PIPE_FIRST + rng.below(PIPES));
                    }
                }
                // Pipe racks over the aisles (none in the shaft).
                if !in_shaft {
                    let mid = corner + Vec3::splat(0.5 * BAY).with_y(0.0);
                    let mesh = racks[rng.below(2) as usize];
                    scene.add_instance(
                        mesh,
                        Mat4::from_translation(mid - Vec3::X * (0.5 * BAY)),
                        PIPE_FIRST + rng.below(PIPES),
                    );
                    if rng.chance(0.6) {
                        let mesh = racks[2 + rng.below(2) as usize];
                        let t = Mat4::from_translation(mid + Vec3::Z * (0.5 * BAY)) * quarter(1);
                        scene.add_instance(mesh, t, PIPE_FIRST + rng.below(PIPES));
                    }
                }
            }
        }
    }
    // A few large tanks outside, beyond the end with the openings.
    for k in 0..3 {
        let p = Vec3::new(wx + 45.0 + 5.0 * k as f32, 0.0, 0.5 * wz + (k as f32 - 1.0) * 18.0);
        scene.add_instance(outdoor, Mat4::from_translation(p), TANK_FIRST + k % TANKS);
    }
    debug_assert!(scene.bounds().max.y >= height);
    if inputs == Inputs::ChcTable1 {
        scene.view_distance = Some(TABLE1_VIEW);
        for key in &mut scene.path.keyframes {
            key.fov_y_deg = TABLE1_FOV_Y_DEG;
        }
    }
    scene
}
