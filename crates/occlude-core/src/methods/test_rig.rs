//! A small scene of boxes, a camera and a [`MockBackend`] for the methods'
//! unit tests: each method's file checks its own behaviour on it.

use super::{check_support, create, BuiltMethod, DrawnSet, MethodOptions, Unsupported};
use crate::camera::Camera;
use crate::frame::render_frame;
use crate::geometry::Aabb;
use crate::gpu_culling::GpuCullingUnsupported;
use crate::hierarchy::{BuildOptions, Hierarchy, HierarchyKind, NodeId};
use crate::mock::{Call, MockBackend, NO_GPU_CULLING};
use crate::scene::{Mesh, Scene};
use glam::{Mat4, Vec3};

/// A closed cube over `[-0.5, 0.5]^3`, every triangle counter-clockwise
/// seen from outside (the software occlusion buffer culls back faces).
fn unit_cube() -> Mesh {
    let corners = Aabb::new(Vec3::splat(-0.5), Vec3::splat(0.5)).corners();
    let mut indices = Vec::new();
    for axis in 0..3 {
        for side in [0, 1] {
            // The face's corners, in the order of a loop around it.
            let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
            let corner = |u: usize, v: usize| (side << axis | u << a | v << b) as u32;
            let quad = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)];
            let outward =
                Vec3::from(std::array::from_fn::<f32, 3, _>(|i| if i == axis { side as f32 * 2.0 - 1.0 } else { 0.0 }));
            let p = |i: u32| corners[i as usize];
            let normal = (p(quad[1]) - p(quad[0])).cross(p(quad[2]) - p(quad[0]));
            let order = if normal.dot(outward) > 0.0 { [0, 1, 2, 0, 2, 3] } else { [0, 2, 1, 0, 3, 2] };
            indices.extend(order.iter().map(|&k| quad[k]));
        }
    }
    Mesh::new(corners.to_vec(), indices)
}

/// The scene, its hierarchy and the camera of a test.
pub(crate) struct Rig {
    pub scene: Scene,
    pub hierarchy: Hierarchy,
    pub camera: Camera,
}

impl Rig {
    /// One cube instance per box (instance `k` fills `boxes[k]`, material
    /// `k`), a BVH with at most `leaf_size` instances per leaf, and a camera
    /// at `(0, 0, 10)` looking at the origin (60 degrees, square image).
    pub fn new(boxes: &[Aabb], leaf_size: usize) -> Self {
        let mut scene = Scene::new("rig");
        let cube = scene.add_mesh(unit_cube());
        for (k, b) in boxes.iter().enumerate() {
            let transform = Mat4::from_translation(b.center()) * Mat4::from_scale(b.extent());
            scene.add_instance(cube, transform, k as u32);
        }
        let options = BuildOptions { leaf_size, ..Default::default() };
        let hierarchy = Hierarchy::build(&scene, HierarchyKind::Bvh, options);
        let camera = Camera::from_matrices(
            Mat4::look_at_rh(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO, Vec3::Y),
            Mat4::perspective_rh(60f32.to_radians(), 1.0, 0.1, 100.0),
            false,
        )
        .expect("a valid camera");
        Self { scene, hierarchy, camera }
    }

    /// A row of `n` unit cubes across the view at `z = 0`, and one behind
    /// the camera (instance `n`), one instance per leaf.
    pub fn row(n: usize) -> Self {
        let mut boxes: Vec<Aabb> = (0..n)
            .map(|k| {
                let x = (k as f32 - (n - 1) as f32 / 2.0) * 1.5;
                Aabb::new(Vec3::new(x - 0.5, -0.5, -0.5), Vec3::new(x + 0.5, 0.5, 0.5))
            })
            .collect();
        boxes.push(Aabb::new(Vec3::new(-0.5, -0.5, 20.0), Vec3::new(0.5, 0.5, 21.0)));
        Self::new(&boxes, 1)
    }

