//! `occlude bench --paper P --plot PATH` as a user runs it: one plot per
//! scene, named after PATH, one line per compared method, titled with the
//! paper's figure, and one per setting of CHC++'s Figure 9; `--csv` beside
//! it writes every run's frames; a bad extension, a paper without a
//! walkthrough or a scene the paper does not have (`--scene`) is a usage
//! error before anything runs.

use std::path::Path;
use std::process::Command;

fn occlude(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_occlude")).args(args).output().expect("occlude runs")
}

/// The y-axis tick labels of the SVG plot at `path` (the text right-aligned
/// left of the plotting area, which only the y-axis has).
fn y_labels(svg: &str) -> Vec<f64> {
    svg.split("<text")
        .filter(|t| t.contains("text-anchor=\"end\""))
        .filter_map(|t| t.split('>').nth(1)?.split('<').next()?.trim().parse().ok())
        .collect()
}

/// The names of the files in `dir`, sorted.
fn file_names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into()).collect();
    names.sort();
    names
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn the_chc_run_writes_the_papers_figures_one_file_per_scene() {
    let dir = tempfile::tempdir().unwrap();
    let plot = dir.path().join("chc.svg");
    let queries = dir.path().join("q.svg");
    let csv = dir.path().join("chc.csv");
    let out = occlude(&[
        "bench",
        "--paper",
        "chc",
        "--size",
        "small",
        "--frames",
        "4",
        "--resolution",
        "96x64",
        "--plot",
        plot.to_str().unwrap(),
        "--plot-queries",
        queries.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "stderr: {stderr}");
    check_paper_csv(&read(&csv));
    let names = file_names(dir.path());
    assert_eq!(
        names,
        ["chc-city.svg", "chc-plant.svg", "chc-teapots.svg", "chc.csv", "q-city.svg", "q-plant.svg", "q-teapots.svg"]
    );
    for (scene, figure) in [("teapots", "Figure 5"), ("city", "Figure 6"), ("plant", "Figure 7")] {
        let svg = read(&dir.path().join(format!("chc-{scene}.svg")));
        assert!(svg.starts_with("<svg"), "{scene}: {}", &svg[..svg.len().min(80)]);
        assert!(svg.contains(&format!("CHC paper, {figure}: frame times: {scene} (small)")), "{scene}: no title");
        assert!(svg.contains("frame (at 30 fps)"), "{scene}: the x axis does not give the frame rate");
        // Table 1's methods, each once: Table 2's variants of chc are no lines.
        for method in ["vfc", "sw", "chc", "ideal", "opt"] {
            let entries = svg.matches(&format!("\n{method}\n</text>")).count();
            assert_eq!(entries, 1, "{scene}: {entries} legend entries of {method}");
        }
        assert!(stderr.contains(&format!("chc-{scene}.svg")), "{stderr}");
        let q = read(&dir.path().join(format!("q-{scene}.svg")));
        assert!(q.contains("queries and state changes (no figure in the paper)"), "{scene}: {q:.300}");
    }
    // Figures 5 and 6 are linear from zero; Figure 7 is logarithmic, as the
    // paper's: at least two labels, powers of ten, each ten times the last.
    let city = y_labels(&read(&dir.path().join("chc-city.svg")));
    assert_eq!(city.first(), Some(&0.0), "city's y labels: {city:?}");
    let plant = y_labels(&read(&dir.path().join("chc-plant.svg")));
    assert!(plant.len() >= 2 && plant[0] > 0.0, "plant's y labels: {plant:?}");
    assert!(plant.windows(2).all(|w| (w[1] / w[0] - 10.0).abs() < 1e-9), "plant's y labels: {plant:?}");
}

/// `--paper chcpp --scene plant`: the plant's Figure 1 with the paper's
/// four lines, Figure 8 with a line per optimisation added, and a plot per
/// setting of Figure 9, each titled with its shading.
#[test]
fn the_chcpp_run_plots_figures_1_8_and_9() {
    let dir = tempfile::tempdir().unwrap();
    let plot = dir.path().join("c.svg");
    let out = occlude(&[
        "bench",
        "--paper",
        "chcpp",
        "--scene",
        "plant",
        "--size",
        "small",
        "--frames",
        "3",
        "--resolution",
        "96x64",
        "--plot",
        plot.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "stderr: {}", String::from_utf8_lossy(&out.stderr));
    let names = file_names(dir.path());
    assert_eq!(
        names,
        ["c-plant-fig8.svg", "c-plant-fig9-dp.svg", "c-plant-fig9-fix.svg", "c-plant-fig9-sh.svg", "c-plant.svg"]
    );
    let figure1 = read(&dir.path().join("c-plant.svg"));
    assert!(figure1.contains("CHC++ paper, Figure 1: frame times"));
    for (method, lines) in [("vfc", 1), ("chc", 1), ("nohc", 1), ("chcpp", 1), ("sw", 0), ("opt", 0)] {
        assert_eq!(figure1.matches(&format!("\n{method}\n</text>")).count(), lines, "Figure 1: {method}");
    }
    let figure8 = read(&dir.path().join("c-plant-fig8.svg"));
    assert!(figure8.contains("CHC++ paper, Figure 8: frame times"));
    for step in ["CHC", "CHC+B", "CHC+B+R", "CHC+B+R+TB", "CHC+B+R+TB+MQ (CHC++)"] {
        assert_eq!(figure8.matches(&format!("\n{step}\n</text>")).count(), 1, "Figure 8: {step}");
    }
    for (file, setting, model) in [("dp", "DP", "modern+dp"), ("sh", "SH", "modern+sh")] {
        let svg = read(&dir.path().join(format!("c-plant-fig9-{file}.svg")));
        assert!(svg.contains(&format!("CHC++ paper, Figure 9, {setting}: frame times")), "{file}: no title");
        assert!(svg.contains(&format!("{model} GPU model")), "{file}: the model is not named");
        for method in ["vfc", "chcpp", "nohc"] {
            assert_eq!(svg.matches(&format!("\n{method}\n</text>")).count(), 1, "{file}: {method}");
        }
    }
}

/// `--csv` of `--paper chc` at 4 frames: every run behind the tables (per
/// scene Table 1's five methods, Table 2's two variants of `chc` and
/// section 5.3's three), each of its frames a row led by the run, the scene
/// and the parameters.
fn check_paper_csv(csv: &str) {
    let mut lines = csv.lines();
    let header = lines.next().unwrap();
    assert!(header.starts_with("run,scene,params,method,frame,frame_ms,"), "{header}");
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert!(rows.iter().all(|r| r.len() == header.split(',').count()), "a row's width differs from the header's");
    assert_eq!(rows.len(), 3 * (5 + 2 + 3) * 4, "3 scenes x 10 method runs x 4 frames");
    for scene in ["teapots", "city", "plant"] {
        let chc: std::collections::BTreeSet<(&str, &str)> =
            rows.iter().filter(|r| r[1] == scene && r[3] == "chc").map(|r| (r[0], r[2])).collect();
        let params: std::collections::BTreeSet<&str> = chc.iter().map(|&(_, p)| p).collect();
        assert_eq!((chc.len(), params.len()), (6, 6), "{scene}: chc's six runs, each with its parameters: {chc:?}");
        assert!(params.iter().all(|p| p.contains("tav=") && p.contains("spec=")), "{scene}: {params:?}");
    }
    let frame_ms: f64 = rows[0][5].parse().unwrap();
    assert!(frame_ms > 0.0, "the first row's frame time: {frame_ms}");
}

#[test]
fn a_bad_plot_is_refused_before_anything_runs() {
    for (args, needle) in [
        (&["bench", "--paper", "chc", "--plot", "chc.jpg"][..], "chc.jpg"),
        (&["bench", "--paper", "chcpp", "--plot-queries", "q.gif"], "q.gif"),
        (&["bench", "--paper", "gvq", "--plot", "gvq.svg"], "--paper gvq"),
        (&["bench", "--paper", "gvq", "--csv", "gvq.csv"], "--csv cannot be combined with --paper gvq"),
    ] {
        let out = occlude(args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
        assert!(out.stdout.is_empty(), "{args:?}: nothing should run");
    }
}

#[test]
fn a_bad_scene_choice_is_refused_before_anything_runs() {
    for (args, needle) in [
        (
            &["bench", "--paper", "chc", "--scene", "city,moon"][..],
            "--paper chc has no scene 'moon': its scenes are teapots, city, plant",
        ),
        (&["bench", "--paper", "om", "--scene", "teapots"], "--paper om has no scene 'teapots'"),
        (&["bench", "--paper", "chcpp", "--scene", ","], "--scene names no scene"),
        (&["bench", "--paper", "gvq", "--scene", "city"], "--scene cannot be combined with --paper gvq"),
    ] {
        let out = occlude(args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
        assert!(out.stdout.is_empty(), "{args:?}: nothing should run");
    }
}
