//! The correctness rule of `docs/design.md` on every frame of every `small` scene
//! and of an imported building, for both hierarchies: conservative methods
//! produce view-frustum culling's depth image bit for bit and never draw
//! fewer triangles than `opt`, which draws exactly the instances the oracle
//! sees (and with `opt.granularity=node` the leaves holding them).

mod common;

use occlude_bench::ideal::IDEALS;
use occlude_bench::runner::{cameras, load_scene, run_moving_scene, run_scene, run_scene_with_variants, Variant};
use occlude_bench::{BenchConfig, BenchReport};
use occlude_core::methods::{create, DrawnSet, MethodOptions, METHOD_NAMES};
use occlude_core::{Backend, FrameContext, FrameStats, Hierarchy, HierarchyKind, Instruments, Scene, UpdatePolicy};
use occlude_scenes::import::{import, Imported, ModelFormat};
use occlude_scenes::{building, export, generate, AutoPath, ImportOptions, Size, MOVING_SCENES, PAPER_SCENES};
use occlude_soft::GpuModel;
use occlude_soft::SoftBackend;
use std::collections::HashSet;

/// Frames and resolution of the correctness runs: the whole walkthrough of
/// each scene, at a resolution that keeps the suite within CI's budget.
fn config(scene: &str, hierarchy: HierarchyKind) -> BenchConfig {
    BenchConfig {
        scene: scene.into(),
        methods: ["vfc", "sw", "chc", "chcpp", "opt", "moc", "nohc", "nohc-opt"].map(String::from).to_vec(),
        frames: 90,
        resolution: (480, 360),
        hierarchy,
        ..BenchConfig::default()
    }
}

/// The first 45 frames of `scene` with only `methods`, set by `options`:
/// a variant of a method checked exact.
fn variant_config(scene: &str, hierarchy: HierarchyKind, methods: &[&str], options: &[&str]) -> BenchConfig {
    BenchConfig {
        methods: methods.iter().map(|m| m.to_string()).collect(),
        options: MethodOptions::parse(options).unwrap(),
        frames: 45,
        ..config(scene, hierarchy)
    }
}

fn small(scene: &str) -> Scene {
    let s = generate(scene, Size::Small, 1).unwrap();
    s.validate().unwrap();
    s
}

/// Every method (and `opt.granularity=node`) on every frame of every small
/// scene, both hierarchies: view-frustum culling's image, and no fewer
/// triangles than `opt`.
#[test]
fn conservative_methods_match_vfc_on_every_frame() {
    for name in PAPER_SCENES {
        let scene = small(name);
        for hierarchy in [HierarchyKind::Bvh, HierarchyKind::KdTree] {
            // `ideal` (the CHC paper's ideal) and `ideal-sorted` (the CHC++
            // paper's OPT) are no methods of their own: the runner records
            // the draw calls `sw` makes in the frame and they draw them on
            // backends of their own, without queries. Their depth images
            // checked against vfc's, as every lane's is, check that they
            // draw the whole of `sw`'s visible set.
            let mut cfg = config(name, hierarchy);
            cfg.methods = METHOD_NAMES.map(String::from).to_vec();
            cfg.methods.extend(IDEALS.map(String::from));
            let leaves =
                Variant { method: "opt".into(), options: MethodOptions::parse(&["opt.granularity=node"]).unwrap() };
            let run = run_scene_with_variants(&scene, &cfg, &[leaves], &()).unwrap();
            assert_eq!(run.methods.last().map(|m| m.name.as_str()), IDEALS.last().copied());
            for m in run.methods.iter().chain(&run.variants) {
                for (f, stats) in m.frames.iter().enumerate() {
                    assert_eq!(stats.missing_pixels, 0, "{name}/{hierarchy}/{}: frame {f} differs from vfc", m.name);
                }
            }
            common::assert_opt_is_a_lower_bound(&run, &format!("{name}/{hierarchy}"));
            // View-frustum culling makes no state change (it never
            // queries), only material switches; the methods that query do
            // make state changes.
            assert!(run.reference.iter().all(|f| f.state_changes == 0), "{name}/{hierarchy}: vfc");
            assert!(run.reference.iter().any(|f| f.material_switches > 0), "{name}/{hierarchy}: vfc");
            let changes = |m: usize| run.methods[m].frames.iter().map(|f| f.state_changes).sum::<u64>();
            assert!(changes(1) > 0 && changes(3) > 0, "{name}/{hierarchy}: sw and chcpp switch to queries");
            // The walkthrough must show something and let occlusion work.
            let vfc = &run.methods[0].frames;
            let sw = &run.methods[1].frames;
            let chc = &run.methods[2].frames;
            let queries = |frames: &[occlude_core::FrameStats]| frames.iter().map(|f| f.queries).sum::<u64>();
            assert!(
                queries(chc) < queries(sw),
                "{name}/{hierarchy}: chc issued {} queries, sw {}",
                queries(chc),
                queries(sw)
            );
            let vfc_tris: u64 = vfc.iter().map(|f| f.triangles).sum();
            let sw_tris: u64 = sw.iter().map(|f| f.triangles).sum();
            assert!(vfc_tris > 0, "{name}: the walkthrough sees nothing");
            assert!(sw_tris < vfc_tris, "{name}/{hierarchy}: stop-and-wait culled nothing ({sw_tris} vs {vfc_tris})");
        }
    }
}

