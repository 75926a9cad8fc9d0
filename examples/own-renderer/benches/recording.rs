//! The CPU time a `GpuCuller` (`hiz`) adds to a frame: recording its two
//! phases into the renderer's encoder, for 1,000, 100,000 and 1,000,000
//! static instances of 50 meshes. `submitted`: each frame is submitted and
//! the GPU's work waited for outside the timed part, as in a renderer.
//! `alone`: nothing is submitted, so the recording runs without the GPU's
//! work before it (on lavapipe that work runs on the same CPU). Needs a GPU
//! adapter (lavapipe will do); without one it says so and measures nothing.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use occlude::glam::{Mat4, Vec3};
use occlude::methods::Method;
use occlude::wgpu::embed::{Attachments, Draws, FrameTarget, GpuCuller, IndirectDraw, InstanceDraw};
use occlude::{Aabb, Camera};
use own_renderer::open_device;
use std::time::{Duration, Instant};

/// Meshes the instances take in turn.
const MESHES: u32 = 50;

/// `n` unit boxes on a square grid in front of the camera.
fn grid(n: u32) -> Vec<Aabb> {
    let side = (n as f32).sqrt().ceil() as u32;
    (0..n)
        .map(|i| {
            let at = Vec3::new((i % side) as f32 * 2.0, 0.0, -((i / side) as f32) * 2.0 - 5.0);
            Aabb::new(at, at + Vec3::ONE)
        })
        .collect()
}

fn recording(c: &mut Criterion) {
    let Ok((device, queue)) = open_device() else {
        eprintln!("recording: no GPU adapter, nothing measured");
        return;
    };
    let attachments = Attachments {
        color: None,
        depth: wgpu::TextureFormat::Depth32Float,
        compare: wgpu::CompareFunction::Less,
        samples: 1,
    };
    let depth = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("depth"),
        size: wgpu::Extent3d { width: 256, height: 256, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: attachments.depth,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    });
    let depth = depth.create_view(&Default::default());
    let view = Mat4::look_at_rh(Vec3::new(0.0, 20.0, 10.0), Vec3::new(100.0, 0.0, -100.0), Vec3::Y);
    let camera = Camera::from_matrices(view, Mat4::perspective_rh(1.0, 1.0, 0.1, 1000.0), false).expect("camera");
    let mut group = c.benchmark_group("gpu_culler_frame_cpu");
    group.sample_size(20).measurement_time(Duration::from_secs(4));
    for n in [1_000, 100_000, 1_000_000] {
        let bounds = grid(n);
        let meshes =
            (0..MESHES).map(|m| IndirectDraw::Indexed { index_count: 36, first_index: 36 * m, base_vertex: 0 });
        let instances = (0..n).map(|i| InstanceDraw { mesh: i % MESHES, group: i % 2 }).collect();
        let draws = Draws::Meshes { meshes: meshes.collect(), instances };
        let hiz: Method = "hiz".parse().expect("a method");
        let mut culler = GpuCuller::new(&device, &queue, attachments, &bounds, &hiz, draws).expect("a culler");
        for submitted in [true, false] {
            let id = BenchmarkId::new(if submitted { "submitted" } else { "alone" }, n);
            group.bench_function(id, |b| {
                b.iter_custom(|iterations| {
                    let mut spent = Duration::ZERO;
                    for _ in 0..iterations {
                        let start = Instant::now();
                        let mut encoder = device.create_command_encoder(&Default::default());
                        let target = FrameTarget::new(None, wgpu::Color::BLACK, &depth);
                        culler.encode_early(&mut encoder, &camera, &target).expect("early phase");
                        culler.encode_late(&mut encoder, &target).expect("late phase");
                        let commands = encoder.finish();
                        spent += start.elapsed();
                        if submitted {
                            queue.submit([commands]);
                            device.poll(wgpu::PollType::wait_indefinitely()).expect("the GPU finishes");
                        }
                    }
                    spent
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, recording);
criterion_main!(benches);
