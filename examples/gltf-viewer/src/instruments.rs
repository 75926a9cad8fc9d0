//! What the overlay shows that the frame itself never reads back: the GPU
//! time of the culling passes (timestamp queries around them) and the
//! instances and triangles GPU-driven culling's visible lists draw (summed
//! from their draw commands by a compute pass of the viewer's own). Both are read on demand, a few
//! times a second, blocking until the GPU is done.

use std::error::Error;

/// The device features the timer needs: timestamps written between passes.
pub const TIMER_FEATURES: wgpu::Features =
    wgpu::Features::TIMESTAMP_QUERY.union(wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS);

/// Timestamps around two spans of a frame's commands.
pub struct Timer {
    queries: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    staging: wgpu::Buffer,
    /// Nanoseconds per tick.
    period: f64,
}

/// Timestamps written: a start and an end per span.
const STAMPS: u32 = 4;

impl Timer {
    /// A timer on `device`, or `None` where it lacks [`TIMER_FEATURES`].
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue) -> Option<Self> {
        if !device.features().contains(TIMER_FEATURES) {
            return None;
        }
        let queries = device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("culling timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count: STAMPS,
        });
        let buffer = |usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("culling timestamps"),
                size: 8 * u64::from(STAMPS),
                usage,
                mapped_at_creation: false,
            })
        };
        let resolved = buffer(wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC);
        let staging = buffer(wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ);
        Some(Self { queries, resolved, staging, period: f64::from(queue.get_timestamp_period()) })
    }

    /// Writes timestamp `k` (0 and 1 around the first span, 2 and 3 around
    /// the second); after the last, keeps the frame's timestamps for
    /// [`Timer::read_ms`].
    pub fn stamp(&self, encoder: &mut wgpu::CommandEncoder, k: u32) {
        encoder.write_timestamp(&self.queries, k);
        if k == STAMPS - 1 {
            encoder.resolve_query_set(&self.queries, 0..STAMPS, &self.resolved, 0);
            encoder.copy_buffer_to_buffer(&self.resolved, 0, &self.staging, 0, 8 * u64::from(STAMPS));
        }
    }

    /// Milliseconds of both spans of the last frame resolved (blocking).
    pub fn read_ms(&self, device: &wgpu::Device) -> Result<f64, Box<dyn Error>> {
        let t: Vec<u64> = bytemuck::cast_slice(&read_buffer(device, &self.staging)?).to_vec();
        let ticks = t[1].saturating_sub(t[0]) + t[3].saturating_sub(t[2]);
        Ok(ticks as f64 * self.period / 1e6)
    }
}

/// Sums the instances and triangles that indexed draw commands draw.
pub struct Tally {
    pipeline: wgpu::ComputePipeline,
    totals: wgpu::Buffer,
    staging: wgpu::Buffer,
}

impl Tally {
    /// A tally on `device`.
    pub fn new(device: &wgpu::Device) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("tally"),
            source: wgpu::ShaderSource::Wgsl(include_str!("tally.wgsl").into()),
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("tally"),
            layout: None,
            module: &module,
            entry_point: Some("cs_tally"),
            compilation_options: Default::default(),
            cache: None,
        });
        let buffer = |usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("tally"),
                size: 8,
                usage,
                mapped_at_creation: false,
            })
        };
        let totals = buffer(wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST);
        let staging = buffer(wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ);
        Self { pipeline, totals, staging }
    }

    /// The instances and triangles the indexed draw commands in `commands`
    /// (buffers with `STORAGE` usage) draw, read back (blocking).
    pub fn count(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        commands: &[&wgpu::Buffer],
    ) -> Result<(u64, u64), Box<dyn Error>> {
        let mut encoder = device.create_command_encoder(&Default::default());
        encoder.clear_buffer(&self.totals, 0, None);
        for list in commands {
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("tally"),
                layout: &self.pipeline.get_bind_group_layout(0),
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: list.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 1, resource: self.totals.as_entire_binding() },
                ],
            });
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups((list.size() / 20).div_ceil(64) as u32, 1, 1);
        }
        encoder.copy_buffer_to_buffer(&self.totals, 0, &self.staging, 0, 8);
        queue.submit([encoder.finish()]);
        let totals: Vec<u32> = bytemuck::cast_slice(&read_buffer(device, &self.staging)?).to_vec();
        Ok((u64::from(totals[0]), u64::from(totals[1])))
    }
}

/// The bytes of a `MAP_READ` buffer once the GPU has written them (blocking).
pub fn read_buffer(device: &wgpu::Device, buffer: &wgpu::Buffer) -> Result<Vec<u8>, Box<dyn Error>> {
    let (sender, receiver) = std::sync::mpsc::channel();
    buffer.slice(..).map_async(wgpu::MapMode::Read, move |r| {
        let _ = sender.send(r);
    });
    device.poll(wgpu::PollType::wait_indefinitely())?;
    receiver.recv()??;
    let bytes = buffer.slice(..).get_mapped_range()?.to_vec();
    buffer.unmap();
    Ok(bytes)
}
