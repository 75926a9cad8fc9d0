//! The GPU-driven methods (`roc`, `ioc`, `hiz`) on the soft backend's
//! [`occlude_core::GpuCulling`]: the correctness rule on every frame of
//! every `small` scene of the papers with both hierarchies, `hiz` on
//! the million-instance `swarm` at its small size, `hiz` at the resolutions
//! where pyramids go wrong (odd sizes, 1x1), each `hiz` test with both
//! granularities (instances, nodes top-down), `ioc` over several depth
//! ranges, with its start chosen per frame, and with and without its
//! frustum test, `roc.mode=last` reporting the pixels it misses, the frame
//! statistics of a GPU-driven frame, and the depth options' errors and
//! warnings. `tests/gpu.rs` runs the same methods on the wgpu backend.

use occlude_bench::config::ALL_FRAMES;
use occlude_bench::runner::{run_scene, BenchRun};
use occlude_bench::BenchConfig;
use occlude_core::depth_pyramid::level_sizes;
use occlude_core::methods::MethodOptions;
use occlude_core::{HierarchyKind, Scene};
use occlude_scenes::{generate, Size, PAPER_SCENES};

fn config(scene: &str, hierarchy: HierarchyKind, methods: &[&str], options: &[&str]) -> BenchConfig {
    BenchConfig {
        scene: scene.into(),
        methods: methods.iter().map(|m| m.to_string()).collect(),
        options: MethodOptions::parse(options).unwrap(),
        frames: 90,
        resolution: (480, 360),
        hierarchy,
        ..BenchConfig::default()
    }
}

fn small(scene: &str) -> Scene {
    generate(scene, Size::Small, 1).unwrap()
}

/// `cfg` over the whole walkthrough, 2.5 frames a second of it (0.4 s
/// apart): `roc` and `ioc` draw last frame's visible set first, in view or
/// not, so they cull only between frames that see much the same (90 frames
/// spread over the plant's 130 s have `roc` draw more than `vfc`).
fn whole_walkthrough(cfg: BenchConfig) -> BenchConfig {
    BenchConfig { fps: Some(2.5), frames: ALL_FRAMES, ..cfg }
}

fn run(scene: &Scene, cfg: &BenchConfig) -> BenchRun {
    run_scene(scene, cfg, &()).unwrap()
}

fn assert_exact(run: &BenchRun, what: &str) {
    for m in &run.methods {
        for (f, stats) in m.frames.iter().enumerate() {
            assert_eq!(stats.missing_pixels, 0, "{what}/{}: frame {f} differs from vfc", m.name);
        }
    }
}

#[test]
fn roc_ioc_and_hiz_match_vfc_on_every_frame_and_cull() {
    for name in PAPER_SCENES {
        let scene = small(name);
        for hierarchy in [HierarchyKind::Bvh, HierarchyKind::KdTree] {
            let r = run(&scene, &whole_walkthrough(config(name, hierarchy, &["vfc", "roc", "ioc", "hiz"], &[])));
            assert_exact(&r, &format!("{name}/{hierarchy}"));
            let triangles = |m: usize| r.methods[m].frames.iter().map(|f| f.triangles).sum::<u64>();
            assert!(triangles(1) < triangles(0), "{name}/{hierarchy}: roc culled nothing");
            assert!(triangles(3) < triangles(0), "{name}/{hierarchy}: hiz culled nothing");
            let node =
                run(&scene, &whole_walkthrough(config(name, hierarchy, &["vfc", "hiz"], &["hiz.granularity=node"])));
            assert_exact(&node, &format!("{name}/{hierarchy}/hiz.granularity=node"));
            let node_triangles = node.methods[1].frames.iter().map(|f| f.triangles).sum::<u64>();
            assert!(node_triangles < triangles(0), "{name}/{hierarchy}: hiz.granularity=node culled nothing");
            // At its bottom depth ioc draws whole subtrees (frustum-culled), and
            // both draw last frame's visible set first, in view or not: ioc
            // draws less than vfc only where occlusion is strong.
            if name == "city" {
                assert!(triangles(2) < triangles(0), "{name}/{hierarchy}: ioc culled nothing");
            }
        }
    }
}

