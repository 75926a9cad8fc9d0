//! The GPU time of a GPU-driven frame's culling passes beside that of its
//! drawing: timestamps written between the passes, read back on demand.

use std::error::Error;

/// The device features the timer needs: timestamps written between passes.
pub const TIMER_FEATURES: wgpu::Features =
    wgpu::Features::TIMESTAMP_QUERY.union(wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS);

/// Timestamps written: before the early phase, after it, after the early
/// list's pass, after the late phase, after the late list's pass.
pub const STAMPS: u32 = 5;

/// A frame's GPU time, in milliseconds.
#[derive(Clone, Copy, Debug)]
pub struct GpuTimes {
    /// Occlude's two phases: the culling passes.
    pub culling_ms: f64,
    /// The renderer's two passes drawing the lists.
    pub drawing_ms: f64,
}

/// Timestamps around the passes of a frame.
pub struct Timer {
    queries: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    staging: wgpu::Buffer,
    /// Nanoseconds per tick.
    period: f64,
}

impl Timer {
    /// A timer on `device`, or `None` where it lacks [`TIMER_FEATURES`].
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue) -> Option<Self> {
        if !device.features().contains(TIMER_FEATURES) {
            return None;
        }
        let queries = device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("frame timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count: STAMPS,
        });
        let buffer = |usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("frame timestamps"),
                size: 8 * u64::from(STAMPS),
                usage,
                mapped_at_creation: false,
            })
        };
        let resolved = buffer(wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC);
        let staging = buffer(wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ);
        Some(Self { queries, resolved, staging, period: f64::from(queue.get_timestamp_period()) })
    }

    /// Writes timestamp `k` (see [`STAMPS`]); after the last, keeps the
    /// frame's timestamps for [`Timer::read`].
    pub fn stamp(&self, encoder: &mut wgpu::CommandEncoder, k: u32) {
        encoder.write_timestamp(&self.queries, k);
        if k == STAMPS - 1 {
            encoder.resolve_query_set(&self.queries, 0..STAMPS, &self.resolved, 0);
            encoder.copy_buffer_to_buffer(&self.resolved, 0, &self.staging, 0, 8 * u64::from(STAMPS));
        }
    }

    /// The last frame's times (blocking until the GPU is done).
    pub fn read(&self, device: &wgpu::Device) -> Result<GpuTimes, Box<dyn Error>> {
        let t: Vec<u64> = bytemuck::pod_collect_to_vec(&super::read_buffer(device, &self.staging)?);
        let ms = |spans: [(usize, usize); 2]| {
            let ticks: u64 = spans.iter().map(|&(a, b)| t[b].saturating_sub(t[a])).sum();
            ticks as f64 * self.period / 1e6
        };
        Ok(GpuTimes { culling_ms: ms([(0, 1), (2, 3)]), drawing_ms: ms([(1, 2), (3, 4)]) })
    }
}
