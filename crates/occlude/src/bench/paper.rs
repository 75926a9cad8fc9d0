//! `occlude bench --paper chc|chcpp|om|ioc`: a paper's experiments on our
//! scenes, printed in the shape of its tables.
//!
//! - `chc` (Bittner et al. 2004, section 6): kD-tree, `gpu-2004`; Table 1
//!   (VFC, S&W, CHC, ideal) and Table 2 (influence of `tav` and `nvp`).
//! - `chcpp` (Mattausch et al. 2008, section 8): BVH, `modern`; the
//!   comparison of VFC, S&W, CHC, CHC++ and OPT, and an ablation of CHC++'s
//!   components.
//! - `om` (Staneker, Bartz, Straßer): city and plant, BVH, `gpu-2004`; single
//!   queries (`sw`) against multiple queries without occupancy-map grouping
//!   and `om`.
//! - `ioc` (the IOC poster, section 3): rooms, downtown and figures, BVH with
//!   one object per leaf (the poster's node counts), the `--gpu-model` given
//!   (default `modern`; the result hangs on what a box test costs, which
//!   `occlude calibrate` measures); Table 1 (the
//!   occlusion test's and the occludees' GPU time of ROC and IOC, each beside
//!   the poster's figure) and Figure 4 (frame time of VFC, ROC, IOC and the
//!   ideal set; the poster gives that one as a chart, without figures, and
//!   its NOCULL has no method here).

use super::config::BenchConfig;
use super::runner::run_scene;
use super::summary::BenchReport;
use anyhow::Result;
use indicatif::ProgressBar;
use occlude_core::hierarchy::BuildOptions;
use occlude_core::methods::MethodOptions;
use occlude_core::{HierarchyKind, Scene};
use occlude_soft::GpuModel;
use std::fmt::Write;

/// Papers whose experiments `--paper` can run.
pub const PAPERS: [&str; 4] = ["chc", "chcpp", "om", "ioc"];

/// The scenes of the CHC papers' tables, in the CHC paper's order.
const CHC_SCENES: &[&str] = &["teapots", "city", "plant"];

/// One paper's setting.
struct Experiment {
    title: &'static str,
    scenes: &'static [&'static str],
    hierarchy: HierarchyKind,
    gpu_model: fn() -> GpuModel,
    methods: &'static [&'static str],
    /// The method whose options the second table varies, and the variants
    /// (each a list of `method.key=value`, labelled by the list).
    varied: &'static str,
    variants: &'static [&'static [&'static str]],
}

const CHC: Experiment = Experiment {
    title: "CHC paper (kD-tree, gpu-2004)",
    scenes: CHC_SCENES,
    hierarchy: HierarchyKind::KdTree,
    gpu_model: GpuModel::gpu_2004,
    methods: &["vfc", "sw", "chc", "opt"],
    varied: "chc",
    variants: &[
        &[],
        &["chc.tav=2"],
        &["chc.tav=5"],
        &["chc.tav=10"],
        &["chc.nvp=10"],
        &["chc.nvp=25"],
        &["chc.nvp=50"],
    ],
};

const CHCPP: Experiment = Experiment {
    title: "CHC++ paper (BVH, modern)",
    scenes: CHC_SCENES,
    hierarchy: HierarchyKind::Bvh,
    gpu_model: GpuModel::modern,
    methods: &["vfc", "sw", "chc", "chcpp", "opt"],
    varied: "chcpp",
    variants: &[
        &[],
        &["chcpp.multiquery=off"],
        &["chcpp.vqueue=off"],
        &["chcpp.sort=off"],
        &["chcpp.random=off"],
        &["chcpp.tight=off"],
        &["chcpp.b=1"],
        &["chcpp.nav=0"],
    ],
};

const OM: Experiment = Experiment {
    title: "Occupancy-map paper (BVH, gpu-2004)",
    scenes: &["city", "plant"],
    hierarchy: HierarchyKind::Bvh,
    gpu_model: GpuModel::gpu_2004,
    methods: &["vfc", "sw", "om", "opt"],
    varied: "om",
    variants: &[&[], &["om.grouping=off"]],
};

/// Tables and the reports behind them.
pub struct PaperResult {
    /// The printed tables.
    pub text: String,
    /// Every run's report, for `--json`.
    pub reports: Vec<BenchReport>,
}

