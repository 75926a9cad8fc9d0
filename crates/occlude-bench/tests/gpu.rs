//! The wgpu backend on a real adapter (lavapipe in CI, with
//! `OCCLUDE_REQUIRE_GPU=1`; skipped with a message where no adapter exists):
//! the correctness rule of `docs/design.md` with depth images read back from the
//! GPU, and a cross-check of what the GPU and the soft rasterizer see.

mod common;

use occlude_bench::config::{BackendKind, ALL_FRAMES};
use occlude_bench::runner::{cameras, run_scene};
use occlude_bench::BenchConfig;
use occlude_core::methods::{MethodOptions, METHOD_NAMES};
use occlude_core::{Backend, HierarchyKind, Instruments, Scene, UpdatePolicy};
use occlude_scenes::{generate, Size, PAPER_SCENES};
use occlude_soft::SoftBackend;
use occlude_wgpu::{GpuContext, GpuScene, WgpuBackend};
use std::sync::Arc;

/// Every method, on the wgpu backend.
fn config(scene: &str, hierarchy: HierarchyKind, frames: usize) -> BenchConfig {
    BenchConfig {
        scene: scene.into(),
        methods: METHOD_NAMES.map(String::from).to_vec(),
        frames,
        resolution: (320, 240),
        hierarchy,
        backend: BackendKind::Wgpu,
        ..BenchConfig::default()
    }
}

fn small(scene: &str) -> Scene {
    generate(scene, Size::Small, 1).unwrap()
}

#[test]
fn every_method_matches_vfc_on_the_gpu_on_every_frame() {
    if GpuContext::for_test("every_method_matches_vfc_on_the_gpu_on_every_frame").is_none() {
        return;
    }
    let runs = PAPER_SCENES.iter().map(|&name| (name, HierarchyKind::Bvh)).chain([("city", HierarchyKind::KdTree)]);
    for (name, hierarchy) in runs {
        let scene = small(name);
        // The whole walkthrough 0.4 s apart: `roc` and `ioc` draw last
        // frame's visible set first, in view or not, so they cull only
        // between frames that see much the same (90 frames spread over the
        // plant's 130 s have `roc` draw more than `vfc`).
        let cfg = BenchConfig { fps: Some(2.5), ..config(name, hierarchy, ALL_FRAMES) };
        let frames = cameras(&scene, &cfg).unwrap().len();
        let run = run_scene(&scene, &cfg, &()).unwrap();
        assert_eq!(run.aborted, None);
        assert!(run.adapter.is_some());
        for m in &run.methods {
            assert_eq!(m.frames.len(), frames, "{name}/{}: frames lost", m.name);
            for (f, stats) in m.frames.iter().enumerate() {
                assert_eq!(stats.missing_pixels, 0, "{name}/{hierarchy}/{}: frame {f} differs from vfc", m.name);
            }
        }
        // No method draws fewer triangles than the instances owning a
        // pixel (the GPU's oracle: `opt`).
        common::assert_opt_is_a_lower_bound(&run, &format!("{name}/{hierarchy} on the GPU"));
        // Occlusion works on the GPU too: the occlusion methods draw less.
        // Not `ioc`: every object in view below a visible bottom node is
        // drawn, hidden or not, which can add up to more than vfc. Not
        // `nocull`, which culls nothing by design.
        let triangles = |m: usize| run.methods[m].frames.iter().map(|f| f.triangles).sum::<u64>();
        for m in (1..run.methods.len()).filter(|&m| !["ioc", "nocull"].contains(&run.methods[m].name.as_str())) {
            assert!(
                triangles(m) < triangles(0),
                "{name}/{hierarchy}: {} drew {} triangles, vfc {}",
                run.methods[m].name,
                triangles(m),
                triangles(0)
            );
        }
    }
}

/// `hiz` on the million-instance scene at its small size (4,000 objects),
/// frames spread over its whole walkthrough: the correctness rule and
/// culling on the GPU.
#[test]
fn hiz_matches_vfc_on_the_gpu_on_every_frame_of_the_swarm() {
    if GpuContext::for_test("hiz_matches_vfc_on_the_gpu_on_every_frame_of_the_swarm").is_none() {
        return;
    }
    let scene = small("swarm");
    let cfg =
        BenchConfig { methods: vec!["vfc".into(), "hiz".into()], fps: None, ..config("swarm", HierarchyKind::Bvh, 60) };
    let run = run_scene(&scene, &cfg, &()).unwrap();
    assert_eq!(run.aborted, None);
    let hiz = &run.methods[1];
    assert_eq!(hiz.frames.len(), 60, "frames lost");
    for (f, stats) in hiz.frames.iter().enumerate() {
        assert_eq!(stats.missing_pixels, 0, "swarm/hiz: frame {f} differs from vfc");
    }
    let drawn = |m: usize| run.methods[m].frames.iter().map(|f| f.triangles).sum::<u64>();
    assert!(drawn(1) * 2 < drawn(0), "swarm: hiz drew {} triangles, vfc {}", drawn(1), drawn(0));
}

