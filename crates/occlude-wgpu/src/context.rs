//! Opening a GPU: adapter, device and queue, with the optional features the
//! backend uses when the adapter has them.

use occlude_core::GpuCullingUnsupported;
use std::sync::{Arc, Mutex};

/// Why the GPU could not be used.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter at all (no driver, no GPU, no software Vulkan).
    #[error(
        "no GPU adapter found ({0}). Install a Vulkan driver (on Debian, `apt-get install \
         mesa-vulkan-drivers libvulkan1` gives lavapipe, a CPU Vulkan), or use occlude's software backend \
         (`occlude-soft`), which needs no GPU"
    )]
    NoAdapter(String),
    /// The adapter exists but refused to open a device.
    #[error("the GPU adapter '{adapter}' refused to open a device: {reason}")]
    Device {
        /// Adapter name.
        adapter: String,
        /// The driver's reason.
        reason: String,
    },
    /// Adapters exist, but none can run the backend (a GL driver without depth
    /// copies, say).
    #[error(
        "no GPU adapter can run the wgpu backend: {0}. Install a Vulkan driver (on Debian, \
         `apt-get install mesa-vulkan-drivers libvulkan1` gives lavapipe, a CPU Vulkan) or pick another \
         adapter with WGPU_BACKEND / WGPU_ADAPTER_NAME, or use occlude's software backend \
         (`occlude-soft`), which needs no GPU"
    )]
    Unsuitable(String),
    /// The scene does not fit the adapter's limits.
    #[error("the scene does not fit GPU adapter '{adapter}': {reason}")]
    TooLarge {
        /// Adapter name.
        adapter: String,
        /// Which limit and by how much.
        reason: String,
    },
}

/// An open GPU device shared by every backend of a run.
pub struct GpuContext {
    /// The device resources are created on.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// What the adapter says about itself.
    pub info: wgpu::AdapterInfo,
    /// Whether render passes can write timestamps (GPU time per frame).
    pub timestamps: bool,
    /// What the GPU-driven methods need that the adapter lacks, in words
    /// (empty when it has everything).
    culling_lacks: Vec<&'static str>,
    /// Whether indirect multi-draws take their count from a GPU buffer.
    multi_draw_count: bool,
    failure: Arc<Mutex<Option<String>>>,
}

impl GpuContext {
    /// Opens the most capable adapter that can run the backend (see
    /// `choose`); the `WGPU_BACKEND` environment variable narrows the
    /// graphics APIs searched and `WGPU_ADAPTER_NAME` the adapters' names.
    /// OpenGL is searched only where `WGPU_BACKEND` names it: wgpu's GL
    /// adapters all lack copies of depth textures to buffers, so the search
    /// could only refuse them, and loading the GL driver to do so is not
    /// free (Mesa's libEGL, unloaded at exit while its own threads end, has
    /// crashed the process after the refusal was printed).
    pub fn new() -> Result<Self, GpuError> {
        let mut descriptor = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        if wgpu::Backends::from_env().is_none() {
            descriptor.backends.remove(wgpu::Backends::GL);
        }
        Self::open(&best_adapter(&wgpu::Instance::new(descriptor), None)?)
    }

    /// The GPU a test named `test` runs on. Without one the test is skipped,
    /// saying so on stderr, unless the environment sets
    /// `OCCLUDE_REQUIRE_GPU=1` (CI does, with lavapipe installed): then the
    /// missing GPU fails the test.
    pub fn for_test(test: &str) -> Option<Arc<Self>> {
        match Self::new() {
            Ok(ctx) => Some(Arc::new(ctx)),
            Err(e) if std::env::var("OCCLUDE_REQUIRE_GPU").is_ok_and(|v| v == "1") => {
                panic!("{test}: OCCLUDE_REQUIRE_GPU=1 but the GPU cannot be used: {e}")
            }
            Err(e) => {
                eprintln!("skipping {test}: {e}");
                None
            }
        }
    }

