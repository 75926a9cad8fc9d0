//! The summed area table of a channel image and the pixel counts it gives
//! (section 3.1.2, figure 2: four reads per rectangle), with Table 2's
//! error statistics against exact counts.

use super::rect::PixelRect;
use super::region::{RegionSet, NO_CHANNEL};
use serde::{Deserialize, Serialize};

/// Per channel, the number of pixels of that channel above and left of
/// each grid point: `(width + 1) x (height + 1)` exact `u32` sums, the
/// first row and column 0.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SummedAreaTable {
    width: u32,
    height: u32,
    channels: u32,
    /// Channel after channel, row-major.
    sums: Vec<u32>,
}

impl SummedAreaTable {
    /// The table of a `width` x `height` row-major channel image (one
    /// channel index per pixel, or [`NO_CHANNEL`]) over `channels`
    /// channels: prefix sums along each row, then down each column.
    ///
    /// # Panics
    /// If `image` is not `width * height` long or names a channel at or
    /// past `channels` other than [`NO_CHANNEL`].
    pub fn from_channel_image(width: u32, height: u32, channels: u32, image: &[u8]) -> Self {
        let (w, h) = (width as usize, height as usize);
        assert_eq!(image.len(), w * h, "channel image of {} pixels for {width}x{height}", image.len());
        let stride = w + 1;
        let plane = stride * (h + 1);
        let mut sums = vec![0u32; plane * channels as usize];
        for (y, row) in image.chunks_exact(w.max(1)).enumerate().take(h) {
            for (x, &c) in row.iter().enumerate() {
                if c != NO_CHANNEL {
                    assert!(u32::from(c) < channels, "channel {c} of {channels}");
                    sums[c as usize * plane + (y + 1) * stride + x + 1] = 1;
                }
            }
        }
        for table in sums.chunks_exact_mut(plane) {
            for row in table.chunks_exact_mut(stride) {
                for x in 1..stride {
                    row[x] += row[x - 1];
                }
            }
            for y in 1..=h {
                for x in 0..stride {
                    table[y * stride + x] += table[(y - 1) * stride + x];
                }
            }
        }
        Self { width, height, channels, sums }
    }

    /// The sum at grid point `(x, y)` of `channel` (pixels of the channel
    /// in columns `0..x`, rows `0..y`).
    pub fn at(&self, channel: u32, x: u32, y: u32) -> u32 {
        let stride = self.width as usize + 1;
        self.sums[channel as usize * stride * (self.height as usize + 1) + y as usize * stride + x as usize]
    }

    /// Pixels of `channel` in `rect` (clamped to the image): four reads.
    pub fn count(&self, channel: u32, rect: &PixelRect) -> u64 {
        let r = PixelRect::new(
            rect.x0.min(self.width),
            rect.y0.min(self.height),
            rect.x1.min(self.width),
            rect.y1.min(self.height),
        );
        if r.is_empty() || channel >= self.channels {
            return 0;
        }
        let (a, b, c, d) = (
            self.at(channel, r.x1, r.y1),
            self.at(channel, r.x0, r.y1),
            self.at(channel, r.x1, r.y0),
            self.at(channel, r.x0, r.y0),
        );
        // a + d >= b + c: inclusion-exclusion of non-negative counts.
        u64::from(a) + u64::from(d) - u64::from(b) - u64::from(c)
    }

    /// An object's pixel count: the sum of its region set's lookups.
    pub fn count_set(&self, set: &RegionSet) -> u64 {
        set.lookups.iter().map(|l| self.count(l.channel, &l.rect)).sum()
    }
}

/// Table 2's statistics of counts against exact counts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CountErrors {
    /// Objects compared.
    pub objects: u32,
    /// Mean of `|count - exact|` over the objects, in pixels.
    pub abs_error_px: f64,
    /// Mean of `|count - exact| / exact` over the objects with `exact > 0`,
    /// in percent (0 when there are none).
    pub rel_error_pct: f64,
    /// `sum |count - exact| / sum exact` over the objects, in percent (0
    /// when nothing is visible): the relative error weighted by size,
    /// which tiny objects do not dominate. The paper does not say which
    /// relative error its Table 2 averages.
    #[serde(default)]
    pub rel_error_of_sums_pct: f64,
    /// Objects whose count differs from the exact count.
    pub wrong: u32,
}

/// The errors of `counts` against `exact`, object for object.
///
/// # Panics
/// If the slices differ in length.
pub fn count_errors(counts: &[u64], exact: &[u64]) -> CountErrors {
    assert_eq!(counts.len(), exact.len(), "counts and exact counts of different objects");
    let diffs = counts.iter().zip(exact).map(|(&c, &e)| (c.abs_diff(e) as f64, e));
    let (abs, rel, visible, wrong) = diffs.fold((0.0, 0.0, 0u32, 0u32), |(abs, rel, visible, wrong), (d, e)| {
        let r = if e > 0 { d / e as f64 } else { 0.0 };
        (abs + d, rel + r, visible + u32::from(e > 0), wrong + u32::from(d > 0.0))
    });
    let n = counts.len() as u32;
    let total: u64 = exact.iter().sum();
    CountErrors {
        rel_error_of_sums_pct: if total > 0 { 100.0 * abs / total as f64 } else { 0.0 },
        objects: n,
        abs_error_px: if n > 0 { abs / f64::from(n) } else { 0.0 },
        rel_error_pct: if visible > 0 { 100.0 * rel / f64::from(visible) } else { 0.0 },
        wrong,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gvq::region::Lookup;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn four_reads_equal_counting_the_pixels(
            (w, h, image) in (1u32..20, 1u32..20).prop_flat_map(|(w, h)| {
                let pixel = prop_oneof![Just(NO_CHANNEL), 0u8..5];
                (Just(w), Just(h), prop::collection::vec(pixel, (w * h) as usize))
            }),
            (x0, y0, x1, y1) in (0u32..22, 0u32..22, 0u32..22, 0u32..22),
            channel in 0u32..6,
        ) {
            let sat = SummedAreaTable::from_channel_image(w, h, 5, &image);
            let rect = PixelRect::new(x0, y0, x1, y1);
            let brute = (0..w * h)
                .filter(|&p| rect.contains(p % w, p / w) && u32::from(image[p as usize]) == channel)
                .count() as u64;
            prop_assert_eq!(sat.count(channel, &rect), brute);
        }
    }

    #[test]
    fn a_region_set_sums_its_lookups() {
        let image = [0, 0, 1, NO_CHANNEL, 1, 0];
        let sat = SummedAreaTable::from_channel_image(3, 2, 2, &image);
        let set = RegionSet {
            lookups: vec![
                Lookup { rect: PixelRect::new(0, 0, 2, 2), channel: 0, shared: false },
                Lookup { rect: PixelRect::new(2, 0, 3, 2), channel: 1, shared: false },
            ],
            ..RegionSet::default()
        };
        assert_eq!(sat.count_set(&set), 3);
    }

    #[test]
    fn errors_are_table_2s_means() {
        let e = count_errors(&[12, 0, 5, 3], &[10, 0, 5, 0]);
        assert_eq!(e.objects, 4);
        assert_eq!(e.wrong, 2);
        assert!((e.abs_error_px - 5.0 / 4.0).abs() < 1e-12);
        assert!((e.rel_error_pct - 100.0 * 0.2 / 2.0).abs() < 1e-9);
        assert!((e.rel_error_of_sums_pct - 100.0 * 5.0 / 15.0).abs() < 1e-9);
        assert_eq!(count_errors(&[], &[]), CountErrors::default());
    }
}