#[test]
fn hiz_matches_vfc_at_odd_and_tiny_resolutions() {
    let scene = small("city");
    for resolution in [(1024, 768), (1920, 1080), (1366, 768), (1023, 767), (641, 479), (1, 1)] {
        // The field's 2x2 texels a box, and more texels of a finer level,
        // testing instances or the hierarchy's nodes top-down.
        for texels in ["hiz.texels=2", "hiz.texels=8"] {
            for granularity in ["hiz.granularity=instance", "hiz.granularity=node"] {
                let what = format!("city/{texels}/{granularity} at {resolution:?}");
                let cfg = config("city", HierarchyKind::Bvh, &["vfc", "hiz"], &[texels, granularity]);
                let r = run(&scene, &BenchConfig { frames: 6, resolution, ..cfg });
                assert_exact(&r, &what);
                let drawn = |m: usize| r.methods[m].frames.iter().map(|f| f.triangles).sum::<u64>();
                if resolution.0 > 1 {
                    assert!(drawn(1) < drawn(0), "{what} culled nothing");
                }
            }
        }
    }
}

/// `hiz` at its defaults on every other `small` scene of the papers at
/// the six target sizes: 0 missing pixels on every frame (the city, with
/// the default's 8 texels among its options: the test above).
#[test]
fn hiz_matches_vfc_on_every_scene_at_every_target_size() {
    for name in PAPER_SCENES.into_iter().filter(|&name| name != "city") {
        let scene = small(name);
        for resolution in [(1024, 768), (1920, 1080), (1366, 768), (1023, 767), (641, 479), (1, 1)] {
            let cfg = config(name, HierarchyKind::Bvh, &["vfc", "hiz"], &[]);
            let r = run(&scene, &BenchConfig { frames: 6, resolution, ..cfg });
            assert_eq!(r.methods.len(), 2, "{name} at {resolution:?}: a method did not run");
            assert_exact(&r, &format!("{name} at {resolution:?}"));
        }
    }
}

/// The million-instance scene at its small size (4,000 objects), frames
/// spread over its whole walkthrough (the overview, the streets, the climb
/// out), with both hierarchies.
#[test]
fn hiz_matches_vfc_on_every_frame_of_the_swarm() {
    let scene = small("swarm");
    for hierarchy in [HierarchyKind::Bvh, HierarchyKind::KdTree] {
        for granularity in ["hiz.granularity=instance", "hiz.granularity=node"] {
            let what = format!("swarm/{hierarchy}/{granularity}");
            let cfg = config("swarm", hierarchy, &["vfc", "hiz"], &[granularity]);
            let r = run(&scene, &BenchConfig { frames: 60, fps: None, ..cfg });
            assert_eq!(r.methods[1].frames.len(), 60);
            assert_exact(&r, &what);
            let drawn = |m: usize| r.methods[m].frames.iter().map(|f| f.triangles).sum::<u64>();
            assert!(drawn(1) * 2 < drawn(0), "{what}: hiz drew {} triangles, vfc {}", drawn(1), drawn(0));
        }
    }
}

#[test]
fn ioc_is_exact_over_every_depth_range() {
    for name in PAPER_SCENES {
        let scene = small(name);
        for (start, bottom) in [("0", "deepest"), ("0", "0"), ("2", "3"), ("deepest", "deepest"), ("6", "deepest-1")] {
            let options = [format!("ioc.start={start}"), format!("ioc.bottom={bottom}")];
            let cfg = config(name, HierarchyKind::Bvh, &["vfc", "ioc"], &[&options[0], &options[1]]);
            assert_exact(&run(&scene, &cfg), &format!("{name}/ioc {start}..{bottom}"));
        }
        let cfg = config(name, HierarchyKind::Bvh, &["vfc", "ioc"], &["ioc.auto=on"]);
        assert_exact(&run(&scene, &cfg), &format!("{name}/ioc auto"));
    }
}

#[test]
fn iocs_frustum_test_draws_less_and_stays_exact() {
    // A shallow bottom: each visible bottom node holds objects far outside
    // the frustum.
    let scene = small("figures");
    let drawn = |options: &[&str]| {
        let r = run(&scene, &config("figures", HierarchyKind::Bvh, &["vfc", "ioc"], options));
        assert_exact(&r, &format!("figures/ioc {options:?}"));
        r.methods[1].frames.iter().map(|f| f.triangles).sum::<u64>()
    };
    let (on, off) = (drawn(&["ioc.bottom=4"]), drawn(&["ioc.bottom=4", "ioc.frustum=off"]));
    assert!(on < off, "ioc drew {on} triangles with the frustum test, {off} without");
}