    /// Opens a device on `adapter`, asking for timestamp queries and the
    /// features of GPU-resident culling (forced early depth tests, a first
    /// instance in indirect draws, multi-draw-indirect-count) when it has them, and routes device loss and
    /// uncaptured errors to [`GpuContext::failure`] instead of wgpu's default
    /// panic.
    ///
    /// An adapter lacking one of [`REQUIRED_DOWNLEVEL`] is refused
    /// ([`GpuError::Unsuitable`]); one lacking what culling needs still runs
    /// the CPU-driven methods.
    pub fn open(adapter: &wgpu::Adapter) -> Result<Self, GpuError> {
        let candidate = Candidate::of(adapter);
        if !candidate.missing.is_empty() {
            return Err(GpuError::Unsuitable(candidate.describe()));
        }
        let info = adapter.get_info();
        let wanted = wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::MULTI_DRAW_INDIRECT_COUNT | CULLING_FEATURES;
        let features = adapter.features() & wanted;
        let downlevel = adapter.get_downlevel_capabilities().flags;
        let culling_lacks = CULLING_NEEDS
            .iter()
            .filter(|(need, _)| match need {
                Need::Feature(f) => !features.contains(*f),
                Need::Downlevel(d) => !downlevel.contains(*d),
            })
            .map(|&(_, words)| words)
            .collect();
        let descriptor = wgpu::DeviceDescriptor {
            label: Some("occlude"),
            required_features: features,
            required_limits: adapter.limits(),
            ..Default::default()
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&descriptor))
            .map_err(|e| GpuError::Device { adapter: info.name.clone(), reason: e.to_string() })?;
        let failure = Arc::new(Mutex::new(None));
        let lost = Arc::clone(&failure);
        device.set_device_lost_callback(move |reason, message| {
            record_failure(&lost, format!("the GPU device was lost ({reason:?}): {message}"));
        });
        let uncaptured = Arc::clone(&failure);
        device.on_uncaptured_error(Arc::new(move |error: wgpu::Error| {
            record_failure(&uncaptured, format!("GPU error: {error}"));
        }));
        Ok(Self {
            device,
            queue,
            info,
            timestamps: features.contains(wgpu::Features::TIMESTAMP_QUERY),
            culling_lacks,
            multi_draw_count: features.contains(wgpu::Features::MULTI_DRAW_INDIRECT_COUNT),
            failure,
        })
    }

    /// A context over a renderer's own `device` and `queue` (handles to
    /// the same device: wgpu's handles are reference-counted), for the
    /// embedding (module `embed`). Unlike [`GpuContext::open`] it installs
    /// no device-lost or uncaptured-error handler: those stay the
    /// renderer's. Its [`GpuContext::failure`] holds only what this crate
    /// found itself (a read-back that failed or never finished). It offers
    /// no timestamps and no GPU-resident culling.
    pub(crate) fn from_device(device: &wgpu::Device, queue: &wgpu::Queue) -> Self {
        Self {
            info: device.adapter_info(),
            device: device.clone(),
            queue: queue.clone(),
            timestamps: false,
            culling_lacks: vec!["an embedding of GPU-resident culling"],
            multi_draw_count: false,
            failure: Arc::new(Mutex::new(None)),
        }
    }

    /// Whether the GPU-driven methods' list draws are one
    /// `multi_draw_indexed_indirect_count` (the count read on the GPU); without
    /// it they draw the list's whole capacity, the draws past its count empty.
    pub fn multi_draw_indirect_count(&self) -> bool {
        self.multi_draw_count
    }

    /// Whether the device can run GPU-resident culling, or what it lacks.
    pub fn gpu_culling_support(&self) -> Result<(), GpuCullingUnsupported> {
        if self.culling_lacks.is_empty() {
            return Ok(());
        }
        Err(GpuCullingUnsupported(format!(
            "the GPU adapter '{}' lacks {}, which the GPU-driven methods (roc, ioc) need",
            self.info.name,
            in_words(&self.culling_lacks)
        )))
    }

    /// A one-line description of the adapter for reports:
    /// name, driver and wgpu backend.
    pub fn adapter_name(&self) -> String {
        let driver = [self.info.driver.as_str(), self.info.driver_info.as_str()]
            .iter()
            .filter(|s| !s.is_empty())
            .copied()
            .collect::<Vec<_>>()
            .join(" ");
        format!("{} ({}, {:?})", self.info.name, driver, self.info.backend)
    }

    /// The first fatal error the device reported (loss, validation, out of
    /// memory), if any.
    pub fn failure(&self) -> Option<String> {
        self.failure.lock().map(|f| f.clone()).unwrap_or_else(|p| p.into_inner().clone())
    }

    /// Records a failure found by the backend itself (a read-back that never
    /// completed, say).
    pub(crate) fn fail(&self, message: String) {
        record_failure(&self.failure, message);
    }
}

