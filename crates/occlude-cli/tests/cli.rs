//! The command line as a user meets it: bad input gets a clear message and
//! exit code 2; a short run prints the table and writes JSON in the schema of
//! `docs/design.md`.

use std::process::Command;

fn occlude(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_occlude")).args(args).output().expect("occlude runs")
}

fn assert_usage_error(args: &[&str], needle: &str) {
    let out = occlude(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: expected exit code 2, stderr: {stderr}");
    assert!(stderr.contains(needle), "{args:?}: stderr should mention '{needle}': {stderr}");
}

#[test]
fn bad_input_is_a_clear_error_with_exit_code_2() {
    assert_usage_error(&["bench", "--scene", "atlantis"], "atlantis");
    assert_usage_error(&["bench", "--size", "huge"], "huge");
    assert_usage_error(&["bench", "--methods", "vfc,magic"], "magic");
    assert_usage_error(&["bench", "--frames", "0"], "frames");
    assert_usage_error(&["bench", "--frames", "some"], "'some' is not a frame count");
    assert_usage_error(&["bench", "--fps", "0"], "'0' is not a frame rate above 0 and at most 1000");
    assert_usage_error(&["bench", "--resolution", "12by4"], "12by4");
    assert_usage_error(&["bench", "--hierarchy", "octree"], "octree");
    assert_usage_error(&["bench", "--queries", "occlusion"], "expected 'hardware' or 'hib'");
    assert_usage_error(&["bench", "--gpu-model", "gpu-1999"], "gpu-1999");
    assert_usage_error(&["bench", "--shading", "phong"], "expected dp, fix or sh");
    assert_usage_error(&["bench", "--shading", "sh", "--backend", "wgpu"], "--shading");
    assert_usage_error(&["bench", "--shading", "dp", "--paper", "chcpp"], "--shading");
    assert_usage_error(&["bench", "--method-opt", "sw.tav=2"], "no parameter 'tav'");
    assert_usage_error(&["bench", "--plot", "frames.jpg"], "frames.jpg");
    assert_usage_error(
        &["bench", "--methods", "chcpp", "--method-opt", "chcpp.b=-1"],
        "chcpp.b = -1: expected an integer from 1",
    );
    assert_usage_error(
        &["bench", "--methods", "chcpp", "--method-opt", "chcpp.smax=0.5"],
        "chcpp.smax = 0.5: expected a number from 1",
    );
    assert_usage_error(&["bench", "--methods", "om", "--method-opt", "om.map=0"], "om.map = 0");
    assert_usage_error(&["bench", "--paper", "nohc"], "nohc");
    assert_usage_error(&["bench", "--method-opt", "chc.tav"], "chc.tav");
    assert_usage_error(&["bench", "--dump-frame", "99", "--frames", "5"], "--dump-frame 99 is past the last frame");
    assert_usage_error(&["bench", "--dump-frame", "1", "--paper", "om"], "--paper");
    assert_usage_error(&["bench", "--methods", "vfc", "--method-opt", "sw.x=1"], "not in --methods");
    assert_usage_error(
        &["bench", "--methods", "ioc", "--method-opt", "ioc.start=7", "--method-opt", "ioc.bottom=5"],
        "ioc.start = 7: expected a level no deeper than ioc.bottom = 5",
    );
    assert_usage_error(&["bench", "--methods", "roc", "--method-opt", "roc.mode=fast"], "roc.mode = fast");
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, "query_latency_us = \"slow\"").unwrap();
    assert_usage_error(&["bench", "--gpu-model", bad.to_str().unwrap()], "bad.toml");
}

/// A file that cannot be written is refused before the run, not after it.
#[test]
fn an_output_file_in_a_missing_folder_is_refused_before_anything_runs() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing").join("out.json");
    let missing = missing.to_str().unwrap();
    for args in [
        &["bench", "--json", missing][..],
        &["bench", "--csv", missing],
        &["bench", "--plot", missing],
        &["bench", "--paper", "chc", "--json", missing],
        &["report", "any.json", "--out", missing],
        &["report", "any.json", "--out", "r.html", "--markdown", missing],
        &["calibrate", "--backend", "wgpu", "--out", missing],
        &["raster-bench", "--json", missing],
        &["view", "--screenshot", missing],
    ] {
        let out = occlude(args);
        assert!(out.stdout.is_empty(), "{args:?}: nothing should run: {}", String::from_utf8_lossy(&out.stdout));
        assert_usage_error(args, "does not exist");
    }
    assert_usage_error(&["bench", "--json", dir.path().to_str().unwrap()], "is a folder");
}

#[test]
fn short_run_prints_table_and_writes_json_and_csv() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("out.json");
    let csv = dir.path().join("out.csv");
    let out = occlude(&[
        "bench",
        "--frames",
        "5",
        "--resolution",
        "320x240",
        "--json",
        json.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "stderr: {}", String::from_utf8_lossy(&out.stderr));
    for method in ["vfc", "sw", "chc", "opt"] {
        assert!(stdout.lines().any(|l| l.starts_with(method)), "table lacks {method}: {stdout}");
    }
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    for key in ["scene", "size", "frames", "resolution", "backend", "gpu_model", "methods"] {
        assert!(v.get(key).is_some(), "JSON lacks top-level key {key}");
    }
    assert_eq!(v["scene"], "city");
    assert_eq!(v["queries"], "hardware", "the default query counting");
    assert_eq!(v["frames"], 5);
    assert_eq!(v["fps"], 30.0, "the default frame rate");
    let methods = v["methods"].as_array().unwrap();
    assert_eq!(methods.len(), 4);
    for m in methods {
        for key in [
            "name",
            "mean_frame_ms",
            "p95_frame_ms",
            "queries_per_frame",
            "wait_ms_per_frame",
            "draw_calls_per_frame",
            "state_changes_per_frame",
            "triangles_per_frame",
            "visible_objects_per_frame",
            "missing_pixels",
            "speedup_vs_vfc",
            "ratio_to_opt",
            "per_frame",
        ] {
            assert!(m.get(key).is_some(), "method {} lacks key {key}", m["name"]);
        }
        assert_eq!(m["per_frame"].as_array().unwrap().len(), 5);
        assert_eq!(m["missing_pixels"], 0);
    }
    let rows = std::fs::read_to_string(&csv).unwrap().lines().count();
    assert_eq!(rows, 1 + 4 * 5, "CSV: header plus one row per method and frame");
}
