//! The two clocks of the simulated GPU (`docs/design.md`): the CPU advances by the
//! cost of each call; the GPU runs commands in order, each starting at
//! max(issue time, GPU free); a blocking read moves the CPU forward (wait time).

/// CPU and GPU time lines of one frame, in microseconds from its start.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SimClock {
    /// Current CPU time.
    pub cpu: f64,
    /// Time the GPU finishes its last queued command.
    pub gpu_free: f64,
    /// Total GPU busy time.
    pub gpu_busy: f64,
    /// Total CPU time spent blocked on results.
    pub wait: f64,
}

impl SimClock {
    /// Charges `us` of CPU work.
    pub fn cpu_work(&mut self, us: f64) {
        self.cpu += us;
    }

    /// Runs a GPU command issued at `issued` costing `us`; returns when it ends.
    pub fn gpu_command(&mut self, issued: f64, us: f64) -> f64 {
        let start = issued.max(self.gpu_free);
        self.gpu_free = start + us;
        self.gpu_busy += us;
        self.gpu_free
    }

    /// Blocks the CPU until `time` (no-op when already past it).
    pub fn wait_until(&mut self, time: f64) {
        if time > self.cpu {
            self.wait += time - self.cpu;
            self.cpu = time;
        }
    }

    /// Frame time: when both CPU and GPU are done.
    pub fn frame_end(&self) -> f64 {
        self.cpu.max(self.gpu_free)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gpu_queue_is_in_order_and_waits_count() {
        let mut c = SimClock::default();
        c.cpu_work(1.0);
        let a = c.gpu_command(c.cpu, 10.0); // runs 1..11
        c.cpu_work(1.0);
        let b = c.gpu_command(c.cpu, 5.0); // queued behind: 11..16
        assert_eq!((a, b), (11.0, 16.0));
        c.wait_until(b + 2.0);
        assert_eq!(c.wait, 16.0);
        assert_eq!(c.frame_end(), 18.0);
        c.wait_until(3.0);
        assert_eq!(c.wait, 16.0, "waiting for the past costs nothing");
    }
}
