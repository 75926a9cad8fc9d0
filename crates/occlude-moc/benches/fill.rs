//! Fill rate of the masked buffer on the rasterizer benchmarks' workload
//! (`occlude_soft::workload::right_triangles`: random right triangles with legs of
//! `N` pixels, back to front, about two screens of pixels per call) at
//! 1920x1080, on 1 and 2 threads; throughput is in triangles. `occlude
//! raster-bench` measures the same calls beside the exact rasterizer.

use std::time::Duration;

use criterion::{criterion_group, criterion_main, BatchSize, BenchmarkId, Criterion, Throughput};
use occlude_moc::{CullMode, MaskedBuffer};
use occlude_soft::workload;

fn fill_rate(c: &mut Criterion) {
    let (width, height) = (1920, 1080);
    let mut group = c.benchmark_group(format!("moc_fill_{width}x{height}"));
    group.sample_size(10);
    group.warm_up_time(Duration::from_millis(500));
    group.measurement_time(Duration::from_secs(2));
    for leg in [10u32, 25, 50, 100, 250, 500] {
        let count = workload::triangles_for_screens(width, height, leg, 2.0);
        let tris = workload::right_triangles(width, height, leg as f32, count);
        group.throughput(Throughput::Elements(count as u64));
        for threads in [1usize, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool");
            group.bench_function(BenchmarkId::new(format!("t{threads}"), leg), |b| {
                pool.install(|| {
                    b.iter_batched_ref(
                        || MaskedBuffer::new(width, height).expect("buffer"),
                        |buffer| buffer.render_clip_triangles(&tris, CullMode::None),
                        BatchSize::LargeInput,
                    )
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, fill_rate);
criterion_main!(benches);