    /// A wall across the middle of the view (instance [`WALL`]), a cube
    /// straight behind it ([`BEHIND`], hidden by it) and one off to the side
    /// beyond the wall's edge ([`SIDE`], in view), one instance per leaf.
    pub fn wall() -> Self {
        let wall = Aabb::new(Vec3::new(-3.0, -3.0, 1.5), Vec3::new(3.0, 3.0, 2.5));
        let behind = Aabb::new(Vec3::new(-0.5, -0.5, -3.5), Vec3::new(0.5, 0.5, -2.5));
        let side = Aabb::new(Vec3::new(6.5, -0.5, -5.5), Vec3::new(7.5, 0.5, -4.5));
        Self::new(&[wall, behind, side], 1)
    }

    /// A mock of the rig's scene at 64x64.
    pub fn mock(&self) -> MockBackend {
        MockBackend::new(&self.scene, 64, 64)
    }

    /// The leaf holding instance `instance`.
    pub fn leaf_of(&self, instance: u32) -> NodeId {
        let h = &self.hierarchy;
        (0..h.node_count() as NodeId)
            .find(|&n| h.is_leaf(n) && h.instances(n).contains(&instance))
            .expect("every instance has a leaf")
    }

    /// Instances whose boxes the camera's frustum meets.
    pub fn in_view(&self) -> Vec<u32> {
        let f = self.camera.frustum();
        (0..self.scene.instances.len() as u32)
            .filter(|&i| f.intersects(&self.scene.instances[i as usize].bounds))
            .collect()
    }

    /// Renders `frames` frames of `method` on `mock` (same camera), returning
    /// each frame's calls.
    pub fn run(&self, method: &mut BuiltMethod, mock: &mut MockBackend, frames: usize) -> Vec<Vec<Call>> {
        let mut drawn = DrawnSet::default();
        (0..frames)
            .map(|_| {
                render_frame(method.method.as_mut(), mock, &self.scene, &self.hierarchy, &self.camera, &mut drawn);
                mock.take_log()
            })
            .collect()
    }
}

/// Instances of [`Rig::wall`].
pub(crate) const WALL: u32 = 0;
/// See [`WALL`].
pub(crate) const BEHIND: u32 = 1;
/// See [`WALL`].
pub(crate) const SIDE: u32 = 2;

/// The method `name` with options `options` (`method.key=value`).
pub(crate) fn method(name: &str, options: &[&str]) -> BuiltMethod {
    create(name, &MethodOptions::parse(options).expect("valid options")).expect("a method")
}

/// The instances drawn by `calls` (draw calls and list draws), in draw
/// order.
pub(crate) fn drawn(calls: &[Call]) -> Vec<u32> {
    calls
        .iter()
        .filter_map(|c| match c {
            Call::Draw(i) | Call::DrawList(i) => Some(i.clone()),
            _ => None,
        })
        .flatten()
        .collect()
}

/// The list draws and box tests of `calls`, in order: `("draw", ids)`,
/// `("test", ids)` (`"pyramid test"` against a pyramid) and
/// `("build pyramid", [])`, ids sorted.
pub(crate) fn culling_steps(calls: &[Call]) -> Vec<(&'static str, Vec<u32>)> {
    let sorted = |ids: &[u32]| {
        let mut ids = ids.to_vec();
        ids.sort_unstable();
        ids
    };
    calls
        .iter()
        .filter_map(|c| match c {
            Call::DrawList(ids) => Some(("draw", sorted(ids))),
            Call::TestBoxes { ids, pyramid: false } => Some(("test", sorted(ids))),
            Call::TestBoxes { ids, pyramid: true } => Some(("pyramid test", sorted(ids))),
            Call::BuildPyramid => Some(("build pyramid", Vec::new())),
            _ => None,
        })
        .collect()
}

