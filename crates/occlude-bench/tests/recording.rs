//! The recording decorator (`occlude_core::recording`) on the soft backend
//! over a real scene: it records what the methods asked and changes nothing
//! they draw.

use occlude_bench::config::NEAR_PLANE;
use occlude_core::methods::{create, DrawnSet, MethodOptions};
use occlude_core::recording::{QueryOutcome, RecordedBoxTest, RecordingBackend};
use occlude_core::{render_frame, Hierarchy, HierarchyKind, Instruments};
use occlude_soft::{GpuModel, SoftBackend};

/// CHC on the soft backend through the recorder: every query is
/// recorded, every one CHC read has its result, and the statistics are
/// those of the unwrapped backend.
#[test]
fn records_every_query_and_changes_nothing() {
    let scene = occlude_scenes::generate("city", occlude_scenes::Size::Small, 1).unwrap();
    let hierarchy = Hierarchy::build(&scene, HierarchyKind::Bvh, Default::default());
    let cameras = scene.path.sample(4, 4.0 / 3.0, NEAR_PLANE, 2000.0);
    let soft = || SoftBackend::new(&scene, 160, 120, GpuModel::modern());
    let mut plain = (create("chc", &MethodOptions::default()).unwrap(), soft(), DrawnSet::default());
    let mut wrapped =
        (create("chc", &MethodOptions::default()).unwrap(), RecordingBackend::new(soft()), DrawnSet::default());
    let (mut visible, mut occluded) = (0, 0);
    for (k, camera) in cameras.iter().enumerate() {
        wrapped.1.set_recording(k % 2 == 1);
        let a = render_frame(plain.0.method.as_mut(), &mut plain.1, &scene, &hierarchy, camera, &mut plain.2);
        let b = render_frame(wrapped.0.method.as_mut(), &mut wrapped.1, &scene, &hierarchy, camera, &mut wrapped.2);
        assert_eq!((a.queries, a.draw_calls, a.triangles), (b.queries, b.draw_calls, b.triangles));
        let recorded = wrapped.1.queries();
        if k % 2 == 0 {
            assert!(recorded.is_empty(), "frame {k} was not recorded");
            continue;
        }
        assert_eq!(recorded.len() as u64, b.queries, "frame {k}");
        assert_eq!(recorded.iter().map(|q| q.boxes.len() as u64).sum::<u64>(), b.query_boxes);
        for q in recorded {
            match q.outcome() {
                QueryOutcome::Visible => visible += 1,
                QueryOutcome::Occluded => occluded += 1,
                QueryOutcome::Unread => panic!("CHC reads every query it issues"),
            }
        }
    }
    assert!(visible > 0 && occluded > 0, "visible {visible}, occluded {occluded}");
}

/// IOC on the soft backend through the recorder: the recorder offers the
/// wrapped backend's GPU culling (so ioc culls rather than falling back
/// to view-frustum culling), records one box test per level with every
/// tested box, and changes no image.
#[test]
fn records_ioc_box_tests_level_by_level_and_changes_no_image() {
    let scene = occlude_scenes::generate("city", occlude_scenes::Size::Small, 1).unwrap();
    let hierarchy = Hierarchy::build(&scene, HierarchyKind::Bvh, Default::default());
    let cameras = scene.path.sample(4, 4.0 / 3.0, NEAR_PLANE, 2000.0);
    let soft = || SoftBackend::new(&scene, 160, 120, GpuModel::modern());
    let options = MethodOptions::parse(&["ioc.start=2", "ioc.bottom=deepest-1"]).unwrap();
    let mut plain = (create("ioc", &options).unwrap(), soft(), DrawnSet::default());
    let mut wrapped = (create("ioc", &options).unwrap(), RecordingBackend::new(soft()), DrawnSet::default());
    let mut vfc = (create("vfc", &options).unwrap(), soft(), DrawnSet::default());
    let (mut visible, mut occluded, mut fewer_than_vfc) = (0, 0, false);
    let (mut plain_depth, mut wrapped_depth) = (Vec::new(), Vec::new());
    wrapped.1.set_recording(true);
    for (k, camera) in cameras.iter().enumerate() {
        let a = render_frame(plain.0.method.as_mut(), &mut plain.1, &scene, &hierarchy, camera, &mut plain.2);
        let b = render_frame(wrapped.0.method.as_mut(), &mut wrapped.1, &scene, &hierarchy, camera, &mut wrapped.2);
        let v = render_frame(vfc.0.method.as_mut(), &mut vfc.1, &scene, &hierarchy, camera, &mut vfc.2);
        plain.1.depth_image(&mut plain_depth);
        wrapped.1.inner_mut().depth_image(&mut wrapped_depth);
        assert!(plain_depth == wrapped_depth, "frame {k}: recording changed the image");
        assert_eq!((a.triangles, a.query_boxes), (b.triangles, b.query_boxes), "frame {k}");
        fewer_than_vfc |= b.triangles < v.triangles;
        let tests = wrapped.1.box_tests();
        assert!(!tests.is_empty(), "frame {k}: no box test recorded");
        let tested: usize = tests.iter().map(|t| t.boxes.len()).sum();
        assert!(tested as u64 >= b.query_boxes, "frame {k}: {tested} recorded, {} rasterized", b.query_boxes);
        assert!(b.readbacks >= 2 * tests.len() as u64, "frame {k}: the recorder's read-backs are counted");
        visible += tests.iter().map(RecordedBoxTest::visible_count).sum::<usize>();
        occluded += tests.iter().map(|t| t.boxes.len() - t.visible_count()).sum::<usize>();
    }
    assert!(fewer_than_vfc, "ioc through the recorder never culled more than vfc");
    assert!(visible > 0 && occluded > 0, "visible {visible}, occluded {occluded}");
}

