//! The papers' published figures (`published.toml`, each table citing its
//! source), which `occlude bench --paper` prints beside its own.

use crate::paper_tables::Row;
use serde::Deserialize;
use std::fmt::Write;
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
    /// Frames per second on an ATI HD4870X2.
    pub fps_hd4870x2: Option<f64>,
}

/// A comparison of two methods a paper states in words, with the ratio of
/// frame times where it gives one (the CHC++ paper gives its comparisons
/// as plots and such statements).
#[derive(Clone, Debug, Deserialize)]
pub struct PublishedClaim {
    /// The paper, as `--paper` names it.
    pub paper: String,
    /// The method the paper finds slower (as `--methods` names it).
    pub slower: String,
    /// The method it finds faster.
    pub faster: String,
    /// The slower method's frame time over the faster one's, if the paper
    /// gives a number.
    pub ratio: Option<f64>,
    /// The paper's words.
    pub quote: String,
    /// Section and page.
    pub source: String,
}

#[derive(Deserialize)]
struct File {
    table: Vec<PublishedTable>,
    #[serde(default)]
    claim: Vec<PublishedClaim>,
}

/// The data file compiled in, read once.
fn file() -> &'static File {
    static FILE: OnceLock<File> = OnceLock::new();
    FILE.get_or_init(|| {
        toml::from_str(include_str!("published.toml")).expect("published.toml is valid (a test reads it)")
    })
}

/// Every published table.
fn tables() -> &'static [PublishedTable] {
    &file().table
}

/// The claims of `paper`, in the data file's order.
pub fn claims(paper: &str) -> impl Iterator<Item = &'static PublishedClaim> + '_ {
    file().claim.iter().filter(move |c| c.paper == paper)
}

/// `paper`'s claims set beside our `rows` (a table of methods compared):
/// per claim and scene, our ratio of the two methods' mean frame times
/// beside the paper's, and whether the order agrees (the slower one's
/// frame time at least the faster one's). Empty for a paper without claims.
pub fn claims_text(paper: &str, rows: &[Row]) -> String {
    let mut scenes: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
    scenes.dedup();
    let mut out = String::new();
    for c in claims(paper) {
        let _ = writeln!(out, "claim ({}): \"{}\"", c.source, c.quote);
        for &scene in &scenes {
            let frame_ms =
                |method: &str| rows.iter().find(|r| r.scene == scene && r.method == method).map(|r| r.frame_ms);
            let (Some(slower), Some(faster)) = (frame_ms(&c.slower), frame_ms(&c.faster)) else { continue };
            let ours = slower / faster;
            let paper = c.ratio.map_or("-".to_string(), |r| format!("{r:.1}"));
            let order = if ours >= 1.0 { "agrees" } else { "DIFFERS" };
            let _ =
                writeln!(out, "  {scene:<8} {} / {} frame time {ours:.2} (paper {paper})  {order}", c.slower, c.faster);
        }
    }
    out
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
        let om = table("om", "Table 2").expect("the occupancy-map paper's Table 2");
        assert_eq!(om.row("city", "om", "").unwrap().frame_ms, Some(48.31));
        assert_eq!(claims("om").next().map(|c| (c.slower.as_str(), c.ratio)), Some(("sw", Some(1.04))));
        let fig8 = table("chcpp", "Figure 8").expect("CHC++ Figure 8's source");
        assert!(fig8.source.contains("p. 229") && fig8.rows.is_empty(), "{}", fig8.source);
        let nohc = claims("chcpp").find(|c| c.slower == "nohc" && c.faster == "chcpp").expect("the 1.5x claim");
        assert_eq!(nohc.ratio, Some(1.5));
        assert!(nohc.source.contains("p. 230"), "{}", nohc.source);
        assert_eq!(claims("chc").count(), 0);
        let gvq = table("gvq", "Table 2").expect("GVQ Table 2");
        let row500 = gvq.rows.iter().find(|r| r.objects == Some(500)).unwrap();
        assert_eq!(
            (row500.conflicts, row500.split_merge_ms, row500.rel_error_pct),
            (Some(249.0), Some(23.0), Some(11.6))
        );
    }
}
