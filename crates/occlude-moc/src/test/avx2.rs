//! The AVX2 version of the box test's tile compare
//! ([`TileTest::lanes_beyond`]): a tile's eight subtiles in one register per
//! field, compared with ordered compares (false on NaN, as the portable
//! `<` is), so the answers are the portable ones.

use std::arch::x86_64::*;

use super::{SubtileRect, TileTest, Visibility};
use crate::buffer::{MaskedBuffer, Tile};
use crate::raster::Avx2;

impl TileTest for Avx2 {
    #[inline(always)]
    fn lanes_beyond(self, tile: &Tile, nearest: f32) -> u32 {
        // SAFETY: an `Avx2` exists only where the CPU supports AVX2.
        unsafe { lanes_beyond(tile, nearest) }
    }
}

impl Avx2 {
    /// [`SubtileRect::scan`] compiled with AVX2.
    #[inline(always)]
    pub(super) fn scan(self, rect: SubtileRect, buffer: &MaskedBuffer, nearest: f32) -> (Visibility, u64) {
        // SAFETY: an `Avx2` exists only where the CPU supports AVX2.
        unsafe { scan(self, rect, buffer, nearest) }
    }
}

#[target_feature(enable = "avx2")]
unsafe fn scan(avx2: Avx2, rect: SubtileRect, buffer: &MaskedBuffer, nearest: f32) -> (Visibility, u64) {
    rect.scan(buffer, nearest, avx2)
}

#[target_feature(enable = "avx2")]
unsafe fn lanes_beyond(tile: &Tile, nearest: f32) -> u32 {
    // `Tile` is 32-byte aligned and each field is 32 bytes.
    let mask = _mm256_load_si256(tile.mask.as_ptr().cast());
    let working = _mm256_load_ps(tile.working.as_ptr());
    let reference = _mm256_load_ps(tile.reference.as_ptr());
    let nearest = _mm256_set1_ps(nearest);
    let empty = _mm256_castsi256_ps(_mm256_cmpeq_epi32(mask, _mm256_setzero_si256()));
    let before_reference = _mm256_cmp_ps::<_CMP_LT_OQ>(nearest, reference);
    let before_working = _mm256_andnot_ps(empty, _mm256_cmp_ps::<_CMP_LT_OQ>(nearest, working));
    _mm256_movemask_ps(_mm256_or_ps(before_reference, before_working)) as u32
}
