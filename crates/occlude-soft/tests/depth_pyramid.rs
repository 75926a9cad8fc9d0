//! The depth pyramid's proof on the exact rasterizer: on random depth
//! images at odd sizes (1x1, 1023x767, 641x479 and small random ones) and
//! random boxes, reading 1x1 to 8x8 texels a box, whenever the
//! full-resolution box test (`GpuCulling::test_boxes`) finds a visible pixel
//! of a box, the pyramid test (`GpuCulling::test_boxes_pyramid`) says
//! visible; and over all cases
//! the pyramid hides boxes the frustum keeps, so the property is not met
//! by calling everything visible.

use glam::Vec3;
use occlude_core::rng::Rng;
use occlude_core::{Aabb, Backend, Camera, Scene};
use occlude_soft::{GpuModel, SoftBackend};
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use std::cell::Cell;

fn empty_scene() -> Scene {
    Scene::new("empty")
}

/// A depth image of a few overlapping rectangles at random depths over a
/// far background, each pixel jittered (so blocks are not uniform).
fn depth_image(rng: &mut Rng, width: u32, height: u32) -> Vec<f32> {
    let mut depth: Vec<f32> = (0..width * height).map(|_| rng.range(0.99, 1.0)).collect();
    for _ in 0..rng.below(6) + 1 {
        let (x0, y0) = (rng.below(width), rng.below(height));
        let (x1, y1) = (x0 + rng.below(width - x0) + 1, y0 + rng.below(height - y0) + 1);
        let d = rng.range(0.8, 0.99);
        for y in y0..y1 {
            for x in x0..x1 {
                let p = &mut depth[(y * width + x) as usize];
                *p = p.min(d + rng.range(0.0, 0.002));
            }
        }
    }
    depth
}

/// Boxes in front of the camera (some crossing the near plane or the image's
/// edges), from a few centimetres to several metres wide, some thin.
fn boxes(rng: &mut Rng, count: usize) -> Vec<Aabb> {
    (0..count)
        .map(|_| {
            let centre = Vec3::new(rng.range(-12.0, 12.0), rng.range(-9.0, 9.0), -rng.range(0.2, 40.0));
            let size = Vec3::new(rng.range(0.0, 1.0), rng.range(0.0, 1.0), rng.range(0.0, 1.0)) * rng.range(0.01, 6.0);
            Aabb::new(centre - size, centre + size)
        })
        .collect()
}

/// What one case found: boxes in the frustum or at the eye, and
/// of those the pyramid hid.
struct Outcome {
    in_view: u32,
    pyramid_hid: u32,
}

/// Runs both tests on one depth image and set of boxes; fails when the
/// full-resolution test finds a box visible that the pyramid test hides.
fn check(width: u32, height: u32, reach: u32, seed: u64) -> Result<Outcome, TestCaseError> {
    let mut rng = Rng::new(seed, 18);
    let camera = Camera {
        position: Vec3::ZERO,
        target: Vec3::NEG_Z,
        up: Vec3::Y,
        fov_y_deg: 60.0,
        aspect: width as f32 / height as f32,
        near: 0.25,
        far: 200.0,
        matrices: None,
    };
    let depth = depth_image(&mut rng, width, height);
    let boxes = boxes(&mut rng, 48);
    let scene = empty_scene();
    let mut backend = SoftBackend::new(&scene, width, height, GpuModel::modern());
    backend.begin_frame(&camera);
    backend.write_depth(&depth);
    let n = boxes.len() as u32;
    let ids: Vec<u32> = (0..n).collect();
    let gpu = backend.gpu_culling().unwrap();
    let (set, all) = (gpu.create_boxes(&boxes), gpu.create_list(n, &ids));
    let (exact, pyramid_flags, scratch) = (gpu.create_flags(n), gpu.create_flags(n), gpu.create_list(n, &[]));
    let pyramid = gpu.create_pyramid();
    gpu.build_pyramid(pyramid);
    gpu.test_boxes_pyramid(set, all, pyramid, reach, pyramid_flags);
    gpu.test_boxes(set, all, exact);
    gpu.compact(exact, Some(pyramid_flags), scratch);
    let missed = gpu.read_count(scratch);
    prop_assert_eq!(
        missed,
        0,
        "{}x{} reach {} seed {}: the pyramid hid boxes the exact test sees",
        width,
        height,
        reach,
        seed
    );
    gpu.compact(pyramid_flags, None, scratch);
    let pyramid_visible = gpu.read_count(scratch);
    let frustum = camera.frustum();
    let padded: Vec<Aabb> = boxes.iter().map(occlude_core::query_box::padded).collect();
    let in_view = padded.iter().filter(|b| frustum.intersects(b) || camera.box_touches_near_region(b)).count() as u32;
    Ok(Outcome { in_view, pyramid_hid: in_view - pyramid_visible })
}

#[test]
fn the_pyramid_never_hides_what_the_full_resolution_test_sees() {
    let (in_view, hid) = (Cell::new(0), Cell::new(0));
    let sizes = prop_oneof![
        Just((1u32, 1u32)),
        Just((1023, 767)),
        Just((641, 479)),
        (1u32..70, 1u32..70),
        (1u32..3, 1u32..300),
    ];
    let mut runner = TestRunner::new(Config { cases: 200, failure_persistence: None, ..Config::default() });
    runner
        .run(&(sizes, 1u32..9, any::<u64>()), |((w, h), reach, seed)| {
            let o = check(w, h, reach, seed)?;
            in_view.set(in_view.get() + o.in_view);
            hid.set(hid.get() + o.pyramid_hid);
            Ok(())
        })
        .unwrap();
    assert!(hid.get() > 0, "the pyramid hid none of {} boxes in view: a vacuous pass", in_view.get());
    eprintln!("the pyramid hid {} of {} boxes in view", hid.get(), in_view.get());
}
