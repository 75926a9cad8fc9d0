//! `occlude view` as a person runs it: in a real window on a virtual X server
//! (Xvfb, started here), rendering frames on the GPU (lavapipe in CI) and
//! saving a screenshot; and the clear errors without a display or adapter.
//!
//! The window tests are skipped, saying so, where Xvfb or a GPU adapter is
//! missing, unless `OCCLUDE_REQUIRE_GPU=1` (CI): then they fail.

use occlude_wgpu::GpuContext;
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Output, Stdio};

/// Outline colours of the query boxes (`view::boxes`): exact, because no
/// material or background colour has a zero channel.
const VISIBLE_GREEN: [u8; 3] = [0, 255, 0];
const OCCLUDED_RED: [u8; 3] = [255, 0, 0];

fn required() -> bool {
    std::env::var("OCCLUDE_REQUIRE_GPU").is_ok_and(|v| v == "1")
}

/// A virtual X server on a display number it picked itself (`-displayfd`,
/// so tests running at once never race for one), stopped on drop.
/// `-noreset`: by default the server resets when its last client leaves, and
/// a client connecting during the reset is refused ("Failed to open
/// connection to X server"; 13 of 500 back-to-back clients on a loaded
/// machine, none with `-noreset`), which a test running several views on one
/// server would hit.
struct Xvfb {
    child: Child,
    display: String,
}

