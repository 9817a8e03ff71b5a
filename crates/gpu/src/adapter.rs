//! Adapters: listing them, choosing one, and the errors of a device that cannot run
//! glint's shaders.

use std::sync::Weak;

use glint_volume::{ColourVolume, Field};
use wgpu::{Backends, DeviceType, DownlevelFlags};

/// Why the GPU back end cannot run: each variant one line for the user.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No adapter at all (no Vulkan, Metal or DX12 driver).
    #[error("no GPU adapter found (Vulkan, Metal or DX12): install the GPU's driver, or Mesa's lavapipe (mesa-vulkan-drivers) for a software one")]
    NoAdapter,
    /// Adapters, but none a hardware GPU (`--device auto` takes only those).
    #[error("no hardware GPU adapter (found only: {found})")]
    NoHardware {
        /// The adapters found, by name.
        found: String,
    },
    /// The adapter cannot run compute shaders.
    #[error("GPU adapter {adapter} cannot run compute shaders")]
    NoCompute {
        /// The adapter's name.
        adapter: String,
    },
    /// The adapter's limits are below what a render needs.
    #[error("GPU adapter {adapter}: {what} is {have}, the render needs {need}")]
    Limits {
        /// The adapter's name.
        adapter: String,
        /// The limit.
        what: &'static str,
        /// The adapter's value.
        have: u64,
        /// What the render needs.
        need: u64,
    },
    /// The scene asks for something the GPU back end does not render yet.
    #[error("{0}")]
    Unsupported(String),
    /// The device failed (out of memory, lost, a driver error).
    #[error("GPU device: {0}")]
    Device(String),
}

/// Which adapters [`Gpu::open`] may take.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Choice {
    /// A hardware GPU only (discrete or integrated): `--device auto`.
    Hardware,
    /// Any adapter, a software one (lavapipe) included: `--device gpu`, the tests.
    Any,
}

/// One adapter as `glint info --devices` lists it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AdapterSummary {
    /// The device's name (e.g. `llvmpipe (LLVM 15.0.6, 256 bits)`).
    pub name: String,
    /// The API: `vulkan`, `metal`, `dx12`.
    pub backend: String,
    /// `DiscreteGpu`, `IntegratedGpu`, `VirtualGpu`, `Cpu` or `Other`.
    pub device_type: String,
    /// The driver and its version.
    pub driver: String,
    /// The largest 3D texture side.
    pub max_texture_3d: u32,
    /// Whether it runs compute shaders.
    pub compute: bool,
    /// Whether it is a hardware GPU (discrete or integrated).
    pub hardware: bool,
}

impl AdapterSummary {
    fn of(adapter: &wgpu::Adapter) -> AdapterSummary {
        let info = adapter.get_info();
        let driver = match (info.driver.is_empty(), info.driver_info.is_empty()) {
            (false, false) => format!("{} {}", info.driver, info.driver_info),
            (false, true) => info.driver.clone(),
            _ => info.driver_info.clone(),
        };
        AdapterSummary {
            name: info.name.clone(),
            backend: info.backend.to_str().to_string(),
            device_type: format!("{:?}", info.device_type),
            driver,
            max_texture_3d: adapter.limits().max_texture_dimension_3d,
            compute: adapter
                .get_downlevel_capabilities()
                .flags
                .contains(DownlevelFlags::COMPUTE_SHADERS),
            hardware: matches!(
                info.device_type,
                DeviceType::DiscreteGpu | DeviceType::IntegratedGpu
            ),
        }
    }
}

fn instance() -> wgpu::Instance {
    wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends: Backends::PRIMARY,
        ..wgpu::InstanceDescriptor::new_without_display_handle()
    })
}

fn all_adapters(instance: &wgpu::Instance) -> Vec<wgpu::Adapter> {
    pollster::block_on(instance.enumerate_adapters(Backends::PRIMARY))
}

/// Every adapter of the primary backends (Vulkan, Metal, DX12), as the driver lists
/// them; empty when there is none.
pub fn adapters() -> Vec<AdapterSummary> {
    all_adapters(&instance())
        .iter()
        .map(AdapterSummary::of)
        .collect()
}

