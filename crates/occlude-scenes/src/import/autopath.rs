//! Walkthroughs for imported models, which come without one.
//!
//! - [`orbit`]: a circle around the model, outside its bounds, a third of its
//!   height above its centre, looking at the centre. Works for every model.
//! - [`walk`]: a walk at eye height ([`EYE`] above the lowest point of the
//!   model) through its free space. A grid of points over the model's
//!   footprint is laid at eye height; a point is free when a box of
//!   [`BOX`] metres around it overlaps no instance box, and two neighbouring
//!   points are joined when the box swept between them overlaps none either.
//!   The largest joined group is visited: [`WAYPOINTS`] points spread over it
//!   by farthest-point sampling, joined by shortest grid paths.
//!
//! Limits of the walk: it tests instance *boxes*, so a model stored as one
//! mesh (even split, a part's box can fill a room) may leave no free space and
//! the walk falls back to the orbit; free space is only looked for at one
//! height, so a building of several floors is walked on its lowest; the path
//! is a smooth curve through grid points, so it may cut a corner by a few
//! centimetres; and a grid cell is at least half a metre, at most 1/64 of the
//! footprint, so narrow gaps in large models are missed.

use crate::walk::{PathBuilder, EYE};
use glam::Vec3;
use occlude_core::{Aabb, CameraPath, Scene};
use std::collections::VecDeque;

/// Side of the free box around every walk point, metres.
pub(crate) const BOX: f32 = 0.5;
/// Smallest spacing of the walk grid, metres.
const MIN_STEP: f32 = 0.5;
/// Most grid points along each side of the footprint.
const MAX_POINTS_PER_SIDE: usize = 64;
/// Fewest joined free points a walk needs.
const MIN_FREE_POINTS: usize = 4;
/// Points of the free space the walk visits.
const WAYPOINTS: usize = 6;
/// Walking speed, metres per second of walkthrough.
const WALK_SPEED: f32 = 1.4;
/// Keyframes of an orbit (the last closes the circle).
const ORBIT_KEYS: usize = 24;

/// A circle around `bounds`: radius 0.75 of the box diagonal plus half a
/// metre (outside the box, clear of the near plane for small models), at a
/// third of the height above the centre, looking at the centre.
pub(crate) fn orbit(bounds: &Aabb) -> CameraPath {
    let centre = bounds.center();
    let extent = bounds.extent();
    let radius = extent.length() * 0.75 + 0.5;
    let height = centre.y + extent.y / 3.0;
    let mut path = PathBuilder::new();
    for k in 0..=ORBIT_KEYS {
        let angle = std::f32::consts::TAU * k as f32 / ORBIT_KEYS as f32;
        path.key(1.0, Vec3::new(centre.x + radius * angle.cos(), height, centre.z + radius * angle.sin()), centre);
    }
    path.build()
}

/// The walk grid at eye height: which points are free and which neighbours
/// are joined.
struct Grid {
    origin: Vec3,
    step: f32,
    nx: usize,
    nz: usize,
    /// Per point (x fastest): free.
    free: Vec<bool>,
    /// Per point: the edge to the +x neighbour is clear.
    clear_x: Vec<bool>,
    /// Per point: the edge to the +z neighbour is clear.
    clear_z: Vec<bool>,
}

impl Grid {
    /// Lays the grid over the footprint of `scene` and marks what its
    /// instance boxes block.
    fn new(scene: &Scene) -> Self {
        let b = scene.bounds();
        let e = b.extent();
        let step = (e.x.max(e.z) / (MAX_POINTS_PER_SIDE - 1) as f32).max(MIN_STEP);
        let count = |len: f32| ((len / step).floor() as usize + 1).min(MAX_POINTS_PER_SIDE);
        let (nx, nz) = (count(e.x), count(e.z));
        let offset = |len: f32, n: usize| (len - (n - 1) as f32 * step) / 2.0;
        let origin = Vec3::new(b.min.x + offset(e.x, nx), b.min.y + EYE, b.min.z + offset(e.z, nz));
        let n = nx * nz;
        let mut grid =
            Self { origin, step, nx, nz, free: vec![true; n], clear_x: vec![true; n], clear_z: vec![true; n] };
        let half = BOX / 2.0;
        for inst in &scene.instances {
            let ib = &inst.bounds;
            if ib.min.y > origin.y + half || ib.max.y < origin.y - half {
                continue;
            }
            let xs = grid.span(ib.min.x, ib.max.x, origin.x, nx);
            let zs = grid.span(ib.min.z, ib.max.z, origin.z, nz);
            let (Some((x0, x1)), Some((z0, z1))) = (xs, zs) else { continue };
            for z in z0..=z1 {
                for x in x0..=x1 {
                    grid.free[z * nx + x] = false;
                }
                // Edges from x - 1 reach into this instance too.
                for x in x0.saturating_sub(1)..=x1 {
                    grid.clear_x[z * nx + x] = false;
                }
            }
            for z in z0.saturating_sub(1)..=z1 {
                for x in x0..=x1 {
                    grid.clear_z[z * nx + x] = false;
                }
            }
        }
        grid
    }

