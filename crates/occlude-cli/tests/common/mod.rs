//! Checks shared by the soft (`correctness.rs`) and wgpu (`gpu.rs`) test
//! files, so that both backends are held to the same rule by the same code.

use glam::Mat4;
use occlude_cli::bench::runner::{cameras, far_plane};
use occlude_cli::bench::BenchConfig;
use occlude_core::methods::{check_support, create, DrawnSet};
use occlude_core::{differing_pixels, render_frame, Backend, Camera, Hierarchy, Scene};

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
    mut backend: impl FnMut() -> Box<dyn Backend + 'b>,
) -> Vec<(String, usize)> {
    assert_eq!(cfg.methods.first().map(String::as_str), Some("vfc"), "vfc is the reference, listed first");
    let h = Hierarchy::build(scene, cfg.hierarchy, cfg.build);
    let mut lanes: Vec<_> =
        cfg.methods.iter().map(|m| (create(m, &cfg.options).unwrap().method, backend(), DrawnSet::default())).collect();
    for (method, backend, _) in &mut lanes {
        check_support(method.as_ref(), backend.as_mut()).expect("the backend runs every method given");
    }
    let mut culled = vec![0; lanes.len()];
    let (mut reference, mut image) = (Vec::new(), Vec::new());
    for (f, (kind, camera)) in cameras_from_matrices(scene, cfg).iter().enumerate() {
        let mut vfc_draws = 0;
        for (k, (method, backend, drawn)) in lanes.iter_mut().enumerate() {
            let stats = render_frame(method.as_mut(), backend.as_mut(), scene, &h, camera, drawn);
            assert_eq!(backend.failure(), None, "{kind} camera {f}: {}", method.name());
            let out = if k == 0 { &mut reference } else { &mut image };
            backend.instruments().expect("the backend has a depth image").depth_image(out);
            if k == 0 {
                assert!(reference.iter().any(|&d| d < 1.0), "{kind} camera {f}: vfc drew nothing");
                vfc_draws = stats.draw_calls;
            } else {
                let differ = differing_pixels(&reference, &image);
                assert_eq!(differ, 0, "{kind} camera {f}: {} differs from vfc in {differ} pixels", method.name());
                culled[k] += usize::from(stats.draw_calls < vfc_draws);
            }
        }
    }
    lanes.iter().map(|(m, ..)| m.name().to_string()).zip(culled).skip(1).collect()
}
