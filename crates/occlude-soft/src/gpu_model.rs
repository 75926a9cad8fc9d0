//! Cost parameters of the simulated GPU clock (`docs/design.md`, "The simulated GPU
//! clock"), with presets and TOML overrides.
//!
//! Where the defaults come from is documented in `docs/gpu-models.md`.

use occlude_core::CostModel;
use serde::{Deserialize, Serialize};
use std::path::Path;
use thiserror::Error;

/// Every cost the simulated clock charges. CPU costs advance the CPU clock at
/// the call; GPU costs occupy the in-order GPU queue.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GpuModel {
    /// Name shown in tables and JSON (`gpu_model`).
    pub name: String,
    /// CPU time to issue one draw call, µs.
    pub cpu_draw_call_us: f64,
    /// CPU time of one render-state change, µs.
    pub cpu_state_change_us: f64,
    /// CPU time to issue one occlusion query (begin, boxes, end), µs.
    pub cpu_query_us: f64,
    /// CPU time to record one query's boxes in an item-buffer batch
    /// (`--queries hib`: no begin and end, the boxes appended to the
    /// batch), µs, as `occlude calibrate` measures it; `None` (the presets,
    /// and model files that predate it): `cpu_query_us`, as a hardware
    /// query ([`GpuModel::hib_query_us`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cpu_hib_query_us: Option<f64>,
    /// CPU time of one non-blocking "is the result available?" check, µs.
    pub cpu_query_poll_us: f64,
    /// CPU time to visit one hierarchy node (frustum test, queue work), µs.
    pub cpu_node_us: f64,
    /// GPU time per draw call (setup, vertex fetch start), µs.
    pub gpu_draw_call_us: f64,
    /// GPU time per drawn triangle, ns.
    pub gpu_triangle_ns: f64,
    /// GPU time per drawn fragment (covered pixel, before the depth test), ns.
    pub gpu_fragment_ns: f64,
    /// GPU time of one render-state change (pipeline flush), µs.
    pub gpu_state_change_us: f64,
    /// GPU time per query box (setup of 12 triangles), µs.
    pub gpu_query_box_us: f64,
    /// GPU time per query fragment (depth test only, no shading), ns.
    pub gpu_query_fragment_ns: f64,
    /// Time from the GPU finishing a query until the CPU can read its
    /// result, µs.
    pub query_latency_us: f64,
    /// GPU work the driver buffers ahead of the GPU, µs: a submitting call
    /// (draw, query, state change) that finds more than this queued blocks
    /// until the GPU has worked it down, as an OpenGL driver blocks when its
    /// command buffer is full; that time is `FrameStats::submit_wait_ms`,
    /// not query wait. `inf`: the CPU may run any distance ahead of the GPU
    /// within a frame.
    pub driver_queue_us: f64,
    /// CPU time to record one compute dispatch or indirect multi-draw
    /// (GPU-driven culling), µs.
    pub cpu_dispatch_us: f64,
    /// GPU time of one compute dispatch (launch and the barrier after it), µs.
    pub gpu_dispatch_us: f64,
    /// GPU time per element a dispatch processes (a flag, a box, a list
    /// entry), ns.
    pub gpu_compute_item_ns: f64,
    /// GPU time per box of a batched box test (its 8 corners and 12
    /// triangles through the vertex stage of one instanced draw; no query
    /// around it), µs.
    pub gpu_box_us: f64,
    /// GPU time per pixel of a batched box test that passes the depth test
    /// (the fragment shader writing the visibility flag), on top of
    /// `gpu_query_fragment_ns` per covered pixel (the depth test), ns.
    pub gpu_box_fragment_ns: f64,
    /// GPU time per texel a depth-pyramid reduction writes (reading its
    /// 2x2 source texels), ns.
    pub gpu_pyramid_texel_ns: f64,
    /// GPU time per box tested against a depth pyramid (its 8 corners
    /// projected, its level chosen), ns.
    pub gpu_hiz_box_ns: f64,
    /// GPU time per pyramid texel such a test reads, ns.
    pub gpu_hiz_texel_ns: f64,
    /// GPU time per draw inside an indirect multi-draw (in place of
    /// `gpu_draw_call_us`), µs.
    pub gpu_indirect_draw_us: f64,
    /// Time from the GPU finishing the commands before a read-back until
    /// the CPU can read the buffer, µs.
    pub readback_us: f64,
    /// GPU time of one item-buffer batch (`--queries hib`: the queries
    /// between two submissions) beyond its boxes' (its pass, the clearing
    /// of its counts), µs, as `occlude calibrate` measures it; `None` (the
    /// presets, and model files that predate it): `gpu_draw_call_us` +
    /// `gpu_dispatch_us` ([`GpuModel::hib_batch_gpu_us`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gpu_hib_batch_us: Option<f64>,
    /// CPU time to set up one occluder triangle in the masked occlusion
    /// buffer (`moc`: transform, near-plane clip, projection, edges), ns.
    #[serde(default = "MocCosts::triangle_ns")]
    pub cpu_moc_triangle_ns: f64,
    /// CPU time per 32x8-pixel tile an occluder triangle's pixel-centre range
    /// overlaps in the masked buffer (coverage masks and merges), ns.
    #[serde(default = "MocCosts::tile_ns")]
    pub cpu_moc_tile_ns: f64,
    /// CPU time to test one box against the masked buffer beyond the
    /// subtiles it reads (corners, projection, the screen rectangle), ns.
    #[serde(default = "MocCosts::box_ns")]
    pub cpu_moc_box_ns: f64,
    /// CPU time per subtile (8x4 pixels) a box test reads from the masked
    /// buffer (compared a tile of eight at a time), ns.
    #[serde(default = "MocCosts::subtile_read_ns")]
    pub cpu_moc_subtile_read_ns: f64,
}

