//! Every input bounded, as the command line meets it: each rule once, with
//! inputs of several kinds, each a clear error with exit code 2 (never a
//! panic, a hang or runaway memory), and outputs written before the table
//! is printed.

use std::path::Path;
use std::process::{Command, Output, Stdio};

fn occlude(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_occlude")).args(args).output().expect("occlude runs")
}

fn assert_usage_error(args: &[&str], needles: &[&str]) {
    let out = occlude(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: expected exit code 2, stderr: {stderr}");
    for needle in needles {
        assert!(stderr.contains(needle), "{args:?}: stderr should mention '{needle}': {stderr}");
    }
}

/// A short soft run: `frames` frames of the small teapots at 64x48, with
/// `extra` options.
fn short_run(frames: &str, extra: &[&str]) -> Vec<String> {
    let short = ["bench", "--scene", "teapots", "--methods", "vfc,chc", "--resolution", "64x48", "--frames", frames];
    short.iter().chain(extra).map(|s| s.to_string()).collect()
}

fn str_args(args: &[String]) -> Vec<&str> {
    args.iter().map(String::as_str).collect()
}

/// Every number a command takes is checked against its range before any
/// work starts, the error naming the option, the value and the range.
#[test]
fn every_numeric_option_out_of_its_range_is_refused_naming_the_range() {
    for (args, needles) in [
        (&["bench", "--threads", "100000"][..], &["--threads", "'100000'", "1 to 256"][..]),
        (&["bench", "--frames", "1000000"], &["--frames", "1 to 100000, or 'all'"]),
        (&["bench", "--fps", "1e30"], &["--fps", "at most 1000"]),
        (&["bench", "--resolution", "100000x100000"], &["--resolution", "16777216 pixels"]),
        (&["view", "--frames", "0"], &["--frames", "1 to 100000"]),
        (&["view", "--resolution", "0x0"], &["--resolution", "1 to 16384"]),
        (&["raster-bench", "--resolution", "0x0"], &["--resolution", "1 to 16384"]),
        (&["raster-bench", "--threads", "1,300"], &["--threads", "'300'", "1 to 256"]),
        (&["raster-bench", "--triangles-per-size", "1000000000"], &["--triangles-per-size", "1 to 4000000"]),
        (&["raster-bench", "--seconds-per-row", "1e300"], &["--seconds-per-row", "at most 600"]),
        (&["calibrate", "--no-check", "--resolution", "0x0", "--repeats", "1"], &["--resolution", "0x0"]),
        (&["calibrate", "--repeats", "0"], &["--repeats", "1 to 1000"]),
        (&["calibrate", "--check-frames", "0"], &["--check-frames", "1 to 100000"]),
    ] {
        assert_usage_error(args, needles);
    }
}

/// Files the command reads are regular files of bounded size, and the
/// figures in them bounded: a device, a GPU model whose costs would make
/// times infinite, a report whose figures would make a plot's axis
/// infinite, and a camera whose view cannot render are all refused.
#[test]
fn input_files_are_regular_and_their_values_in_range() {
    let dir = tempfile::tempdir().unwrap();
    let file = |name: &str, text: &str| {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        path.to_str().unwrap().to_string()
    };
    for (option, args) in [
        ("--camera-path", vec!["bench", "--camera-path", "/dev/zero"]),
        ("--gpu-model", vec!["bench", "--gpu-model", "/dev/zero"]),
        ("report", vec!["report", "/dev/zero", "--out", "x.html"]),
    ] {
        let out = occlude(&args);
        assert_eq!(out.status.code(), Some(2), "{option}: {}", String::from_utf8_lossy(&out.stderr));
        assert!(String::from_utf8_lossy(&out.stderr).contains("not a regular file"), "{option}");
    }
    let huge = file("huge.toml", "gpu_fragment_ns = 1e305\n");
    assert_usage_error(&["bench", "--gpu-model", &huge], &["gpu_fragment_ns = 1e305", "from 0 to 1e6"]);
    let report = file("max.json", &format!("{{\"scene\": \"x\", \"frame_ms\": {:e}}}", f64::MAX));
    let out = dir.path().join("r.html");
    assert_usage_error(&["report", &report, "--out", out.to_str().unwrap()], &["max.json", "frame_ms", "1e15"]);
    let keyframe = |position: &str, target: &str, fov: &str| {
        format!("{{\"keyframes\":[{{\"time\":0,\"position\":{position},\"target\":{target},\"fov_y_deg\":{fov}}}]}}")
    };
    for (name, path, needle) in [
        ("near.json", keyframe("[0,0,0]", "[0,0,1e-30]", "60"), "at least 0.001 m away"),
        ("sliver.json", keyframe("[0,0,0]", "[0,0,1]", "1e-40"), "0.01 to 179 degrees"),
        ("far.json", keyframe("[0,0,1e30]", "[0,0,1]", "60"), "within ±1e9 m"),
    ] {
        assert_usage_error(&["bench", "--camera-path", &file(name, &path)], &[name, needle]);
    }
}

/// Frame counts cannot wrap or run away: a walkthrough with more frames
/// than a run takes is refused before its frames are made, and so is one
/// whose camera passes through its target.
#[test]
fn walkthroughs_too_long_or_through_their_target_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str, keyframes: &str| {
        let file = dir.path().join(name);
        std::fs::write(&file, format!("{{\"keyframes\":[{keyframes}]}}")).unwrap();
        file.to_str().unwrap().to_string()
    };
    let k = |t: &str, p: &str, q: &str| format!("{{\"time\":{t},\"position\":{p},\"target\":{q},\"fov_y_deg\":60}}");
    let long = path("long.json", &format!("{},{}", k("0", "[0,0,9]", "[0,0,0]"), k("1e5", "[0,0,8]", "[0,0,0]")));
    let all = short_run("all", &["--camera-path", &long]);
    assert_usage_error(&str_args(&all), &["3000001 frames", "more than the 100000"]);
    let first = short_run("2", &["--camera-path", &long]);
    assert_eq!(occlude(&str_args(&first)).status.code(), Some(0), "the first frames of a long path run");
    let swap = path("swap.json", &format!("{},{}", k("0", "[0,0,9]", "[0,0,8]"), k("1", "[0,0,8]", "[0,0,9]")));
    // Halfway, at frame 15 of 31, position and target meet.
    let through = short_run("all", &["--camera-path", &swap]);
    assert_usage_error(&str_args(&through), &["frame 15", "passes through its target"]);
    // The viewer refuses the walkthrough it would play, before any window.
    let view = ["view", "--camera-path", &swap, "--record", "unused.json", "--play"];
    assert_usage_error(&view, &["frame 15", "passes through its target"]);
}

