//! The tables `occlude bench --paper` prints and writes as JSON (`--json`):
//! each of our rows beside the published one ([`crate::published`]), and
//! whether the order of the methods by frame time agrees with the paper's.
//! One shape serves every paper: [`PaperTables`] and [`Table`] are generic
//! over the rows, [`Row`] (the methods' frame times, the default) or a
//! paper's own (`--paper gvq`'s, [`crate::gvq::GvqRows`]).

use crate::published::PublishedTable;
use crate::summary::{BenchReport, MethodSummary};
use serde::{Deserialize, Serialize};
use std::fmt::Write;

/// What `--paper P --json FILE` writes: tables whose rows are `R` (a
/// table's rows: [`Row`]s, or a paper's own rows, module documentation).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PaperTables<R = Vec<Row>> {
    /// The paper, as `--paper` names it.
    pub paper: String,
    /// Its tables, in the order printed.
    pub tables: Vec<Table<R>>,
    /// Every run's full report (what `occlude report` reads); left out of
    /// the JSON when there is none (`--paper gvq` runs no bench).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub reports: Vec<BenchReport>,
}

/// One table, its rows `R`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Table<R = Vec<Row>> {
    /// The paper's name for it ("Table 1"), or what it shows.
    pub name: String,
    /// Where the published figures come from (`null`: none were published).
    pub source: Option<String>,
    /// Our rows (for [`Row`]s, scene by scene).
    pub rows: R,
    /// Whether, in every scene, the rows ordered by our frame time come in
    /// the order of the published frame times: `Some(None)` (`null`):
    /// nothing published to compare; `None` (left out of the JSON): rows
    /// that are not ordered by method ([`Table::new`] always gives one).
    #[serde(default, skip_serializing_if = "Option::is_none", deserialize_with = "present")]
    pub ordering_agrees: Option<Option<bool>>,
}

/// A field that is in the JSON, `null` included: `Some` of its value (a
/// missing field is `None` by `#[serde(default)]`).
fn present<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<Option<bool>>, D::Error> {
    Option::<bool>::deserialize(d).map(Some)
}

/// One method (or variant) on one scene, beside the published figures.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// Scene.
    pub scene: String,
    /// Method.
    pub method: String,
    /// Method options of a variant, space separated ("" for the defaults).
    pub options: String,
    /// Mean frame time, ms.
    pub frame_ms: f64,
    /// The paper's.
    pub published_frame_ms: Option<f64>,
    /// Occlusion queries per frame.
    pub queries: f64,
    /// The paper's.
    pub published_queries: Option<f64>,
    /// Wait time (CPU stalls) per frame, ms.
    pub wait_ms: f64,
    /// The paper's.
    pub published_wait_ms: Option<f64>,
    /// Rendered triangles per frame.
    pub triangles: f64,
    /// The paper's.
    pub published_triangles: Option<f64>,
    /// Speedup over VFC as the papers average it: the mean of per-frame
    /// ratios.
    pub speedup: f64,
    /// VFC's mean frame time over this row's.
    pub speedup_of_means: f64,
    /// The paper's.
    pub published_speedup: Option<f64>,
    /// State changes (switches between drawing and querying) per frame.
    pub state_changes: f64,
    /// Material switches per frame.
    #[serde(default)]
    pub material_switches: f64,
    /// Pixels differing from VFC's image, over all frames.
    pub missing_pixels: u64,
}

impl Row {
    /// Our figures of `m` on `scene` (run with `options`), beside `published`'s row.
    pub fn new(scene: &str, m: &MethodSummary, options: &str, published: Option<&PublishedTable>) -> Self {
        let p = published.and_then(|t| t.row(scene, &m.name, options));
        Self {
            scene: scene.to_string(),
            method: m.name.clone(),
            options: options.to_string(),
            frame_ms: m.mean_frame_ms,
            published_frame_ms: p.and_then(|p| p.frame_ms),
            queries: m.queries_per_frame,
            published_queries: p.and_then(|p| p.queries),
            wait_ms: m.wait_ms_per_frame,
            published_wait_ms: p.and_then(|p| p.wait_ms),
            triangles: m.triangles_per_frame,
            published_triangles: p.and_then(|p| p.triangles),
            speedup: m.mean_speedup_vs_vfc,
            speedup_of_means: m.speedup_vs_vfc,
            published_speedup: p.and_then(|p| p.speedup),
            state_changes: m.state_changes_per_frame,
            material_switches: m.material_switches_per_frame,
            missing_pixels: m.missing_pixels,
        }
    }

    /// The row's label: its method, and its options if any.
    fn label(&self) -> String {
        if self.options.is_empty() {
            self.method.clone()
        } else {
            format!("{} {}", self.method, self.options)
        }
    }
}

/// Whether the rows of `scene` that have a published frame time come in the
/// same order by our frame time as by the published one (`None`: fewer than
/// two such rows).
pub fn scene_order_agrees(rows: &[Row], scene: &str) -> Option<bool> {
    let compared: Vec<&Row> = rows.iter().filter(|r| r.scene == scene && r.published_frame_ms.is_some()).collect();
    if compared.len() < 2 {
        return None;
    }
    let order = |key: fn(&Row) -> f64| {
        let mut sorted = compared.clone();
        sorted.sort_by(|a, b| key(a).total_cmp(&key(b)));
        sorted.into_iter().map(Row::label).collect::<Vec<_>>()
    };
    Some(order(|r| r.frame_ms) == order(|r| r.published_frame_ms.unwrap_or(0.0)))
}

