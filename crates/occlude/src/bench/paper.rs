//! `occlude bench --paper chc`: the CHC paper's experiments (Bittner et al.
//! 2004, section 6) on our teapots, city and plant scenes, printed in the
//! shape of its Table 1 (methods compared) and Table 2 (influence of the
//! assumed-visible frames `tav` and the pixel threshold `nvp`).

use super::config::BenchConfig;
use super::runner::run_scene;
use super::summary::BenchReport;
use anyhow::Result;
use indicatif::ProgressBar;
use occlude_core::methods::MethodOptions;
use occlude_core::HierarchyKind;
use occlude_soft::GpuModel;
use std::fmt::Write;

/// Papers whose experiments `--paper` can run.
pub const PAPERS: [&str; 1] = ["chc"];

/// The scenes of the CHC paper's Table 1, in its order.
const CHC_SCENES: [&str; 3] = ["teapots", "city", "plant"];
/// `tav` values of the CHC paper's Table 2.
const TAV_VALUES: [u32; 3] = [2, 5, 10];
/// `nvp` values of the CHC paper's Table 2.
const NVP_VALUES: [u32; 3] = [10, 25, 50];

/// Tables and the reports behind them.
pub struct PaperResult {
    /// The printed tables.
    pub text: String,
    /// Every run's report, for `--json`.
    pub reports: Vec<BenchReport>,
}

/// Runs the experiments of `paper` with the size, seed, frames and
/// resolution of `base`; scene, methods, hierarchy and GPU model are the
/// paper's.
pub fn run(paper: &str, base: &BenchConfig, progress: &ProgressBar) -> Result<PaperResult> {
    match paper {
        "chc" => run_chc(base, progress),
        _ => anyhow::bail!("unknown paper '{paper}': expected one of {}", PAPERS.join(", ")),
    }
}

fn run_chc(base: &BenchConfig, progress: &ProgressBar) -> Result<PaperResult> {
    let mut table1 = String::from(
        "CHC paper, Table 1 (kD-tree, gpu-2004; times simulated)\n\
         scene     method  queries  wait ms  rendered triangles  frame ms  speedup\n",
    );
    let mut table2 = String::from(
        "CHC paper, Table 2 (influence of tav and nvp on chc)\n\
         scene     option  queries  frame ms  missing px/frame\n",
    );
    let mut reports = Vec::new();
    for scene_name in CHC_SCENES {
        let config = BenchConfig {
            scene: scene_name.into(),
            methods: ["vfc", "sw", "chc", "opt"].map(String::from).to_vec(),
            hierarchy: HierarchyKind::KdTree,
            gpu_model: GpuModel::gpu_2004(),
            options: MethodOptions::default(),
            ..base.clone()
        };
        config.validate()?;
        let scene = occlude_scenes::generate(scene_name, config.size, config.seed)?;
        progress.set_message(format!("chc paper: {scene_name}"));
        let report = run_scene(&scene, &config, progress)?.report(&config);
        for m in &report.methods {
            let _ = writeln!(
                table1,
                "{:<9} {:<6} {:>8.0} {:>8.2} {:>19.0} {:>9.2} {:>8.2}",
                scene_name,
                m.name,
                m.queries_per_frame,
                m.wait_ms_per_frame,
                m.triangles_per_frame,
                m.mean_frame_ms,
                m.speedup_vs_vfc
            );
        }
        reports.push(report);

        let variants =
            TAV_VALUES.iter().map(|t| format!("chc.tav={t}")).chain(NVP_VALUES.iter().map(|n| format!("chc.nvp={n}")));
        for option in std::iter::once(String::new()).chain(variants) {
            let options = if option.is_empty() { MethodOptions::default() } else { MethodOptions::parse(&[&option])? };
            let config = BenchConfig { methods: vec!["chc".into()], options, ..config.clone() };
            progress.set_message(format!("chc paper: {scene_name} {option}"));
            let report = run_scene(&scene, &config, progress)?.report(&config);
            let m = &report.methods[0];
            let label =
                if option.is_empty() { "basic".to_string() } else { option.trim_start_matches("chc.").to_string() };
            let _ = writeln!(
                table2,
                "{:<9} {:<7} {:>7.0} {:>9.2} {:>17.0}",
                scene_name,
                label,
                m.queries_per_frame,
                m.mean_frame_ms,
                m.missing_pixels as f64 / report.frames.max(1) as f64
            );
            reports.push(report);
        }
    }
    Ok(PaperResult { text: format!("{table1}\n{table2}"), reports })
}
