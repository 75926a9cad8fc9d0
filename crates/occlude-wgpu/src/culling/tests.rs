//! GPU-resident culling on a real adapter (lavapipe in CI), on a hand-built
//! scene: a wall in front of the camera, boxes behind it, beside it, around
//! the eye, behind the eye and off to the side.

use super::*;
use crate::{GpuContext, GpuScene, WgpuBackend};
use glam::{Mat4, Quat, Vec3};
use occlude_core::query_box::BOX_TRIANGLES;
use occlude_core::{Backend, FrameStats, GpuCulling, Instruments, Mesh};

const SIZE: u32 = 64;

/// Instances of [`scene`], by role.
const WALL: u32 = 0;
const HIDDEN: u32 = 1;
const BESIDE: u32 = 2;
const AROUND_EYE: u32 = 3;
const BEHIND_EYE: u32 = 4;
const OFF_SIDE: u32 = 5;
const IN_FRONT: u32 = 6;

/// Instances a depth test draws (in view, not all hidden by the wall).
const IN_VIEW: [u32; 4] = [WALL, HIDDEN, BESIDE, IN_FRONT];

fn camera() -> Camera {
    Camera {
        position: Vec3::ZERO,
        target: Vec3::NEG_Z,
        up: Vec3::Y,
        fov_y_deg: 60.0,
        aspect: 1.0,
        near: 0.25,
        far: 100.0,
        matrices: None,
    }
}

fn scene() -> Scene {
    let mut scene = Scene::new("culling");
    // A quad first, so that the cube lies past the pools' start.
    let quad = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0)], vec![0, 1, 2, 1, 3, 2]);
    let quad = scene.add_mesh(quad);
    let corners = Aabb::new(Vec3::splat(-0.5), Vec3::splat(0.5)).corners().to_vec();
    let cube = scene.add_mesh(Mesh::new(corners, BOX_TRIANGLES.iter().flatten().map(|&c| u32::from(c)).collect()));
    let place = |scale: Vec3, angle: f32, at: Vec3| {
        Mat4::from_scale_rotation_translation(scale, Quat::from_rotation_y(angle), at)
    };
    scene.add_instance(cube, place(Vec3::new(6.0, 20.0, 0.5), 0.0, Vec3::new(0.0, 0.0, -10.0)), 0);
    scene.add_instance(cube, place(Vec3::ONE, 0.3, Vec3::new(0.0, 0.0, -20.0)), 1);
    scene.add_instance(cube, place(Vec3::ONE, 0.7, Vec3::new(8.0, 0.0, -20.0)), 2);
    // Around the eye, its faces beyond the far plane: flagged, never seen.
    scene.add_instance(cube, place(Vec3::splat(300.0), 0.0, Vec3::ZERO), 1);
    scene.add_instance(cube, place(Vec3::ONE, 0.0, Vec3::new(0.0, 0.0, 5.0)), 1);
    scene.add_instance(cube, place(Vec3::ONE, 0.0, Vec3::new(50.0, 0.0, -10.0)), 1);
    scene.add_instance(quad, place(Vec3::splat(2.0), 0.5, Vec3::new(-2.0, -1.0, -6.0)), 3);
    scene
}

/// The GPU, when there is one that runs GPU-resident culling; without one
/// the test is skipped unless `OCCLUDE_REQUIRE_GPU=1`.
fn gpu(test: &str, scene: &Scene) -> Option<Arc<GpuScene>> {
    let ctx = GpuContext::for_test(test)?;
    if let Err(e) = ctx.gpu_culling_support() {
        let required = std::env::var("OCCLUDE_REQUIRE_GPU").is_ok_and(|v| v == "1");
        assert!(!required, "{test}: OCCLUDE_REQUIRE_GPU=1 but {e}");
        eprintln!("skipping {test}: {e}");
        return None;
    }
    eprintln!("{test}: multi-draw-indirect-count: {}", ctx.multi_draw_indirect_count());
    Some(Arc::new(GpuScene::new(ctx, scene).expect("the scene fits")))
}

/// The flags of `flags` as 0 or 1, read through the backend's instrument.
fn read_flags(backend: &mut WgpuBackend, flags: Flags) -> Vec<u32> {
    GpuCulling::read_flags(backend, flags).into_iter().map(u32::from).collect()
}

/// The ids of `list`, sorted, read through the backend's instrument.
fn read_list(backend: &mut WgpuBackend, list: IdList) -> Vec<u32> {
    let mut ids = GpuCulling::read_list(backend, list);
    ids.sort_unstable();
    ids
}