/// Cameras from matrices (reverse-Z infinite, forward infinite,
/// orthographic) on the GPU: the depth flip, the frustum and the near
/// region reach the wgpu backend's draws, queries and GPU-resident culling
/// as they reach the soft backend's, and a query method, a GPU-driven one
/// and the CPU buffer give vfc's depth on every camera.
#[test]
fn methods_match_vfc_on_the_gpu_with_cameras_from_matrices() {
    let Some(ctx) = GpuContext::for_test("methods_match_vfc_on_the_gpu_with_cameras_from_matrices") else { return };
    let scene = small("city");
    let cfg = BenchConfig {
        methods: ["vfc", "sw", "chcpp", "roc", "hiz", "moc"].map(String::from).to_vec(),
        resolution: (240, 180),
        ..config("city", HierarchyKind::Bvh, 6)
    };
    let gpu = Arc::new(GpuScene::new(ctx, &scene).unwrap());
    let (w, h) = cfg.resolution;
    let culled = common::assert_methods_match_vfc_with_cameras_from_matrices(&scene, &cfg, || {
        Box::new(WgpuBackend::new(Arc::clone(&gpu), &scene, w, h))
    });
    for (method, cameras) in culled {
        assert!(cameras > 0, "{method} never drew fewer objects than vfc: the cameras test no occlusion");
    }
}

/// `hiz` on the GPU at the six target sizes and 67x45 (pyramids with odd
/// levels, and a one-texel pyramid at 1x1), reading the field's 2x2 texels
/// a box and 8x8, and walking the hierarchy's nodes top-down
/// (`hiz.granularity=node`): 0 missing pixels on every frame.
#[test]
fn hiz_matches_vfc_on_the_gpu_at_odd_and_tiny_sizes() {
    if GpuContext::for_test("hiz_matches_vfc_on_the_gpu_at_odd_and_tiny_sizes").is_none() {
        return;
    }
    let scene = small("city");
    for resolution in [(1024, 768), (1920, 1080), (1366, 768), (1023, 767), (641, 479), (67, 45), (1, 1)] {
        for option in ["hiz.texels=2", "hiz.texels=8", "hiz.granularity=node"] {
            assert_hiz_exact_on_the_gpu(&scene, "city", resolution, &[option]);
        }
    }
}

/// `vfc` and `hiz` with `options` on the GPU over 6 frames of `scene`
/// (named `name`) at `resolution`: every frame of both kept, each with 0
/// missing pixels.
fn assert_hiz_exact_on_the_gpu(scene: &Scene, name: &str, resolution: (u32, u32), options: &[&str]) {
    let what = format!("{name} {options:?} at {resolution:?}");
    let cfg = BenchConfig {
        methods: vec!["vfc".into(), "hiz".into()],
        options: MethodOptions::parse(options).unwrap(),
        resolution,
        ..config(name, HierarchyKind::Bvh, 6)
    };
    let run = run_scene(scene, &cfg, &()).unwrap();
    assert_eq!(run.aborted, None, "{what}");
    assert_eq!(run.methods.len(), 2, "{what}: a method did not run");
    for m in &run.methods {
        assert_eq!(m.frames.len(), 6, "{what}/{}: frames lost", m.name);
        for (f, stats) in m.frames.iter().enumerate() {
            assert_eq!(stats.missing_pixels, 0, "{what}/{}: frame {f}", m.name);
        }
    }
}

/// `hiz` at its defaults on the GPU on every other `small` scene of the
/// papers at the six target sizes: 0 missing pixels on every frame (the
/// city, with the default's 8 texels among its options: the test above).
#[test]
fn hiz_matches_vfc_on_the_gpu_on_every_scene_at_every_target_size() {
    if GpuContext::for_test("hiz_matches_vfc_on_the_gpu_on_every_scene_at_every_target_size").is_none() {
        return;
    }
    for name in PAPER_SCENES.into_iter().filter(|&name| name != "city") {
        let scene = small(name);
        for resolution in [(1024, 768), (1920, 1080), (1366, 768), (1023, 767), (641, 479), (1, 1)] {
            assert_hiz_exact_on_the_gpu(&scene, name, resolution, &[]);
        }
    }
}

