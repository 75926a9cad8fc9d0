//! The software backend: an exact depth rasterizer, parallel over screen tiles,
//! driven by a simulated GPU clock so that results are deterministic.

pub mod raster;