fn all_instances(scene: &Scene) -> Vec<u32> {
    (0..scene.instances.len() as u32).collect()
}

fn depth_after(backend: &mut WgpuBackend, frame: impl FnOnce(&mut WgpuBackend)) -> (Vec<f32>, FrameStats) {
    backend.begin_frame(&camera());
    frame(backend);
    let stats = backend.end_frame();
    let mut depth = Vec::new();
    backend.depth_image(&mut depth);
    assert_eq!(backend.failure(), None);
    (depth, stats)
}

fn assert_same_depth(a: &[f32], b: &[f32], what: &str) {
    assert_eq!(a.len(), b.len());
    assert!(a.iter().filter(|&&d| d < 1.0).count() > a.len() / 2, "{what}: the reference image is mostly empty");
    let differ = a.iter().zip(b).filter(|(x, y)| x.to_bits() != y.to_bits()).count();
    assert_eq!(differ, 0, "{what}: {differ} of {} depth pixels differ", a.len());
}

#[test]
fn box_tests_flag_what_the_depth_buffer_does_not_hide() {
    let scene = scene();
    let Some(gpu) = gpu("box_tests_flag_what_the_depth_buffer_does_not_hide", &scene) else { return };
    let mut backend = WgpuBackend::new(gpu, &scene, SIZE, SIZE);
    let n = scene.instances.len();
    let mut boxes: Vec<Aabb> = scene.instances.iter().map(|i| i.bounds).collect();
    boxes.push(Aabb::EMPTY);
    let c = backend.gpu_culling().expect("lavapipe runs GPU culling");
    let set = c.create_boxes(&boxes);
    let flags = c.create_flags(n as u32 + 1);
    let ids = c.create_list(n as u32 + 1, &(0..=n as u32).collect::<Vec<_>>());
    let visible = c.create_list(n as u32 + 1, &[]);

    backend.begin_frame(&camera());
    backend.draw(&[WALL]);
    let c = backend.gpu_culling().unwrap();
    c.test_boxes(set, ids, flags);
    c.compact(flags, None, visible);
    let count = c.read_count(visible);
    backend.end_frame();
    assert_eq!(backend.failure(), None);
    let mut expected = vec![0u32; n + 1];
    for i in [WALL, BESIDE, AROUND_EYE, IN_FRONT] {
        expected[i as usize] = 1;
    }
    assert_eq!(
        read_flags(&mut backend, flags),
        expected,
        "flags (hidden {HIDDEN}, behind eye {BEHIND_EYE}, off side {OFF_SIDE}, empty {n})"
    );
    assert_eq!(count, 4);
    assert_eq!(read_list(&mut backend, visible), [WALL, BESIDE, AROUND_EYE, IN_FRONT]);

    // A frame that starts with a test clears the depth first: nothing hides
    // the box behind the wall now. Flags are kept until cleared.
    backend.begin_frame(&camera());
    let c = backend.gpu_culling().unwrap();
    c.clear_flags(flags);
    c.test_boxes(set, ids, flags);
    backend.end_frame();
    expected[HIDDEN as usize] = 1;
    assert_eq!(read_flags(&mut backend, flags), expected);
}

/// The resources of [`culled_frame`].
#[derive(Clone, Copy)]
struct Handles {
    all: IdList,
    set: BoxSet,
    flags: Flags,
    visible: IdList,
}

/// A CPU draw, a box test, compaction, a list draw and a CPU draw, in that
/// order, on any backend with GPU-resident culling.
fn culled_frame(b: &mut dyn Backend, h: Handles) {
    b.draw(&[WALL]);
    let c = b.gpu_culling().unwrap();
    c.clear_flags(h.flags);
    c.test_boxes(h.set, h.all, h.flags);
    c.compact(h.flags, None, h.visible);
    assert_eq!(c.read_count(h.visible), 4);
    c.draw_list(h.visible);
    b.draw(&[HIDDEN]);
}

/// The counts of `stats`, leaving out times and fragments (which the wgpu
/// backend does not count).
fn counts(s: &FrameStats) -> [u64; 12] {
    [
        s.queries,
        s.query_boxes,
        s.draw_calls,
        s.state_changes,
        s.material_switches,
        s.triangles,
        s.visible_objects,
        s.traversal_steps,
        s.dispatches,
        s.indirect_draws,
        s.indirect_draw_calls,
        s.readbacks,
    ]
}