/// `opt` draws exactly the instances the oracle sees, `opt.granularity=node`
/// the leaves holding them, and `sw` draws them all too.
#[test]
fn opt_draws_exactly_what_the_oracle_sees_and_sw_draws_it_too() {
    for name in PAPER_SCENES {
        let scene = small(name);
        for hierarchy in [HierarchyKind::Bvh, HierarchyKind::KdTree] {
            let cfg = BenchConfig { frames: 30, ..config(name, hierarchy) };
            let h = Hierarchy::build(&scene, hierarchy, cfg.build);
            let (w, ht) = cfg.resolution;
            let mut oracle = SoftBackend::new(&scene, w, ht, cfg.gpu_model.clone());
            let lanes: [(&str, &[&str]); 3] = [("sw", &[]), ("opt", &[]), ("opt", &["opt.granularity=node"])];
            let mut lanes: Vec<_> = lanes
                .iter()
                .map(|&(m, opts)| {
                    (
                        create(m, &MethodOptions::parse(opts).unwrap()).unwrap(),
                        SoftBackend::new(&scene, w, ht, cfg.gpu_model.clone()),
                        DrawnSet::default(),
                    )
                })
                .collect();
            for (f, camera) in cameras(&scene, &cfg).unwrap().iter().enumerate() {
                let all: Vec<u32> = (0..scene.instances.len() as u32).collect();
                let seen: HashSet<u32> = oracle.oracle(camera, &all).visible.into_iter().collect();
                for (built, backend, drawn) in &mut lanes {
                    let method = &mut built.method;
                    let leaves = built.params.contains(&("granularity".to_string(), "node".to_string()));
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
                    if method.name() == "opt" && !leaves {
                        for i in (0..scene.instances.len() as u32).filter(|i| !seen.contains(i)) {
                            assert!(
                                !ctx.was_drawn(i),
                                "{name}/{hierarchy}: frame {f}: opt drew {i}, which is not seen"
                            );
                        }
                    } else if method.name() == "opt" {
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

/// Runs `methods` with `options` and checks every frame against vfc.
fn exact_run(scene: &Scene, cfg: &BenchConfig) -> occlude_bench::BenchRun {
    let run = run_scene(scene, cfg, &()).unwrap();
    for m in &run.methods {
        for (f, stats) in m.frames.iter().enumerate() {
            assert_eq!(stats.missing_pixels, 0, "{}/{}: frame {f} differs from vfc", scene.name, m.name);
        }
    }
    run
}

#[test]
fn chc_options_save_queries_and_keep_the_image_exact() {
    for name in PAPER_SCENES {
        let scene = small(name);
        for hierarchy in [HierarchyKind::Bvh, HierarchyKind::KdTree] {
            let with = |opts: &[&str]| BenchConfig {
                methods: vec!["chc".into()],
                options: MethodOptions::parse(opts).unwrap(),
                ..config(name, hierarchy)
            };
            let queries = |run: &occlude_bench::BenchRun| run.methods[0].frames.iter().map(|f| f.queries).sum::<u64>();
            let plain = queries(&exact_run(&scene, &with(&[])));
            let tav = queries(&exact_run(&scene, &with(&["chc.tav=3"])));
            exact_run(&scene, &with(&["chc.spec=2000", "chc.tav=1"]));
            assert!(tav < plain, "{name}/{hierarchy}: tav=3 issued {tav} queries, tav=0 {plain}");
        }
    }
}

/// CHC++ with all components, with each switched off in turn, and with
/// virtual leaves: exact on every frame of every small scene, both
/// hierarchies.
#[test]
fn chcpp_is_exact_with_every_component_on_and_off() {
    let variants: [&[&str]; 9] = [
        &[],
        &["chcpp.multiquery=off"],
        &["chcpp.pkeep=measured"],
        &["chcpp.vqueue=off"],
        &["chcpp.sort=off"],
        &["chcpp.random=off"],
        &["chcpp.tight=off"],
        &["chcpp.b=1", "chcpp.nav=0"],
        &["chcpp.vleaf=2000", "chcpp.dmax=5", "chcpp.smax=2"],
    ];
    for name in PAPER_SCENES {
        let scene = small(name);
        for hierarchy in [HierarchyKind::Bvh, HierarchyKind::KdTree] {
            for opts in variants {
                let cfg = variant_config(name, hierarchy, &["chcpp"], opts);
                exact_run(&scene, &cfg);
            }
        }
    }
}

/// `moc` with the other choices of occluders and the quick-mask merge (the
/// default is in the test above): exact on every frame of every small scene,
/// both hierarchies, and culling something (fewer triangles than view-frustum
/// culling) with each.
#[test]
fn moc_is_exact_with_every_occluder_choice() {
    let variants: [&[&str]; 3] =
        [&["moc.occluders=last"], &["moc.occluders=largest", "moc.count=8"], &["moc.merge=quick"]];
    for name in PAPER_SCENES {
        let scene = small(name);
        for hierarchy in [HierarchyKind::Bvh, HierarchyKind::KdTree] {
            for opts in variants {
                let cfg = variant_config(name, hierarchy, &["vfc", "moc"], opts);
                let run = exact_run(&scene, &cfg);
                let triangles = |m: usize| run.methods[m].frames.iter().map(|f| f.triangles).sum::<u64>();
                assert!(triangles(1) < triangles(0), "{name}/{hierarchy}/{opts:?}: moc culled nothing");
            }
        }
    }
}

/// The generated building (two floors of two by two rooms, furnished)
/// written as GLB and imported with its automatic walk, as `occlude bench
/// --scene building.glb --auto-path walk` would.
fn imported_building() -> Imported {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("building.glb");
    std::fs::write(&path, export::glb(&building::generate(2, 2, 1))).unwrap();
    let options = ImportOptions { auto_path: AutoPath::Walk, ..ImportOptions::default() };
    import(&path, ModelFormat::Glb, &options).unwrap()
}

/// `moc.proxies=on`: occluders rendered as their meshes' inner boxes where
/// the argument allows (`moc`'s module doc), with occluders drawn during the
/// walk and with last frame's: exact on every frame of every small scene and
/// of the imported building, both hierarchies, and boxes rendered in place
/// of meshes on every scene that has closed meshes.
#[test]
fn moc_with_inner_box_proxies_is_exact() {
    let mut scenes: Vec<Scene> = PAPER_SCENES.iter().map(|name| small(name)).collect();
    scenes.push(imported_building().scene);
    let variants: [&[&str]; 2] = [&["moc.proxies=on"], &["moc.proxies=on", "moc.occluders=last"]];
    let mut proxied_scenes = 0;
    for scene in &scenes {
        for hierarchy in [HierarchyKind::Bvh, HierarchyKind::KdTree] {
            for opts in variants {
                let cfg = variant_config(&scene.name, hierarchy, &["vfc", "moc"], opts);
                let run = exact_run(scene, &cfg);
                let proxied: f64 = run.methods[1].counters["proxy_occluders"].iter().sum();
                if proxied > 0.0 && hierarchy == HierarchyKind::Bvh && opts.len() == 1 {
                    proxied_scenes += 1;
                }
            }
        }
    }
    assert!(proxied_scenes >= 3, "inner boxes were rendered on {proxied_scenes} scenes only");
}

/// CHC++'s batching and multiqueries must show: fewer queries and state
/// changes than CHC on the city walkthrough.
#[test]
fn chcpp_saves_queries_and_state_changes_over_chc() {
    let scene = small("city");
    let cfg = BenchConfig { methods: vec!["chc".into(), "chcpp".into()], ..config("city", HierarchyKind::Bvh) };
    let run = exact_run(&scene, &cfg);
    let total = |m: usize, f: fn(&occlude_core::FrameStats) -> u64| run.methods[m].frames.iter().map(f).sum::<u64>();
    assert!(total(1, |f| f.queries) < total(0, |f| f.queries), "queries");
    assert!(total(1, |f| f.state_changes) * 3 < total(0, |f| f.state_changes), "state changes");

    // Skipping re-queries of visible leaves for `nav` frames saves queries.
    let every_frame = BenchConfig {
        methods: vec!["chcpp".into()],
        options: MethodOptions::parse(&["chcpp.nav=0"]).unwrap(),
        ..config("city", HierarchyKind::Bvh)
    };
    let queries_nav0: u64 = exact_run(&scene, &every_frame).methods[0].frames.iter().map(|f| f.queries).sum();
    assert!(total(1, |f| f.queries) < queries_nav0, "nav=10 should query less than nav=0");
}

/// An imported model with real occlusion: the generated building (two
/// floors of two by two rooms, furnished) written as GLB and imported with its
/// automatic walk, as `occlude bench --scene building.glb --auto-path walk`
/// would. Every conservative method is exact, walls and ceilings hide most
/// of what is in the frustum, and CHC++ renders less than view-frustum
/// culling.
#[test]
fn conservative_methods_match_vfc_on_an_imported_building() {
    let imported = imported_building();
    assert!(imported.warnings.is_empty(), "{:?}", imported.warnings);
    for hierarchy in [HierarchyKind::Bvh, HierarchyKind::KdTree] {
        let run = exact_run(&imported.scene, &config("building.glb", hierarchy));
        let triangles = |m: usize| run.methods[m].frames.iter().map(|f| f.triangles).sum::<u64>();
        let (vfc, chcpp, opt) = (triangles(0), triangles(3), triangles(4));
        assert!(opt * 2 < vfc, "{hierarchy}: walls and ceilings hide most of it: opt {opt}, vfc {vfc}");
        assert!(chcpp < vfc, "{hierarchy}: chcpp {chcpp} vs vfc {vfc}");
    }
}

#[test]
fn approximate_chc_reports_its_missing_pixels() {
    let scene = small("city");
    let cfg = BenchConfig {
        methods: vec!["chc".into()],
        options: MethodOptions::parse(&["chc.nvp=200"]).unwrap(),
        ..config("city", HierarchyKind::Bvh)
    };
    let run = run_scene(&scene, &cfg, &()).unwrap();
    let missing: u64 = run.methods[0].frames.iter().map(|f| f.missing_pixels).sum();
    assert!(missing > 0, "a 200-pixel threshold should cull something visible on the city walkthrough");
}

/// A camera inside an object's box (a closed room around the eye): every
/// query method must still draw the room.
#[test]
fn node_seen_from_inside_its_box_is_never_culled() {
    use glam::{Mat4, Vec3};
    use occlude_core::{CameraPath, Mesh};
    let mut scene = Scene::new("room");
    scene.path = CameraPath::through(
        [(Vec3::new(0.0, 1.5, 0.0), Vec3::new(3.0, 1.0, -2.0)), (Vec3::new(1.0, 1.5, 1.0), Vec3::new(-3.0, 1.0, -2.0))],
        70.0,
    );
    let corners: Vec<Vec3> =
        occlude_core::Aabb::new(Vec3::new(-5.0, 0.0, -5.0), Vec3::new(5.0, 4.0, 5.0)).corners().to_vec();
    let faces = [[0, 4, 6, 2], [1, 3, 7, 5], [0, 1, 5, 4], [2, 6, 7, 3], [0, 2, 3, 1], [4, 5, 7, 6]];
    let indices = faces.iter().flat_map(|&[a, b, c, d]| [a, b, c, a, c, d]).collect();
    let room = scene.add_mesh(Mesh::new(corners, indices));
    scene.add_instance(room, Mat4::IDENTITY, 0);
    let crate_mesh = scene.add_mesh(Mesh::new(
        occlude_core::Aabb::new(Vec3::ZERO, Vec3::ONE).corners().to_vec(),
        faces.iter().flat_map(|&[a, b, c, d]| [a, b, c, a, c, d]).collect(),
    ));
    for x in [-3.0, 2.0] {
        scene.add_instance(crate_mesh, Mat4::from_translation(Vec3::new(x, 0.0, -3.0)), 1);
    }
    scene.validate().unwrap();
    for hierarchy in [HierarchyKind::Bvh, HierarchyKind::KdTree] {
        let cfg = BenchConfig { frames: 10, ..config("room", hierarchy) };
        let run = exact_run(&scene, &cfg);
        for m in &run.methods {
            assert!(m.frames.iter().all(|f| f.visible_objects >= 1), "{}: the room was culled", m.name);
        }
    }
}

#[test]
fn simulated_figures_are_identical_between_runs() {
    let cfg = BenchConfig { frames: 20, resolution: (320, 240), ..config("city", HierarchyKind::Bvh) };
    let scene = small("city");
    let a = run_scene(&scene, &cfg, &()).unwrap().report(&cfg);
    let b = run_scene(&scene, &cfg, &()).unwrap().report(&cfg);
    assert_eq!(simulated(a), simulated(b));
    let moving = BenchConfig { motion: 0.2, ..cfg };
    let a = run_scene(&scene, &moving, &()).unwrap().report(&moving);
    let b = run_scene(&scene, &moving, &()).unwrap().report(&moving);
    assert_eq!(simulated(a), simulated(b), "a moving scene's figures differ between runs");
}

/// A report's JSON without its real times (which vary between runs).
fn simulated(mut r: BenchReport) -> String {
    r.scene_stats.build_wall_ms = 0.0;
    for m in &mut r.methods {
        m.wall_ms = 0.0;
        m.update_ms_per_frame = 0.0;
        for f in &mut m.per_frame {
            f.wall_ms = 0.0;
            f.update_ms = 0.0;
        }
    }
    serde_json::to_string(&r).unwrap()
}

#[test]
fn a_variant_lane_gives_the_figures_of_a_run_of_its_own() {
    // `--paper` runs a method's settings as lanes beside the methods, on the
    // same frames and `vfc` reference: each must measure what a run with
    // only that setting measures.
    let scene = small("city");
    let cfg = BenchConfig {
        methods: vec!["vfc".into(), "chc".into()],
        frames: 20,
        resolution: (160, 120),
        ..config("city", HierarchyKind::KdTree)
    };
    let items = ["chc.tav=2", "chc.nvp=25"];
    let variant = Variant { method: "chc".into(), options: MethodOptions::parse(&items).unwrap() };
    let run = run_scene_with_variants(&scene, &cfg, &[variant], &()).unwrap();
    assert_eq!(run.variants.len(), 1);
    let lane = BenchReport::with_methods(&run, &run.variants, &cfg);

    let own =
        BenchConfig { methods: vec!["chc".into()], options: MethodOptions::parse(&items).unwrap(), ..cfg.clone() };
    let alone = run_scene(&scene, &own, &()).unwrap().report(&own);
    assert_eq!(lane.methods[0].params.get("tav").map(String::as_str), Some("2"), "{:?}", lane.methods[0].params);
    // The variant's frames differ from the defaults', so the comparison
    // below could fail.
    let frame_ms = |frames: &[FrameStats]| frames.iter().map(|f| f.frame_ms).collect::<Vec<_>>();
    assert_ne!(frame_ms(&run.methods[1].frames), frame_ms(&run.variants[0].frames));
    assert_eq!(simulated(lane), simulated(alone));
}

#[test]
fn conservative_methods_match_vfc_with_cameras_from_matrices() {
    let name = "city";
    let scene = small(name);
    let cfg = BenchConfig {
        methods: METHOD_NAMES.map(String::from).to_vec(),
        frames: 12,
        resolution: (240, 180),
        ..config(name, HierarchyKind::Bvh)
    };
    let (w, ht) = cfg.resolution;
    let culled = common::assert_methods_match_vfc_with_cameras_from_matrices(&scene, &cfg, || {
        Box::new(SoftBackend::new(&scene, w, ht, cfg.gpu_model.clone()))
    });
    let sw = culled.iter().find(|(m, _)| m == "sw").unwrap().1;
    assert!(sw > 0, "sw never drew fewer objects than vfc: the cameras test no occlusion");
}

/// `--queries hib` on the soft backend: the query methods (`sw`, `chc`,
/// `chcpp`, `om`) give vfc's image on every frame of every `small` scene.
/// The methods that wait for each result (`sw`, `om`) cull exactly as with
/// hardware queries, frame by frame: the counts are exact either way. `chc`
/// and `chcpp` read results as they become available, which is later in a
/// batch, and so take other paths. `chc.nvp=25` compares the counts with
/// its threshold: it draws less than `chc` and misses pixels.
#[test]
fn query_methods_with_hib_counts_match_vfc_and_hardware_queries() {
    use occlude_core::QueryMode;
    for name in PAPER_SCENES {
        let scene = small(name);
        let nvp = Variant { method: "chc".into(), options: MethodOptions::parse(&["chc.nvp=25"]).unwrap() };
        let run = |queries| {
            let cfg = BenchConfig {
                methods: ["vfc", "sw", "chc", "chcpp", "om"].map(String::from).to_vec(),
                resolution: (320, 240),
                queries,
                ..config(name, HierarchyKind::Bvh)
            };
            run_scene_with_variants(&scene, &cfg, std::slice::from_ref(&nvp), &()).unwrap()
        };
        let (hardware, hib) = (run(QueryMode::Hardware), run(QueryMode::Hib));
        let culled = |f: &FrameStats| (f.queries, f.query_boxes, f.draw_calls, f.triangles);
        let sum = |frames: &[FrameStats], v: fn(&FrameStats) -> f64| frames.iter().map(v).sum::<f64>();
        for (a, b) in hardware.methods.iter().zip(&hib.methods) {
            for (f, (x, y)) in a.frames.iter().zip(&b.frames).enumerate() {
                assert_eq!(y.missing_pixels, 0, "{name}/{}: frame {f} differs from vfc with hib counts", b.name);
                if ["sw", "om"].contains(&a.name.as_str()) {
                    assert_eq!(culled(x), culled(y), "{name}/{}: frame {f} culled otherwise with hib counts", a.name);
                }
            }
            if a.frames.iter().any(|f| f.queries > 0) {
                let frame_ms = |frames| sum(frames, |f| f.frame_ms);
                assert_ne!(frame_ms(&a.frames), frame_ms(&b.frames), "{name}/{}: hib costs nothing else", a.name);
            }
        }
        let (chc, approximate) = (&hib.methods[2].frames, &hib.variants[0].frames);
        assert!(
            sum(approximate, |f| f.triangles as f64) < sum(chc, |f| f.triangles as f64),
            "{name}: nvp=25 drew as much"
        );
        assert!(sum(approximate, |f| f.missing_pixels as f64) > 0.0, "{name}: nvp=25 missed nothing");
    }
}

#[test]
fn every_method_matches_vfc_in_scripted_motion_refitted_and_rebuilt() {
    let refit_only = UpdatePolicy { max_cost_ratio: f32::INFINITY };
    let rebuild_always = UpdatePolicy { max_cost_ratio: 0.0 };
    for kind in [HierarchyKind::Bvh, HierarchyKind::KdTree] {
        for (policy, rebuilt) in [(refit_only, false), (rebuild_always, true)] {
            let rebuilds = common::assert_methods_match_vfc_in_motion(&METHOD_NAMES, kind, policy, |scene| {
                Box::new(SoftBackend::new(scene, 160, 120, GpuModel::modern()))
            });
            assert_eq!(rebuilds > 0, rebuilt, "{kind}: {rebuilds} rebuilds");
        }
    }
}

#[test]
fn conservative_methods_match_vfc_on_every_frame_of_moving_scenes() {
    for name in PAPER_SCENES.iter().copied().chain(["swarm"]) {
        let scene = small(name);
        let mut cfg = config(name, HierarchyKind::Bvh);
        cfg.methods = METHOD_NAMES.map(String::from).to_vec();
        cfg.methods.extend(IDEALS.map(String::from));
        cfg.frames = 40;
        cfg.motion = 0.3;
        let run = run_scene(&scene, &cfg, &()).unwrap();
        for m in &run.methods {
            for (f, stats) in m.frames.iter().enumerate() {
                assert_eq!(stats.missing_pixels, 0, "{name}/{}: frame {f} differs from vfc", m.name);
                assert!(stats.instances_moved > 0, "{name}: nothing moved before frame {f}");
            }
        }
        common::assert_opt_is_a_lower_bound(&run, &format!("{name} in motion"));
        let still = BenchConfig { motion: 0.0, methods: vec!["vfc".into()], ..cfg };
        let still = run_scene(&scene, &still, &()).unwrap();
        let tris = |r: &occlude_bench::BenchRun| r.reference.iter().map(|f| f.triangles).collect::<Vec<_>>();
        assert_ne!(tris(&run), tris(&still), "{name}: motion changed nothing vfc draws");
    }
}

/// Every method on a few frames of the scenes that move by themselves,
/// loaded with their motion as `occlude bench` loads them: view-frustum
/// culling's image, and things move.
#[test]
fn every_method_matches_vfc_on_the_scenes_that_move_by_themselves() {
    for name in MOVING_SCENES {
        let mut cfg = config(name, HierarchyKind::Bvh);
        cfg.methods = METHOD_NAMES.map(String::from).to_vec();
        cfg.frames = 8;
        cfg.resolution = (160, 120);
        cfg.size = Size::Small;
        let (scene, own) = load_scene(&cfg).unwrap();
        assert!(own.is_some(), "{name} does not move");
        let run = run_moving_scene(&scene, own.as_ref(), &cfg, &[], &()).unwrap();
        for m in &run.methods {
            for (f, stats) in m.frames.iter().enumerate() {
                assert_eq!(stats.missing_pixels, 0, "{name}/{}: frame {f} differs from vfc", m.name);
                assert!(stats.instances_moved > 0, "{name}: nothing moved before frame {f}");
            }
        }
    }
}