/// What the backend needs beyond WebGL 2 level: storage buffers read by
/// vertex shaders (instance transforms and query boxes), indexed draws with a
/// base vertex (one vertex pool for every mesh), and depth textures copied to
/// buffers (the depth image the correctness rule compares). Vulkan, Metal and
/// D3D12 adapters have them all; some GL drivers lack the depth copies.
pub const REQUIRED_DOWNLEVEL: wgpu::DownlevelFlags = {
    let mut flags = wgpu::DownlevelFlags::empty();
    let mut i = 0;
    while i < NEEDS.len() {
        flags = flags.union(NEEDS[i].0);
        i += 1;
    }
    flags
};

/// [`REQUIRED_DOWNLEVEL`] flag by flag, each with the words a refusal uses.
const NEEDS: [(wgpu::DownlevelFlags, &str); 3] = [
    (wgpu::DownlevelFlags::VERTEX_STORAGE, "storage buffers in vertex shaders"),
    (wgpu::DownlevelFlags::BASE_VERTEX, "a base vertex in indexed draws"),
    (wgpu::DownlevelFlags::DEPTH_TEXTURE_AND_BUFFER_COPIES, "copies of depth textures to buffers"),
];

/// Optional device features that GPU-resident culling needs: fragment
/// shaders that set visibility flags only for fragments that passed the depth
/// test, and indirect draws whose first instance names the instance drawn.
const CULLING_FEATURES: wgpu::Features =
    wgpu::Features::SHADER_EARLY_DEPTH_TEST.union(wgpu::Features::INDIRECT_FIRST_INSTANCE);

/// A capability GPU-resident culling needs.
enum Need {
    Feature(wgpu::Features),
    Downlevel(wgpu::DownlevelFlags),
}

/// What GPU-resident culling needs, each with the words a refusal uses.
const CULLING_NEEDS: [(Need, &str); 5] = [
    (Need::Downlevel(wgpu::DownlevelFlags::COMPUTE_SHADERS), "compute shaders"),
    (Need::Downlevel(wgpu::DownlevelFlags::FRAGMENT_WRITABLE_STORAGE), "storage buffers written by fragment shaders"),
    (Need::Downlevel(wgpu::DownlevelFlags::INDIRECT_EXECUTION), "indirect draws and dispatches"),
    (Need::Feature(wgpu::Features::SHADER_EARLY_DEPTH_TEST), "forced early depth tests (shader-early-depth-test)"),
    (
        Need::Feature(wgpu::Features::INDIRECT_FIRST_INSTANCE),
        "a first instance in indirect draws (indirect-first-instance)",
    ),
];

/// `a`, `a and b`, `a, b and c`.
fn in_words(items: &[&str]) -> String {
    match items {
        [] => String::new(),
        [one] => (*one).to_string(),
        [init @ .., last] => format!("{} and {last}", init.join(", ")),
    }
}

/// The adapter of `instance` to open, as `choose` picks it (of those that
/// can draw to `surface`, when given); `WGPU_ADAPTER_NAME` narrows the names.
pub fn best_adapter(instance: &wgpu::Instance, surface: Option<&wgpu::Surface<'_>>) -> Result<wgpu::Adapter, GpuError> {
    let mut adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
    if let Some(surface) = surface {
        adapters.retain(|a| a.is_surface_supported(surface));
    }
    let candidates: Vec<Candidate> = adapters.iter().map(Candidate::of).collect();
    let wanted = std::env::var("WGPU_ADAPTER_NAME").ok();
    let chosen = choose(&candidates, wanted.as_deref())?;
    Ok(adapters.swap_remove(chosen))
}

/// An adapter as [`choose`] sees it.
#[derive(Clone, Debug)]
struct Candidate {
    /// Name, driver API in brackets.
    name: String,
    device_type: wgpu::DeviceType,
    /// Which of [`REQUIRED_DOWNLEVEL`] it lacks.
    missing: wgpu::DownlevelFlags,
}

impl Candidate {
    fn of(adapter: &wgpu::Adapter) -> Self {
        let info = adapter.get_info();
        Self {
            name: format!("{} ({:?})", info.name, info.backend),
            device_type: info.device_type,
            missing: REQUIRED_DOWNLEVEL.difference(adapter.get_downlevel_capabilities().flags),
        }
    }

    /// The adapter's name and, if it lacks some, what it lacks, in words.
    fn describe(&self) -> String {
        let lacks: Vec<&str> = NEEDS.iter().filter(|(f, _)| self.missing.contains(*f)).map(|&(_, w)| w).collect();
        if lacks.is_empty() {
            self.name.clone()
        } else {
            format!("{} lacks {}", self.name, lacks.join(", "))
        }
    }
}