#[test]
fn soft_and_wgpu_count_culling_work_alike() {
    let scene = scene();
    let Some(gpu) = gpu("soft_and_wgpu_count_culling_work_alike", &scene) else { return };
    let mut on_gpu = WgpuBackend::new(gpu, &scene, SIZE, SIZE);
    let mut soft = occlude_soft::SoftBackend::new(&scene, SIZE, SIZE, occlude_soft::GpuModel::modern());
    let frame = |b: &mut dyn Backend| {
        let n = scene.instances.len() as u32;
        let c = b.gpu_culling().unwrap();
        let all = c.create_list(n, &all_instances(&scene));
        let boxes: Vec<Aabb> = scene.instances.iter().map(|i| i.bounds).collect();
        let h = Handles { all, set: c.create_boxes(&boxes), flags: c.create_flags(n), visible: c.create_list(n, &[]) };
        assert_eq!(c.pyramid_support(), Ok(()));
        let pyramid = c.create_pyramid();
        b.begin_frame(&camera());
        culled_frame(b, h);
        // hiz's commands: a pyramid of the depth so far, boxes tested on it.
        let c = b.gpu_culling().unwrap();
        c.build_pyramid(pyramid);
        c.clear_flags(h.flags);
        c.test_boxes_pyramid(h.set, h.all, pyramid, 2, h.flags);
        b.end_frame()
    };
    let (g, s) = (frame(&mut on_gpu), frame(&mut soft));
    assert_eq!(on_gpu.failure(), None);
    assert_eq!(counts(&g), counts(&s), "wgpu {g:?}\nsoft {s:?}");
}

/// List draws against `Backend::draw` of the same instances, bit for bit,
/// interleaved with CPU draws, box tests and compaction; and their
/// statistics.
fn list_draws_match_cpu_draws(test: &str, multi_draw_count: bool) {
    let scene = scene();
    let Some(gpu) = gpu(test, &scene) else { return };
    let mut backend = WgpuBackend::new(gpu, &scene, SIZE, SIZE);
    let n = scene.instances.len() as u32;
    let boxes: Vec<Aabb> = scene.instances.iter().map(|i| i.bounds).collect();
    let c = backend.gpu_culling().unwrap();
    let all = c.create_list(n, &all_instances(&scene));
    let set = c.create_boxes(&boxes);
    let flags = c.create_flags(n);
    let visible = c.create_list(n, &[]);
    backend.culling.as_mut().unwrap().multi_draw_count = multi_draw_count;

    let (reference, vfc) = depth_after(&mut backend, |b| b.draw(&all_instances(&scene)));
    let (listed, stats) = depth_after(&mut backend, |b| b.gpu_culling().unwrap().draw_list(all));
    assert_same_depth(&reference, &listed, "a list of every instance");
    assert_eq!(
        (stats.draw_calls, stats.indirect_draw_calls, stats.triangles, stats.visible_objects),
        (vfc.draw_calls, vfc.draw_calls, vfc.triangles, vfc.visible_objects)
    );
    assert_eq!((stats.indirect_draws, stats.dispatches, stats.readbacks), (1, 1, 0));

    let (culled, stats) = depth_after(&mut backend, |b| culled_frame(b, Handles { all, set, flags, visible }));
    let (reference, _) = depth_after(&mut backend, |b| b.draw(&IN_VIEW));
    assert_same_depth(&reference, &culled, "draw, test, compact, draw list, draw");
    let cube = 12;
    let expected = FrameStats {
        draw_calls: 1 + 4 + 1,
        indirect_draw_calls: 4,
        triangles: cube * (1 + 3 + 1) + 2,
        // The wall is drawn twice.
        visible_objects: 5,
        // The boxes in the frustum and away from the eye.
        query_boxes: 4,
        // To the box test and back to drawing for the list draw (the first
        // state is no change).
        state_changes: 2,
        // From the list draw to the last draw's material.
        material_switches: 1,
        indirect_draws: 2,
        dispatches: 4,
        readbacks: 1,
        ..stats
    };
    assert_eq!(stats, expected);
    assert!(stats.cull_ms + stats.render_ms <= stats.gpu_ms + 1e-9, "{stats:?}");
    // The next frame counts afresh; its one pass only draws.
    let (_, stats) = depth_after(&mut backend, |b| b.draw(&[HIDDEN]));
    assert_eq!((stats.draw_calls, stats.visible_objects, stats.indirect_draw_calls, stats.dispatches), (1, 1, 0, 0));
    assert!(stats.cull_ms == 0.0 && (stats.render_ms - stats.gpu_ms).abs() < 1e-9, "{stats:?}");
}