/// Rank of an adapter for [`Gpu::open`]: discrete before integrated before the rest.
fn rank(t: DeviceType) -> u8 {
    match t {
        DeviceType::DiscreteGpu => 0,
        DeviceType::IntegratedGpu => 1,
        DeviceType::VirtualGpu => 2,
        DeviceType::Cpu => 3,
        DeviceType::Other => 4,
    }
}

/// An open GPU device with glint's pipelines, and the field last uploaded to it.
pub struct Gpu {
    pub(crate) summary: AdapterSummary,
    pub(crate) device: wgpu::Device,
    pub(crate) queue: wgpu::Queue,
    pub(crate) limits: wgpu::Limits,
    pub(crate) local: wgpu::ComputePipeline,
    /// The same for the tricubic filter (its 64-tap spline compiled in only there),
    /// built on the first tricubic frame.
    pub(crate) local_tricubic: Option<wgpu::ComputePipeline>,
    /// The same two for a paged field (trilinear, tricubic), built on first use.
    pub(crate) local_paged: [Option<wgpu::ComputePipeline>; 2],
    /// A 3D texture side below the adapter's to keep to ([`Gpu::limit_texture_side`]).
    pub(crate) side_limit: Option<u32>,
    /// The `shadows` light volumes' sweep, built on the first frame that sweeps.
    pub(crate) sweep: Option<wgpu::ComputePipeline>,
    /// The light volumes last swept, kept while their inputs are the same.
    pub(crate) lights: Option<SweptCache>,
    /// Light-volume sweeps run so far (each builds every light's grid).
    pub(crate) sweeps_run: u64,
    pub(crate) field: Option<FieldCache>,
    pub(crate) colour: Option<ColourCache>,
}

