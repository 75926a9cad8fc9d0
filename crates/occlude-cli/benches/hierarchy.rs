//! Hierarchy build speed in instances per second, BVH against kD-tree, on the
//! procedural scenes with the most objects.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use occlude_core::hierarchy::BuildOptions;
use occlude_core::{Hierarchy, HierarchyKind};
use occlude_scenes::{generate, Size};
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

criterion_group!(benches, build_speed);
criterion_main!(benches);