/// Soft and wgpu oracles over every instance in view: the visible sets agree
/// except for objects the exact soft rasterizer sees with at most
/// `ROUNDING_PIXELS` pixels (the two rasterizers round vertex positions
/// differently); the worst disagreement is printed.
#[test]
fn soft_and_gpu_see_the_same_objects() {
    const ROUNDING_PIXELS: u64 = 8;
    let Some(ctx) = GpuContext::for_test("soft_and_gpu_see_the_same_objects") else { return };
    let mut worst = (0u64, String::new());
    for name in PAPER_SCENES {
        let scene = small(name);
        let cfg = config(name, HierarchyKind::Bvh, 12);
        let (w, h) = cfg.resolution;
        let gpu = Arc::new(GpuScene::new(Arc::clone(&ctx), &scene).unwrap());
        let mut on_gpu = WgpuBackend::new(gpu, &scene, w, h);
        let mut soft = SoftBackend::new(&scene, w, h, cfg.gpu_model.clone());
        let mut compared = 0;
        for (k, camera) in cameras(&scene, &cfg).unwrap().iter().enumerate() {
            let frustum = camera.frustum();
            let candidates: Vec<u32> = (0..scene.instances.len() as u32)
                .filter(|&i| frustum.intersects(&scene.instances[i as usize].bounds))
                .collect();
            let a = soft.oracle(camera, &candidates);
            let b = on_gpu.oracle(camera, &candidates);
            assert_eq!(on_gpu.failure(), None);
            for (j, &i) in candidates.iter().enumerate() {
                let (s, g) = (a.pixels[j], b.pixels[j]);
                if (s > 0) != (g > 0) {
                    let what = format!("{name} frame {k} instance {i}: soft {s} px, gpu {g} px");
                    assert!(s <= ROUNDING_PIXELS, "{what}");
                    if s >= worst.0 {
                        worst = (s, what);
                    }
                }
            }
            compared += a.visible.len();
        }
        assert!(compared > 0, "{name}: nothing visible");
    }
    eprintln!("worst soft/gpu visibility disagreement: {}", if worst.1.is_empty() { "none" } else { &worst.1 });
}

/// `--queries hib` on the GPU: the query methods give vfc's image on every
/// frame of every `small` scene, each submission's queries counted by their
/// boxes' fragments in one pass.
#[test]
fn query_methods_with_hib_counts_match_vfc_on_the_gpu() {
    if GpuContext::for_test("query_methods_with_hib_counts_match_vfc_on_the_gpu").is_none() {
        return;
    }
    for name in PAPER_SCENES {
        let scene = small(name);
        let cfg = BenchConfig {
            methods: ["vfc", "sw", "chc", "chcpp", "om"].map(String::from).to_vec(),
            queries: occlude_core::QueryMode::Hib,
            ..config(name, HierarchyKind::Bvh, 90)
        };
        let run = run_scene(&scene, &cfg, &()).unwrap();
        assert_eq!(run.aborted, None);
        for m in &run.methods {
            assert_eq!(m.frames.len(), 90, "{name}/{}: frames lost", m.name);
            assert!(m.name == "vfc" || m.frames.iter().any(|f| f.queries > 0), "{name}/{}: no queries", m.name);
            for (f, stats) in m.frames.iter().enumerate() {
                assert_eq!(stats.missing_pixels, 0, "{name}/{}: frame {f} differs from vfc with hib counts", m.name);
            }
        }
    }
}

