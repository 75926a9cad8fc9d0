//! Fill-rate benchmark of the depth rasterizer: random right triangles with legs of
//! `N` pixels at random positions and rotations, drawn back to front (each triangle
//! nearer than the previous, so every fragment passes the depth test and writes), on
//! 1 and 2 threads. Throughput is reported in triangles; pixels = triangles * N^2 / 2.

use std::time::Duration;

use criterion::{criterion_group, criterion_main, BatchSize, BenchmarkId, Criterion, Throughput};
use glam::Vec4;
use occlude_core::rng::Rng;
use occlude_soft::raster::{Command, CommandKind, DepthBuffer, Rasterizer};

/// `count` right triangles with legs of `leg` pixels on a `width` x `height` screen,
/// in clip space (w = 1), depth decreasing from one triangle to the next.
fn workload(width: u32, height: u32, leg: f32, count: usize) -> Vec<[Vec4; 3]> {
    let mut rng = Rng::new(0x5EED ^ leg.to_bits() as u64, 0);
    let (w, h) = (width as f32, height as f32);
    (0..count)
        .map(|i| {
            let (cx, cy) = (rng.unit() * w, rng.unit() * h);
            let angle = rng.unit() * std::f32::consts::TAU;
            let (u, v) = (
                glam::Vec2::from_angle(angle) * leg,
                glam::Vec2::from_angle(angle + std::f32::consts::FRAC_PI_2) * leg,
            );
            let z = 1.0 - (i + 1) as f32 / (count + 1) as f32;
            let clip = |p: glam::Vec2| Vec4::new(p.x * 2.0 / w - 1.0, 1.0 - p.y * 2.0 / h, z, 1.0);
            let o = glam::Vec2::new(cx, cy) - (u + v) / 3.0;
            [clip(o), clip(o + u), clip(o + v)]
        })
        .collect()
}

fn fill_rate(c: &mut Criterion, width: u32, height: u32, legs: &[u32]) {
    let mut group = c.benchmark_group(format!("raster_fill_{width}x{height}"));
    group.sample_size(10);
    group.warm_up_time(Duration::from_millis(500));
    group.measurement_time(Duration::from_secs(2));
    for &leg in legs {
        // About two screens of pixels per iteration, at least 64 triangles.
        let pixels_per_tri = f64::from(leg * leg) / 2.0;
        let count = ((2.0 * f64::from(width * height) / pixels_per_tri) as usize).max(64);
        let tris = workload(width, height, leg as f32, count);
        let commands = [Command { kind: CommandKind::Draw, triangles: 0..count as u32, cull_back: false }];
        group.throughput(Throughput::Elements(count as u64));
        for threads in [1usize, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool");
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

fn benches(c: &mut Criterion) {
    fill_rate(c, 1920, 1080, &[10, 25, 50, 100, 250, 500]);
    fill_rate(c, 1024, 768, &[25, 100]);
}

criterion_group!(raster, benches);
criterion_main!(raster);
