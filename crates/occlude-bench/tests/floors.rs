//! Each method's `CullingMethod::floor_ms` is a lower bound: no frame it
//! renders on the soft backend takes less simulated time, from nothing
//! (its first frame, `cold`) or warm, under either GPU model. `auto` spares
//! trying a method by that bound, so a bound above a real frame would keep
//! it from a method that wins.

use occlude_bench::runner::cameras;
use occlude_bench::BenchConfig;
use occlude_core::methods::{create, DrawnSet, FrameContext, MethodOptions};
use occlude_core::{Backend, Hierarchy};
use occlude_scenes::Size;
use occlude_soft::{GpuModel, SoftBackend};

#[test]
fn no_frame_takes_less_than_its_methods_floor() {
    for scene_name in ["city", "rooms"] {
        let scene = occlude_scenes::generate(scene_name, Size::Small, 1).unwrap();
        for model in [GpuModel::modern(), GpuModel::gpu_2004()] {
            let cfg = BenchConfig {
                scene: scene_name.into(),
                frames: 24,
                resolution: (160, 120),
                gpu_model: model.clone(),
                ..BenchConfig::default()
            };
            let hierarchy = Hierarchy::build(&scene, cfg.hierarchy, cfg.build);
            for name in ["roc", "hiz", "chcpp"] {
                let mut method = create(name, &MethodOptions::default()).unwrap().method;
                let mut backend = SoftBackend::new(&scene, cfg.resolution.0, cfg.resolution.1, model.clone());
                let costs = backend.cost_model().expect("the soft backend models its costs");
                let mut drawn = DrawnSet::default();
                let mut floors_above_zero = 0;
                for (frame, camera) in cameras(&scene, &cfg).unwrap().iter().enumerate() {
                    let mut ctx = FrameContext::new(&scene, &hierarchy, *camera, &mut drawn);
                    let floor = method.floor_ms(&ctx, &costs, cfg.resolution, frame == 0);
                    floors_above_zero += usize::from(floor > 0.0);
                    method.prepare(&mut ctx, &mut backend);
                    backend.begin_frame(camera);
                    method.render(&mut ctx, &mut backend);
                    let stats = backend.end_frame();
                    method.finish_frame(&stats);
                    let at = format!("{scene_name} {} {name} frame {frame}", model.name);
                    assert!(stats.frame_ms >= floor, "{at}: {} ms, below its floor {floor} ms", stats.frame_ms);
                }
                // roc and hiz have a floor on every frame, chcpp on its first.
                let expected = if name == "chcpp" { 1 } else { 24 };
                assert_eq!(floors_above_zero, expected, "{scene_name} {} {name}", model.name);
            }
        }
    }
}
