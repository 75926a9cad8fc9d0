//! The bookkeeping of a frame's occlusion queries, shared by every backend
//! of this crate that records queries into render passes ([`WgpuBackend`]
//! and the embedding, module `embed`): slots in query sets, the state of each
//! query (recorded, in flight with a submission, read), the read-backs of
//! each submission, and the time spent waiting for them (CHC paper, section
//! 3: "is it available?" never blocks, "give me the result" waits).
//!
//! A backend asks [`QueryBook::record`] for a slot, submits its passes when
//! [`QueryBook::starts_new_set`] says the next query needs another set or
//! when a recorded query's result is wanted, and hands each submission's
//! read-back to [`QueryBook::submitted`].
//!
//! [`WgpuBackend`]: crate::WgpuBackend

use crate::context::GpuContext;
use crate::queries::{read_values, QueryPool, Readback, QUERIES_PER_SET};
use crate::readback::Mapping;
use occlude_core::QueryHandle;
use std::time::{Duration, Instant};

/// Where a query's answer is.
#[derive(Clone, Copy, Debug)]
enum QueryState {
    /// Recorded, not yet submitted; `slot` is its place in the frame's query sets.
    Recorded { slot: u32 },
    /// Submitted with batch `batch`, at position `index` of its values.
    InFlight { batch: usize, index: usize },
    /// Read back.
    Ready(u64),
}

/// The queries of one submission, read back together.
struct Batch {
    readback: Option<Readback>,
    mapping: Mapping,
    bytes: u64,
    values: Vec<u64>,
}

/// The queries recorded since the last submission: their query set and
/// their slots in it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Pending {
    /// Index of the query set (in [`QueryBook::set`]).
    pub set: u32,
    /// First slot in the set.
    pub first: u32,
    /// Number of slots from `first`.
    pub count: u32,
}

/// A frame's queries, their submissions' read-backs and the frame's wait
/// time.
#[derive(Default)]
pub(crate) struct QueryBook {
    pool: QueryPool,
    queries: Vec<QueryState>,
    batches: Vec<Batch>,
    /// Query set of the recorded queries, if any are recorded.
    recorded_set: Option<u32>,
    next_slot: u32,
    /// Time spent blocked in [`QueryBook::poll`] since the last
    /// [`QueryBook::start_frame`].
    pub wait: Duration,
}

impl QueryBook {
    /// Forgets the last frame's queries (their read-backs must be settled)
    /// and its wait time.
    pub fn start_frame(&mut self) {
        self.next_slot = 0;
        self.queries.clear();
        self.wait = Duration::ZERO;
    }

    /// Whether the next recorded query takes a slot in another query set
    /// than the queries recorded so far: the recorded ones must be submitted
    /// first, since a render pass has one set.
    pub fn starts_new_set(&self) -> bool {
        self.recorded_set.is_some_and(|s| s != self.next_slot / QUERIES_PER_SET)
    }

    /// A new query, recorded in the next slot (returned with its handle).
    pub fn record(&mut self) -> (QueryHandle, u32) {
        let slot = self.next_slot;
        self.next_slot += 1;
        self.recorded_set = Some(slot / QUERIES_PER_SET);
        self.queries.push(QueryState::Recorded { slot });
        (QueryHandle(self.queries.len() as u32 - 1), slot)
    }

    /// A query whose answer is known without rasterizing (`value`).
    pub fn answered(&mut self, value: u64) -> QueryHandle {
        self.queries.push(QueryState::Ready(value));
        QueryHandle(self.queries.len() as u32 - 1)
    }

    /// Whether `query` is recorded but not yet submitted.
    pub fn is_recorded(&self, query: QueryHandle) -> bool {
        matches!(self.queries[query.0 as usize], QueryState::Recorded { .. })
    }

    /// Query set `k`, made on first use.
    pub fn set(&mut self, ctx: &GpuContext, k: u32) -> &wgpu::QuerySet {
        self.pool.set(ctx, k as usize)
    }

    /// The queries recorded since the last submission, forgetting their set
    /// (the submission about to be made takes them, and hands its read-back
    /// to [`QueryBook::submitted`]).
    pub fn take_pending(&mut self) -> Option<Pending> {
        let set = self.recorded_set.take()?;
        let mut slots = self.queries.iter().filter_map(|q| match q {
            QueryState::Recorded { slot } => Some(*slot),
            _ => None,
        });
        let first = slots.next()?;
        Some(Pending { set, first: first % QUERIES_PER_SET, count: 1 + slots.count() as u32 })
    }

