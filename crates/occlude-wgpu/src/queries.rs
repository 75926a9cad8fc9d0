//! GPU query resources: occlusion query sets, the buffers their results are
//! resolved into and mapped from, and the timestamp queries that give a
//! frame's GPU time.

use crate::context::GpuContext;
use crate::readback::{take_bytes, Mapping};

/// Occlusion queries per query set (wgpu's maximum). A render pass uses one
/// set, so a batch of queries never crosses a set boundary.
pub(crate) const QUERIES_PER_SET: u32 = wgpu::QUERY_SET_MAX_QUERIES;

/// Bytes of one resolved query value.
const QUERY_BYTES: u64 = 8;

/// A resolve buffer and the mappable buffer its values are copied into, big
/// enough for one full query set.
pub(crate) struct Readback {
    pub resolve: wgpu::Buffer,
    pub staging: wgpu::Buffer,
}

/// Query sets by index, and read-back buffers ready for reuse.
#[derive(Default)]
pub(crate) struct QueryPool {
    sets: Vec<wgpu::QuerySet>,
    free: Vec<Readback>,
}

impl QueryPool {
    /// Occlusion query set `k`, created on first use.
    pub fn set(&mut self, ctx: &GpuContext, k: usize) -> &wgpu::QuerySet {
        while self.sets.len() <= k {
            self.sets.push(ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("occlusion queries"),
                ty: wgpu::QueryType::Occlusion,
                count: QUERIES_PER_SET,
            }));
        }
        &self.sets[k]
    }

    /// A read-back pair, reused when one is free.
    pub fn readback(&mut self, ctx: &GpuContext) -> Readback {
        self.free.pop().unwrap_or_else(|| new_readback(ctx, u64::from(QUERIES_PER_SET) * QUERY_BYTES, "queries"))
    }

    /// Returns an unmapped read-back pair for reuse.
    pub fn recycle(&mut self, readback: Readback) {
        self.free.push(readback);
    }
}

/// A resolve buffer and its mappable copy of `size` bytes.
pub(crate) fn new_readback(ctx: &GpuContext, size: u64, label: &str) -> Readback {
    let buffer = |usage| {
        ctx.device.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false })
    };
    Readback {
        resolve: buffer(wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC),
        staging: buffer(wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ),
    }
}

/// Encodes the resolve of `count` queries of `set` starting at `first` and
/// their copy into `readback`'s mappable buffer; the returned byte count is
/// what to map once the commands are submitted.
pub(crate) fn encode_resolve(
    encoder: &mut wgpu::CommandEncoder,
    set: &wgpu::QuerySet,
    first: u32,
    count: u32,
    readback: &Readback,
) -> u64 {
    let bytes = u64::from(count) * QUERY_BYTES;
    encoder.resolve_query_set(set, first..first + count, &readback.resolve, 0);
    encoder.copy_buffer_to_buffer(&readback.resolve, 0, &readback.staging, 0, bytes);
    bytes
}

/// The values of a finished read-back of `bytes` bytes.
pub(crate) fn read_values(readback: &Readback, bytes: u64) -> Result<Vec<u64>, String> {
    let raw = take_bytes(&readback.staging, bytes)?;
    Ok(raw.chunks_exact(8).map(|b| u64::from_le_bytes(b.try_into().expect("8-byte chunk"))).collect())
}

/// Passes of one frame whose GPU time is measured; passes past this count go
/// untimed, and the frame's `gpu_ms` undercounts.
const TIMED_PASSES: u32 = 2048;

/// What a pass does, for splitting the frame's GPU time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PassKind {
    /// Occlusion tests only: queries, batched box tests, the compute passes
    /// of GPU-resident culling (`cull_ms`).
    Cull,
    /// Draws of the scene's instances only (`render_ms`).
    Render,
    /// A depth-pyramid build: culling work (`cull_ms`), and `pyramid_ms`;
    /// the passes after the frame's first are `late_ms`.
    Pyramid,
    /// Both, or neither (a pass that only clears): counted in `gpu_ms` only.
    Other,
}

/// A frame's GPU time in milliseconds: all passes, and the cull and render
/// passes among them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct GpuTimes {
    pub total: f64,
    pub cull: f64,
    pub render: f64,
    /// Pyramid builds.
    pub pyramid: f64,
    /// The passes after the first pyramid build.
    pub late: f64,
}