impl<R> Table<R> {
    /// A table of `rows` that are not ordered by method (no
    /// `ordering_agrees`), with the published source, if any.
    pub fn unordered(name: &str, published: Option<&PublishedTable>, rows: R) -> Self {
        Self { name: name.to_string(), source: published.map(|t| t.source.clone()), rows, ordering_agrees: None }
    }
}

impl Table {
    /// A table of `rows` with the published source, if any, and the
    /// ordering verdict over its scenes.
    pub fn new(name: &str, published: Option<&PublishedTable>, rows: Vec<Row>) -> Self {
        let mut scenes: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
        scenes.dedup();
        let verdicts: Vec<bool> = scenes.iter().filter_map(|s| scene_order_agrees(&rows, s)).collect();
        let ordering_agrees = Some((!verdicts.is_empty()).then(|| verdicts.iter().all(|&v| v)));
        Self { ordering_agrees, ..Self::unordered(name, published, rows) }
    }

    /// The table as text: every figure beside the paper's (in brackets,
    /// `-` where it published none), and per scene whether the order agrees.
    pub fn render(&self, title: &str) -> String {
        let mut out = format!("{title} — {}\n", self.name);
        if let Some(source) = &self.source {
            let _ = writeln!(out, "published: {source}");
        }
        // The method column fits the longest label (a variant's options).
        let width = self.rows.iter().map(|r| r.label().chars().count()).max().unwrap_or(0).max(28);
        let _ = writeln!(
            out,
            "{:<8} {:<width$} {:>18} {:>24} {:>16} {:>16} {:>22} {:>8} {:>9} {:>10}  order",
            "scene",
            "method",
            "frame ms (paper)",
            "speedup r̄ / t̄ (paper)",
            "queries (paper)",
            "wait ms (paper)",
            "triangles (paper)",
            "states",
            "materials",
            "missing px"
        );
        let paper = |v: Option<f64>, decimals: usize| v.map_or("-".to_string(), |v| format!("{v:.decimals$}"));
        let mut previous = "";
        for r in &self.rows {
            let order = if r.scene != previous {
                match scene_order_agrees(&self.rows, &r.scene) {
                    Some(true) => "agrees",
                    Some(false) => "DIFFERS",
                    None => "",
                }
            } else {
                ""
            };
            previous = &r.scene;
            let _ = writeln!(
                out,
                "{:<8} {:<width$} {:>18} {:>24} {:>16} {:>16} {:>22} {:>8.0} {:>9.0} {:>10}  {order}",
                r.scene,
                r.label(),
                format!("{:.2} ({})", r.frame_ms, paper(r.published_frame_ms, 2)),
                format!("{:.2} / {:.2} ({})", r.speedup, r.speedup_of_means, paper(r.published_speedup, 1)),
                format!("{:.0} ({})", r.queries, paper(r.published_queries, 0)),
                format!("{:.2} ({})", r.wait_ms, paper(r.published_wait_ms, 2)),
                format!("{:.0} ({})", r.triangles, paper(r.published_triangles, 0)),
                r.state_changes,
                r.material_switches,
                r.missing_pixels,
            );
        }
        match self.ordering_agrees.flatten() {
            Some(v) => {
                let _ = writeln!(out, "order of methods by frame time agrees with the paper in every scene: {v}");
            }
            None => out.push_str("(no published figures to compare)\n"),
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(scene: &str, method: &str, frame_ms: f64, published: Option<f64>) -> Row {
        Row { scene: scene.into(), method: method.into(), frame_ms, published_frame_ms: published, ..Row::default() }
    }

    #[test]
    fn the_order_agrees_only_when_every_scene_ranks_as_the_paper() {
        let agreeing = vec![
            row("city", "vfc", 20.0, Some(19.8)),
            row("city", "chc", 9.0, Some(8.5)),
            row("city", "opt", 3.0, None),
            row("plant", "vfc", 100.0, Some(138.8)),
            row("plant", "chc", 40.0, Some(38.7)),
        ];
        let t = Table::new("Table 1", None, agreeing.clone());
        assert_eq!(t.ordering_agrees, Some(Some(true)));
        assert!(t.render("t").contains("agrees"));
        let mut differing = agreeing;
        differing[4].frame_ms = 120.0;
        let t = Table::new("Table 1", None, differing);
        assert_eq!(scene_order_agrees(&t.rows, "city"), Some(true));
        assert_eq!(scene_order_agrees(&t.rows, "plant"), Some(false));
        assert_eq!(t.ordering_agrees, Some(Some(false)));
        assert!(t.render("t").contains("DIFFERS"));
        let unpublished =
            Table::new("ablation", None, vec![row("city", "chc", 1.0, None), row("city", "vfc", 2.0, None)]);
        assert_eq!(unpublished.ordering_agrees, Some(None));
        // A method table's verdict is in the JSON, `null` included; an
        // unordered table's is not, and each reads back as it was.
        let json = serde_json::to_value(&unpublished).unwrap();
        assert!(json["ordering_agrees"].is_null() && json.get("ordering_agrees").is_some());
        assert_eq!(serde_json::from_value::<Table>(json).unwrap(), unpublished);
        let unordered = Table::unordered("Table 3", None, vec![row("city", "chc", 1.0, None)]);
        let json = serde_json::to_value(&unordered).unwrap();
        assert!(json.get("ordering_agrees").is_none(), "{json}");
        assert_eq!(serde_json::from_value::<Table>(json).unwrap(), unordered);
    }
}