impl Xvfb {
    /// The server, or `None` (after saying why) where Xvfb is not installed.
    fn start(test: &str) -> Option<Self> {
        let spawned = Command::new("Xvfb")
            .args(["-displayfd", "1", "-screen", "0", "1024x768x24", "-nolisten", "tcp", "-noreset"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn();
        let mut child = match spawned {
            Ok(child) => child,
            Err(e) if required() => panic!("{test}: OCCLUDE_REQUIRE_GPU=1 but Xvfb cannot start: {e}"),
            Err(e) => {
                eprintln!("skipping {test}: Xvfb cannot start ({e}); apt-get install xvfb");
                return None;
            }
        };
        let mut line = String::new();
        BufReader::new(child.stdout.take().expect("piped")).read_line(&mut line).expect("Xvfb prints its display");
        let number = line.trim();
        assert!(number.parse::<u32>().is_ok(), "{test}: Xvfb did not start (it printed '{number}')");
        Some(Self { display: format!(":{number}"), child })
    }

    /// `occlude view ARGS` on this display.
    fn view(&self, args: &[&str]) -> Output {
        Command::new(env!("CARGO_BIN_EXE_occlude"))
            .arg("view")
            .args(args)
            .env("DISPLAY", &self.display)
            .env_remove("WAYLAND_DISPLAY")
            .env_remove("WAYLAND_SOCKET")
            .output()
            .expect("occlude runs")
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Xvfb and a GPU, or `None` where the test is skipped.
fn window_setup(test: &str) -> Option<Xvfb> {
    GpuContext::for_test(test)?;
    Xvfb::start(test)
}

fn assert_success(out: &Output) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "occlude view failed: {stderr}");
}

/// The screenshot's pixels, after checking its size.
fn pixels(path: &Path, width: u32, height: u32) -> Vec<[u8; 3]> {
    let image = image::open(path).expect("the screenshot is a PNG").to_rgb8();
    assert_eq!(image.dimensions(), (width, height), "screenshot size");
    image.pixels().map(|p| p.0).collect()
}

fn count(pixels: &[[u8; 3]], colour: [u8; 3]) -> usize {
    pixels.iter().filter(|&&p| p == colour).count()
}

/// The pixels of a 640x480 screenshot of the city after 5 frames, with
/// `args` besides, written to `name` in `dir`; the viewer must succeed.
fn city_screenshot(x: &Xvfb, dir: &Path, name: &str, args: &[&str]) -> Vec<[u8; 3]> {
    let shot = dir.join(name);
    let common =
        ["--scene", "city", "--frames", "5", "--resolution", "640x480", "--screenshot", shot.to_str().unwrap()];
    let out = x.view(&[&common[..], args].concat());
    assert_success(&out);
    pixels(&shot, 640, 480)
}

#[test]
fn a_screenshot_of_the_city_shows_the_scene() {
    let Some(x) = window_setup("a_screenshot_of_the_city_shows_the_scene") else { return };
    let dir = tempfile::tempdir().unwrap();
    let px = city_screenshot(&x, dir.path(), "out.png", &[]);
    let mut distinct = px.clone();
    distinct.sort_unstable();
    distinct.dedup();
    assert!(distinct.len() > 50, "a scene has many colours; the screenshot has {}", distinct.len());
    // The sky (the clear colour) shows above the street, and buildings hide part of it.
    let sky = count(&px, [158, 189, 219]);
    assert!(sky > 0 && sky < px.len() * 9 / 10, "sky pixels: {sky} of {}", px.len());
    assert_eq!(count(&px, OCCLUDED_RED) + count(&px, VISIBLE_GREEN), 0, "no query boxes without --figure4");
}

/// The query boxes of the CPU-driven methods, and the batched box tests of
/// the GPU-driven ones (ioc: every level's).
#[test]
fn figure4_shows_visible_and_occluded_query_boxes() {
    let Some(x) = window_setup("figure4_shows_visible_and_occluded_query_boxes") else { return };
    let dir = tempfile::tempdir().unwrap();
    for method in ["chc", "chcpp", "ioc"] {
        let px =
            city_screenshot(&x, dir.path(), &format!("{method}.png"), &["--method", method, "--play", "--figure4"]);
        let (green, red) = (count(&px, VISIBLE_GREEN), count(&px, OCCLUDED_RED));
        assert!(green > 100, "{method}: {green} pixels of visible (green) box outlines");
        assert!(red > 100, "{method}: {red} pixels of occluded (red) box outlines");
    }
}

/// With `--motion` the scene moves while the camera stands still, and the
/// query boxes follow it: the same view shows other pixels, boxes included.
#[test]
fn the_scene_moves_in_the_viewer_with_its_boxes() {
    let Some(x) = window_setup("the_scene_moves_in_the_viewer_with_its_boxes") else { return };
    let dir = tempfile::tempdir().unwrap();
    let still = city_screenshot(&x, dir.path(), "still.png", &["--method", "chcpp", "--figure4"]);
    let args = ["--method", "chcpp", "--figure4", "--motion", "1"];
    let moving = city_screenshot(&x, dir.path(), "moving.png", &args);
    let differ = still.iter().zip(&moving).filter(|(a, b)| a != b).count();
    assert!(differ > still.len() / 20, "only {differ} pixels moved");
    let (green, red) = (count(&moving, VISIBLE_GREEN), count(&moving, OCCLUDED_RED));
    assert!(green > 100 && red > 100, "boxes while moving: {green} green, {red} red pixels");
}

/// `hiz`'s box tests coloured by the pyramid level each was tested at
/// (`--pyramid-levels`, key Z): outlines in the colours of several levels.
#[test]
fn pyramid_levels_colour_hiz_boxes_by_level() {
    let Some(x) = window_setup("pyramid_levels_colour_hiz_boxes_by_level") else { return };
    let dir = tempfile::tempdir().unwrap();
    let px = city_screenshot(&x, dir.path(), "hiz-levels.png", &["--method", "hiz", "--play", "--pyramid-levels"]);
    // Levels 0 to 6 but 4 (orange, not exact): blue, cyan, green, yellow,
    // red, magenta (`view::boxes::LEVEL_COLOURS`; white, 7 and coarser, is
    // also the text's colour).
    let palette = [[0, 0, 255], [0, 255, 255], [0, 255, 0], [255, 255, 0], [255, 0, 0], [255, 0, 255]];
    let levels = palette.map(|c| count(&px, c));
    let shown = levels.iter().filter(|&&n| n > 100).count();
    assert!(shown >= 2, "outline pixels of levels 0-3, 5 and 6: {levels:?}");
}

#[test]
fn without_an_adapter_view_says_so_with_exit_code_2() {
    let Some(x) = Xvfb::start("without_an_adapter_view_says_so_with_exit_code_2") else { return };
    // wgpu on Linux has no Metal backend: asking for only Metal finds no adapter.
    let out = Command::new(env!("CARGO_BIN_EXE_occlude"))
        .args(["view", "--frames", "1", "--screenshot", "never.png"])
        .env("DISPLAY", &x.display)
        .env("WGPU_BACKEND", "metal")
        .output()
        .expect("occlude runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("no GPU adapter found"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn without_a_display_view_suggests_xvfb_with_exit_code_2() {
    let out = Command::new(env!("CARGO_BIN_EXE_occlude"))
        .args(["view", "--frames", "1", "--screenshot", "never.png"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .output()
        .expect("occlude runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("cannot open a window") && stderr.contains("xvfb-run"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

#[test]
fn bad_input_is_the_same_clear_error_as_bench() {
    for (args, needle) in [
        (&["--method", "magic"][..], "unknown method 'magic'"),
        (&["--scene", "atlantis"], "atlantis"),
        (&["--size", "huge"], "huge"),
        (&["--method-opt", "chcpp.b=-1"], "chcpp.b = -1"),
        (&["--frames", "0"], "frames"),
        (&["--resolution", "12by4"], "12by4"),
        (&["--screenshot", "shot.jpg"], "shot.jpg"),
    ] {
        // No display either: the options are checked before a window opens.
        let out = Command::new(env!("CARGO_BIN_EXE_occlude"))
            .arg("view")
            .args(args)
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .output()
            .expect("occlude runs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: stderr should mention '{needle}': {stderr}");
    }
}
