//! Fuzzes the GPU-model TOML reader (`bench --gpu-model FILE`). Any input
//! may be refused with an error; none may panic or hang, and a model that
//! is accepted must keep every simulated time finite, however many draws,
//! triangles and fragments a frame has.

#![no_main]

use occlude_soft::GpuModel;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let Ok(model) = GpuModel::from_toml(text) else { return };
    model.validate().expect("an accepted model validates");
    let many = 1u64 << 40;
    let times = [
        model.draw_us(model.cpu_draw_call_us, many),
        model.fragments_us(many),
        model.compute_items_us(many),
        model.hib_query_us(),
        model.hib_batch_gpu_us(),
    ];
    assert!(times.iter().all(|t| t.is_finite() && *t >= 0.0), "{times:?}");
});