#[test]
fn roc_last_mode_reports_the_pixels_it_misses() {
    let scene = small("city");
    let r = run(&scene, &config("city", HierarchyKind::Bvh, &["roc"], &["roc.mode=last"]));
    let frames = &r.methods[0].frames;
    // The first frame has no previous visible set: nothing is drawn.
    assert_eq!(frames[0].triangles, 0);
    assert!(frames[0].missing_pixels > 0);
    // Later frames draw what the frame before found, which is not always enough.
    let later: u64 = frames[1..].iter().map(|f| f.missing_pixels).sum();
    assert!(frames[1..].iter().all(|f| f.triangles > 0));
    assert!(later > 0, "the walkthrough never shows an object a frame late");
}

#[test]
fn a_gpu_driven_frame_reads_nothing_back_and_counts_its_passes() {
    let scene = small("figures");
    let r = run(&scene, &config("figures", HierarchyKind::Bvh, &["vfc", "roc", "ioc", "hiz"], &[]));
    let (vfc, roc, ioc, hiz) = (&r.methods[0].frames, &r.methods[1].frames, &r.methods[2].frames, &r.methods[3].frames);
    for f in vfc {
        assert_eq!((f.dispatches, f.indirect_draws, f.readbacks), (0, 0, 0));
        assert!((f.render_ms > 0.0 || f.triangles == 0) && f.cull_ms == 0.0);
    }
    for f in roc.iter().chain(ioc).chain(hiz) {
        assert_eq!((f.queries, f.readbacks, f.traversal_steps), (0, 0, 0));
        assert_eq!(f.draw_calls, f.indirect_draw_calls, "every draw is inside a multi-draw");
        assert!(f.cull_ms > 0.0 && (f.render_ms > 0.0 || f.triangles == 0));
        assert!((f.cull_ms + f.render_ms - f.gpu_ms).abs() < 1e-9, "GPU time is culling plus drawing");
    }
    assert!(roc.iter().chain(ioc).map(|f| f.query_boxes).sum::<u64>() > 0);
    // roc: occluders, one box test, newly visible; 6 dispatches (clear, test,
    // two compactions, two draw-argument passes).
    assert!(roc.iter().all(|f| f.indirect_draws == 3 && f.dispatches == 6), "{:?}", roc[1]);
    // The levels' box tests are indirect draws too.
    let levels = ioc[1].indirect_draws - 2;
    assert!(levels >= 1 && ioc.iter().all(|f| f.indirect_draws == levels + 2));
    // hiz: two list draws and no box drawn; 7 dispatches (frustum drop,
    // three compactions, clear, pyramid test, two draw-argument passes)
    // and one per pyramid level past level 0.
    let reductions = level_sizes(480, 360).len() as u64 - 1;
    assert!(hiz.iter().all(|f| f.indirect_draws == 2 && f.dispatches == 7 + reductions), "{:?}", hiz[1]);
    assert!(hiz.iter().map(|f| f.query_boxes).sum::<u64>() > 0, "hiz tested no box against its pyramid");
    // hiz's GPU time splits into early, pyramid and late passes; the others
    // build no pyramid.
    for f in hiz {
        assert!(f.pyramid_ms > 0.0 && f.late_ms > 0.0 && f.pyramid_ms < f.cull_ms, "{f:?}");
        assert!(f.pyramid_ms + f.late_ms < f.gpu_ms, "the early pass takes time too: {f:?}");
    }
    assert!(vfc.iter().chain(roc).chain(ioc).all(|f| f.pyramid_ms == 0.0 && f.late_ms == 0.0));
}

#[test]
fn ioc_depths_past_the_tree_are_clamped_with_a_warning() {
    let scene = small("teapots");
    let cfg = config("teapots", HierarchyKind::Bvh, &["vfc", "ioc"], &["ioc.start=2", "ioc.bottom=400"]);
    let r = run(&scene, &BenchConfig { frames: 5, ..cfg });
    assert_exact(&r, "teapots/ioc bottom=400");
    assert_eq!(r.warnings.len(), 1, "{:?}", r.warnings);
    assert!(r.warnings[0].contains("ioc.bottom = 400 is past the hierarchy's depth"), "{}", r.warnings[0]);
    let cfg = config("teapots", HierarchyKind::Bvh, &["ioc"], &["ioc.start=7", "ioc.bottom=5"]);
    let err = run_scene(&scene, &cfg, &()).err().expect("start below bottom is an error");
    assert!(err.to_string().contains("ioc.bottom = 5"), "{err:#}");
}
