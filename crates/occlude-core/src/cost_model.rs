//! What a draw, an occlusion query and a GPU-driven pass cost, as a backend
//! estimates them: the "calibrated model of graphics hardware" that NOHC's
//! decision per node needs (CHC++ paper, section 3.2, after Guthe et al.
//! 2006), and the fixed passes whose cost bounds a method's frame from
//! below (`CullingMethod::floor_ms`).
//!
//! A backend with a cost model of its own (the soft backend's `GpuModel`)
//! gives it through [`Backend::cost_model`](crate::Backend::cost_model); one
//! that measures its time instead (wgpu, a renderer of one's own) has none,
//! and methods use [`CostModel::default`]: the soft backend's `modern`
//! preset, a current desktop GPU (`docs/gpu-models.md`), so that a run on a
//! real GPU decides as a simulated `modern` run would.

/// Costs of drawing, querying and GPU-driven passes, split as the soft
/// backend's clock charges them: CPU time per call, GPU time per call, per
/// triangle and per pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CostModel {
    /// CPU time to issue one draw call, µs.
    pub cpu_draw_call_us: f64,
    /// GPU time per draw call, µs.
    pub gpu_draw_call_us: f64,
    /// GPU time per drawn triangle, ns.
    pub gpu_triangle_ns: f64,
    /// GPU time per drawn fragment, ns.
    pub gpu_fragment_ns: f64,
    /// CPU time to issue one occlusion query, µs.
    pub cpu_query_us: f64,
    /// GPU time per query box, µs.
    pub gpu_query_box_us: f64,
    /// GPU time per query fragment (depth test only), ns.
    pub gpu_query_fragment_ns: f64,
    /// Time from the GPU finishing a query until the CPU can read its
    /// result, µs.
    pub query_latency_us: f64,
    /// CPU time to record one compute dispatch or indirect draw, µs.
    pub cpu_dispatch_us: f64,
    /// GPU time of one compute dispatch (launch and the barrier after it),
    /// µs.
    pub gpu_dispatch_us: f64,
    /// GPU time per texel a depth-pyramid level writes, ns.
    pub gpu_pyramid_texel_ns: f64,
}

impl Default for CostModel {
    /// The soft backend's `modern` preset (`GpuModel::modern`; a test in
    /// `occlude-soft` keeps the two equal).
    fn default() -> Self {
        Self {
            cpu_draw_call_us: 1.0,
            gpu_draw_call_us: 0.5,
            gpu_triangle_ns: 0.4,
            gpu_fragment_ns: 0.02,
            cpu_query_us: 0.5,
            gpu_query_box_us: 0.3,
            gpu_query_fragment_ns: 0.005,
            query_latency_us: 30.0,
            cpu_dispatch_us: 1.0,
            gpu_dispatch_us: 3.0,
            gpu_pyramid_texel_ns: 0.05,
        }
    }
}

impl CostModel {
    /// Time to draw `draws` draw calls of `triangles` triangles covering
    /// `pixels` fragments, µs: CPU and GPU time added, as neither hides the
    /// other when the method waits on a query.
    pub fn render_us(&self, draws: u64, triangles: u64, pixels: f64) -> f64 {
        draws as f64 * (self.cpu_draw_call_us + self.gpu_draw_call_us)
            + triangles as f64 * self.gpu_triangle_ns * 1e-3
            + pixels * self.gpu_fragment_ns * 1e-3
    }

    /// Time of one occlusion query of `boxes` boxes covering `pixels`
    /// fragments, µs, CPU and GPU time added.
    pub fn query_us(&self, boxes: u64, pixels: f64) -> f64 {
        self.cpu_query_us + boxes as f64 * self.gpu_query_box_us + pixels * self.gpu_query_fragment_ns * 1e-3
    }

    /// The least time a frame takes that issues `draws` draw calls of
    /// `triangles` triangles, ms: the CPU issues them while the GPU draws,
    /// and the frame ends after both (fragments and state changes left
    /// out).
    pub fn draws_floor_ms(&self, draws: u64, triangles: u64) -> f64 {
        let cpu = draws as f64 * self.cpu_draw_call_us;
        let gpu = draws as f64 * self.gpu_draw_call_us + triangles as f64 * self.gpu_triangle_ns * 1e-3;
        cpu.max(gpu) * 1e-3
    }

    /// The least time a frame takes that records `dispatches` compute
    /// dispatches and `draws` indirect draws and has the GPU write
    /// `pyramid_texels` depth-pyramid texels, ms: the CPU records them all,
    /// the GPU runs the dispatches one after another, and the frame ends
    /// after both.
    pub fn passes_ms(&self, dispatches: u64, draws: u64, pyramid_texels: u64) -> f64 {
        let cpu = (dispatches + draws) as f64 * self.cpu_dispatch_us;
        let gpu = dispatches as f64 * self.gpu_dispatch_us + pyramid_texels as f64 * self.gpu_pyramid_texel_ns * 1e-3;
        cpu.max(gpu) * 1e-3
    }

    /// The least time a frame takes that waits for one occlusion query's
    /// result, ms: the latency of its result alone.
    pub fn query_round_trip_ms(&self) -> f64 {
        self.query_latency_us * 1e-3
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn costs_grow_with_work() {
        let m = CostModel::default();
        assert!((m.render_us(2, 1000, 0.0) - (2.0 * 1.5 + 0.4)).abs() < 1e-12);
        assert!((m.query_us(1, 1000.0) - (0.5 + 0.3 + 0.005)).abs() < 1e-12);
        assert!(m.render_us(1, 10, 100.0) < m.render_us(1, 10, 1000.0));
        // Six dispatches on the GPU (18 µs) outlast nine recordings on the
        // CPU (9 µs); a pyramid's texels add GPU time. Two draws of 10,000
        // triangles: the GPU's 5 µs outlast the CPU's 2.
        assert!((m.passes_ms(6, 3, 0) - 0.018).abs() < 1e-12);
        assert!((m.passes_ms(6, 3, 20_000) - 0.019).abs() < 1e-12);
        assert!((m.draws_floor_ms(2, 10_000) - 0.005).abs() < 1e-12);
        assert!((m.query_round_trip_ms() - 0.030).abs() < 1e-12);
    }
}
