//! The correctness rule of DESIGN.md on every frame of every `small` scene,
//! for both hierarchies: conservative methods produce view-frustum culling's
//! depth image bit for bit, and `opt` draws exactly the leaves holding an
//! instance that the oracle sees.

use indicatif::ProgressBar;
use occlude::bench::runner::{cameras, run_scene};
use occlude::bench::BenchConfig;
use occlude_core::methods::{create, DrawnSet};
use occlude_core::{Backend, FrameContext, Hierarchy, HierarchyKind, Scene};
use occlude_scenes::{generate, Size, SCENE_NAMES};
use occlude_soft::SoftBackend;
use std::collections::HashSet;

/// Frames and resolution of the correctness runs: the whole walkthrough of
/// each scene, at a resolution that keeps the suite within CI's budget.
fn config(scene: &str, hierarchy: HierarchyKind) -> BenchConfig {
    BenchConfig {
        scene: scene.into(),
        methods: vec!["vfc".into(), "sw".into(), "opt".into()],
        frames: 90,
        resolution: (480, 360),
        hierarchy,
        ..BenchConfig::default()
    }
}

fn small(scene: &str) -> Scene {
    let s = generate(scene, Size::Small, 1).unwrap();
    s.validate().unwrap();
    s
}

#[test]
fn conservative_methods_match_vfc_on_every_frame() {
    for name in SCENE_NAMES {
        let scene = small(name);
        for hierarchy in [HierarchyKind::Bvh, HierarchyKind::KdTree] {
            let cfg = config(name, hierarchy);
            let run = run_scene(&scene, &cfg, &ProgressBar::hidden()).unwrap();
            for m in &run.methods {
                for (f, stats) in m.frames.iter().enumerate() {
                    assert_eq!(stats.missing_pixels, 0, "{name}/{hierarchy}/{}: frame {f} differs from vfc", m.name);
                }
            }
            // The walkthrough must show something and let occlusion work.
            let vfc = &run.methods[0].frames;
            let sw = &run.methods[1].frames;
            let vfc_tris: u64 = vfc.iter().map(|f| f.triangles).sum();
            let sw_tris: u64 = sw.iter().map(|f| f.triangles).sum();
            assert!(vfc_tris > 0, "{name}: the walkthrough sees nothing");
            assert!(sw_tris < vfc_tris, "{name}/{hierarchy}: stop-and-wait culled nothing ({sw_tris} vs {vfc_tris})");
        }
    }
}

#[test]
fn opt_draws_exactly_the_leaves_the_oracle_sees_and_sw_draws_them_too() {
    for name in SCENE_NAMES {
        let scene = small(name);
        for hierarchy in [HierarchyKind::Bvh, HierarchyKind::KdTree] {
            let cfg = BenchConfig { frames: 30, ..config(name, hierarchy) };
            let h = Hierarchy::build(&scene, hierarchy, cfg.build);
            let (w, ht) = cfg.resolution;
            let mut oracle = SoftBackend::new(&scene, w, ht, cfg.gpu_model.clone());
            let mut lanes: Vec<_> = ["sw", "opt"]
                .iter()
                .map(|m| {
                    (create(m, &Default::default()).unwrap().method, SoftBackend::new(&scene, w, ht, cfg.gpu_model.clone()), DrawnSet::default())
                })
                .collect();
            for (f, camera) in cameras(&scene, &cfg).iter().enumerate() {
                let all: Vec<u32> = (0..scene.instances.len() as u32).collect();
                let seen: HashSet<u32> = oracle.visible_instances(camera, &all).into_iter().collect();
                for (method, backend, drawn) in &mut lanes {
                    let mut ctx = FrameContext::new(&scene, &h, *camera, drawn);
                    method.prepare(&mut ctx, backend);
                    backend.begin_frame(camera);
                    method.render(&mut ctx, backend);
                    backend.end_frame();
                    for &i in &seen {
                        assert!(
                            ctx.was_drawn(i),
                            "{name}/{hierarchy}/{}: frame {f}: visible instance {i} not drawn",
                            method.name()
                        );
                    }
                    if method.name() == "opt" {
                        // Nothing beyond the leaves that hold a seen instance.
                        let allowed: HashSet<u32> = (0..h.node_count() as u32)
                            .filter(|&n| h.is_leaf(n) && h.instances(n).iter().any(|i| seen.contains(i)))
                            .flat_map(|n| h.instances(n).iter().copied())
                            .collect();
                        for i in 0..scene.instances.len() as u32 {
                            assert!(
                                !ctx.was_drawn(i) || allowed.contains(&i),
                                "{name}/{hierarchy}: frame {f}: opt drew {i}, which shares no leaf with a visible instance"
                            );
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn simulated_figures_are_identical_between_runs() {
    let cfg = BenchConfig { frames: 20, resolution: (320, 240), ..config("city", HierarchyKind::Bvh) };
    let scene = small("city");
    let strip = |mut r: occlude::bench::BenchReport| {
        r.scene_stats.build_wall_ms = 0.0;
        for m in &mut r.methods {
            m.wall_ms = 0.0;
            for f in &mut m.per_frame {
                f.wall_ms = 0.0;
            }
        }
        serde_json::to_string(&r).unwrap()
    };
    let a = run_scene(&scene, &cfg, &ProgressBar::hidden()).unwrap().report(&cfg);
    let b = run_scene(&scene, &cfg, &ProgressBar::hidden()).unwrap().report(&cfg);
    assert_eq!(strip(a), strip(b));
}
