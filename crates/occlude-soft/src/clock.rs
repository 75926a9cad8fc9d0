//! The two clocks of the simulated GPU (`docs/design.md`): the CPU advances by the
//! cost of each call; the GPU runs commands in order, each starting at
//! max(issue time, GPU free); a blocking read moves the CPU forward (wait
//! time). The driver buffers a bounded amount of GPU work ahead of the GPU:
//! a submitting call that finds more queued blocks until the GPU has worked
//! it down (submission time, apart from the wait).

/// CPU and GPU time lines of one frame, in microseconds from its start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimClock {
    /// Current CPU time.
    pub cpu: f64,
    /// Time the GPU finishes its last queued command.
    pub gpu_free: f64,
    /// Total GPU busy time.
    pub gpu_busy: f64,
    /// Total CPU time spent blocked on results.
    pub wait: f64,
    /// Total CPU time spent blocked in submitting calls, the driver's queue
    /// being full.
    pub submit_wait: f64,
    /// GPU work the driver queues ahead of the GPU before a submitting call
    /// blocks, µs (`f64::INFINITY`: it never blocks).
    pub queue_limit_us: f64,
}

impl Default for SimClock {
    /// A frame's clocks at zero with an unbounded driver queue.
    fn default() -> Self {
        Self::new(f64::INFINITY)
    }
}

/// Where [`SimClock::gpu_command`] put a command.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Submitted {
    /// How long the submitting call blocked, the driver's queue being full.
    pub blocked: f64,
    /// When the command ends on the GPU.
    pub end: f64,
}

impl SimClock {
    /// A frame's clocks at zero; a submitting call blocks while more than
    /// `queue_limit_us` of GPU work is queued ahead of the GPU.
    pub fn new(queue_limit_us: f64) -> Self {
        Self { cpu: 0.0, gpu_free: 0.0, gpu_busy: 0.0, wait: 0.0, submit_wait: 0.0, queue_limit_us }
    }

    /// Charges `us` of CPU work.
    pub fn cpu_work(&mut self, us: f64) {
        self.cpu += us;
    }

    /// Runs a GPU command submitted at CPU time `issued` costing `us`. If
    /// more than the queue limit of GPU work is then queued ahead of it, the
    /// submitting call blocks until the GPU has worked the queue down to
    /// the limit: the CPU clock moves forward by that time (counted in
    /// `submit_wait`), and so do the CPU times of commands submitted after
    /// this one but replayed later (their caller adds `blocked`).
    pub fn gpu_command(&mut self, issued: f64, us: f64) -> Submitted {
        let blocked = (self.gpu_free - self.queue_limit_us - issued).max(0.0);
        self.cpu += blocked;
        self.submit_wait += blocked;
        let start = (issued + blocked).max(self.gpu_free);
        self.gpu_free = start + us;
        self.gpu_busy += us;
        Submitted { blocked, end: self.gpu_free }
    }

    /// Blocks the CPU until `time` (no-op when already past it).
    pub fn wait_until(&mut self, time: f64) {
        if time > self.cpu {
            self.wait += time - self.cpu;
            self.cpu = time;
        }
    }

    /// Whether a submitting call can block (the driver's queue is bounded).
    pub fn queue_is_bounded(&self) -> bool {
        self.queue_limit_us.is_finite()
    }

    /// Frame time: when both CPU and GPU are done.
    pub fn frame_end(&self) -> f64 {
        self.cpu.max(self.gpu_free)
    }

    /// CPU time spent working: neither waiting for results nor blocked in
    /// a submitting call.
    pub fn cpu_busy(&self) -> f64 {
        self.cpu - self.wait - self.submit_wait
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gpu_queue_is_in_order_and_waits_count() {
        let mut c = SimClock::default();
        c.cpu_work(1.0);
        let a = c.gpu_command(c.cpu, 10.0).end; // runs 1..11
        c.cpu_work(1.0);
        let b = c.gpu_command(c.cpu, 5.0).end; // queued behind: 11..16
        assert_eq!((a, b), (11.0, 16.0));
        c.wait_until(b + 2.0);
        assert_eq!(c.wait, 16.0);
        assert_eq!(c.frame_end(), 18.0);
        c.wait_until(3.0);
        assert_eq!(c.wait, 16.0, "waiting for the past costs nothing");
        assert_eq!(c.submit_wait, 0.0, "an unbounded queue never blocks a submission");
    }

    #[test]
    fn a_full_driver_queue_blocks_the_submitting_call() {
        let mut c = SimClock::new(4.0);
        let a = c.gpu_command(0.0, 10.0); // runs 0..10
        assert_eq!(a, Submitted { blocked: 0.0, end: 10.0 });
        // Two commands recorded at CPU times 1 and 2, replayed afterwards
        // (as the soft backend does).
        c.cpu_work(2.0);
        // At 1, 9 µs are queued: blocks until 6, when 4 are left; runs 10..15.
        let b = c.gpu_command(1.0, 5.0);
        assert_eq!(b, Submitted { blocked: 5.0, end: 15.0 });
        assert_eq!((c.cpu, c.submit_wait, c.wait), (7.0, 5.0, 0.0));
        // Recorded at 2, so submitted at 7 after that block: 8 µs queued,
        // blocks until 11; runs 15..16.
        let d = c.gpu_command(2.0 + b.blocked, 1.0);
        assert_eq!(d, Submitted { blocked: 4.0, end: 16.0 });
        assert_eq!((c.cpu, c.submit_wait), (11.0, 9.0));
        // Within the limit (2 µs queued at 14): no block.
        c.cpu_work(3.0);
        assert_eq!(c.gpu_command(c.cpu, 1.0), Submitted { blocked: 0.0, end: 17.0 });
        assert_eq!(c.cpu_busy(), 5.0, "CPU work only: 2 + 3");
        // A result then waits only for what the queue still holds.
        c.wait_until(c.gpu_free + 2.0);
        assert_eq!((c.wait, c.frame_end()), (5.0, 19.0));
    }
}
