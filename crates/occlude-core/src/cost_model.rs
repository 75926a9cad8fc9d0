//! What a draw and an occlusion query cost, as a backend estimates them: the
//! "calibrated model of graphics hardware" that NOHC's decision per node
//! needs (CHC++ paper, section 3.2, after Guthe et al. 2006).
//!
//! A backend with a cost model of its own (the soft backend's `GpuModel`)
//! gives it through [`Backend::cost_model`](crate::Backend::cost_model); one
//! that measures its time instead (wgpu, a renderer of one's own) has none,
//! and methods use [`CostModel::default`]: the soft backend's `modern`
//! preset, a current desktop GPU (`docs/gpu-models.md`), so that a run on a
//! real GPU decides as a simulated `modern` run would.

/// Costs of drawing and querying, split as the soft backend's clock charges
/// them: CPU time per call, GPU time per call, per triangle and per pixel.
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
    }
}
