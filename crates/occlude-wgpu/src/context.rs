//! Opening a GPU: adapter, device and queue, with the optional features the
//! backend uses when the adapter has them.

use std::sync::{Arc, Mutex};

/// Why the GPU could not be used.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter at all (no driver, no GPU, no software Vulkan).
    #[error(
        "no GPU adapter found ({0}). Install a Vulkan driver (on Debian, `apt-get install \
         mesa-vulkan-drivers libvulkan1` gives lavapipe, a CPU Vulkan), or benchmark without a GPU: \
         `occlude bench --backend soft` (the default)"
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
    failure: Arc<Mutex<Option<String>>>,
}

impl GpuContext {
    /// Opens the first high-performance adapter wgpu finds (the `WGPU_BACKEND`
    /// and `WGPU_ADAPTER_NAME` environment variables narrow the choice).
    pub fn new() -> Result<Self, GpuError> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let options = wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            ..Default::default()
        };
        let adapter =
            pollster::block_on(instance.request_adapter(&options)).map_err(|e| GpuError::NoAdapter(e.to_string()))?;
        Self::open(&adapter)
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

    /// Opens a device on `adapter`, asking for timestamp queries when it has
    /// them, and routes device loss and uncaptured errors to
    /// [`GpuContext::failure`] instead of wgpu's default panic.
    pub fn open(adapter: &wgpu::Adapter) -> Result<Self, GpuError> {
        let info = adapter.get_info();
        let timestamps = adapter.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        let descriptor = wgpu::DeviceDescriptor {
            label: Some("occlude"),
            required_features: if timestamps { wgpu::Features::TIMESTAMP_QUERY } else { wgpu::Features::empty() },
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
        Ok(Self { device, queue, info, timestamps, failure })
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

/// Keeps the first failure: later ones are usually its consequences.
fn record_failure(slot: &Mutex<Option<String>>, message: String) {
    let mut slot = slot.lock().unwrap_or_else(|p| p.into_inner());
    slot.get_or_insert(message);
}
