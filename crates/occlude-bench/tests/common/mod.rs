//! Checks shared by the soft (`correctness.rs`) and wgpu (`gpu.rs`) test
//! files, so that both backends are held to the same rule by the same code.

use glam::{Mat4, Quat, Vec3};
use occlude_bench::runner::{cameras, far_plane};
use occlude_bench::{BenchConfig, BenchRun};
use occlude_core::hierarchy::BuildOptions;
use occlude_core::methods::{check_support, create, DrawnSet, MethodOptions};
use occlude_core::{
    differing_pixels, render_frame, Aabb, Backend, Camera, CullingMethod, FrameStats, Hierarchy, HierarchyKind,
    InstanceChange, Mesh, Scene, UpdatePolicy,
};

/// Cameras from matrices: each walkthrough camera's view with a reverse-Z
/// infinite-far perspective, a forward infinite-far perspective and an
/// orthographic projection (near plane behind the eye).
pub fn cameras_from_matrices(scene: &Scene, cfg: &BenchConfig) -> Vec<(&'static str, Camera)> {
    let aspect = cfg.resolution.0 as f32 / cfg.resolution.1 as f32;
    let half_height = scene.bounds().extent().length() * 0.1;
    let far = far_plane(scene);
    cameras(scene, cfg)
        .unwrap()
        .into_iter()
        .flat_map(|c| {
            let fov = c.fov_y_deg.to_radians();
            let ortho = Mat4::orthographic_rh(
                -half_height * aspect,
                half_height * aspect,
                -half_height,
                half_height,
                -2.0,
                far,
            );
            [
                ("reverse-Z infinite", Mat4::perspective_infinite_reverse_rh(fov, aspect, c.near), true),
                ("infinite", Mat4::perspective_infinite_rh(fov, aspect, c.near), false),
                ("orthographic", ortho, false),
            ]
            .map(|(kind, p, reverse)| (kind, Camera::from_matrices(c.view(), p, reverse).unwrap()))
        })
        .collect()
}

/// Renders `cfg`'s methods (`vfc` first) on backends from `backend` with
/// [`cameras_from_matrices`] (each method refused unless the backend runs
/// it, never its fallback) and asserts that every method's depth image
/// equals vfc's on every camera, and that vfc draws something each time.
/// Returns, per method after vfc, on how many cameras it drew fewer objects
/// than vfc (so that a caller can require occlusion to have been tested).
pub fn assert_methods_match_vfc_with_cameras_from_matrices<'b>(
    scene: &Scene,
    cfg: &BenchConfig,
    backend: impl FnMut() -> Box<dyn Backend + 'b>,
) -> Vec<(String, usize)> {
    let h = Hierarchy::build(scene, cfg.hierarchy, cfg.build);
    let mut lanes = Lanes::new(&cfg.methods, &cfg.options, backend);
    let mut culled = vec![0; lanes.0.len()];
    for (f, (kind, camera)) in cameras_from_matrices(scene, cfg).iter().enumerate() {
        let stats = lanes.frame(scene, &h, camera, &format!("{kind} camera {f}"));
        for (k, s) in stats.iter().enumerate().skip(1) {
            culled[k] += usize::from(s.draw_calls < stats[0].draw_calls);
        }
    }
    lanes.0.iter().map(|l| l.method.name().to_string()).zip(culled).skip(1).collect()
}

/// A method on a backend of its own, with its draw bookkeeping.
struct Lane<'b> {
    method: Box<dyn CullingMethod + Send>,
    backend: Box<dyn Backend + 'b>,
    drawn: DrawnSet,
}

/// Methods (`vfc` first, the reference) rendering the same frames.
struct Lanes<'b>(Vec<Lane<'b>>);

impl<'b> Lanes<'b> {
    /// `methods` with `options`, each on a backend from `backend`, which
    /// must run it (never its fallback).
    fn new<S: AsRef<str>>(
        methods: &[S],
        options: &MethodOptions,
        mut backend: impl FnMut() -> Box<dyn Backend + 'b>,
    ) -> Self {
        assert_eq!(methods.first().map(AsRef::as_ref), Some("vfc"), "vfc is the reference, listed first");
        let mut lanes: Vec<_> = methods
            .iter()
            .map(|m| Lane {
                method: create(m.as_ref(), options).unwrap().method,
                backend: backend(),
                drawn: DrawnSet::default(),
            })
            .collect();
        for l in &mut lanes {
            check_support(l.method.as_ref(), l.backend.as_mut()).expect("the backend runs every method given");
        }
        Self(lanes)
    }

    /// Renders one frame on every lane and asserts that vfc draws something
    /// and every other method's depth image equals vfc's; `what` names the
    /// frame in messages. Returns each lane's statistics.
    fn frame(&mut self, scene: &Scene, h: &Hierarchy, camera: &Camera, what: &str) -> Vec<FrameStats> {
        let (mut reference, mut image) = (Vec::new(), Vec::new());
        let mut stats = Vec::with_capacity(self.0.len());
        for (k, l) in self.0.iter_mut().enumerate() {
            stats.push(render_frame(l.method.as_mut(), l.backend.as_mut(), scene, h, camera, &mut l.drawn));
            assert_eq!(l.backend.failure(), None, "{what}: {}", l.method.name());
            let out = if k == 0 { &mut reference } else { &mut image };
            l.backend.instruments().expect("the backend has a depth image").depth_image(out);
            if k == 0 {
                assert!(reference.iter().any(|&d| d < 1.0), "{what}: vfc drew nothing");
            } else {
                let differ = differing_pixels(&reference, &image);
                assert_eq!(differ, 0, "{what}: {} differs from vfc in {differ} pixels", l.method.name());
            }
        }
        stats
    }
}

