//! `auto` in a [`GpuCuller`](super::GpuCuller): each frame one late test
//! runs (`roc`'s box raster, `hiz`'s pyramid, or only the frustum: `vfc`),
//! chosen by the rules of [`occlude_core::methods::auto`] (its
//! [`Chooser`]). The tests share the culler's visibility flags, so a switch
//! keeps what the last frame found.
//!
//! The evidence is GPU time: from the start of the early phase's first
//! pass to the end of the late phase's last, the early list's draws
//! between (what a looser test costs shows there, a frame later).
//! Timestamps are resolved in the frame's own encoder and read back
//! without waiting, some frames late, through a ring of read-back buffers;
//! a frame whose slot is still being read goes unmeasured. On a device
//! without timestamp queries a frame is charged the wall time from its
//! early phase to the next frame's.

use crate::context::GpuContext;
use crate::queries::{encode_resolve, new_readback, read_values, Readback};
use crate::readback::Mapping;
use occlude_core::methods::auto::{AutoParams, Chooser, Ticket};
use std::time::Instant;

/// Frames whose timestamps may be in flight at once.
const SLOTS: u32 = 4;

/// Bytes of a frame's two timestamps.
const STAMP_BYTES: u64 = 16;

/// One frame's timestamps on their way back.
struct Slot {
    readback: Readback,
    /// The frame whose timestamps were resolved into it.
    ticket: Option<Ticket>,
    /// Whether its resolve was recorded and not yet mapped.
    resolved: bool,
    mapping: Option<Mapping>,
}

/// Where frame times come from.
enum Clock {
    /// Two timestamps a frame, in ring slot `frame % SLOTS`.
    Stamps { set: wgpu::QuerySet, slots: Vec<Slot>, period_ns: f64, frame: u32, timed: bool },
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
    /// A choice among `stateless.len()` late tests (see [`Chooser::new`]),
    /// timed by timestamps where `ctx`'s device has them.
    pub fn new(ctx: &GpuContext, params: AutoParams, stateless: &[bool]) -> Self {
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
                timed: false,
            }
        } else {
            Clock::Wall { last: None }
        };
        Self { chooser: Chooser::new(params, stateless), clock, ticket: None }
    }

    /// Begins a frame at its early phase: the times that have come back
    /// are recorded, then the late test to run is chosen. The frames
    /// before were submitted (a renderer submits its frames in order).
    pub fn begin(&mut self, ctx: &GpuContext) -> Result<usize, String> {
        let ticket = match &mut self.clock {
            Clock::Stamps { slots, period_ns, frame, timed, .. } => {
                for slot in slots.iter_mut() {
                    if std::mem::take(&mut slot.resolved) {
                        slot.mapping = Some(Mapping::start(&slot.readback.staging, STAMP_BYTES));
                    }
                    if slot.mapping.as_ref().is_some_and(|m| m.is_done(ctx)) {
                        slot.mapping = None;
                        let stamps = read_values(&slot.readback, STAMP_BYTES)?;
                        let ms = stamps[1].saturating_sub(stamps[0]) as f64 * *period_ns * 1e-6;
                        let ticket = slot.ticket.take().expect("a resolved slot has its frame");
                        self.chooser.record(ticket, ms);
                    }
                }
                let ticket = self.chooser.begin(|_, _| None);
                *frame = frame.wrapping_add(1);
                let slot = &mut slots[(*frame % SLOTS) as usize];
                // A slot not being read is free, or its frame's late phase
                // never came (its resolve was never recorded).
                *timed = slot.mapping.is_none();
                if *timed {
                    slot.ticket = Some(ticket);
                }
                ticket
            }
            Clock::Wall { last } => {
                let now = Instant::now();
                if let Some((start, ticket)) = last.take() {
                    self.chooser.record(ticket, now.duration_since(start).as_secs_f64() * 1e3);
                }
                let ticket = self.chooser.begin(|_, _| None);
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

    /// The timestamp write for the early phase's first pass, if the frame
    /// is timed.
    pub fn start_write(&self) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        self.writes().map(|(set, k)| wgpu::ComputePassTimestampWrites {
            query_set: set,
            beginning_of_pass_write_index: Some(k),
            end_of_pass_write_index: None,
        })
    }

    /// The timestamp write for the late phase's last pass, if the frame is
    /// timed.
    pub fn end_write(&self) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        self.writes().map(|(set, k)| wgpu::ComputePassTimestampWrites {
            query_set: set,
            beginning_of_pass_write_index: None,
            end_of_pass_write_index: Some(k + 1),
        })
    }

    /// Records the resolve of the frame's timestamps into `encoder`, after
    /// its last pass.
    pub fn resolve(&mut self, encoder: &mut wgpu::CommandEncoder) {
        if let Clock::Stamps { set, slots, frame, timed: true, .. } = &mut self.clock {
            let slot = &mut slots[(*frame % SLOTS) as usize];
            encode_resolve(encoder, set, 2 * (*frame % SLOTS), 2, &slot.readback);
            slot.resolved = true;
        }
    }

    /// The query set and this frame's first index in it, if timed.
    fn writes(&self) -> Option<(&wgpu::QuerySet, u32)> {
        match &self.clock {
            Clock::Stamps { set, frame, timed: true, .. } => Some((set, 2 * (*frame % SLOTS))),
            _ => None,
        }
    }
}
