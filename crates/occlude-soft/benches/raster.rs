//! Benchmarks of the depth rasterizer on the workloads of `occlude_soft::workload`:
//!
//! - fill rate: random right triangles with legs of `N` pixels drawn back to front
//!   (every fragment passes the depth test and writes), on 1 and 2 threads;
//!   throughput is in triangles, pixels = triangles * N^2 / 2;
//! - occlusion queries: `workload::query_boxes`, 64 boxes per call covering 1%, 10%
//!   or 50% of the screen each, in front of a screen-filling occluder (visible) or
//!   behind it (hidden), counting fragments or only asking whether any passes, on
//!   one thread; throughput is in queries. The depth buffer is redrawn before each
//!   call, so that every call starts from the occluder's fresh (dirty)
//!   hierarchical depth, as `occlude raster-bench` does.

use std::time::Duration;

use criterion::{criterion_group, criterion_main, BatchSize, BenchmarkId, Criterion, Throughput};
use glam::Vec4;
use occlude_soft::raster::{Command, CommandKind, DepthBuffer, DepthTest, Rasterizer};
use occlude_soft::workload;

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool")
}

fn fill_rate(c: &mut Criterion, width: u32, height: u32, legs: &[u32]) {
    let mut group = c.benchmark_group(format!("raster_fill_{width}x{height}"));
    group.sample_size(10);
    group.warm_up_time(Duration::from_millis(500));
    group.measurement_time(Duration::from_secs(2));
    for &leg in legs {
        let count = workload::triangles_for_screens(width, height, leg, 2.0);
        let tris = workload::right_triangles(width, height, leg as f32, count);
        let commands = [Command { kind: CommandKind::Draw, triangles: 0..count as u32, cull_back: false }];
        group.throughput(Throughput::Elements(count as u64));
        for threads in [1usize, 2] {
            let pool = pool(threads);
            let mut raster = Rasterizer::new();
            group.bench_function(BenchmarkId::new(format!("t{threads}"), leg), |b| {
                pool.install(|| {
                    b.iter_batched_ref(
                        || DepthBuffer::new(width, height),
                        |depth| raster.execute(depth, &tris, &commands),
                        BatchSize::LargeInput,
                    )
                })
            });
        }
    }
    group.finish();
}

fn queries(c: &mut Criterion, width: u32, height: u32) {
    let mut group = c.benchmark_group(format!("raster_query_{width}x{height}"));
    group.sample_size(10);
    group.warm_up_time(Duration::from_millis(300));
    group.measurement_time(Duration::from_secs(1));
    let pool = pool(1);
    let mut raster = Rasterizer::new();
    let occluder = workload::screen_quad(workload::OCCLUDER_DEPTH);
    let draw = [Command { kind: CommandKind::Draw, triangles: 0..2, cull_back: false }];
    let mut depth = DepthBuffer::new(width, height);
    pool.install(|| raster.execute(&mut depth, &occluder, &draw));
    for coverage in [0.01f32, 0.1, 0.5] {
        for (visibility, visible) in [("visible", true), ("hidden", false)] {
            let boxes = workload::query_boxes(coverage, visible);
            let tris: Vec<[Vec4; 3]> = boxes.iter().flatten().copied().collect();
            for (mode, kind) in
                [("count", CommandKind::Query(DepthTest::Less)), ("any", CommandKind::QueryAny(DepthTest::Less))]
            {
                let commands: Vec<Command> = (0..boxes.len() as u32)
                    .map(|i| Command { kind, triangles: i * 12..i * 12 + 12, cull_back: true })
                    .collect();
                group.throughput(Throughput::Elements(boxes.len() as u64));
                let id = BenchmarkId::new(format!("{visibility}_{mode}"), format!("{}%", coverage * 100.0));
                group.bench_function(id, |b| {
                    pool.install(|| {
                        b.iter_batched_ref(
                            || depth.clone(),
                            |depth| raster.execute(depth, &tris, &commands),
                            BatchSize::LargeInput,
                        )
                    })
                });
            }
        }
    }
    group.finish();
}

fn benches(c: &mut Criterion) {
    fill_rate(c, 1920, 1080, &[10, 25, 50, 100, 250, 500]);
    fill_rate(c, 1024, 768, &[25, 100]);
    queries(c, 1920, 1080);
}

criterion_group!(raster, benches);
criterion_main!(raster);
