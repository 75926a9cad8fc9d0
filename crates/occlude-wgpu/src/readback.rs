//! Reading GPU buffers back to the CPU: `map_async` with a completion flag
//! that can be polled ("is it available?") or waited on ("give me the
//! result"), as the backend interface asks.

use crate::context::GpuContext;
use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// How long a wait for the GPU may take before the device counts as hung.
const WAIT_LIMIT: Duration = Duration::from_secs(60);

const PENDING: u8 = 0;
const MAPPED: u8 = 1;
const FAILED: u8 = 2;

/// A buffer range being mapped for reading.
#[derive(Clone, Debug)]
pub(crate) struct Mapping(Arc<AtomicU8>);

impl Mapping {
    /// Starts mapping `size` bytes of `buffer` (a `MAP_READ` buffer whose
    /// copy has been submitted).
    pub fn start(buffer: &wgpu::Buffer, size: u64) -> Self {
        let state = Arc::new(AtomicU8::new(PENDING));
        let done = Arc::clone(&state);
        buffer.slice(..size).map_async(wgpu::MapMode::Read, move |r| {
            done.store(if r.is_ok() { MAPPED } else { FAILED }, Ordering::Release);
        });
        Self(state)
    }

    /// Whether the mapping finished, after letting the device make progress
    /// without blocking.
    pub fn is_done(&self, ctx: &GpuContext) -> bool {
        if self.0.load(Ordering::Acquire) == PENDING {
            // An error here (a lost device) shows in `ctx.failure()`.
            let _ = ctx.device.poll(wgpu::PollType::Poll);
        }
        self.0.load(Ordering::Acquire) != PENDING
    }

    /// Blocks until the mapping finished; an error when it failed or the
    /// device stopped answering (the failure is also recorded on `ctx`).
    pub fn wait(&self, ctx: &GpuContext) -> Result<(), String> {
        let start = std::time::Instant::now();
        while self.0.load(Ordering::Acquire) == PENDING {
            let wait = wgpu::PollType::Wait { submission_index: None, timeout: Some(WAIT_LIMIT) };
            if let Err(e) = ctx.device.poll(wait) {
                let message = format!("waiting for the GPU failed: {e}");
                ctx.fail(message.clone());
                return Err(message);
            }
            if start.elapsed() > WAIT_LIMIT && self.0.load(Ordering::Acquire) == PENDING {
                let message = format!("the GPU did not finish a read-back within {} s", WAIT_LIMIT.as_secs());
                ctx.fail(message.clone());
                return Err(message);
            }
        }
        match self.0.load(Ordering::Acquire) {
            MAPPED => Ok(()),
            _ => {
                let message = ctx.failure().unwrap_or_else(|| "mapping a GPU buffer for reading failed".into());
                ctx.fail(message.clone());
                Err(message)
            }
        }
    }
}

/// Copies `size` bytes out of `buffer`, mapped by a finished [`Mapping`],
/// and unmaps it.
pub(crate) fn take_bytes(buffer: &wgpu::Buffer, size: u64) -> Result<Vec<u8>, String> {
    let bytes = match buffer.slice(..size).get_mapped_range() {
        Ok(view) => Ok(view.to_vec()),
        Err(e) => Err(format!("reading a mapped GPU buffer failed: {e}")),
    };
    buffer.unmap();
    bytes
}
