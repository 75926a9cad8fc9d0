//! `occlude raster-bench` as a user meets it: a tiny run prints both tables and
//! writes JSON of the documented shape, with the wgpu backend's rows beside the soft
//! rasterizer's when a GPU adapter opens; bad options are usage errors (exit code 2).

use std::process::Command;

fn occlude(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_occlude")).args(args).output().expect("occlude runs")
}

#[test]
fn tiny_run_prints_tables_and_writes_json() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("raster.json");
    let out = occlude(&[
        "raster-bench",
        "--sizes",
        "10,50",
        "--triangles-per-size",
        "100",
        "--seconds-per-row",
        "0.01",
        "--resolution",
        "160x120",
        "--gpu",
        "off",
        "--json",
        json.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "stderr: {}", String::from_utf8_lossy(&out.stderr));
    assert!(stdout.contains("MTris/s") && stdout.contains("queries/s"), "{stdout}");

    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let rows = report["rows"].as_array().expect("rows");
    // Two sizes, the soft rasterizer then the masked buffer, threads 1 and 2, in order.
    let keys: Vec<(u64, &str, u64)> = rows
        .iter()
        .map(|r| (r["n"].as_u64().unwrap(), r["backend"].as_str().unwrap(), r["threads"].as_u64().unwrap()))
        .collect();
    let per_size = |n| [(n, "soft", 1), (n, "soft", 2), (n, "moc", 1), (n, "moc", 2)];
    assert_eq!(keys, [per_size(10), per_size(50)].concat());
    for r in rows {
        let (mtris, gpix) = (r["mtris_per_s"].as_f64().unwrap(), r["gpixels_per_s"].as_f64().unwrap());
        let n = r["n"].as_f64().unwrap();
        assert!(mtris > 0.0);
        assert!((gpix - mtris * n * n / 2.0 / 1000.0).abs() <= 1e-9 * gpix, "{r}");
    }
    assert!(!report["cpu"].as_str().expect("cpu").is_empty());
    assert!(report["adapter"].is_null());
    let queries = report["queries"].as_array().expect("queries");
    // Coverages 1, 10, 50 %, visible and hidden, count and any, threads 1 and 2.
    assert_eq!(queries.len(), 3 * 2 * 2 * 2);
    for q in queries {
        assert!([1, 10, 50].contains(&q["coverage_percent"].as_u64().unwrap()), "{q}");
        assert!(q["visible"].is_boolean());
        assert!(["count", "any"].contains(&q["mode"].as_str().unwrap()), "{q}");
        assert_eq!(q["backend"], "soft");
        assert!(q["queries_per_s"].as_f64().unwrap() > 0.0);
    }
}

#[test]
fn wgpu_rows_run_beside_the_soft_ones_when_an_adapter_opens() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("raster.json");
    let require = std::env::var("OCCLUDE_REQUIRE_GPU").is_ok_and(|v| v == "1");
    let out = occlude(&[
        "raster-bench",
        "--sizes",
        "25",
        "--triangles-per-size",
        "200",
        "--seconds-per-row",
        "0.01",
        "--resolution",
        "160x120",
        "--threads",
        "2",
        "--gpu",
        if require { "required" } else { "auto" },
        "--json",
        json.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "stderr: {}", String::from_utf8_lossy(&out.stderr));
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let keys: Vec<(&str, u64)> = report["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| (r["backend"].as_str().unwrap(), r["threads"].as_u64().unwrap()))
        .collect();
    let Some(adapter) = report["adapter"].as_str() else {
        assert!(!require, "OCCLUDE_REQUIRE_GPU=1 but no wgpu rows");
        eprintln!("skipping the wgpu rows: no GPU adapter");
        assert_eq!(keys, [("soft", 2), ("moc", 2)]);
        return;
    };
    assert!(!adapter.is_empty() && stdout.contains(adapter), "{stdout}");
    assert_eq!(keys, [("soft", 2), ("moc", 2), ("wgpu", 0)]);
    for r in report["rows"].as_array().unwrap() {
        assert!(r["mtris_per_s"].as_f64().unwrap() > 0.0, "{r}");
    }
    // The GPU counts samples; it has no visibility-only early-out.
    let gpu_modes: Vec<&str> = report["queries"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|q| q["backend"] == "wgpu")
        .map(|q| q["mode"].as_str().unwrap())
        .collect();
    assert_eq!(gpu_modes, ["count"; 6]);
}

#[test]
fn a_required_gpu_without_an_adapter_is_a_usage_error() {
    // Asking wgpu for a graphics API this platform lacks leaves no adapter.
    let missing_api = if cfg!(target_os = "macos") { "dx12" } else { "metal" };
    let out = Command::new(env!("CARGO_BIN_EXE_occlude"))
        .args(["raster-bench", "--sizes", "10", "--resolution", "64x64", "--gpu", "required"])
        .env("WGPU_BACKEND", missing_api)
        .output()
        .expect("occlude runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("no GPU adapter found"), "{stderr}");
}

#[test]
fn bad_options_are_usage_errors() {
    for (args, needle) in [
        (&["raster-bench", "--sizes", "0"][..], "--sizes"),
        (&["raster-bench", "--seconds-per-row", "-1"][..], "-1"),
        (&["raster-bench", "--threads", "0"][..], "--threads"),
        (&["raster-bench", "--resolution", "big"][..], "big"),
        (&["raster-bench", "--gpu", "maybe"][..], "maybe"),
    ] {
        let out = occlude(args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: stderr should mention '{needle}': {stderr}");
    }
}