    /// The first and last grid index (of `n` from `origin`) whose point box
    /// overlaps `[lo, hi]`, if any.
    fn span(&self, lo: f32, hi: f32, origin: f32, n: usize) -> Option<(usize, usize)> {
        let half = BOX / 2.0;
        let first = ((lo - half - origin) / self.step).ceil().max(0.0);
        let last = ((hi + half - origin) / self.step).floor().min((n - 1) as f32);
        (first <= last).then_some((first as usize, last as usize))
    }

    /// Position of point `i`.
    fn point(&self, i: usize) -> Vec3 {
        self.origin + Vec3::new((i % self.nx) as f32, 0.0, (i / self.nx) as f32) * self.step
    }

    /// Free neighbours of free point `i` joined to it, in a fixed order.
    fn neighbours(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        let (x, z) = (i % self.nx, i / self.nx);
        let candidates = [
            (x + 1 < self.nx && self.clear_x[i]).then(|| i + 1),
            (x > 0 && self.clear_x[i.wrapping_sub(1)]).then(|| i - 1),
            (z + 1 < self.nz && self.clear_z[i]).then(|| i + self.nx),
            (z > 0 && self.clear_z[i.wrapping_sub(self.nx)]).then(|| i - self.nx),
        ];
        candidates.into_iter().flatten().filter(|&j| self.free[j])
    }

    /// Grid steps from `start` to every point (`usize::MAX`: not reachable),
    /// and the previous point on a shortest path.
    fn distances(&self, start: usize) -> (Vec<usize>, Vec<usize>) {
        let mut dist = vec![usize::MAX; self.free.len()];
        let mut previous = vec![usize::MAX; self.free.len()];
        let mut queue = VecDeque::from([start]);
        dist[start] = 0;
        while let Some(i) = queue.pop_front() {
            for j in self.neighbours(i) {
                if dist[j] == usize::MAX {
                    dist[j] = dist[i] + 1;
                    previous[j] = i;
                    queue.push_back(j);
                }
            }
        }
        (dist, previous)
    }
}