impl Gpu {
    /// Opens the best adapter `choice` allows (discrete, then integrated, then the
    /// rest), with its own limits: errors when there is none, when `choice` is
    /// [`Choice::Hardware`] and only software adapters exist, or when the adapter
    /// cannot run compute shaders.
    pub fn open(choice: Choice) -> Result<Gpu, GpuError> {
        let instance = instance();
        let mut found = all_adapters(&instance);
        if found.is_empty() {
            return Err(GpuError::NoAdapter);
        }
        found.sort_by_key(|a| rank(a.get_info().device_type));
        let adapter = found.swap_remove(0);
        let summary = AdapterSummary::of(&adapter);
        if choice == Choice::Hardware && !summary.hardware {
            let mut names = vec![summary.name.clone()];
            names.extend(found.iter().map(|a| a.get_info().name));
            return Err(GpuError::NoHardware {
                found: names.join(", "),
            });
        }
        if !summary.compute {
            return Err(GpuError::NoCompute {
                adapter: summary.name,
            });
        }
        let limits = adapter.limits();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("glint"),
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device(e.to_string()))?;
        let local = pipeline(&device, false, false);
        Ok(Gpu {
            summary,
            device,
            queue,
            limits,
            local,
            local_tricubic: None,
            local_paged: [None, None],
            side_limit: None,
            sweep: None,
            lights: None,
            sweeps_run: 0,
            field: None,
            colour: None,
        })
    }

    /// The adapter this device runs on.
    pub fn adapter(&self) -> &AdapterSummary {
        &self.summary
    }

    /// Keeps the field's 3D textures to `side` texels along each axis (at most the
    /// adapter's own limit), as an adapter with that limit would: a field past it is
    /// paged into an atlas within it. For holding GPU memory to smaller textures,
    /// and for testing paging on any adapter. Applies from the next field uploaded.
    pub fn limit_texture_side(&mut self, side: u32) {
        self.side_limit = Some(side.max(1));
    }

    /// The largest 3D texture side the field's textures may take: the adapter's,
    /// or the lower one [`Gpu::limit_texture_side`] set.
    pub fn texture_side(&self) -> u32 {
        let have = self.limits.max_texture_dimension_3d;
        self.side_limit.map_or(have, |s| s.min(have))
    }

    /// A limit check: `have >= need`, else [`GpuError::Limits`].
    pub(crate) fn need(&self, what: &'static str, have: u64, need: u64) -> Result<(), GpuError> {
        if have >= need {
            return Ok(());
        }
        Err(GpuError::Limits {
            adapter: self.summary.name.clone(),
            what,
            have,
            need,
        })
    }

    /// Waits for the queue's work, then the errors `scopes` caught (validation, out of
    /// memory) as [`GpuError::Device`].
    pub(crate) fn finish(&self, scopes: Vec<wgpu::ErrorScopeGuard>) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Device(e.to_string()))?;
        for scope in scopes.into_iter().rev() {
            if let Some(e) = pollster::block_on(scope.pop()) {
                return Err(GpuError::Device(e.to_string()));
            }
        }
        Ok(())
    }

    /// Error scopes for out-of-memory and validation errors, popped by
    /// [`Gpu::finish`].
    pub(crate) fn scopes(&self) -> Vec<wgpu::ErrorScopeGuard> {
        vec![
            self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory),
            self.device.push_error_scope(wgpu::ErrorFilter::Validation),
        ]
    }

    /// Reads back `size` bytes of `buffer` (a `COPY_SRC` storage buffer).
    pub(crate) fn read(&self, buffer: &wgpu::Buffer, size: u64) -> Result<Vec<u8>, GpuError> {
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("glint readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
        self.queue.submit([encoder.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        staging.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Device(e.to_string()))?;
        rx.recv()
            .map_err(|e| GpuError::Device(e.to_string()))?
            .map_err(|e| GpuError::Device(e.to_string()))?;
        let bytes = staging
            .get_mapped_range(..)
            .map_err(|e| GpuError::Device(e.to_string()))?
            .to_vec();
        staging.unmap();
        Ok(bytes)
    }
}

/// Light volumes swept on the device and what they were swept from: the same
/// extinction grid (alive, the same allocation), the same sweeps (one per light,
/// in index space: a world-fixed light keeps its sweep while the camera orbits)
/// and the same occlusion give the same values, so a frame reuses the buffer.
pub(crate) struct SweptCache {
    pub(crate) sigma: Weak<Vec<f32>>,
    pub(crate) lights: Vec<glint_volume::LightSweep>,
    pub(crate) occlusion: Option<Weak<Vec<f32>>>,
    pub(crate) buffer: wgpu::Buffer,
}

/// The colour volume last uploaded (`None`: the placeholder of frames without one)
/// and its texture of 8-bit sRGB codes.
pub(crate) struct ColourCache {
    pub(crate) colour: Option<Weak<ColourVolume>>,
    pub(crate) codes: wgpu::TextureView,
}

/// A field's textures on the device, kept while the same field is rendered.
pub(crate) struct FieldCache {
    pub(crate) field: Weak<Field>,
    pub(crate) values: wgpu::TextureView,
    pub(crate) gradients: wgpu::TextureView,
    pub(crate) gradient_scale: f32,
    /// The page table of a paged field ([`crate::pages`]); a placeholder otherwise.
    pub(crate) pages: wgpu::Buffer,
    /// Whether the textures are a paged atlas.
    pub(crate) paged: bool,
}

/// The `local` compute pipeline (its bind group layout derived from the shader),
/// for the tricubic filter or the trilinear one: the shader's `TRICUBIC` override,
/// so that the other filter's code is compiled out (the spline's 64 taps, inlined
/// into every sample of a trilinear frame behind a branch on a uniform, made
/// lavapipe's trilinear frames 3.5 times slower).
pub(crate) fn pipeline(
    device: &wgpu::Device,
    tricubic: bool,
    paged: bool,
) -> wgpu::ComputePipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("glint local"),
        source: wgpu::ShaderSource::Wgsl(include_str!("local.wgsl").into()),
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("glint local"),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants: &[
                ("TRICUBIC", f64::from(u8::from(tricubic))),
                ("PAGED", f64::from(u8::from(paged))),
            ],
            ..Default::default()
        },
        cache: None,
    })
}
