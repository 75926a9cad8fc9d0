//! Multiqueries for previously invisible nodes (CHC++ paper, section 5.1):
//! nodes likely to stay invisible share one occlusion query, grouped greedily
//! by a benefit/cost ratio. How likely is `p_keep(i)`, a function of the
//! frames `i` a node has kept its classification: the paper's analytic fit
//! (Eq. 2) or its measured estimate (Eq. 1, [`KeepCounts`]).

use std::fmt;
use std::str::FromStr;

/// Probability that a node keeps its visibility classification in the next
/// frame after `i` frames in the same state: the paper's analytic fit,
/// p_keep(i) = 0.99 - 0.7 e^(-i) (Eq. 2).
pub fn p_keep(i: u32) -> f64 {
    0.99 - 0.7 * (-f64::from(i)).exp()
}

/// Which estimate of `p_keep` the multiqueries use (`chcpp.pkeep`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum KeepEstimate {
    /// Eq. 2, the paper's analytic fit ([`p_keep`]).
    #[default]
    Fit,
    /// Eq. 1, measured over the walkthrough so far ([`KeepCounts`]).
    Measured,
}

impl fmt::Display for KeepEstimate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            KeepEstimate::Fit => "fit",
            KeepEstimate::Measured => "measured",
        })
    }
}

impl FromStr for KeepEstimate {
    type Err = ();
    fn from_str(s: &str) -> Result<Self, ()> {
        match s {
            "fit" => Ok(KeepEstimate::Fit),
            "measured" => Ok(KeepEstimate::Measured),
            _ => Err(()),
        }
    }
}

/// Eq. 1's counters, accumulated over every frame so far: of the tested
/// nodes that had kept their classification for `i` frames, how many kept
/// it at the test (`n_keep_i`) and how many there were (`n_all_i`).
#[derive(Clone, Debug, Default)]
pub struct KeepCounts {
    kept: Vec<u64>,
    all: Vec<u64>,
}

impl KeepCounts {
    /// Persistences from this one on share one counter (Figure 4 of the
    /// paper plots up to 40 frames; the fit is flat long before).
    pub const LAST: u32 = 64;
    /// Tests a persistence needs before its own ratio is used; with fewer,
    /// the paper propagates the value of the nearest lower persistence
    /// ("piecewise constant propagation"). A ratio of a handful of tests
    /// would be 0 or 1.
    pub const MIN_TESTS: u64 = 20;

    /// Counts one test of a node that had kept its classification for `i`
    /// frames, and whether the test found it unchanged.
    pub fn record(&mut self, i: u32, kept: bool) {
        let i = i.min(Self::LAST) as usize;
        if self.all.len() <= i {
            self.kept.resize(i + 1, 0);
            self.all.resize(i + 1, 0);
        }
        self.all[i] += 1;
        self.kept[i] += u64::from(kept);
    }

    /// `n_keep_i / n_all_i` at the largest persistence up to `i` with
    /// [`Self::MIN_TESTS`] tests; the fit ([`p_keep`]) before any has.
    pub fn p_keep(&self, i: u32) -> f64 {
        let top = (i.min(Self::LAST) as usize).min(self.all.len().saturating_sub(1));
        (0..=top)
            .rev()
            .find(|&j| self.all.get(j).is_some_and(|&n| n >= Self::MIN_TESTS))
            .map_or_else(|| p_keep(i), |j| self.kept[j] as f64 / self.all[j] as f64)
    }
}

/// Splits `keep` (each node's `p_keep`, already sorted descending) into
/// consecutive group sizes. Each group is the prefix that maximises
/// V(M) = |M| / (1 + p_fail(M) |M|) with p_fail(M) = 1 - prod p_keep
/// (Eqs. 3-5); grouping restarts after it.
pub fn group_sizes(keep: &[f64]) -> Vec<usize> {
    let mut sizes = Vec::new();
    let mut start = 0;
    while start < keep.len() {
        let (mut best_size, mut best_value) = (1, f64::MIN);
        let mut kept = 1.0;
        for (j, &p) in keep[start..].iter().enumerate() {
            kept *= p;
            let size = (j + 1) as f64;
            let value = size / (1.0 + (1.0 - kept) * size);
            if value > best_value {
                (best_size, best_value) = (j + 1, value);
            } else {
                break; // V rises to one maximum, then falls.
            }
        }
        sizes.push(best_size);
        start += best_size;
    }
    sizes
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_invisible_nodes_form_large_groups() {
        // Nodes invisible for 50 frames: p_keep ~ 0.99, groups grow large.
        let stable = group_sizes(&[p_keep(50); 40]);
        // Nodes that just turned invisible: p_keep(1) ~ 0.73, small groups.
        let fresh = group_sizes(&[p_keep(1); 40]);
        assert_eq!(stable.iter().sum::<usize>(), 40);
        assert_eq!(fresh.iter().sum::<usize>(), 40);
        // V(j) = j / (1 + (1 - 0.99^j) j) peaks near j = 10; with
        // p_keep(1) = 0.73 it peaks at j = 3.
        assert!(stable[0] >= 8, "{stable:?}");
        assert_eq!(fresh[0], 3, "{fresh:?}");
        assert!(stable.len() < fresh.len());
    }

    #[test]
    fn p_keep_matches_the_paper_fit() {
        assert!((p_keep(0) - 0.29).abs() < 1e-12);
        assert!(p_keep(100) > 0.989 && p_keep(100) <= 0.99);
        assert!(p_keep(1) < p_keep(2));
        assert!(group_sizes(&[]).is_empty());
    }

    #[test]
    fn measured_estimates_propagate_down_and_fall_back_to_the_fit() {
        let mut counts = KeepCounts::default();
        assert_eq!(counts.p_keep(3), p_keep(3), "nothing measured: the fit");
        // Persistence 2: 15 of 20 kept; persistence 5: too few tests.
        for k in 0..20 {
            counts.record(2, k < 15);
        }
        for _ in 0..5 {
            counts.record(5, true);
        }
        assert_eq!(counts.p_keep(1), p_keep(1), "below every measured persistence");
        assert_eq!(counts.p_keep(2), 0.75);
        assert_eq!(counts.p_keep(5), 0.75, "too few at 5: 2's value carried up");
        assert_eq!(counts.p_keep(1000), 0.75);
        for _ in 0..20 {
            counts.record(5000, true);
        }
        assert_eq!(counts.p_keep(KeepCounts::LAST), 1.0, "persistences past LAST share its counter");
        assert_eq!(counts.p_keep(40), 0.75);
    }

    #[test]
    fn estimates_parse_and_print() {
        for e in [KeepEstimate::Fit, KeepEstimate::Measured] {
            assert_eq!(e.to_string().parse(), Ok(e));
        }
        assert!("eq1".parse::<KeepEstimate>().is_err());
    }
}