/// Timestamps at the start and end of each pass of a frame; their
/// differences summed are the frame's GPU busy time.
pub(crate) struct PassTimer {
    set: wgpu::QuerySet,
    readback: Readback,
    period_ns: f64,
    /// What each timed pass of the frame does, in order.
    kinds: Vec<PassKind>,
}

impl PassTimer {
    /// A timer, when the device has timestamp queries.
    pub fn new(ctx: &GpuContext) -> Option<Self> {
        ctx.timestamps.then(|| Self {
            set: ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * TIMED_PASSES,
            }),
            readback: new_readback(ctx, u64::from(2 * TIMED_PASSES) * QUERY_BYTES, "timestamps"),
            period_ns: f64::from(ctx.queue.get_timestamp_period()),
            kinds: Vec::new(),
        })
    }

    /// The first of the next pass's two timestamp slots, while any are left.
    fn next_slots(&mut self, kind: PassKind) -> Option<u32> {
        let k = self.kinds.len() as u32;
        (k < TIMED_PASSES).then(|| {
            self.kinds.push(kind);
            2 * k
        })
    }

    /// Timestamp writes for the next render pass, doing `kind`.
    pub fn render_pass(&mut self, kind: PassKind) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        self.next_slots(kind).map(|k| wgpu::RenderPassTimestampWrites {
            query_set: &self.set,
            beginning_of_pass_write_index: Some(k),
            end_of_pass_write_index: Some(k + 1),
        })
    }

    /// Timestamp writes for the next compute pass (culling work).
    pub fn compute_pass(&mut self) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        self.compute_pass_doing(PassKind::Cull)
    }

    /// Timestamp writes for the next compute pass, doing `kind` (culling
    /// work, or a pyramid build).
    pub fn compute_pass_doing(&mut self, kind: PassKind) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        self.next_slots(kind).map(|k| wgpu::ComputePassTimestampWrites {
            query_set: &self.set,
            beginning_of_pass_write_index: Some(k),
            end_of_pass_write_index: Some(k + 1),
        })
    }

    /// Reads the frame's timestamps back (blocking) and returns its GPU busy
    /// times; resets for the next frame.
    pub fn finish(&mut self, ctx: &GpuContext) -> Result<GpuTimes, String> {
        let kinds = std::mem::take(&mut self.kinds);
        if kinds.is_empty() {
            return Ok(GpuTimes::default());
        }
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let bytes = encode_resolve(&mut encoder, &self.set, 0, 2 * kinds.len() as u32, &self.readback);
        ctx.queue.submit([encoder.finish()]);
        Mapping::start(&self.readback.staging, bytes).wait(ctx)?;
        let stamps = read_values(&self.readback, bytes)?;
        Ok(split_times(&stamps, &kinds, self.period_ns))
    }
}

/// The GPU times of passes timed by `stamps` (start and end, in ticks of
/// `period_ns`) doing `kinds`, in order.
fn split_times(stamps: &[u64], kinds: &[PassKind], period_ns: f64) -> GpuTimes {
    let mut times = GpuTimes::default();
    let mut after_pyramid = false;
    for (pair, &kind) in stamps.chunks_exact(2).zip(kinds) {
        let ms = pair[1].saturating_sub(pair[0]) as f64 * period_ns * 1e-6;
        times.total += ms;
        if after_pyramid {
            times.late += ms;
        }
        match kind {
            PassKind::Cull => times.cull += ms,
            PassKind::Render => times.render += ms,
            PassKind::Pyramid => {
                times.cull += ms;
                if !after_pyramid {
                    times.pyramid += ms;
                }
                after_pyramid = true;
            }
            PassKind::Other => {}
        }
    }
    times
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_frame_splits_at_its_first_pyramid_build() {
        use PassKind::*;
        // Early draw 2, a cull 1, the pyramid 3, the late test 4 and draw 5,
        // a second pyramid 6 (late, not pyramid); ticks of 1 ms.
        let stamps = [0, 2, 2, 3, 3, 6, 6, 10, 10, 15, 15, 21].map(|t| t * 1_000_000);
        let t = split_times(&stamps, &[Render, Cull, Pyramid, Cull, Render, Pyramid], 1.0);
        assert_eq!((t.total, t.cull, t.render), (21.0, 14.0, 7.0));
        assert_eq!((t.pyramid, t.late), (3.0, 15.0));
        let none = split_times(&stamps[..4], &[Render, Cull], 1.0);
        assert_eq!((none.pyramid, none.late), (0.0, 0.0));
    }
}