    /// A read-back pair for the next submission's values.
    pub fn readback(&mut self, ctx: &GpuContext) -> Readback {
        self.pool.readback(ctx)
    }

    /// Takes the submission just made, whose recorded queries' values
    /// (`bytes` of them, in slot order) are copied into `readback`: starts
    /// mapping it, and those queries are in flight.
    pub fn submitted(&mut self, readback: Readback, bytes: u64) {
        let batch = self.batches.len();
        let mapping = Mapping::start(&readback.staging, bytes);
        self.batches.push(Batch { readback: Some(readback), mapping, bytes, values: Vec::new() });
        let mut first = None;
        for q in &mut self.queries {
            if let QueryState::Recorded { slot } = *q {
                let first = *first.get_or_insert(slot);
                *q = QueryState::InFlight { batch, index: (slot - first) as usize };
            }
        }
    }

    /// The value of `query` (submitted or answered) once its batch is read;
    /// `block` waits for it, counting the wait. `unknown` is what a failed
    /// read-back answers (all pixels: a failure never hides geometry).
    pub fn poll(&mut self, ctx: &GpuContext, query: QueryHandle, block: bool, unknown: u64) -> Option<u64> {
        let (batch, index) = match self.queries[query.0 as usize] {
            QueryState::Ready(v) => return Some(v),
            QueryState::InFlight { batch, index } => (batch, index),
            QueryState::Recorded { .. } => panic!("poll of a query not yet submitted"),
        };
        if self.batches[batch].readback.is_some() {
            let mapping = self.batches[batch].mapping.clone();
            if block {
                let start = Instant::now();
                let waited = mapping.wait(ctx);
                self.wait += start.elapsed();
                if waited.is_err() {
                    return Some(unknown);
                }
            } else if !mapping.is_done(ctx) {
                return None;
            }
            self.collect(ctx, batch);
        }
        let value = self.batches[batch].values.get(index).copied().unwrap_or(unknown);
        self.queries[query.0 as usize] = QueryState::Ready(value);
        Some(value)
    }

    /// Waits for every submitted read-back and collects it, so that the next
    /// frame starts clean.
    pub fn settle(&mut self, ctx: &GpuContext) {
        for batch in 0..self.batches.len() {
            if self.batches[batch].readback.is_some() {
                let mapping = self.batches[batch].mapping.clone();
                if mapping.wait(ctx).is_ok() {
                    self.collect(ctx, batch);
                } else if let Some(r) = self.batches[batch].readback.take() {
                    self.pool.recycle(r);
                }
            }
        }
        self.batches.clear();
    }

    /// Reads a finished batch's values and frees its read-back buffers.
    fn collect(&mut self, ctx: &GpuContext, batch: usize) {
        let Some(readback) = self.batches[batch].readback.take() else { return };
        let values = read_values(&readback, self.batches[batch].bytes);
        self.pool.recycle(readback);
        self.batches[batch].values = values.unwrap_or_else(|e| {
            ctx.fail(e);
            Vec::new()
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pending_queries_are_the_recorded_slots_of_one_set() {
        let mut book = QueryBook::default();
        assert_eq!(book.take_pending(), None);
        let (a, slot_a) = book.record();
        let known = book.answered(7);
        let (b, slot_b) = book.record();
        assert_eq!((slot_a, slot_b), (0, 1));
        assert!(book.is_recorded(a) && book.is_recorded(b) && !book.is_recorded(known));
        assert!(!book.starts_new_set());
        assert_eq!(book.take_pending(), Some(Pending { set: 0, first: 0, count: 2 }));

        // The last slot of a set: the next query starts another set (its
        // slot is the set's first), so the recorded ones are submitted first.
        let mut book = QueryBook { next_slot: 2 * QUERIES_PER_SET - 1, ..QueryBook::default() };
        book.record();
        assert!(book.starts_new_set());
        assert_eq!(book.take_pending(), Some(Pending { set: 1, first: QUERIES_PER_SET - 1, count: 1 }));
    }
}
