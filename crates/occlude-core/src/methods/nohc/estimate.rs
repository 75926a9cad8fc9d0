//! NOHC's estimate of how likely a node is occluded, and its test of whether
//! a query pays (CHC++ paper, section 3.2, describing Guthe et al. 2006:
//! "a simple screen coverage model and further corrections assuming
//! temporal coherence", weighed against a calibrated hardware model).
//!
//! Screen coverage: the boxes of the leaves drawn so far this frame cover
//! `c` screens (their footprints' pixels over the image's). If those pixels
//! fell on the screen at random, a given pixel would be left uncovered with
//! probability `e^-c` (a Poisson count of covering boxes), so a node is taken
//! to be occluded with probability `1 - e^-c`. Temporal correction: a node
//! whose last query, in the frames it has been visited without a gap, found
//! it occluded is occluded again with at least the probability that a
//! classification persists, `p_keep(i)` after `i` frames (CHC++ paper,
//! section 5.1, Eq. 2, the same fit `chcpp`'s multiqueries use); one found
//! visible is occluded with at most `1 - p_keep(i)`. Which fit corrects the
//! coverage is our choice: the CHC++ paper does not give Guthe's.

use crate::methods::chcpp::multiquery::p_keep;

/// What the traversal knows of a node's visibility from its queries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum History {
    /// No query result since the node was last out of the traversal.
    Unknown,
    /// Its last query found it occluded; the classification has held `frames` frames.
    Occluded {
        /// Frames since the classification last changed (at least 1).
        frames: u32,
    },
    /// Its last query found it visible; the classification has held `frames` frames.
    Visible {
        /// Frames since the classification last changed (at least 1).
        frames: u32,
    },
}

/// The probability that a node is occluded, from the screens' worth of
/// pixels the boxes drawn so far cover (`coverage`) and its `history`
/// (module documentation).
pub fn occlusion_probability(coverage: f64, history: History) -> f64 {
    let covered = 1.0 - (-coverage.max(0.0)).exp();
    match history {
        History::Unknown => covered,
        History::Occluded { frames } => covered.max(p_keep(frames)),
        History::Visible { frames } => covered.min(1.0 - p_keep(frames)),
    }
}

/// Whether a query pays: the rendering it saves in expectation
/// (`occluded` x `render_us`) exceeds its own cost. A query that finds the
/// node visible saves nothing, so the query's cost is paid either way.
pub fn query_pays(occluded: f64, render_us: f64, query_us: f64) -> bool {
    occluded * render_us > query_us
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coverage_and_history_move_the_estimate_the_right_way() {
        assert_eq!(occlusion_probability(0.0, History::Unknown), 0.0);
        let half = occlusion_probability(0.5, History::Unknown);
        assert!((half - (1.0 - (-0.5f64).exp())).abs() < 1e-12);
        assert!(occlusion_probability(2.0, History::Unknown) > half);
        // An occluded node stays likely occluded on an empty screen, and the
        // more so the longer it has been; a visible one the reverse.
        let (o1, o9) = (History::Occluded { frames: 1 }, History::Occluded { frames: 9 });
        assert!((occlusion_probability(0.0, o1) - p_keep(1)).abs() < 1e-12);
        assert!(occlusion_probability(0.0, o9) > occlusion_probability(0.0, o1));
        let v9 = History::Visible { frames: 9 };
        assert!(occlusion_probability(5.0, v9) < 0.02);
        assert!(occlusion_probability(0.1, v9) <= occlusion_probability(0.1, History::Unknown));
    }

    #[test]
    fn a_query_pays_only_when_the_expected_saving_exceeds_its_cost() {
        assert!(query_pays(0.5, 10.0, 4.0));
        assert!(!query_pays(0.5, 10.0, 5.0));
        assert!(!query_pays(0.0, 1e9, 0.1));
        assert!(query_pays(1.0, 2.0, 1.0));
    }
}
