//! A frame on the soft backend's simulated clock ([`SimClock`]) charged
//! with a GPU model's costs, for the experiments that count their own
//! triangles and fragments rather than run a culling method through a
//! backend: `--paper gvq`'s Tables 1 ([`crate::gvq_shadows`]) and 3
//! ([`crate::gvq_parts`]). The CPU issues each command at its cost; the GPU
//! runs them in order (`SimClock::gpu_command`).

use occlude_soft::clock::SimClock;
use occlude_soft::GpuModel;

/// One frame's clock and the model it charges.
pub struct SimFrame<'m> {
    /// The costs.
    pub model: &'m GpuModel,
    clock: SimClock,
}

impl<'m> SimFrame<'m> {
    /// An empty frame charged with `model`'s costs.
    pub fn new(model: &'m GpuModel) -> Self {
        Self { model, clock: SimClock::new(model.driver_queue_us) }
    }

    /// `us` of CPU work.
    pub fn cpu_work(&mut self, us: f64) {
        self.clock.cpu_work(us);
    }

    /// A GPU command of `us` issued now.
    pub fn gpu(&mut self, us: f64) {
        self.clock.gpu_command(self.clock.cpu, us);
    }

    /// One draw call of `triangles` and `fragments`.
    pub fn draw(&mut self, triangles: u64, fragments: u64) {
        let m = self.model;
        self.cpu_work(m.cpu_draw_call_us);
        self.gpu(m.draw_us(m.gpu_draw_call_us, triangles) + m.fragments_us(fragments));
    }

    /// A compute dispatch over `items`.
    pub fn dispatch(&mut self, items: u64) {
        let m = self.model;
        self.cpu_work(m.cpu_dispatch_us);
        self.gpu(m.gpu_dispatch_us + m.compute_items_us(items));
    }

    /// `reads` texel reads of shaders' visibility tests (item-buffer bins,
    /// summed-area-table corners), each `gpu_hiz_texel_ns`.
    pub fn texel_reads(&mut self, reads: u64) {
        self.gpu(reads as f64 * self.model.gpu_hiz_texel_ns * 1e-3);
    }

    /// The frame time: when both CPU and GPU are done, ms.
    pub fn ms(&self) -> f64 {
        self.clock.frame_end() * 1e-3
    }
}
