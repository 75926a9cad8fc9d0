//! A frame drawing more triangles than the soft backend keeps recorded
//! (2^20, after which a draw rasterizes what waits first): its depth image,
//! counts and simulated times are those of the same draws rasterized one
//! instance at a time, so splitting the recorded work changes nothing.

use glam::{Mat4, Vec3};
use occlude_core::{Backend, Camera, CameraPath, FrameStats, Instruments, Keyframe, Mesh, Scene};
use occlude_soft::{GpuModel, SoftBackend};

/// A square sheet of `n` x `n` cells, two triangles each, facing +z.
fn sheet(n: u32) -> Mesh {
    let positions = (0..=n)
        .flat_map(|y| (0..=n).map(move |x| Vec3::new(x as f32 / n as f32 - 0.5, y as f32 / n as f32 - 0.5, 0.0)))
        .collect();
    let at = |x: u32, y: u32| y * (n + 1) + x;
    let indices = (0..n)
        .flat_map(|y| {
            (0..n)
                .flat_map(move |x| [at(x, y), at(x + 1, y), at(x + 1, y + 1), at(x, y), at(x + 1, y + 1), at(x, y + 1)])
        })
        .collect();
    Mesh::new(positions, indices)
}

/// 40 sheets of 2 x 128 x 128 triangles (1.31 million) one behind the
/// other, shifted so that each shows a little.
fn stack() -> Scene {
    let mut scene = Scene::new("stack");
    scene.path = CameraPath::default();
    let mesh = scene.add_mesh(sheet(128));
    for k in 0..40 {
        let at = Vec3::new(0.02 * k as f32, 0.01 * k as f32, -2.0 - 0.05 * k as f32);
        scene.add_instance(mesh, Mat4::from_translation(at), k % 4);
    }
    scene
}

fn camera() -> Camera {
    let key = Keyframe { time: 0.0, position: Vec3::ZERO, target: -Vec3::Z, fov_y_deg: 60.0 };
    key.camera(4.0 / 3.0, 0.1, 100.0)
}

#[test]
fn a_frame_past_the_recorded_limit_matches_one_drawn_instance_by_instance() {
    let scene = stack();
    assert!(scene.triangle_count() > 1 << 20, "{} triangles", scene.triangle_count());
    let all: Vec<u32> = (0..scene.instances.len() as u32).collect();
    let frame = |one_by_one: bool| -> (Vec<f32>, FrameStats) {
        let mut backend = SoftBackend::new(&scene, 64, 48, GpuModel::modern());
        let mut image = Vec::new();
        backend.begin_frame(&camera());
        if one_by_one {
            for i in &all {
                backend.draw(std::slice::from_ref(i));
                backend.depth_image(&mut image);
            }
        } else {
            backend.draw(&all);
        }
        let stats = backend.end_frame();
        backend.depth_image(&mut image);
        (image, FrameStats { wall_ms: 0.0, ..stats })
    };
    let (whole, split) = (frame(false), frame(true));
    assert!(whole.0.iter().any(|&d| d < 1.0), "the sheets are in view");
    assert_eq!(whole.0, split.0, "depth images differ");
    assert_eq!(whole.1, split.1, "statistics differ");
}
