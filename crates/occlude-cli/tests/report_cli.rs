//! `occlude report` as a user meets it: a short bench run's JSON becomes an
//! HTML and a Markdown report, bad JSON is an error naming the file with exit
//! code 2, and the HTML page renders in a headless Chromium.

use occlude_cli::bench::plot::COLOURS;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn occlude(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_occlude")).args(args).output().expect("occlude runs")
}

/// Runs `occlude` and asserts it succeeded.
fn occlude_ok(args: &[&str]) {
    let out = occlude(args);
    assert!(out.status.success(), "{args:?} failed: {}", String::from_utf8_lossy(&out.stderr));
}

/// A short bench run's JSON and the HTML report of it, in `dir`.
fn bench_and_report(dir: &Path, markdown: Option<&Path>) -> (PathBuf, PathBuf) {
    let json = dir.join("a.json");
    let html = dir.join("r.html");
    occlude_ok(&["bench", "--frames", "5", "--resolution", "160x120", "--json", json.to_str().unwrap()]);
    let mut args = vec!["report", json.to_str().unwrap(), "--out", html.to_str().unwrap()];
    if let Some(md) = markdown {
        args.extend(["--markdown", md.to_str().unwrap()]);
    }
    occlude_ok(&args);
    (json, html)
}

#[test]
fn bench_json_becomes_html_and_markdown_reports() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let md = dir.join("r.md");
    let (json, html) = bench_and_report(dir, Some(&md));
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let methods: Vec<&str> =
        report["methods"].as_array().unwrap().iter().map(|m| m["name"].as_str().unwrap()).collect();
    assert!(methods.len() >= 2, "{methods:?}");

    let page = std::fs::read_to_string(&html).unwrap();
    assert!(page.starts_with("<!DOCTYPE html>"));
    assert_eq!(page.matches("<svg").count(), 2);
    assert!(!page.contains("http://") && !page.contains("https://"));
    assert!(page.contains("5 frames at 160x120"));
    let page_md = std::fs::read_to_string(&md).unwrap();
    for m in &methods {
        assert!(page.contains(&format!("<td>{m}</td>")), "HTML lacks {m}");
        assert!(page_md.contains(&format!("\n| {m} | ")), "Markdown lacks {m}");
    }
    for plot in ["r-1-frame-time.svg", "r-1-queries.svg"] {
        assert!(page_md.contains(&format!("(<{plot}>)")), "Markdown does not link {plot}");
        let svg = std::fs::read_to_string(dir.join(plot)).unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("<polyline"), "{plot} has no lines");
    }
}

#[test]
fn bad_json_is_an_error_naming_the_file_with_exit_code_2() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let out_html = dir.join("r.html");
    for (name, text, what) in [
        ("missing.json", r#"{"scene": "city"}"#, "missing field"),
        ("list.json", "[1, 2]", "item 0 of the array"),
        ("garbage.json", "not json", "not valid JSON"),
        ("string.json", "\"city\"", "found a string"),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let out = occlude(&["report", path.to_str().unwrap(), "--out", out_html.to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {stderr}");
        assert!(stderr.contains(name) && stderr.contains(what), "{name}: stderr should say {what:?}: {stderr}");
    }
    let out = occlude(&["report", dir.join("absent.json").to_str().unwrap(), "--out", out_html.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("absent.json"));
    assert!(!out_html.exists(), "a failed report must not write its page");
}

/// The headless Chromium on PATH, if any.
fn chromium() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path).map(|d| d.join("chromium")).find(|p| p.is_file())
}

/// Waits for `child` at most `limit`, killing it past that.
fn wait_with_timeout(mut child: std::process::Child, limit: Duration) -> std::process::ExitStatus {
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().expect("chromium can be waited for") {
            return status;
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("chromium took longer than {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(100));
    }
}

#[test]
fn html_report_renders_in_headless_chromium() {
    let Some(browser) = chromium() else {
        assert!(
            std::env::var("OCCLUDE_REQUIRE_BROWSER").as_deref() != Ok("1"),
            "OCCLUDE_REQUIRE_BROWSER=1 but no `chromium` is on PATH"
        );
        eprintln!("SKIPPED html_report_renders_in_headless_chromium: no `chromium` on PATH (set OCCLUDE_REQUIRE_BROWSER=1 to make this a failure)");
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let (_, html) = bench_and_report(dir, None);
    let screenshot = Path::new(env!("CARGO_TARGET_TMPDIR")).join("report.png");
    let _ = std::fs::remove_file(&screenshot);
    let profile = dir.join("profile");
    let child = Command::new(&browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--no-first-run",
            &format!("--user-data-dir={}", profile.display()),
            &format!("--screenshot={}", screenshot.display()),
            "--window-size=1200,1600",
            &format!("file://{}", html.canonicalize().unwrap().display()),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("chromium starts");
    let status = wait_with_timeout(child, Duration::from_secs(120));
    assert!(status.success(), "chromium exited with {status}");
    eprintln!("screenshot of the report: {}", screenshot.display());

    let img = image::open(&screenshot).expect("chromium wrote a PNG screenshot").to_rgb8();
    assert_eq!(img.dimensions(), (1200, 1600));
    let total = img.pixels().count();
    let ink = img.pixels().filter(|p| p.0.iter().any(|&c| c < 235)).count();
    assert!(ink > total / 50, "the page looks blank: only {ink} of {total} pixels are not white");
    // The first method's line of the frame-time plot, anti-aliasing allowed for.
    let line = COLOURS[0];
    let near = |p: &image::Rgb<u8>| p.0.iter().zip([line.0, line.1, line.2]).all(|(&a, b)| a.abs_diff(b) <= 12);
    let line_pixels = img.pixels().filter(|p| near(p)).count();
    assert!(line_pixels > 50, "only {line_pixels} pixels in the first plot line's colour {line:?}");
}