/// A stage for scripted motion, seen by a camera that stands still: a wall
/// (instance 0) with four cubes behind it (1 to 4) and a fifth cube (5)
/// hidden to start with, then one list of changes per frame: a cube jumps
/// from behind the wall into view within one frame, the wall moves away to
/// reveal the cubes it hid and comes back, the hidden cube appears in view,
/// a visible one disappears, and every cube wanders for a few frames.
pub fn motion_stage() -> (Scene, Camera, Vec<Vec<InstanceChange>>) {
    let mut scene = Scene::new("stage");
    let cube = scene.add_mesh(Mesh::new(
        Aabb::new(Vec3::splat(-0.5), Vec3::splat(0.5)).corners().to_vec(),
        occlude_core::query_box::BOX_TRIANGLES.iter().flatten().map(|&c| u32::from(c)).collect(),
    ));
    let wall =
        Mat4::from_scale_rotation_translation(Vec3::new(8.0, 4.0, 0.3), Quat::IDENTITY, Vec3::new(0.0, 2.0, 0.0));
    scene.add_instance(cube, wall, 0);
    let behind = |x: f32| Mat4::from_translation(Vec3::new(x, 1.0, -3.0));
    for (k, x) in [-2.0, -0.5, 1.0, 2.5].into_iter().enumerate() {
        scene.add_instance(cube, behind(x), 1 + k as u32 % 2);
    }
    scene.add_instance(cube, Mat4::from_translation(Vec3::new(1.5, 0.8, 2.0)), 2);
    let view = Mat4::look_at_rh(Vec3::new(0.0, 2.0, 9.0), Vec3::new(0.0, 1.5, 0.0), Vec3::Y);
    let camera = Camera::from_matrices(view, Mat4::perspective_rh(1.0, 4.0 / 3.0, 0.1, 100.0), false).unwrap();
    let moved = |i: u32, to: Mat4| InstanceChange::Move { instance: i, transform: to };
    let mut script = vec![
        vec![InstanceChange::Hide(5)],
        vec![],
        vec![moved(2, Mat4::from_translation(Vec3::new(-0.5, 1.0, 3.0)))],
        vec![moved(0, Mat4::from_translation(Vec3::X * 20.0) * wall)],
        vec![],
        vec![moved(0, wall)],
        vec![InstanceChange::Show(5)],
        vec![InstanceChange::Hide(2)],
        vec![InstanceChange::Show(2), moved(2, behind(-0.5))],
    ];
    for f in 0..8 {
        let t = f as f32 * 0.7;
        script.push(
            (1..=4)
                .map(|i| {
                    let at = Vec3::new((t + i as f32).sin() * 4.0, 1.0, (t * 1.3 + i as f32).cos() * 4.0 - 1.0);
                    moved(i, Mat4::from_translation(at))
                })
                .collect(),
        );
    }
    (scene, camera, script)
}

/// Runs every method of `methods` (`vfc` first) on its own backend from
/// `backend` through `script` ([`motion_stage`]), updating the hierarchy of
/// `kind` with `policy` and each backend before each frame, and asserts
/// that every method's depth image equals vfc's on every frame. Returns
/// how many frames rebuilt the hierarchy.
pub fn assert_methods_match_vfc_in_motion(
    methods: &[&str],
    kind: HierarchyKind,
    policy: UpdatePolicy,
    mut backend: impl FnMut(&Scene) -> Box<dyn Backend>,
) -> usize {
    let (mut scene, camera, script) = motion_stage();
    let options = BuildOptions { leaf_size: 1, ..BuildOptions::default() };
    let mut h = Hierarchy::build(&scene, kind, options);
    let mut lanes = Lanes::new(methods, &MethodOptions::default(), || backend(&scene));
    let mut rebuilds = 0;
    for (f, changes) in script.iter().enumerate() {
        let changed = scene.apply(changes).unwrap();
        rebuilds += usize::from(h.update(&scene, &changed, policy).rebuilt);
        for l in &mut lanes.0 {
            l.backend.update_instances(&scene, &changed);
        }
        lanes.frame(&scene, &h, &camera, &format!("{kind} frame {f}"));
    }
    rebuilds
}

/// `opt` (the instances owning a pixel of the final image, a method of
/// `run`) is a lower bound: every method and variant of `run`, each of which
/// the caller has checked draws view-frustum culling's image, draws at least
/// `opt`'s triangles on every frame. `what` names the run in messages. The
/// bound is checked not to be empty or trivial: `opt` draws something, and
/// less than `vfc`, over the run.
pub fn assert_opt_is_a_lower_bound(run: &BenchRun, what: &str) {
    let opt = run.methods.iter().find(|m| m.name == "opt").expect("opt is one of the run's methods");
    for m in run.methods.iter().chain(&run.variants).filter(|m| !std::ptr::eq(*m, opt)) {
        assert_eq!(m.frames.len(), opt.frames.len(), "{what}/{}", m.name);
        for (f, (stats, bound)) in m.frames.iter().zip(&opt.frames).enumerate() {
            assert!(
                stats.triangles >= bound.triangles,
                "{what}/{} {:?}: frame {f}: {} triangles, fewer than opt's {}",
                m.name,
                m.params,
                stats.triangles,
                bound.triangles
            );
        }
    }
    let total = |frames: &[occlude_core::FrameStats]| frames.iter().map(|f| f.triangles).sum::<u64>();
    let (opt, vfc) = (total(&opt.frames), total(&run.reference));
    assert!(0 < opt && opt < vfc, "{what}: opt drew {opt} triangles, vfc {vfc}");
}