/// Runs the experiments of `paper` with the size, seed, frames and
/// resolution of `base`; scenes, methods, hierarchy and GPU model are the
/// paper's.
pub fn run(paper: &str, base: &BenchConfig, progress: &ProgressBar) -> Result<PaperResult> {
    let experiment = match paper {
        "chc" => &CHC,
        "chcpp" => &CHCPP,
        "om" => &OM,
        "ioc" => return run_ioc(base, progress),
        _ => anyhow::bail!("unknown paper '{paper}': expected one of {}", PAPERS.join(", ")),
    };
    run_experiment(experiment, base, progress)
}

fn run_experiment(e: &Experiment, base: &BenchConfig, progress: &ProgressBar) -> Result<PaperResult> {
    let mut comparison = format!(
        "{} — methods compared (times simulated)\n\
         scene     method  queries  wait ms  states  rendered triangles  frame ms  speedup  ratio opt\n",
        e.title
    );
    let mut variants = format!(
        "{} — {} variants\n\
         scene     variant                 queries  states  frame ms  missing px/frame\n",
        e.title, e.varied
    );
    let mut reports = Vec::new();
    for &scene_name in e.scenes {
        let config = BenchConfig {
            scene: scene_name.into(),
            methods: e.methods.iter().map(|m| m.to_string()).collect(),
            hierarchy: e.hierarchy,
            gpu_model: (e.gpu_model)(),
            options: MethodOptions::default(),
            ..base.clone()
        };
        config.validate()?;
        let scene = occlude_scenes::generate(scene_name, config.size, config.seed)?;
        let report = run_labelled(&scene, &config, progress, "methods")?;
        for m in &report.methods {
            let _ = writeln!(
                comparison,
                "{:<9} {:<6} {:>8.0} {:>8.2} {:>7.0} {:>19.0} {:>9.3} {:>8.2} {:>10}",
                scene_name,
                m.name,
                m.queries_per_frame,
                m.wait_ms_per_frame,
                m.state_changes_per_frame,
                m.triangles_per_frame,
                m.mean_frame_ms,
                m.speedup_vs_vfc,
                m.ratio_to_opt.map_or("-".into(), |r| format!("{r:.2}")),
            );
        }
        reports.push(report);
        for opts in e.variants {
            let config =
                BenchConfig { methods: vec![e.varied.into()], options: MethodOptions::parse(opts)?, ..config.clone() };
            let label = if opts.is_empty() { "all defaults".to_string() } else { opts.join(" ") };
            let report = run_labelled(&scene, &config, progress, &label)?;
            let m = &report.methods[0];
            let _ = writeln!(
                variants,
                "{:<9} {:<23} {:>7.0} {:>7.0} {:>9.3} {:>17.0}{}",
                scene_name,
                label,
                m.queries_per_frame,
                m.state_changes_per_frame,
                m.mean_frame_ms,
                m.missing_pixels as f64 / report.frames.max(1) as f64,
                m.counters_per_frame.iter().map(|(k, v)| format!("  {k} {v:.1}")).collect::<String>()
            );
            reports.push(report);
        }
    }
    Ok(PaperResult { text: format!("{comparison}\n{variants}"), reports })
}

/// The IOC poster's scenes, as its tables name them.
const IOC_SCENES: [(&str, &str); 3] = [("rooms", "RM"), ("downtown", "DT"), ("figures", "GF")];

/// The poster's Table 1 (GTX 1080 Ti, 1920x1080): per scene, ROC's and IOC's
/// occlusion test and occludee rendering, ms.
const IOC_TABLE_1: [[(f64, f64); 2]; 3] =
    [[(0.41, 0.40), (0.61, 0.40)], [(3.47, 3.50), (0.78, 3.58)], [(7.96, 7.81), (1.05, 8.04)]];

