//! Hierarchy build speed in instances per second, BVH against kD-tree, on the
//! procedural scenes with the most objects; and the upkeep of a moving scene
//! (`occlude_core::motion`): a full binned-SAH BVH build of 100,000
//! scattered objects beside a refit of that tree after all of them moved and
//! after a tenth moved (`SceneMotion`). The refit alternates between two
//! frames' poses, so that every iteration changes every moved box.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use occlude_core::hierarchy::BuildOptions;
use occlude_core::{Hierarchy, HierarchyKind};
use occlude_scenes::scattered::scattered;
use occlude_scenes::{generate, SceneMotion, Size};
use std::hint::black_box;
use std::time::Duration;

fn build_speed(c: &mut Criterion) {
    let mut group = c.benchmark_group("hierarchy_build");
    group.sample_size(10).measurement_time(Duration::from_secs(4));
    for (name, size) in [("figures", Size::Medium), ("city", Size::Medium)] {
        let scene = generate(name, size, 1).expect("built-in scene");
        group.throughput(Throughput::Elements(scene.instances.len() as u64));
        for kind in [HierarchyKind::Bvh, HierarchyKind::KdTree] {
            group.bench_with_input(BenchmarkId::new(kind.to_string(), format!("{name}-{size}")), &scene, |b, s| {
                b.iter(|| Hierarchy::build(s, kind, BuildOptions::default()))
            });
        }
    }
    group.finish();
}

/// Objects of the upkeep benchmark.
const MOVING_OBJECTS: u32 = 100_000;

fn upkeep(c: &mut Criterion) {
    let scene = scattered(MOVING_OBJECTS, 1);
    let mut group = c.benchmark_group("upkeep_100k");
    group.sample_size(10).measurement_time(Duration::from_secs(4));
    group.bench_function("sah_build", |b| {
        b.iter(|| black_box(Hierarchy::build(&scene, HierarchyKind::Bvh, BuildOptions::default())))
    });
    for (name, fraction) in [("refit_all_moved", 1.0), ("refit_tenth_moved", 0.1)] {
        let motion = SceneMotion::new(&scene, fraction, 1);
        let frames: Vec<_> = [1.0, 2.0]
            .into_iter()
            .map(|t| {
                let mut s = scene.clone();
                let changed = s.apply(&motion.changes_at(t)).expect("finite motion");
                (s, changed)
            })
            .collect();
        let mut h = Hierarchy::build(&scene, HierarchyKind::Bvh, BuildOptions::default());
        let mut k = 0;
        group.bench_function(name, |b| {
            b.iter(|| {
                let (s, changed) = &frames[k % 2];
                k += 1;
                black_box(h.refit(s, changed))
            })
        });
    }
    group.finish();
}

criterion_group!(benches, build_speed, upkeep);
criterion_main!(benches);