/// Index of the adapter to open: of those whose name contains `wanted` (any
/// case) and that lack nothing in [`REQUIRED_DOWNLEVEL`], the first of the
/// most capable kind (a discrete GPU, then integrated, virtual, a CPU
/// rasterizer such as lavapipe, other).
fn choose(candidates: &[Candidate], wanted: Option<&str>) -> Result<usize, GpuError> {
    if candidates.is_empty() {
        return Err(GpuError::NoAdapter("wgpu found none on this machine's graphics APIs".into()));
    }
    let named: Vec<usize> = (0..candidates.len())
        .filter(|&i| wanted.is_none_or(|w| candidates[i].name.to_lowercase().contains(&w.to_lowercase())))
        .collect();
    let list = |which: &[usize]| which.iter().map(|&i| candidates[i].describe()).collect::<Vec<_>>().join("; ");
    if named.is_empty() {
        let all: Vec<usize> = (0..candidates.len()).collect();
        return Err(GpuError::NoAdapter(format!(
            "none is named like WGPU_ADAPTER_NAME={}; there are: {}",
            wanted.unwrap_or_default(),
            list(&all)
        )));
    }
    let rank = |t: wgpu::DeviceType| match t {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Cpu => 3,
        wgpu::DeviceType::Other => 4,
    };
    named
        .iter()
        .copied()
        .filter(|&i| candidates[i].missing.is_empty())
        .min_by_key(|&i| (rank(candidates[i].device_type), i))
        .ok_or_else(|| GpuError::Unsuitable(list(&named)))
}

/// Keeps the first failure: later ones are usually its consequences.
fn record_failure(slot: &Mutex<Option<String>>, message: String) {
    let mut slot = slot.lock().unwrap_or_else(|p| p.into_inner());
    slot.get_or_insert(message);
}

#[cfg(test)]
mod tests {
    use super::*;
    use wgpu::{DeviceType, DownlevelFlags};

    fn candidate(name: &str, device_type: DeviceType, missing: DownlevelFlags) -> Candidate {
        Candidate { name: name.into(), device_type, missing }
    }

    #[test]
    fn the_most_capable_suitable_adapter_is_chosen() {
        let none = DownlevelFlags::empty();
        let adapters = [
            candidate("llvmpipe (Gl)", DeviceType::Cpu, DownlevelFlags::DEPTH_TEXTURE_AND_BUFFER_COPIES),
            candidate("llvmpipe (Vulkan)", DeviceType::Cpu, none),
            candidate("NVIDIA H200 (Gl)", DeviceType::DiscreteGpu, DownlevelFlags::VERTEX_STORAGE),
            candidate("NVIDIA H200 (Vulkan)", DeviceType::DiscreteGpu, none),
            candidate("Intel UHD (Vulkan)", DeviceType::IntegratedGpu, none),
        ];
        assert_eq!(choose(&adapters, None).unwrap(), 3);
        assert_eq!(choose(&adapters, Some("LLVMPIPE")).unwrap(), 1);
        assert_eq!(choose(&adapters[..3], None).unwrap(), 1, "a suitable CPU adapter beats an unsuitable GPU");
    }

    #[test]
    fn refusals_say_what_each_adapter_lacks() {
        let gl = candidate("llvmpipe (Gl)", DeviceType::Cpu, DownlevelFlags::DEPTH_TEXTURE_AND_BUFFER_COPIES);
        match choose(std::slice::from_ref(&gl), None) {
            Err(e @ GpuError::Unsuitable(_)) => {
                let message = e.to_string();
                assert!(message.contains("llvmpipe (Gl) lacks copies of depth textures to buffers"), "{message}");
                assert!(message.contains("software backend"), "{message}");
            }
            other => panic!("expected Unsuitable, got {other:?}"),
        }
        match choose(&[gl], Some("nvidia")) {
            Err(GpuError::NoAdapter(why)) => assert!(why.contains("WGPU_ADAPTER_NAME=nvidia"), "{why}"),
            other => panic!("expected NoAdapter, got {other:?}"),
        }
        assert!(matches!(choose(&[], None), Err(GpuError::NoAdapter(_))));
    }

    #[test]
    fn lacks_are_listed_in_words() {
        assert_eq!(in_words(&["a"]), "a");
        assert_eq!(in_words(&["a", "b"]), "a and b");
        assert_eq!(in_words(&["a", "b", "c"]), "a, b and c");
    }
}