/// Files first, table second: with standard output closed before the run
/// ends, the JSON and CSV are still written and the command ends quietly;
/// a standard output that cannot take the table is an error, not a panic.
#[test]
fn files_are_written_before_the_table_and_a_closed_pipe_ends_quietly() {
    let dir = tempfile::tempdir().unwrap();
    let (json, csv) = (dir.path().join("o.json"), dir.path().join("o.csv"));
    let args = short_run("2", &["--json", json.to_str().unwrap(), "--csv", csv.to_str().unwrap()]);
    let mut child = Command::new(env!("CARGO_BIN_EXE_occlude"))
        .args(&args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(matches!(out.status.code(), Some(0 | 141)), "{:?}: {stderr}", out.status);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(json.is_file() && csv.is_file(), "the files are written whatever happens to the table");
    if Path::new("/dev/full").exists() {
        let full = std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
        let out = Command::new(env!("CARGO_BIN_EXE_occlude")).args(["scenes", "--size", "small"]).stdout(full).output();
        let out = out.unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{stderr}");
        assert!(stderr.contains("cannot write to standard output") && !stderr.contains("panicked"), "{stderr}");
    }
}

/// No output overwrites an input or another output of the same command,
/// however the paths are spelled.
#[test]
fn an_output_naming_an_input_or_another_output_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("a.json");
    std::fs::write(&json, "{}").unwrap();
    let same = dir.path().join(".").join("a.json");
    let (json, same) = (json.to_str().unwrap(), same.to_str().unwrap());
    assert_usage_error(&["report", json, "--out", same], &["--out", "FILE.json", "overwrite"]);
    let x = dir.path().join("x").to_str().unwrap().to_string();
    let twice = short_run("2", &["--json", &x, "--csv", &x]);
    assert_usage_error(&str_args(&twice), &["--json and --csv name the same file"]);
    let path = dir.path().join("path.json");
    std::fs::write(&path, r#"{"keyframes":[{"time":0,"position":[0,0,9],"target":[0,0,0],"fov_y_deg":60}]}"#).unwrap();
    let path = path.to_str().unwrap();
    let overwrite = short_run("2", &["--camera-path", path, "--json", path]);
    assert_usage_error(&str_args(&overwrite), &["--json", "--camera-path"]);
}