/// The masked occlusion buffer's CPU costs, the same in every preset (the
/// AVX2 build of `occlude-moc` measured on the development machine by its
/// `moc_costs` example, docs/gpu-models.md), and the defaults of model files
/// that predate them.
struct MocCosts;

impl MocCosts {
    fn triangle_ns() -> f64 {
        MOC_TRIANGLE_NS
    }
    fn tile_ns() -> f64 {
        MOC_TILE_NS
    }
    fn box_ns() -> f64 {
        MOC_BOX_NS
    }
    fn subtile_read_ns() -> f64 {
        MOC_SUBTILE_READ_NS
    }
}

/// See [`GpuModel::cpu_moc_triangle_ns`].
const MOC_TRIANGLE_NS: f64 = 76.4;
/// See [`GpuModel::cpu_moc_tile_ns`].
const MOC_TILE_NS: f64 = 4.4;
/// See [`GpuModel::cpu_moc_box_ns`].
const MOC_BOX_NS: f64 = 63.8;
/// See [`GpuModel::cpu_moc_subtile_read_ns`].
const MOC_SUBTILE_READ_NS: f64 = 0.22;

/// Errors loading a GPU model.
#[derive(Debug, Error)]
pub enum GpuModelError {
    /// The name is neither a preset nor a readable file.
    #[error("unknown GPU model '{0}': expected a preset ({presets}) or a TOML file", presets = GpuModel::PRESETS.join(", "))]
    Unknown(String),
    /// The file could not be read (not a regular file, larger than
    /// [`GpuModel::MAX_FILE_BYTES`], or a system error). The reason is part
    /// of the message, not a separate source, so that it is printed once.
    #[error("cannot read GPU model file {path}: {reason}")]
    Io {
        /// The file.
        path: String,
        /// Why reading failed.
        reason: std::io::Error,
    },
    /// The file is not a valid model.
    #[error("invalid GPU model file {path}: {message}")]
    Invalid {
        /// The file.
        path: String,
        /// What is wrong, naming the field.
        message: String,
    },
}

