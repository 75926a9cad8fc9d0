//! Multiqueries for previously invisible nodes (CHC++ paper, section 5.1):
//! nodes likely to stay invisible share one occlusion query, grouped greedily
//! by a benefit/cost ratio.

/// Probability that a node keeps its visibility classification in the next
/// frame after `i` frames in the same state: the paper's analytic fit,
/// p_keep(i) = 0.99 - 0.7 e^(-i) (Eq. 2).
pub fn p_keep(i: u32) -> f64 {
    0.99 - 0.7 * (-f64::from(i)).exp()
}

/// Splits `persistence` (visibility persistence of each node, already sorted
/// by descending p_keep) into consecutive group sizes. Each group is the
/// prefix that maximises V(M) = |M| / (1 + p_fail(M) |M|) with
/// p_fail(M) = 1 - prod p_keep (Eqs. 3-5); grouping restarts after it.
pub fn group_sizes(persistence: &[u32]) -> Vec<usize> {
    let mut sizes = Vec::new();
    let mut start = 0;
    while start < persistence.len() {
        let (mut best_size, mut best_value) = (1, f64::MIN);
        let mut keep = 1.0;
        for (j, &i) in persistence[start..].iter().enumerate() {
            keep *= p_keep(i);
            let size = (j + 1) as f64;
            let value = size / (1.0 + (1.0 - keep) * size);
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
        let stable = group_sizes(&[50; 40]);
        // Nodes that just turned invisible: p_keep(1) ~ 0.73, small groups.
        let fresh = group_sizes(&[1; 40]);
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
}
