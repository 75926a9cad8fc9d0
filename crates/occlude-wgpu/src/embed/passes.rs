//! The passes and dispatches a [`GpuCuller`](super::GpuCuller) records in a
//! frame, counted where they are begun and issued: every culling pass is
//! begun through a [`Tally`], and every dispatch goes through the counted
//! [`ComputePass`] it begins.

use super::backend::{begin_pass, PassStart};
use super::{Attachments, FrameTarget};
use crate::culling::workgroups;
use std::sync::atomic::{AtomicU32, Ordering};

/// The passes and dispatches a [`GpuCuller`](super::GpuCuller) recorded in
/// its last frame ([`GpuCuller::pass_counts`](super::GpuCuller::pass_counts)):
/// an instrument, for tests and printouts. The renderer's own passes are
/// not counted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PassCounts {
    /// Compute passes begun.
    pub compute_passes: u32,
    /// Render passes begun (the box tests of `roc` and `ioc`).
    pub render_passes: u32,
    /// Compute dispatches issued.
    pub dispatches: u32,
}

/// Counters of the culling passes and dispatches recorded since the last
/// [`Tally::reset`]. Shared by reference, so the counting sits where the
/// recording is. Atomic, so that a culler holding one stays `Sync`; only
/// the recording thread counts.
#[derive(Default)]
pub(super) struct Tally {
    compute_passes: AtomicU32,
    render_passes: AtomicU32,
    dispatches: AtomicU32,
}

impl Tally {
    /// Starts a frame's count at zero.
    pub fn reset(&self) {
        for counter in [&self.compute_passes, &self.render_passes, &self.dispatches] {
            counter.store(0, Ordering::Relaxed);
        }
    }

    /// What was counted since the last reset.
    pub fn counts(&self) -> PassCounts {
        PassCounts {
            compute_passes: self.compute_passes.load(Ordering::Relaxed),
            render_passes: self.render_passes.load(Ordering::Relaxed),
            dispatches: self.dispatches.load(Ordering::Relaxed),
        }
    }

    /// Begins a compute pass in `encoder`, counted, whose dispatches are
    /// counted too.
    pub fn compute_pass<'e>(&'e self, encoder: &'e mut wgpu::CommandEncoder) -> ComputePass<'e> {
        self.timed_compute_pass(encoder, None)
    }

    /// [`Tally::compute_pass`] writing the timestamps `writes` says, if any.
    pub fn timed_compute_pass<'e>(
        &'e self,
        encoder: &'e mut wgpu::CommandEncoder,
        writes: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) -> ComputePass<'e> {
        bump(&self.compute_passes);
        let descriptor = wgpu::ComputePassDescriptor { label: None, timestamp_writes: writes };
        ComputePass { pass: encoder.begin_compute_pass(&descriptor), tally: self }
    }

    /// Begins a render pass on `target`'s views as
    /// [`begin_pass`](super::backend::begin_pass) does, counted.
    pub fn render_pass<'e>(
        &self,
        encoder: &'e mut wgpu::CommandEncoder,
        target: &FrameTarget<'_>,
        attachments: &Attachments,
        start: PassStart,
    ) -> wgpu::RenderPass<'e> {
        bump(&self.render_passes);
        begin_pass(encoder, target, attachments, start, None)
    }
}

/// A compute pass begun by [`Tally::compute_pass`]: each dispatch is
/// counted.
pub(super) struct ComputePass<'e> {
    pass: wgpu::ComputePass<'e>,
    tally: &'e Tally,
}

impl ComputePass<'_> {
    /// One dispatch of `pipeline` with `group` as bind group 0, over
    /// `threads` threads.
    pub fn dispatch(&mut self, pipeline: &wgpu::ComputePipeline, group: &wgpu::BindGroup, threads: u32) {
        self.pass.set_pipeline(pipeline);
        self.pass.set_bind_group(0, group, &[]);
        let (x, y) = workgroups(threads);
        self.pass.dispatch_workgroups(x, y, 1);
        bump(&self.tally.dispatches);
    }
}

/// Adds one to `counter`.
fn bump(counter: &AtomicU32) {
    counter.fetch_add(1, Ordering::Relaxed);
}