/// A walk through the free space of `scene` at eye height, or why there is
/// none (see the module documentation for the algorithm and its limits).
pub(crate) fn walk(scene: &Scene) -> Result<CameraPath, String> {
    let bounds = scene.bounds();
    if bounds.extent().y < EYE {
        return Err(format!("the model is {:.2} m high, lower than eye height ({EYE} m)", bounds.extent().y));
    }
    let grid = Grid::new(scene);
    // The largest group of joined free points (the first one on ties).
    let mut best: Option<(usize, usize)> = None;
    let mut seen = vec![false; grid.free.len()];
    for start in (0..grid.free.len()).filter(|&i| grid.free[i]) {
        if seen[start] {
            continue;
        }
        let (dist, _) = grid.distances(start);
        let size = dist.iter().enumerate().filter(|(_, d)| **d != usize::MAX).inspect(|(j, _)| seen[*j] = true).count();
        if best.is_none_or(|(_, s)| size > s) {
            best = Some((start, size));
        }
    }
    let (start, size) = best.unwrap_or((0, 0));
    if size < MIN_FREE_POINTS {
        return Err(format!(
            "{size} joined free points at eye height, fewer than {MIN_FREE_POINTS}: instance boxes fill the space"
        ));
    }
    // Waypoints by farthest-point sampling over grid distances.
    let (mut nearest, _) = grid.distances(start);
    let mut waypoints = Vec::new();
    while waypoints.len() < WAYPOINTS {
        let (far, &d) = nearest
            .iter()
            .enumerate()
            .filter(|(_, d)| **d != usize::MAX)
            .max_by_key(|&(i, d)| (*d, usize::MAX - i))
            .expect("non-empty group");
        if d == 0 && !waypoints.is_empty() {
            break;
        }
        waypoints.push(far);
        let (from_far, _) = grid.distances(far);
        nearest.iter_mut().zip(from_far).for_each(|(n, f)| *n = (*n).min(f));
    }
    // Shortest grid paths between consecutive waypoints.
    let mut points = vec![waypoints[0]];
    for pair in waypoints.windows(2) {
        let (_, previous) = grid.distances(pair[1]);
        let mut i = pair[0];
        while i != pair[1] {
            i = previous[i];
            points.push(i);
        }
    }
    let positions: Vec<Vec3> = points.iter().map(|&i| grid.point(i)).collect();
    let mut path = PathBuilder::new();
    for (k, &position) in positions.iter().enumerate() {
        let ahead = positions[(k + 3).min(positions.len() - 1)];
        let target = if ahead != position { ahead } else { position + (position - positions[k - 1]) };
        path.key(grid.step / WALK_SPEED, position, target);
    }
    Ok(path.build())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Mat4;

    /// A scene of unit-cube instances scaled and moved to `boxes`.
    fn boxes(boxes: &[Aabb]) -> Scene {
        let mut scene = Scene::new("boxes");
        let cube = scene.add_mesh(crate::shapes::cuboid(Vec3::ZERO, Vec3::ONE));
        for b in boxes {
            scene.add_instance(cube, Mat4::from_scale_rotation_translation(b.extent(), Default::default(), b.min), 0);
        }
        scene
    }

    /// A 10 x 10 m room, 3 m high: floor, four walls, a pillar in the middle.
    fn room() -> Scene {
        boxes(&[
            Aabb::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(10.0, 0.1, 10.0)),
            Aabb::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.2, 3.0, 10.0)),
            Aabb::new(Vec3::new(9.8, 0.0, 0.0), Vec3::new(10.0, 3.0, 10.0)),
            Aabb::new(Vec3::new(0.0, 0.0, 0.0), Vec3::new(10.0, 3.0, 0.2)),
            Aabb::new(Vec3::new(0.0, 0.0, 9.8), Vec3::new(10.0, 3.0, 10.0)),
            Aabb::new(Vec3::new(4.0, 0.0, 4.0), Vec3::new(6.0, 3.0, 6.0)),
        ])
    }

    #[test]
    fn orbit_stays_outside_the_bounds_looking_at_the_centre() {
        let b = Aabb::new(Vec3::new(-2.0, 0.0, 1.0), Vec3::new(4.0, 3.0, 5.0));
        let path = orbit(&b);
        assert_eq!(path.keyframes.len(), ORBIT_KEYS + 1);
        for k in &path.keyframes {
            assert!(!b.contains_point(k.position), "{k:?} is inside the bounds");
            assert_eq!(k.target, b.center());
            assert!((k.position.y - (b.center().y + 1.0)).abs() < 1e-5);
        }
        assert!((path.keyframes[0].position - path.keyframes[ORBIT_KEYS].position).length() < 1e-4);
    }

    #[test]
    fn walk_stays_in_free_space_at_eye_height_and_goes_round_the_room() {
        let scene = room();
        let path = walk(&scene).expect("the room has free space");
        assert!(path.keyframes.len() > 10);
        let cameras = path.sample(2000, 1.0, 0.1, 100.0);
        let half = Vec3::splat(0.2);
        for c in &cameras {
            assert!((c.position.y - EYE).abs() < 1e-3);
            let eye = Aabb::new(c.position - half, c.position + half);
            assert!(scene.instances.iter().all(|i| !i.bounds.overlaps(&eye)), "{:?} touches an object", c.position);
        }
        let visited = Aabb::from_points(cameras.iter().map(|c| &c.position));
        assert!(visited.extent().x > 6.0 && visited.extent().z > 6.0, "the walk covers the room: {visited:?}");
        assert_eq!(walk(&scene).unwrap(), path, "deterministic");
    }

    #[test]
    fn walk_refuses_solid_and_flat_models() {
        let solid = boxes(&[Aabb::new(Vec3::ZERO, Vec3::splat(10.0))]);
        assert!(walk(&solid).unwrap_err().contains("fewer than"));
        let flat = boxes(&[Aabb::new(Vec3::ZERO, Vec3::new(10.0, 1.0, 10.0))]);
        assert!(walk(&flat).unwrap_err().contains("lower than eye height"));
    }
}