#[test]
fn list_draws_match_cpu_draws_bit_for_bit() {
    list_draws_match_cpu_draws("list_draws_match_cpu_draws_bit_for_bit", true);
}

#[test]
fn list_draws_without_a_count_buffer_match_too() {
    list_draws_match_cpu_draws("list_draws_without_a_count_buffer_match_too", false);
}

#[test]
fn expand_and_compact_build_lists_and_flags() {
    let scene = scene();
    let Some(gpu) = gpu("expand_and_compact_build_lists_and_flags", &scene) else { return };
    let mut backend = WgpuBackend::new(gpu, &scene, SIZE, SIZE);
    let c = backend.gpu_culling().unwrap();
    // One box around the eye: its test sets flag 0 without drawing.
    let eye = c.create_boxes(&[Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0))]);
    let seed = c.create_flags(3);
    let first = c.create_list(1, &[0]);
    let roots = c.create_table(&[ItemRange { first: 0, count: 2 }], &[0, 2]);
    let flags = c.create_flags(3);
    let src = c.create_list(3, &[0, 1, 2]);
    let children = c.create_table(
        &[ItemRange { first: 0, count: 2 }, ItemRange { first: 2, count: 1 }, ItemRange { first: 3, count: 3 }],
        &[10, 11, 12, 13, 14, 15],
    );
    let dst = c.create_list(8, &[7, 7, 7]);
    let rest = c.create_list(3, &[]);

    backend.begin_frame(&camera());
    let c = backend.gpu_culling().unwrap();
    assert_eq!(c.read_count(dst), 3, "a list holds its ids until replaced");
    c.test_boxes(eye, first, seed);
    c.expand(first, seed, roots, ExpandInto::Flags(flags));
    c.expand(src, flags, children, ExpandInto::List(dst));
    c.compact(flags, Some(seed), rest);
    assert_eq!(c.read_count(dst), 5);
    let stats = backend.end_frame();
    assert_eq!(backend.failure(), None);
    assert_eq!(read_flags(&mut backend, seed), [1, 0, 0]);
    assert_eq!(read_flags(&mut backend, flags), [1, 0, 1]);
    assert_eq!(read_list(&mut backend, dst), [10, 11, 13, 14, 15]);
    assert_eq!(read_list(&mut backend, rest), [2]);
    assert_eq!((stats.dispatches, stats.readbacks, stats.draw_calls), (4, 2, 0));
}

#[test]
fn frustum_culling_clears_only_the_flags_of_boxes_out_of_view() {
    let scene = scene();
    let Some(gpu) = gpu("frustum_culling_clears_only_the_flags_of_boxes_out_of_view", &scene) else { return };
    let mut backend = WgpuBackend::new(gpu, &scene, SIZE, SIZE);
    let n = scene.instances.len() as u32;
    let boxes: Vec<Aabb> = scene.instances.iter().map(|i| i.bounds).collect();
    let c = backend.gpu_culling().unwrap();
    let set = c.create_boxes(&boxes);
    let eye = c.create_boxes(&[Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0))]);
    let first = c.create_list(1, &[0]);
    let every = c.create_table(&[ItemRange { first: 0, count: n }], &all_instances(&scene));
    let (seed, flags) = (c.create_flags(1), c.create_flags(n));
    let visible = c.create_list(n, &[]);
    backend.begin_frame(&camera());
    let c = backend.gpu_culling().unwrap();
    // Every flag set (the box around the eye passes untested), then culled.
    c.test_boxes(eye, first, seed);
    c.expand(first, seed, every, ExpandInto::Flags(flags));
    c.drop_outside_frustum(set, flags);
    c.compact(flags, None, visible);
    backend.end_frame();
    assert_eq!(backend.failure(), None);
    assert_eq!(read_list(&mut backend, visible), [WALL, HIDDEN, BESIDE, AROUND_EYE, IN_FRONT]);
}

#[test]
fn dispatches_cover_every_thread() {
    assert_eq!(workgroups(0), (1, 1));
    assert_eq!(workgroups(64), (1, 1));
    assert_eq!(workgroups(65), (2, 1));
    let (x, y) = workgroups(u32::MAX);
    assert!(x <= MAX_GROUPS_PER_DIMENSION && u64::from(x) * u64::from(y) * 64 >= u64::from(u32::MAX));
}