/// `hiz` on the soft backend through the recorder, at an odd size: every
/// box of its pyramid tests carries the level the test read, which is
/// `depth_pyramid`'s selection for the padded box's footprint in that
/// frame's camera, at the backend's size and the method's `hiz.texels`;
/// the boxes the recorder gives a level or a level-less footprint are
/// exactly those the backend counted as tested.
#[test]
fn records_the_pyramid_level_of_each_hiz_box_test() {
    use occlude_core::depth_pyramid::{box_footprint, level_sizes, select_level, Footprint};
    use occlude_core::query_box::padded;
    let scene = occlude_scenes::generate("city", occlude_scenes::Size::Small, 1).unwrap();
    let hierarchy = Hierarchy::build(&scene, HierarchyKind::Bvh, Default::default());
    let (width, height, reach) = (161, 121, 3);
    let cameras = scene.path.sample(6, width as f32 / height as f32, NEAR_PLANE, 2000.0);
    let options = MethodOptions::parse(&[&format!("hiz.texels={reach}")]).unwrap();
    let mut hiz = create("hiz", &options).unwrap();
    let mut backend = RecordingBackend::new(SoftBackend::new(&scene, width, height, GpuModel::modern()));
    let mut drawn = DrawnSet::default();
    backend.set_recording(true);
    let coarsest = level_sizes(width, height).len() as u32 - 1;
    let mut levels_seen = std::collections::BTreeSet::new();
    for (k, camera) in cameras.iter().enumerate() {
        let stats = render_frame(hiz.method.as_mut(), &mut backend, &scene, &hierarchy, camera, &mut drawn);
        let tests = backend.box_tests();
        assert_eq!(tests.len(), 1, "frame {k}: hiz tests every instance in one pyramid test");
        let (frustum, view_projection) = (camera.frustum(), camera.view_projection());
        let mut tested = 0;
        for (i, (b, &level)) in tests[0].boxes.iter().zip(&tests[0].levels).enumerate() {
            let p = padded(b);
            let expected = if b.is_empty() || camera.box_touches_near_region(&p) || !frustum.intersects(&p) {
                None
            } else {
                tested += 1;
                match box_footprint(&view_projection, width, height, &p) {
                    Footprint::Rect(rect) => Some(select_level(&rect, reach)),
                    Footprint::Near | Footprint::Empty => None,
                }
            };
            assert_eq!(level, expected, "frame {k}, box {i}");
            assert!(level.is_none_or(|l| l <= coarsest), "frame {k}, box {i}: level {level:?}");
            levels_seen.extend(level);
        }
        assert_eq!(tests[0].levels.len(), tests[0].boxes.len(), "frame {k}");
        assert_eq!(tested, stats.query_boxes, "frame {k}: the boxes the backend tested");
    }
    assert!(levels_seen.len() >= 3, "boxes at several pyramid levels: {levels_seen:?}");
}
