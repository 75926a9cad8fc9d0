//! `om` (occupancy maps + multiple occlusion queries, Staneker, Bartz and
//! Straßer) against the correctness rule of `docs/design.md`, and against
//! stop-and-wait for the queries its first stage saves.

use occlude_bench::runner::run_scene;
use occlude_bench::{BenchConfig, BenchRun};
use occlude_core::methods::{MethodOptions, NodeClass};
use occlude_core::{FrameStats, HierarchyKind, Scene};
use occlude_scenes::{generate, Size, PAPER_SCENES};

/// The whole walkthrough of each small scene at the resolution the
/// correctness suite uses, running `methods` with `options`.
fn config(scene: &str, hierarchy: HierarchyKind, methods: &[&str], options: &[&str]) -> BenchConfig {
    BenchConfig {
        scene: scene.into(),
        methods: methods.iter().map(|m| m.to_string()).collect(),
        frames: 90,
        resolution: (480, 360),
        hierarchy,
        options: MethodOptions::parse(options).unwrap(),
        ..BenchConfig::default()
    }
}

fn small(scene: &str) -> Scene {
    let s = generate(scene, Size::Small, 1).unwrap();
    s.validate().unwrap();
    s
}

fn run(scene: &Scene, cfg: &BenchConfig) -> BenchRun {
    run_scene(scene, cfg, &()).unwrap()
}

fn total(frames: &[FrameStats], field: fn(&FrameStats) -> u64) -> u64 {
    frames.iter().map(field).sum()
}

/// With and without occupancy-map grouping of its queries, with the paper's
/// stage-2 rule and queue order and the alternatives, `om` produces view-frustum
/// culling's depth image bit for bit on every frame, while actually culling
/// (so the check is not met by drawing everything).
#[test]
fn om_matches_vfc_on_every_frame_of_every_small_scene() {
    for name in PAPER_SCENES {
        let scene = small(name);
        for hierarchy in [HierarchyKind::Bvh, HierarchyKind::KdTree] {
            for options in [&[][..], &["om.grouping=off"], &["om.overlap=off", "om.corner=off"]] {
                let r = run(&scene, &config(name, hierarchy, &["om"], options));
                let om = &r.methods[0];
                for (f, stats) in om.frames.iter().enumerate() {
                    assert_eq!(
                        stats.missing_pixels, 0,
                        "{name}/{hierarchy}/om {options:?}: frame {f} differs from vfc"
                    );
                }
                let (om_tris, vfc_tris) = (total(&om.frames, |f| f.triangles), total(&r.reference, |f| f.triangles));
                assert!(
                    om_tris < vfc_tris,
                    "{name}/{hierarchy}/om {options:?}: culled nothing ({om_tris} vs {vfc_tris})"
                );
                assert!(total(&om.frames, |f| f.queries) > 0, "{name}/{hierarchy}/om {options:?}: no query issued");
            }
        }
    }
}

/// Stage 1 draws the nodes that reach uncovered screen space without a
/// query, so on the city walkthrough `om` issues fewer queries per frame than
/// stop-and-wait, which queries every node it reaches.
#[test]
fn stage_one_saves_queries_over_stop_and_wait_on_the_city() {
    let scene = small("city");
    for hierarchy in [HierarchyKind::Bvh, HierarchyKind::KdTree] {
        let r = run(&scene, &config("city", hierarchy, &["sw", "om"], &[]));
        let (sw, om) = (&r.methods[0], &r.methods[1]);
        assert_eq!((sw.name.as_str(), om.name.as_str()), ("sw", "om"));
        let per_frame = |frames: &[FrameStats]| total(frames, |f| f.queries) as f64 / frames.len() as f64;
        let (sw_q, om_q) = (per_frame(&sw.frames), per_frame(&om.frames));
        assert!(om_q < sw_q, "{hierarchy}: om issued {om_q:.1} queries per frame, sw {sw_q:.1}");
        // The savings are reported per frame as stage-1 decisions and rounds.
        let stage1 = &om.counters["stage1_no_query_nodes"];
        assert_eq!(stage1.len(), om.frames.len());
        assert!(stage1.iter().sum::<f64>() > 0.0, "{hierarchy}: no stage-1 decision recorded");
        assert!(om.counters["stage2_rounds"].iter().any(|&r| r >= 1.0));
        assert!(sw.counters.is_empty());
    }
}

/// Grouping the queries into rounds of boxes that do not overlap on screen
/// avoids the false "visible" answers of boxes queried behind undrawn
/// geometry, so on the city walkthrough `om` draws fewer triangles with
/// grouping than without it.
#[test]
fn grouping_avoids_redundant_visible_answers_on_the_city() {
    let scene = small("city");
    for hierarchy in [HierarchyKind::Bvh, HierarchyKind::KdTree] {
        let triangles = |options: &[&str]| {
            let r = run(&scene, &config("city", hierarchy, &["om"], options));
            total(&r.methods[0].frames, |f| f.triangles)
        };
        let (grouped, brute) = (triangles(&[]), triangles(&["om.grouping=off"]));
        assert!(grouped < brute, "{hierarchy}: {grouped} triangles with grouping, {brute} without");
    }
}

/// Asked for frame 10 of the small city, `om` records its decisions without
/// changing them: the run's statistics equal those of a run that records
/// nothing, stage 1 drew nodes, and the map has covered and clear cells.
#[test]
fn om_debug_view_of_a_city_frame_records_without_changing_decisions() {
    let scene = small("city");
    let mut cfg = config("city", HierarchyKind::Bvh, &["vfc", "om"], &[]);
    cfg.frames = 20;
    let plain = run(&scene, &cfg);
    assert!(plain.dumps.is_empty());
    cfg.dump_frame = Some(10);
    let dumped = run(&scene, &cfg);
    // All but the real time (`wall_ms`) is deterministic.
    let decided = |r: &BenchRun| -> Vec<FrameStats> {
        r.methods[1].frames.iter().map(|f| FrameStats { wall_ms: 0.0, ..*f }).collect()
    };
    assert_eq!(decided(&plain), decided(&dumped));

    assert_eq!(dumped.dumps.len(), 1, "only om records a view");
    let d = &dumped.dumps[0];
    assert_eq!((d.method.as_str(), d.frame, d.resolution), ("om", 10, (480, 360)));
    assert_eq!(d.depth.len(), 480 * 360);
    let v = &d.view;
    assert_eq!((v.map_width, v.map_height), (64, 48));
    assert_eq!(v.occupancy.len(), 64 * 48);
    assert!(v.occupancy.contains(&true) && v.occupancy.contains(&false), "map should be partly covered");
    let count = |class| v.nodes.iter().filter(|(c, _)| *c == class).count();
    assert!(count(NodeClass::DrawnWithoutQuery) > 0, "stage 1 drew nothing");
    // Every query of the frame is a node drawn after a query, found hidden,
    // or an interior node found visible and opened; the last are not listed.
    let queried = count(NodeClass::DrawnAfterQuery) + count(NodeClass::FoundHidden);
    assert!(queried as u64 <= dumped.methods[1].frames[10].queries);
    assert!(count(NodeClass::FoundHidden) > 0, "the city hides something in frame 10");
}
