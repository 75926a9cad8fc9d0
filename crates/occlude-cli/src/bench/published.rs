//! The papers' published figures (`published.toml`, each table citing its
//! source), which `occlude bench --paper` prints beside its own.

use serde::Deserialize;
use std::sync::OnceLock;

/// One published table.
#[derive(Clone, Debug, Deserialize)]
pub struct PublishedTable {
    /// The paper, as `--paper` names it.
    pub paper: String,
    /// The table's name in the paper ("Table 1").
    pub name: String,
    /// Paper, section and table the figures come from.
    pub source: String,
    /// Its rows.
    pub rows: Vec<PublishedRow>,
}

/// One published row: per-frame averages over the paper's walkthrough.
#[derive(Clone, Debug, Default, Deserialize)]
pub struct PublishedRow {
    /// Our scene standing for the paper's.
    pub scene: String,
    /// Our method standing for the paper's.
    pub method: String,
    /// Method options of a table of variants, space separated ("" for the
    /// defaults).
    #[serde(default)]
    pub options: String,
    /// Frame time, ms.
    pub frame_ms: Option<f64>,
    /// CPU stalls waiting for query results, ms.
    pub wait_ms: Option<f64>,
    /// Occlusion queries.
    pub queries: Option<f64>,
    /// Rendered triangles.
    pub triangles: Option<f64>,
    /// Speedup over view-frustum culling.
    pub speedup: Option<f64>,
    /// Objects in the scene (granular visibility queries' rows).
    pub objects: Option<u32>,
    /// Conflict objects.
    pub conflicts: Option<f64>,
    /// CPU time of the overlap test, ms.
    pub overlap_ms: Option<f64>,
    /// CPU time of the colouring, ms.
    pub colouring_ms: Option<f64>,
    /// CPU time of split and merge, ms.
    pub split_merge_ms: Option<f64>,
    /// Mean absolute pixel-count error, pixels.
    pub abs_error_px: Option<f64>,
    /// Mean relative pixel-count error, percent.
    pub rel_error_pct: Option<f64>,
    /// The view of a table of views (granular visibility queries' Table 3:
    /// `full`, `partial`, `occluded`).
    #[serde(default)]
    pub view: String,
    /// Frames per second on an NVIDIA 280GTX.
    pub fps_gtx280: Option<f64>,
    /// Frames per second on an ATI HD3870.
    pub fps_hd3870: Option<f64>,
}

#[derive(Deserialize)]
struct File {
    table: Vec<PublishedTable>,
}

/// Every published table, read once from the data file compiled in.
fn tables() -> &'static [PublishedTable] {
    static TABLES: OnceLock<Vec<PublishedTable>> = OnceLock::new();
    TABLES.get_or_init(|| {
        let file: File =
            toml::from_str(include_str!("published.toml")).expect("published.toml is valid (a test reads it)");
        file.table
    })
}

/// The table `name` of `paper`, if the paper published one.
pub fn table(paper: &str, name: &str) -> Option<&'static PublishedTable> {
    tables().iter().find(|t| t.paper == paper && t.name == name)
}

impl PublishedTable {
    /// The row of `method` with `options` on `scene`.
    pub fn row(&self, scene: &str, method: &str, options: &str) -> Option<&PublishedRow> {
        self.rows.iter().find(|r| r.scene == scene && r.method == method && r.options == options)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_data_file_reads_and_names_its_sources() {
        let t1 = table("chc", "Table 1").expect("CHC Table 1");
        assert_eq!(t1.rows.len(), 12);
        assert!(t1.source.contains("Table 1"), "{}", t1.source);
        let chc_city = t1.row("city", "chc", "").unwrap();
        assert_eq!((chc_city.frame_ms, chc_city.queries, chc_city.speedup), (Some(8.47), Some(345.0), Some(4.0)));
        assert_eq!(t1.row("plant", "ideal", "").unwrap().triangles, Some(392962.0));
        let t2 = table("chc", "Table 2").expect("CHC Table 2");
        assert_eq!(t2.row("teapots", "chc", "chc.tav=2 chc.nvp=25").unwrap().frame_ms, Some(55.90));
        assert!(table("chc", "Table 9").is_none() && table("om", "Table 1").is_none());
        let gvq = table("gvq", "Table 2").expect("GVQ Table 2");
        let row500 = gvq.rows.iter().find(|r| r.objects == Some(500)).unwrap();
        assert_eq!(
            (row500.conflicts, row500.split_merge_ms, row500.rel_error_pct),
            (Some(249.0), Some(23.0), Some(11.6))
        );
    }
}
