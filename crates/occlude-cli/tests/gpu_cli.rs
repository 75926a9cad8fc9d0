//! The command line on the wgpu backend: a missing adapter or driver is a
//! clear error with exit code 2; `bench` and `calibrate` measure on the GPU
//! where there is one (skipped with a message without an adapter, unless
//! `OCCLUDE_REQUIRE_GPU=1`).

use occlude_wgpu::GpuContext;

fn occlude(args: &[&str], env: &[(&str, &str)]) -> std::process::Output {
    let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_occlude"));
    command.args(args).envs(env.iter().copied());
    command.output().expect("occlude runs")
}

#[test]
fn no_adapter_is_a_clear_error_with_exit_code_2() {
    // Asking wgpu for a graphics API this platform lacks leaves no adapter.
    let missing_api = if cfg!(target_os = "macos") { "dx12" } else { "metal" };
    let out = occlude(&["bench", "--backend", "wgpu", "--frames", "2"], &[("WGPU_BACKEND", missing_api)]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "stderr: {stderr}");
    assert!(stderr.contains("no GPU adapter") && stderr.contains("--backend soft"), "{stderr}");
}

#[test]
fn without_a_vulkan_driver_other_apis_are_refused_or_absent_with_exit_code_2() {
    // No Vulkan driver: OpenGL is searched only where `WGPU_BACKEND` names it
    // (no GL adapter can copy depth textures, which the correctness rule
    // needs; its refusal is `occlude-wgpu`'s unit test), so nothing is left
    // here, and the run must not start.
    let no_vulkan = [("VK_DRIVER_FILES", "/nonexistent/icd.json"), ("VK_ICD_FILENAMES", "/nonexistent/icd.json")];
    let out = occlude(&["bench", "--backend", "wgpu", "--frames", "2"], &no_vulkan);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "stderr: {stderr}");
    assert!(stderr.contains("no GPU adapter") && stderr.contains("--backend soft"), "{stderr}");
    assert!(!stderr.contains("Validation Error"), "{stderr}");
}

#[test]
fn wgpu_bench_writes_measured_times_and_the_adapter() {
    if GpuContext::for_test("wgpu_bench_writes_measured_times_and_the_adapter").is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("gpu.json");
    let args =
        ["bench", "--backend", "wgpu", "--frames", "4", "--resolution", "160x120", "--methods", "vfc,chc,roc,ioc"];
    let out = occlude(&[&args[..], &["--json", json.to_str().unwrap()]].concat(), &[]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(stdout.contains("backend wgpu") && !stdout.contains("sim ms"), "{stdout}");
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["backend"], "wgpu");
    assert!(report["adapter"].as_str().is_some_and(|a| !a.is_empty()));
    for m in report["methods"].as_array().unwrap() {
        assert!(m["mean_frame_ms"].as_f64().unwrap() > 0.0);
        assert_eq!(m["missing_pixels"], 0);
        // The GPU-driven methods ran their passes on the GPU: box tests and
        // compaction in dispatches, the scene in indirect draws.
        if m["name"] == "roc" || m["name"] == "ioc" {
            assert!(m["dispatches_per_frame"].as_f64().unwrap() > 0.0, "{m}");
            assert!(m["indirect_draw_calls_per_frame"].as_f64().unwrap() > 0.0, "{m}");
            assert_eq!(m["readbacks_per_frame"].as_f64(), Some(0.0), "{m}");
        }
    }
}

#[test]
fn calibrate_writes_a_model_the_soft_backend_loads() {
    let out = occlude(&["calibrate", "--backend", "soft"], &[]);
    assert_eq!(out.status.code(), Some(2), "{}", String::from_utf8_lossy(&out.stderr));
    if GpuContext::for_test("calibrate_writes_a_model_the_soft_backend_loads").is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let toml = dir.path().join("gpu.toml");
    // Three frames per cost, so each is a median: with one, a single slow
    // empty frame on a loaded machine made a cost measure 0.
    let args = ["calibrate", "--repeats", "3", "--resolution", "160x120", "--check-frames", "3"];
    let check = ["--check-methods", "vfc,chc", "--out", toml.to_str().unwrap()];
    let out = occlude(&[&args[..], &check[..]].concat(), &[]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(&toml).unwrap();
    assert!(text.contains("# check vfc: measured") && text.contains("# check chc: measured"), "{text}");
    let model = occlude_soft::GpuModel::load(toml.to_str().unwrap()).unwrap();
    assert_eq!(model.name, "calibrated");
    // Each cost may measure 0 on a noisy machine at this tiny size (a frame
    // minus the empty frame's time is clamped at 0), but not all of them.
    let measured = [model.gpu_draw_call_us, model.gpu_triangle_ns, model.gpu_fragment_ns, model.query_latency_us];
    assert!(measured.iter().sum::<f64>() > 0.0, "{model:?}");
    // lavapipe runs GPU-resident culling, so its costs are measured too (200
    // dispatches are well above the noise of an empty frame).
    assert!(!text.contains("culling costs not measured"), "{text}");
    assert!(model.gpu_dispatch_us > 0.0 && model.cpu_dispatch_us > 0.0, "{model:?}");
    // And so is the CPU cost of a query recorded in an item-buffer batch.
    assert!(text.contains("cpu_hib_query_us") && model.cpu_hib_query_us.is_some(), "{text}");
    // And the GPU cost of an item-buffer batch, fitted over frames of more
    // and fewer batches (it may fit 0 at this size, clamped, never below).
    let batch_us = model.gpu_hib_batch_us;
    assert!(text.contains("gpu_hib_batch_us") && batch_us.is_some_and(|us| us.is_finite() && us >= 0.0), "{text}");
    // The model drives a soft run.
    let run =
        occlude(&["bench", "--frames", "2", "--resolution", "160x120", "--gpu-model", toml.to_str().unwrap()], &[]);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
}
