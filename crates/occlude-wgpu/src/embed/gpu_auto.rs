//! `auto` in a [`GpuCuller`](super::GpuCuller): each frame one late test
//! runs (`roc`'s box raster, `hiz`'s pyramid, or only the frustum: `vfc`),
//! chosen by the rules of [`occlude_core::methods::auto`] (its
//! [`Chooser`]). The tests share the culler's visibility flags, so a switch
//! keeps what the last frame found.
//!
//! The evidence is GPU time, frame to frame: from the end of a frame's
//! first pass (the early list's compaction) to the start of the next
//! frame's, so that both lists' draws count, and whatever else the
//! renderer draws. A looser test shows there too: its extra instances are
//! drawn in the next frame's early list. Timestamps are resolved in the
//! renderer's encoder and read back without waiting, some frames late,
//! through a ring of read-back buffers; a frame whose slot is still being
//! read goes unmeasured. On a device without timestamp queries a frame is
//! charged the wall time from its early phase to the next frame's.

use crate::context::GpuContext;
use crate::queries::{encode_resolve, new_readback, read_values, Readback};
use crate::readback::Mapping;
use occlude_core::methods::auto::{AutoParams, Chooser, Ticket};
use std::time::Instant;

/// Frames whose timestamps may be in flight at once.
const SLOTS: u32 = 4;

/// Bytes of a frame's two timestamps.
const STAMP_BYTES: u64 = 16;

/// One frame's timestamps (its start at index `2 * slot`, its end at
/// `2 * slot + 1`) on their way back.
struct Slot {
    readback: Readback,
    /// The frame timed in it.
    ticket: Option<Ticket>,
    /// Whether its resolve was recorded and not yet mapped.
    resolved: bool,
    mapping: Option<Mapping>,
}

/// Where frame times come from.
enum Clock {
    /// Timestamps in a ring of slots.
    Stamps {
        set: wgpu::QuerySet,
        slots: Vec<Slot>,
        period_ns: f64,
        /// Frames begun.
        frame: u32,
        /// This frame's slot, if it is timed.
        timed: Option<u32>,
        /// The last frame's slot, if timed: this frame's first pass writes
        /// its end.
        closing: Option<u32>,
    },
    /// The wall time between early phases, charged to the earlier frame.
    Wall { last: Option<(Instant, Ticket)> },
}

/// `auto`'s choice of late test in a `GpuCuller`.
pub(super) struct GpuAuto {
    chooser: Chooser,
    clock: Clock,
    ticket: Option<Ticket>,
}

impl GpuAuto {
    /// A choice among `cold.len()` late tests, `baseline` the frustum's
    /// alone (see [`Chooser::new`]), timed by timestamps where `ctx`'s
    /// device has them.
    pub fn new(ctx: &GpuContext, params: AutoParams, cold: &[u64], baseline: Option<usize>) -> Self {
        let clock = if ctx.device.features().contains(wgpu::Features::TIMESTAMP_QUERY) {
            Clock::Stamps {
                set: ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("auto frame timestamps"),
                    ty: wgpu::QueryType::Timestamp,
                    count: 2 * SLOTS,
                }),
                slots: (0..SLOTS)
                    .map(|_| Slot {
                        readback: new_readback(ctx, STAMP_BYTES, "auto frame timestamps"),
                        ticket: None,
                        resolved: false,
                        mapping: None,
                    })
                    .collect(),
                period_ns: f64::from(ctx.queue.get_timestamp_period()),
                frame: 0,
                timed: None,
                closing: None,
            }
        } else {
            Clock::Wall { last: None }
        };
        Self { chooser: Chooser::new(params, cold, baseline), clock, ticket: None }
    }

    /// Begins a frame at its early phase: the times that have come back
    /// are recorded, then the late test to run is chosen. The frames
    /// before were submitted (a renderer submits its frames in order).
    pub fn begin(&mut self, ctx: &GpuContext) -> Result<usize, String> {
        let ticket = match &mut self.clock {
            Clock::Stamps { slots, period_ns, frame, timed, closing, .. } => {
                for slot in slots.iter_mut() {
                    if std::mem::take(&mut slot.resolved) {
                        slot.mapping = Some(Mapping::start(&slot.readback.staging, STAMP_BYTES));
                    }
                    if slot.mapping.as_ref().is_some_and(|m| m.is_done(ctx)) {
                        slot.mapping = None;
                        let stamps = read_values(&slot.readback, STAMP_BYTES)?;
                        let ms = stamps[1].saturating_sub(stamps[0]) as f64 * *period_ns * 1e-6;
                        if let Some(ticket) = slot.ticket.take() {
                            self.chooser.record(ticket, ms);
                        }
                    }
                }
                let ticket = self.chooser.begin(|_, _, _| None);
                *closing = timed.take();
                let k = *frame % SLOTS;
                *frame = frame.wrapping_add(1);
                // A slot not being read is free, or its frame was never
                // closed (no late phase followed): it is taken.
                let slot = &mut slots[k as usize];
                if slot.mapping.is_none() {
                    slot.ticket = Some(ticket);
                    *timed = Some(k);
                }
                ticket
            }
            Clock::Wall { last } => {
                let now = Instant::now();
                if let Some((start, ticket)) = last.take() {
                    self.chooser.record(ticket, now.duration_since(start).as_secs_f64() * 1e3);
                }
                let ticket = self.chooser.begin(|_, _, _| None);
                *last = Some((now, ticket));
                ticket
            }
        };
        self.ticket = Some(ticket);
        Ok(ticket.choice)
    }

    /// Whether this frame runs a probe.
    pub fn probing(&self) -> bool {
        self.ticket.is_some_and(|t| t.is_probe())
    }

    /// The timestamp writes of the frame's first pass: at its start the
    /// last frame's end, at its end this frame's start.
    pub fn first_pass_writes(&self) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let Clock::Stamps { set, timed, closing, .. } = &self.clock else { return None };
        (timed.is_some() || closing.is_some()).then(|| wgpu::ComputePassTimestampWrites {
            query_set: set,
            beginning_of_pass_write_index: closing.map(|k| 2 * k + 1),
            end_of_pass_write_index: timed.map(|k| 2 * k),
        })
    }

    /// Records into `encoder`, after the frame's first pass, the resolve of
    /// the last frame's timestamps, both written by then.
    pub fn resolve(&mut self, encoder: &mut wgpu::CommandEncoder) {
        let Clock::Stamps { set, slots, closing, .. } = &mut self.clock else { return };
        if let Some(k) = closing.take() {
            let slot = &mut slots[k as usize];
            encode_resolve(encoder, set, 2 * k, 2, &slot.readback);
            slot.resolved = true;
        }
    }
}