/// `--paper ioc` (module documentation).
fn run_ioc(base: &BenchConfig, progress: &ProgressBar) -> Result<PaperResult> {
    let times = match base.backend {
        super::config::BackendKind::Soft => format!("GPU model {}, times simulated", base.gpu_model.name),
        super::config::BackendKind::Wgpu => "times measured".to_string(),
    };
    let mut table = format!(
        "IOC poster (BVH, one object per leaf, {times}) — Table 1: GPU time per frame, ms\n\
         scene          method  occlusion test  (poster)  occludee rendering  (poster)  test vs roc  (poster)\n"
    );
    let mut figure = String::from(
        "IOC poster — Figure 4: frame time per frame, ms (the poster's chart gives no figures)\n\
         scene          method  frame ms  speedup vs vfc  rendered triangles  missing px\n",
    );
    let mut reports = Vec::new();
    for (&(scene_name, label), published) in IOC_SCENES.iter().zip(IOC_TABLE_1) {
        let config = BenchConfig {
            scene: scene_name.into(),
            methods: ["vfc", "roc", "ioc", "opt"].map(String::from).to_vec(),
            hierarchy: HierarchyKind::Bvh,
            build: BuildOptions { leaf_size: 1, ..base.build },
            // The user's model (default `modern`): the poster's result hangs
            // on what a box costs, which a calibrated model measures.
            gpu_model: base.gpu_model.clone(),
            options: MethodOptions::default(),
            ..base.clone()
        };
        config.validate()?;
        let scene = occlude_scenes::generate(scene_name, config.size, config.seed)?;
        let report = run_labelled(&scene, &config, progress, "vfc, roc, ioc, opt")?;
        let method = |name: &str| report.methods.iter().find(|m| m.name == name);
        let roc_test = method("roc").map_or(0.0, |m| m.cull_ms_per_frame);
        let shown = format!("{scene_name} ({label})");
        for (name, (test, render)) in ["roc", "ioc"].into_iter().zip(published) {
            let Some(m) = method(name) else { continue };
            let ratio = if name == "roc" || roc_test == 0.0 {
                format!("{:>11}  {:>8}", "", "")
            } else {
                format!("{:>11.2}  {:>8.2}", m.cull_ms_per_frame / roc_test, test / published[0].0)
            };
            let _ = writeln!(
                table,
                "{shown:<14} {name:<6} {:>15.3}  {test:>8.2}  {:>18.3}  {render:>8.2}  {ratio}",
                m.cull_ms_per_frame, m.render_ms_per_frame,
            );
        }
        for m in &report.methods {
            let _ = writeln!(
                figure,
                "{shown:<14} {:<6} {:>9.3} {:>15.2} {:>19.0} {:>11}",
                m.name, m.mean_frame_ms, m.speedup_vs_vfc, m.triangles_per_frame, m.missing_pixels,
            );
        }
        reports.push(report);
    }
    Ok(PaperResult { text: format!("{table}\n{figure}"), reports })
}

fn run_labelled(scene: &Scene, config: &BenchConfig, progress: &ProgressBar, label: &str) -> Result<BenchReport> {
    progress.set_message(format!("{} {}: {label}", config.scene, config.size));
    Ok(run_scene(scene, config, progress)?.report(config))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ioc_tables_set_every_scene_beside_the_posters_figures() {
        let base = BenchConfig { frames: 3, resolution: (96, 64), ..BenchConfig::default() };
        let result = run("ioc", &base, &ProgressBar::hidden()).unwrap();
        assert_eq!(result.reports.len(), 3);
        for (report, (scene, label)) in result.reports.iter().zip(IOC_SCENES) {
            assert_eq!(report.scene, scene);
            assert_eq!(report.hierarchy, "bvh");
            // One object per leaf: a binary tree of 2n - 1 nodes.
            let s = &report.scene_stats;
            assert_eq!(s.nodes, 2 * s.instances - 1, "{scene}: {s:?}");
            for m in &report.methods {
                assert_eq!(m.missing_pixels, 0, "{scene}/{}", m.name);
            }
            for method in ["roc", "ioc"] {
                let row = format!("{scene} ({label})");
                let lines = result.text.lines().filter(|l| l.starts_with(&row) && l.contains(method)).count();
                assert_eq!(lines, 2, "{scene}/{method}: a Table 1 row and a Figure 4 row\n{}", result.text);
            }
        }
        // The poster's figures stand beside ours: DT's test times and ratio.
        assert!(
            result.text.contains("3.47") && result.text.contains("0.78") && result.text.contains("0.22"),
            "{}",
            result.text
        );
    }
}