impl GpuModel {
    /// Names of the built-in presets.
    pub const PRESETS: [&'static str; 2] = ["gpu-2004", "modern"];

    /// The largest GPU model file read, bytes.
    pub const MAX_FILE_BYTES: u64 = 1 << 20;

    /// The largest cost, in the cost's own unit (µs or ns): a second per
    /// triangle or fragment is already absurd, and with costs this size a
    /// run's simulated times stay finite.
    pub const MAX_COST: f64 = 1e6;

    /// Close to the CHC paper's GeForce FX 5950 / Pentium 4 (2004): slow draw
    /// calls, long query round trips and a driver that lets the CPU run no
    /// further ahead than the command the GPU is running. Derived from the
    /// paper's Table 1 and the chip's published rates (`docs/gpu-models.md`).
    pub fn gpu_2004() -> Self {
        Self {
            name: "gpu-2004".into(),
            cpu_draw_call_us: 4.0,
            cpu_state_change_us: 2.0,
            cpu_query_us: 2.0,
            cpu_hib_query_us: None,
            cpu_query_poll_us: 0.5,
            cpu_node_us: 0.3,
            gpu_draw_call_us: 3.0,
            gpu_triangle_ns: 25.0,
            gpu_fragment_ns: 0.6,
            gpu_state_change_us: 2.0,
            gpu_query_box_us: 2.0,
            gpu_query_fragment_ns: 0.3,
            query_latency_us: 12.0,
            driver_queue_us: 0.0,
            cpu_dispatch_us: 4.0,
            gpu_dispatch_us: 10.0,
            gpu_compute_item_ns: 2.0,
            gpu_box_us: 0.3,
            gpu_box_fragment_ns: 0.6,
            gpu_pyramid_texel_ns: 2.0,
            gpu_hiz_box_ns: 67.0,
            gpu_hiz_texel_ns: 0.6,
            gpu_indirect_draw_us: 1.5,
            readback_us: 12.0,
            gpu_hib_batch_us: None,
            cpu_moc_triangle_ns: MOC_TRIANGLE_NS,
            cpu_moc_tile_ns: MOC_TILE_NS,
            cpu_moc_box_ns: MOC_BOX_NS,
            cpu_moc_subtile_read_ns: MOC_SUBTILE_READ_NS,
        }
    }

    /// A current desktop GPU driven by a modern API: cheap draw calls and
    /// triangles, but a deep pipeline whose query results come back late;
    /// command buffers never block a submission within a frame.
    pub fn modern() -> Self {
        Self {
            name: "modern".into(),
            cpu_draw_call_us: 1.0,
            cpu_state_change_us: 1.5,
            cpu_query_us: 0.5,
            cpu_hib_query_us: None,
            cpu_query_poll_us: 0.1,
            cpu_node_us: 0.05,
            gpu_draw_call_us: 0.5,
            gpu_triangle_ns: 0.4,
            gpu_fragment_ns: 0.02,
            gpu_state_change_us: 1.0,
            gpu_query_box_us: 0.3,
            gpu_query_fragment_ns: 0.005,
            query_latency_us: 30.0,
            driver_queue_us: f64::INFINITY,
            cpu_dispatch_us: 1.0,
            gpu_dispatch_us: 3.0,
            gpu_compute_item_ns: 0.05,
            gpu_box_us: 0.005,
            gpu_box_fragment_ns: 0.02,
            gpu_pyramid_texel_ns: 0.05,
            gpu_hiz_box_ns: 1.0,
            gpu_hiz_texel_ns: 0.02,
            gpu_indirect_draw_us: 0.1,
            readback_us: 30.0,
            gpu_hib_batch_us: None,
            cpu_moc_triangle_ns: MOC_TRIANGLE_NS,
            cpu_moc_tile_ns: MOC_TILE_NS,
            cpu_moc_box_ns: MOC_BOX_NS,
            cpu_moc_subtile_read_ns: MOC_SUBTILE_READ_NS,
        }
    }

    /// GPU time of a draw before its fragments: the call's fixed cost
    /// `call_us` (`gpu_draw_call_us`, or `gpu_indirect_draw_us` for a draw
    /// from an indirect list) plus `gpu_triangle_ns` per triangle, µs. The
    /// soft backend and the `--paper gvq` experiments charge draws by it.
    pub fn draw_us(&self, call_us: f64, triangles: u64) -> f64 {
        call_us + triangles as f64 * self.gpu_triangle_ns * 1e-3
    }

    /// CPU time to record one query in an item-buffer batch, µs:
    /// `cpu_hib_query_us` where measured, else `cpu_query_us`.
    pub fn hib_query_us(&self) -> f64 {
        self.cpu_hib_query_us.unwrap_or(self.cpu_query_us)
    }

    /// GPU time of one item-buffer batch beyond its boxes', µs:
    /// `gpu_hib_batch_us` where measured, else a draw call and a dispatch
    /// (`gpu_draw_call_us` + `gpu_dispatch_us`: its draw and the clearing
    /// of its counts).
    pub fn hib_batch_gpu_us(&self) -> f64 {
        self.gpu_hib_batch_us.unwrap_or(self.gpu_draw_call_us + self.gpu_dispatch_us)
    }

    /// GPU time of `fragments` drawn fragments, `gpu_fragment_ns` each, µs.
    pub fn fragments_us(&self, fragments: u64) -> f64 {
        fragments as f64 * self.gpu_fragment_ns * 1e-3
    }

    /// GPU work of a compute dispatch over `items` elements,
    /// `gpu_compute_item_ns` each, on top of the dispatch's fixed
    /// `gpu_dispatch_us`, µs.
    pub fn compute_items_us(&self, items: u64) -> f64 {
        items as f64 * self.gpu_compute_item_ns * 1e-3
    }

    /// The costs of draws, queries and GPU-driven passes this model
    /// charges, for methods that decide by cost whether a query pays
    /// (`nohc`) or which method to run (`auto`).
    pub fn cost_model(&self) -> CostModel {
        CostModel {
            cpu_draw_call_us: self.cpu_draw_call_us,
            gpu_draw_call_us: self.gpu_draw_call_us,
            gpu_triangle_ns: self.gpu_triangle_ns,
            gpu_fragment_ns: self.gpu_fragment_ns,
            cpu_query_us: self.cpu_query_us,
            gpu_query_box_us: self.gpu_query_box_us,
            gpu_query_fragment_ns: self.gpu_query_fragment_ns,
            query_latency_us: self.query_latency_us,
            cpu_dispatch_us: self.cpu_dispatch_us,
            gpu_dispatch_us: self.gpu_dispatch_us,
            gpu_pyramid_texel_ns: self.gpu_pyramid_texel_ns,
        }
    }

    /// The preset called `name`.
    pub fn preset(name: &str) -> Option<Self> {
        match name {
            "gpu-2004" => Some(Self::gpu_2004()),
            "modern" => Some(Self::modern()),
            _ => None,
        }
    }

    /// A preset by name, or a TOML file holding `preset = "..."` (default
    /// `modern`) plus any fields to override.
    pub fn load(name_or_path: &str) -> Result<Self, GpuModelError> {
        if let Some(model) = Self::preset(name_or_path) {
            return Ok(model);
        }
        let path = Path::new(name_or_path);
        if !path.exists() {
            return Err(GpuModelError::Unknown(name_or_path.to_string()));
        }
        let text = occlude_core::input_file::read_text(path, Self::MAX_FILE_BYTES)
            .map_err(|reason| GpuModelError::Io { path: name_or_path.to_string(), reason })?;
        Self::from_toml(&text).map_err(|message| GpuModelError::Invalid { path: name_or_path.to_string(), message })
    }

    /// Parses a TOML override (see [`GpuModel::load`]).
    pub fn from_toml(text: &str) -> Result<Self, String> {
        let mut table: toml::Table = text.parse().map_err(|e: toml::de::Error| e.message().to_string())?;
        let base = match table.remove("preset") {
            None => Self::modern(),
            Some(toml::Value::String(p)) => Self::preset(&p)
                .ok_or_else(|| format!("unknown preset '{p}': expected one of {}", Self::PRESETS.join(", ")))?,
            Some(other) => return Err(format!("'preset' must be a string, not {other}")),
        };
        let mut merged = toml::Table::try_from(&base).map_err(|e| e.to_string())?;
        merged.extend(table);
        let model: Self = merged.try_into().map_err(|e: toml::de::Error| e.message().to_string())?;
        model.validate()?;
        Ok(model)
    }

    /// Every cost must be a number from 0 to [`Self::MAX_COST`]; the driver's
    /// queue a non-negative one or `inf`.
    pub fn validate(&self) -> Result<(), String> {
        let costs = [
            ("cpu_draw_call_us", self.cpu_draw_call_us),
            ("cpu_state_change_us", self.cpu_state_change_us),
            ("cpu_query_us", self.cpu_query_us),
            ("cpu_hib_query_us", self.hib_query_us()),
            ("cpu_query_poll_us", self.cpu_query_poll_us),
            ("cpu_node_us", self.cpu_node_us),
            ("gpu_draw_call_us", self.gpu_draw_call_us),
            ("gpu_triangle_ns", self.gpu_triangle_ns),
            ("gpu_fragment_ns", self.gpu_fragment_ns),
            ("gpu_state_change_us", self.gpu_state_change_us),
            ("gpu_query_box_us", self.gpu_query_box_us),
            ("gpu_query_fragment_ns", self.gpu_query_fragment_ns),
            ("query_latency_us", self.query_latency_us),
            ("cpu_dispatch_us", self.cpu_dispatch_us),
            ("gpu_dispatch_us", self.gpu_dispatch_us),
            ("gpu_compute_item_ns", self.gpu_compute_item_ns),
            ("gpu_box_us", self.gpu_box_us),
            ("gpu_box_fragment_ns", self.gpu_box_fragment_ns),
            ("gpu_pyramid_texel_ns", self.gpu_pyramid_texel_ns),
            ("gpu_hiz_box_ns", self.gpu_hiz_box_ns),
            ("gpu_hiz_texel_ns", self.gpu_hiz_texel_ns),
            ("gpu_indirect_draw_us", self.gpu_indirect_draw_us),
            ("readback_us", self.readback_us),
            ("gpu_hib_batch_us", self.hib_batch_gpu_us()),
            ("cpu_moc_triangle_ns", self.cpu_moc_triangle_ns),
            ("cpu_moc_tile_ns", self.cpu_moc_tile_ns),
            ("cpu_moc_box_ns", self.cpu_moc_box_ns),
            ("cpu_moc_subtile_read_ns", self.cpu_moc_subtile_read_ns),
        ];
        if let Some((name, v)) = costs.iter().find(|(_, v)| !(0.0..=Self::MAX_COST).contains(v)) {
            // Huge and tiny values in exponent form, as a TOML file would
            // write them, not as hundreds of digits.
            let v = if (1e-6..1e15).contains(&v.abs()) || *v == 0.0 { v.to_string() } else { format!("{v:e}") };
            return Err(format!("{name} = {v}: costs must be numbers from 0 to {:e}", Self::MAX_COST));
        }
        if self.driver_queue_us.is_nan() || self.driver_queue_us < 0.0 {
            return Err(format!("driver_queue_us = {}: must be >= 0 (inf: unbounded)", self.driver_queue_us));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Methods on a backend without a model of its own decide as on `modern`.
    #[test]
    fn the_default_cost_model_is_the_modern_presets() {
        assert_eq!(GpuModel::modern().cost_model(), CostModel::default());
        assert_ne!(GpuModel::gpu_2004().cost_model(), CostModel::default());
    }

    #[test]
    fn presets_are_valid_and_distinct() {
        for p in GpuModel::PRESETS {
            let m = GpuModel::preset(p).unwrap();
            assert_eq!(m.name, p);
            m.validate().unwrap();
        }
        assert!(GpuModel::gpu_2004().cpu_draw_call_us > GpuModel::modern().cpu_draw_call_us);
    }

    #[test]
    fn toml_overrides_a_preset() {
        let m = GpuModel::from_toml("preset = \"gpu-2004\"\nquery_latency_us = 99.0\nname = \"mine\"").unwrap();
        assert_eq!(m.query_latency_us, 99.0);
        assert_eq!(m.name, "mine");
        assert_eq!(m.cpu_draw_call_us, GpuModel::gpu_2004().cpu_draw_call_us);
    }

    /// The driver's queue is a bound, not a cost: any depth, or none.
    #[test]
    fn the_driver_queue_is_a_bound_or_unbounded() {
        let m = GpuModel::from_toml("preset = \"gpu-2004\"\ndriver_queue_us = 500.0").unwrap();
        assert_eq!(m.driver_queue_us, 500.0);
        let m = GpuModel::from_toml("driver_queue_us = inf").unwrap();
        assert_eq!(m.driver_queue_us, f64::INFINITY);
        // A written model reads back the same, bounded or not.
        let bounded = GpuModel { driver_queue_us: 250.0, ..GpuModel::gpu_2004() };
        for m in [bounded, GpuModel::gpu_2004(), GpuModel::modern()] {
            assert_eq!(GpuModel::from_toml(&toml::to_string(&m).unwrap()).unwrap(), m);
        }
    }

    /// The item buffer's optional costs: a model file without one (older
    /// than it) loads with none and charges what the cost stood in for
    /// before (a batched query at `cpu_query_us`; a batch, a draw call and a
    /// dispatch); one with it, its value; the presets have none.
    #[test]
    fn the_item_buffers_optional_costs_default_to_what_they_replace() {
        type Field = fn(&GpuModel) -> Option<f64>;
        type Charge = fn(&GpuModel) -> f64;
        let costs: [(&str, Field, Charge, Charge); 2] = [
            ("cpu_hib_query_us", |m| m.cpu_hib_query_us, GpuModel::hib_query_us, |m| m.cpu_query_us),
            (
                "gpu_hib_batch_us",
                |m| m.gpu_hib_batch_us,
                GpuModel::hib_batch_gpu_us,
                |m| m.gpu_draw_call_us + m.gpu_dispatch_us,
            ),
        ];
        for (name, field, charge, fallback) in costs {
            let old = GpuModel::from_toml("preset = \"gpu-2004\"\ncpu_query_us = 3.0\ngpu_dispatch_us = 7.0").unwrap();
            assert_eq!((field(&old), charge(&old)), (None, fallback(&old)), "{name}");
            assert!(!toml::to_string(&old).unwrap().contains(name), "{name}");
            let new = GpuModel::from_toml(&format!("{name} = 0.25")).unwrap();
            assert_eq!((field(&new), charge(&new)), (Some(0.25), 0.25), "{name}");
            assert_eq!(GpuModel::from_toml(&toml::to_string(&new).unwrap()).unwrap(), new, "{name}");
            for preset in [GpuModel::modern(), GpuModel::gpu_2004()] {
                assert_eq!(charge(&preset), fallback(&preset), "{name}: {}", preset.name);
            }
            assert!(GpuModel::from_toml(&format!("{name} = -1.0")).unwrap_err().contains(name));
        }
    }

    /// A model file without `cpu_moc_subtile_read_ns` (older than it) loads
    /// with the preset's per-read cost; one with it, its value; a negative
    /// one is refused by name.
    #[test]
    fn the_box_tests_per_read_cost_loads_defaults_and_validates() {
        let old = GpuModel::from_toml("preset = \"gpu-2004\"\ncpu_moc_box_ns = 500.0").unwrap();
        assert_eq!((old.cpu_moc_box_ns, old.cpu_moc_subtile_read_ns), (500.0, MOC_SUBTILE_READ_NS));
        let new = GpuModel::from_toml("cpu_moc_subtile_read_ns = 2.5").unwrap();
        assert_eq!(new.cpu_moc_subtile_read_ns, 2.5);
        assert_eq!(GpuModel::from_toml(&toml::to_string(&new).unwrap()).unwrap(), new);
        // A whole model written before the field deserializes with the default.
        let mut table = toml::Table::try_from(GpuModel::modern()).unwrap();
        table.remove("cpu_moc_subtile_read_ns");
        let model: GpuModel = table.try_into().unwrap();
        assert_eq!(model.cpu_moc_subtile_read_ns, MOC_SUBTILE_READ_NS);
        let err = GpuModel::from_toml("cpu_moc_subtile_read_ns = -1.0").unwrap_err();
        assert!(err.contains("cpu_moc_subtile_read_ns"), "{err}");
    }

    #[test]
    fn toml_errors_name_the_problem() {
        assert!(GpuModel::from_toml("no_such_cost = 1.0").unwrap_err().contains("no_such_cost"));
        assert!(GpuModel::from_toml("preset = \"gpu-1999\"").unwrap_err().contains("gpu-1999"));
        assert!(GpuModel::from_toml("query_latency_us = -1.0").unwrap_err().contains("query_latency_us"));
        assert!(matches!(GpuModel::load("nonexistent-model"), Err(GpuModelError::Unknown(_))));
        assert!(GpuModel::from_toml("driver_queue_us = -1.0").unwrap_err().contains("driver_queue_us"));
        assert!(GpuModel::from_toml("driver_queue_us = nan").unwrap_err().contains("driver_queue_us"));
        let huge = GpuModel::from_toml("gpu_fragment_ns = 1e305").unwrap_err();
        assert!(huge.contains("gpu_fragment_ns = 1e305") && huge.contains("from 0 to 1e6"), "{huge}");
        GpuModel::from_toml("gpu_fragment_ns = 1e6").unwrap();
    }

    #[test]
    fn only_a_small_regular_file_is_read_and_its_error_said_once() {
        let e = GpuModel::load("/dev/zero").unwrap_err().to_string();
        assert!(e.contains("/dev/zero") && e.contains("not a regular file"), "{e}");
        let folder = std::env::temp_dir();
        let e = GpuModel::load(folder.to_str().unwrap()).unwrap_err();
        assert!(std::error::Error::source(&e).is_none(), "the reason is in the message, not a source too");
    }
}