/// Boxes in front of the camera of [`scene`] at many places and depths, some
/// behind the wall, some beside it, some small enough to fall between pixels.
fn scattered_boxes() -> Vec<Aabb> {
    let mut rng = occlude_core::rng::Rng::new(18, 0);
    (0..200)
        .map(|_| {
            let at = Vec3::new(rng.unit() * 24.0 - 12.0, rng.unit() * 24.0 - 12.0, -2.0 - rng.unit() * 30.0);
            let half = Vec3::new(rng.unit(), rng.unit(), rng.unit()) * rng.unit() * 2.0 + Vec3::splat(0.001);
            Aabb::new(at - half, at + half)
        })
        .collect()
}

/// The pyramid box test on the GPU against `DepthPyramid::test` on the CPU,
/// both over the wgpu backend's depth after drawing the scene, at odd sizes
/// and 1x1, reach 2 and 8: the GPU never hides a box the CPU finds visible.
/// (The flags need not be equal box for box: the GPU divides in `f32` where
/// the CPU divides in `f64`, so `cull.wgsl` grows each footprint by a bound
/// on that rounding, which can only add texels and lower the depth.)
#[test]
fn pyramid_tests_never_hide_what_the_cpu_pyramid_finds_visible() {
    use occlude_core::depth_pyramid::{box_footprint, DepthPyramid};
    let scene = scene();
    let Some(gpu) = gpu("pyramid_tests_never_hide_what_the_cpu_pyramid_finds_visible", &scene) else { return };
    let boxes = scattered_boxes();
    let n = boxes.len() as u32;
    let camera = camera();
    let (mut visible, mut hidden, mut hidden_on_gpu) = (0, 0, 0);
    for (width, height) in [(1, 1), (67, 45), (SIZE, SIZE), (5, 130)] {
        let mut backend = WgpuBackend::new(Arc::clone(&gpu), &scene, width, height);
        let c = backend.gpu_culling().unwrap();
        let set = c.create_boxes(&boxes);
        let ids = c.create_list(n, &(0..n).collect::<Vec<_>>());
        let flags = c.create_flags(n);
        let pyramid = c.create_pyramid();
        for reach in [2, 8] {
            backend.begin_frame(&camera);
            backend.draw(&[WALL, BESIDE, IN_FRONT]);
            let c = backend.gpu_culling().unwrap();
            c.clear_flags(flags);
            c.build_pyramid(pyramid);
            c.test_boxes_pyramid(set, ids, pyramid, reach, flags);
            backend.end_frame();
            let on_gpu = read_flags(&mut backend, flags);
            let mut depth = Vec::new();
            backend.depth_image(&mut depth);
            assert_eq!(backend.failure(), None);
            let mut cpu = DepthPyramid::new(width, height);
            cpu.build(&depth);
            let vp = camera.view_projection();
            let frustum = camera.frustum();
            let on_cpu: Vec<u32> = boxes
                .iter()
                .map(|b| {
                    let b = occlude_core::query_box::padded(b);
                    let visible = camera.box_touches_near_region(&b)
                        || frustum.intersects(&b) && cpu.test(&box_footprint(&vp, width, height, &b), reach).visible;
                    u32::from(visible)
                })
                .collect();
            let what = format!("{width}x{height}, reach {reach}");
            let hidden_on_cpu = on_cpu.iter().filter(|&&v| v == 0).count();
            (visible, hidden) = (visible + boxes.len() - hidden_on_cpu, hidden + hidden_on_cpu);
            let falsely_hidden: Vec<usize> = (0..boxes.len()).filter(|&i| on_cpu[i] == 1 && on_gpu[i] == 0).collect();
            assert!(falsely_hidden.is_empty(), "{what}: the GPU hides boxes {falsely_hidden:?}");
            let extra = (0..boxes.len()).filter(|&i| on_cpu[i] == 0 && on_gpu[i] == 1).count();
            hidden_on_gpu += hidden_on_cpu - extra;
            eprintln!("{what}: {hidden_on_cpu} boxes hidden on the CPU, {extra} of them visible on the GPU");
        }
    }
    assert!(visible > 0 && hidden > 0, "the CPU finds {visible} boxes visible and {hidden} hidden in all");
    assert!(hidden_on_gpu > 0, "the GPU hides no box");
}