/// The queries of `calls`, as their boxes.
pub(crate) fn queries(calls: &[Call]) -> Vec<&[Aabb]> {
    calls.iter().filter_map(|c| if let Call::IssueQuery { boxes, .. } = c { Some(&boxes[..]) } else { None }).collect()
}

/// True when one of `calls`' queries tests exactly `b`.
pub(crate) fn queried_alone(calls: &[Call], b: &Aabb) -> bool {
    queries(calls).iter().any(|q| q == &[*b])
}

/// Asserts the mock's script was honoured: every visible instance in view
/// drawn exactly once, nothing outside the view drawn, and no hidden one.
pub(crate) fn assert_draws_exactly(calls: &[Call], visible_in_view: &[u32]) {
    let mut got = drawn(calls);
    got.sort_unstable();
    let mut want = visible_in_view.to_vec();
    want.sort_unstable();
    assert_eq!(got, want, "drawn instances");
}

/// For a method needing GPU-resident culling: refused on a backend without
/// it (the backend's reason given); run anyway, it falls back to
/// view-frustum culling: everything in view drawn, no query.
pub(crate) fn assert_refused_without_gpu_culling_and_falls_back_to_frustum_culling(name: &str) {
    let rig = Rig::row(4);
    let mut mock = rig.mock();
    let mut m = method(name, &[]);
    let refused = check_support(m.method.as_ref(), &mut mock).unwrap_err();
    assert_eq!(refused, Unsupported::GpuCulling(GpuCullingUnsupported(NO_GPU_CULLING.into())));
    for calls in rig.run(&mut m, &mut mock, 2) {
        assert_draws_exactly(&calls, &rig.in_view());
        assert!(queries(&calls).is_empty());
    }
}

/// A frame's box tests of one kind: the ids tested by each level of a
/// top-down walk, and by each test after it.
pub(crate) type WalkTests = (Vec<Vec<u32>>, Vec<Vec<u32>>);

/// Runs `name` with `options` for 3 frames on a row of 8 objects whose
/// last four are hidden, and checks that each frame's first
/// `max_depth + 1` box tests of kind `step` walk the hierarchy top-down:
/// the root, then exactly the children of the nodes the level before found
/// visible (a node whose box meets a visible object), so that a hidden
/// subtree is not opened; and that each frame draws exactly the visible
/// objects. Returns the rig and, per frame, the walk's levels and the
/// `step` tests after them.
pub(crate) fn assert_walks_top_down(name: &str, options: &[&str], step: &str) -> (Rig, Vec<WalkTests>) {
    let rig = Rig::row(8);
    let h = &rig.hierarchy;
    let mut mock = rig.mock().with_gpu_culling();
    for hidden in 4..8 {
        mock.set_visible(hidden, false);
    }
    let seen: Vec<Aabb> = (0..4).map(|i| rig.scene.instances[i].bounds).collect();
    let visible = |n: &u32| seen.iter().any(|b| b.overlaps(h.bounds(*n)));
    let mut built = method(name, options);
    let mut frames = Vec::new();
    for calls in rig.run(&mut built, &mut mock, 3) {
        let mut tests: Vec<Vec<u32>> =
            culling_steps(&calls).into_iter().filter(|(s, _)| *s == step).map(|(_, ids)| ids).collect();
        let levels = h.max_depth() as usize + 1;
        assert!(tests.len() >= levels, "{name}: {} {step}s for {levels} levels", tests.len());
        let rest = tests.split_off(levels);
        assert_eq!(tests[0], [h.root()]);
        for pair in tests.windows(2) {
            let mut opened: Vec<u32> =
                pair[0].iter().filter(|n| visible(n)).flat_map(|&n| h.children(n).to_vec()).collect();
            opened.sort_unstable();
            assert_eq!(pair[1], opened);
        }
        assert_draws_exactly(&calls, &[0, 1, 2, 3]);
        frames.push((tests, rest));
    }
    (rig, frames)
}