/// The counts of `--queries hib` are the hardware queries' counts, query for
/// query (lavapipe's occlusion queries are exact): with half the instances
/// in view drawn, each instance's box queried, and each pair of
/// neighbouring boxes as one multi-query (boxes that overlap, counted twice
/// where they do, as a hardware query counts them), in both modes; the list
/// repeated past one query set of 4096. On the soft backend too.
#[test]
fn hib_counts_equal_hardware_counts() {
    use occlude_core::{Aabb, QueryMode};
    let Some(ctx) = GpuContext::for_test("hib_counts_equal_hardware_counts") else { return };
    for name in ["city", "plant"] {
        let scene = small(name);
        let cfg = config(name, HierarchyKind::Bvh, 30);
        let (w, h) = cfg.resolution;
        let gpu = Arc::new(GpuScene::new(Arc::clone(&ctx), &scene).unwrap());
        let mut hardware = WgpuBackend::new(Arc::clone(&gpu), &scene, w, h);
        let mut hib = WgpuBackend::new(gpu, &scene, w, h);
        hib.set_query_mode(QueryMode::Hib).expect("lavapipe runs counted queries");
        let mut soft = SoftBackend::new(&scene, w, h, cfg.gpu_model.clone());
        let mut soft_hib = SoftBackend::new(&scene, w, h, cfg.gpu_model.clone());
        soft_hib.set_query_mode(QueryMode::Hib);
        let (mut partial, mut zero) = (0, 0);
        for camera in cameras(&scene, &cfg).unwrap().iter().step_by(10) {
            let frustum = camera.frustum();
            let in_view: Vec<u32> = (0..scene.instances.len() as u32)
                .filter(|&i| frustum.intersects(&scene.instances[i as usize].bounds))
                .collect();
            let occluders: Vec<u32> = in_view.iter().copied().step_by(2).collect();
            let bounds = |i: &u32| scene.instances[*i as usize].bounds;
            let mut queries: Vec<Vec<Aabb>> = in_view.iter().map(|i| vec![bounds(i)]).collect();
            queries.extend(in_view.windows(2).map(|p| p.iter().map(bounds).collect()));
            let repeats = 4100 / queries.len().max(1) + 1;
            let queries: Vec<Vec<Aabb>> = queries.iter().cycle().take(queries.len() * repeats).cloned().collect();
            let answer = |backend: &mut dyn Backend| {
                backend.begin_frame(camera);
                backend.draw(&occluders);
                let handles: Vec<_> = queries.iter().map(|q| backend.issue_query(q)).collect();
                let counts: Vec<u64> = handles.into_iter().map(|q| backend.result(q)).collect();
                backend.end_frame();
                counts
            };
            let expected = answer(&mut hardware);
            assert_eq!(answer(&mut hib), expected, "{name}: hib counts differ from the hardware queries'");
            assert_eq!(answer(&mut soft_hib), answer(&mut soft), "{name}: soft hib counts differ");
            assert_eq!((hardware.failure(), hib.failure()), (None, None));
            partial += expected.iter().filter(|&&c| c > 1 && c < 100).count();
            zero += expected.iter().filter(|&&c| c == 0).count();
        }
        // Counts that zero / not zero would not tell apart.
        assert!(partial > 0 && zero > 0, "{name}: {partial} small counts, {zero} zero");
    }
}

#[test]
fn every_method_matches_vfc_on_the_gpu_in_scripted_motion_refitted_and_rebuilt() {
    let Some(ctx) = GpuContext::for_test("every_method_matches_vfc_on_the_gpu_in_scripted_motion_refitted_and_rebuilt")
    else {
        return;
    };
    let refit_only = UpdatePolicy { max_cost_ratio: f32::INFINITY };
    let rebuild_always = UpdatePolicy { max_cost_ratio: 0.0 };
    for (policy, rebuilt) in [(refit_only, false), (rebuild_always, true)] {
        let rebuilds = common::assert_methods_match_vfc_in_motion(&METHOD_NAMES, HierarchyKind::Bvh, policy, |scene| {
            let gpu = Arc::new(GpuScene::new(Arc::clone(&ctx), scene).unwrap());
            Box::new(WgpuBackend::new(gpu, scene, 160, 120))
        });
        assert_eq!(rebuilds > 0, rebuilt, "{rebuilds} rebuilds");
    }
}

#[test]
fn every_method_matches_vfc_on_the_gpu_on_every_frame_of_a_moving_city() {
    if GpuContext::for_test("every_method_matches_vfc_on_the_gpu_on_every_frame_of_a_moving_city").is_none() {
        return;
    }
    let scene = small("city");
    let cfg = BenchConfig { motion: 0.3, ..config("city", HierarchyKind::Bvh, 30) };
    let run = run_scene(&scene, &cfg, &()).unwrap();
    assert_eq!(run.aborted, None);
    for m in &run.methods {
        for (f, stats) in m.frames.iter().enumerate() {
            assert_eq!(stats.missing_pixels, 0, "moving city/{}: frame {f} differs from vfc", m.name);
            assert!(stats.instances_moved > 0);
        }
    }
}
